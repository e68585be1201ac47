/* The occupancy grid (see occupancy.h). */
#include "occupancy.h"

#include <math.h>
#include <string.h>

#include "error.h"
#include "parallel.h"
#include "rng.h"

/* Cells per block of the reductions (mean, occupied count): a multiple of
 * 64 so that a block owns whole words; the blocks are fixed, so sums do
 * not depend on the thread count. */
#define BLOCK_CELLS ((size_t)1 << 15)
#define BLOCK_WORDS (BLOCK_CELLS / 64)

/* Domain separation of the grid's random streams from every other user
 * of the seed. */
#define OCCUPANCY_STREAM UINT64_C(0x6f63637570616e63)

float nerf__march_step(const float lo[3], const float hi[3], uint32_t steps)
{
    double d2 = 0.0;
    for (int a = 0; a < 3; a++) {
        double e = (double)hi[a] - (double)lo[a];
        d2 += e * e;
    }
    return (float)(sqrt(d2) / (double)(steps ? steps : 1));
}

float nerf__occupancy_threshold(float alpha, float dt)
{
    return (float)(-log1p(-(double)alpha) / (double)dt);
}

void nerf__occupancy_defaults(nerf__occupancy_options *o, const float lo[3],
                              const float hi[3])
{
    memset(o, 0, sizeof *o);
    o->resolution = 128;
    for (int a = 0; a < 3; a++) {
        o->lo[a] = lo[a];
        o->hi[a] = hi[a];
    }
    o->decay = 0.95f;
    o->density_threshold = nerf__occupancy_threshold(
        NERF__OCCUPANCY_ALPHA_DEFAULT,
        nerf__march_step(lo, hi, NERF__MARCH_STEPS_DEFAULT));
    o->chunk = (size_t)1 << 16;
}

int nerf__occupancy_create(const nerf__env *env,
                           const nerf__occupancy_options *o,
                           nerf__occupancy **out)
{
    *out = NULL;
    const uint32_t R = o->resolution;
    if (R < 1 || R > NERF__OCCUPANCY_MAX_RESOLUTION) {
        return nerf__error(NERF_EINVAL, "occupancy grid: resolution %u "
                           "outside 1..%u", R, NERF__OCCUPANCY_MAX_RESOLUTION);
    }
    for (int a = 0; a < 3; a++) {
        if (!(o->lo[a] < o->hi[a]) || !isfinite(o->lo[a]) ||
            !isfinite(o->hi[a])) {
            return nerf__error(NERF_EINVAL, "occupancy grid: bound [%g, %g] "
                               "on axis %d is empty or not finite",
                               (double)o->lo[a], (double)o->hi[a], a);
        }
    }
    if (!(o->decay > 0.0f && o->decay <= 1.0f)) {
        return nerf__error(NERF_EINVAL, "occupancy grid: decay %g outside "
                           "(0, 1]", (double)o->decay);
    }
    if (!(o->density_threshold >= 0.0f)) {
        return nerf__error(NERF_EINVAL, "occupancy grid: density threshold "
                           "%g is negative", (double)o->density_threshold);
    }
    if (o->chunk < 1 || o->chunk > ((size_t)1 << 26)) {
        return nerf__error(NERF_EINVAL, "occupancy grid: chunk of %zu "
                           "points outside 1..2^26", o->chunk);
    }
    const size_t cells = (size_t)R * R * R;
    const size_t words = (cells + 63) / 64;
    const size_t blocks = (cells + BLOCK_CELLS - 1) / BLOCK_CELLS;
    const size_t chunk = o->chunk < cells ? o->chunk : cells;
    const uint32_t bs = 1u << NERF__OCCUPANCY_BLOCK_SHIFT;
    const uint32_t rc = (R + bs - 1) / bs;
    const size_t coarse_words = ((size_t)rc * rc * rc + 63) / 64;
    /* One block holds the struct and every array. */
    const size_t sizes[] = {
        sizeof(nerf__occupancy), cells * sizeof(float),
        words * sizeof(uint64_t), words * sizeof(uint64_t),
        chunk * sizeof(uint32_t), 3 * chunk * sizeof(float),
        chunk * sizeof(float), blocks * sizeof(double),
        coarse_words * sizeof(uint64_t),
    };
    const size_t count = sizeof sizes / sizeof sizes[0];
    unsigned char *mem = nerf__alloc(env, nerf__carve_size(sizes, count));
    if (mem == NULL) {
        return NERF_ENOMEM;
    }
    nerf__occupancy *g = (nerf__occupancy *)mem;
    memset(g, 0, sizeof *g);
    unsigned char *p = mem;
    void *at[sizeof sizes / sizeof sizes[0]];
    for (size_t i = 0; i < count; i++) {
        at[i] = nerf__carve(&p, sizes[i]);
    }
    g->ema = at[1];
    g->bits = at[2];
    g->sel = at[3];
    g->chunk_cells = at[4];
    g->chunk_xyz = at[5];
    g->chunk_sigma = at[6];
    g->block_sum = at[7];
    g->coarse = at[8];
    g->env = *env;
    g->opts = *o;
    g->opts.chunk = chunk;
    g->res = R;
    g->cells = cells;
    g->words = words;
    g->blocks = blocks;
    g->coarse_res = rc;
    for (int a = 0; a < 3; a++) {
        g->lo[a] = o->lo[a];
        g->hi[a] = o->hi[a];
        g->cell_size[a] = (o->hi[a] - o->lo[a]) / (float)R;
        g->inv_cell[a] = (float)R / (o->hi[a] - o->lo[a]);
    }
    nerf__occupancy_reset(g);
    *out = g;
    return NERF_OK;
}

void nerf__occupancy_destroy(nerf__occupancy *g)
{
    if (g) {
        nerf__env env = g->env;
        nerf__free(&env, g);
    }
}

/* Mask of the cells of word w that exist (the last word may be partial). */
static uint64_t word_mask(const nerf__occupancy *g, size_t w)
{
    size_t left = g->cells - 64 * w;
    return left >= 64 ? ~UINT64_C(0) : (UINT64_C(1) << left) - 1;
}

/* Whether any of the len <= 64 bits from bit `start` is set. */
static bool any_bits(const uint64_t *bits, size_t start, unsigned len)
{
    const size_t w = start >> 6;
    const unsigned off = (unsigned)(start & 63);
    uint64_t v = bits[w] >> off;
    if (off + len > 64) {
        v |= bits[w + 1] << (64 - off);
    }
    return (len < 64 ? v & ((UINT64_C(1) << len) - 1) : v) != 0;
}

/* The coarse level from the bits, and the occupied count: one test per
 * run of a block's cells along x. */
static void sync_coarse(nerf__occupancy *g)
{
    const size_t R = g->res, rc = g->coarse_res;
    const uint32_t s = NERF__OCCUPANCY_BLOCK_SHIFT, bs = 1u << s;
    memset(g->coarse, 0, (rc * rc * rc + 63) / 64 * sizeof(uint64_t));
    for (size_t k = 0; k < R; k++) {
        for (size_t j = 0; j < R; j++) {
            const size_t row = R * (j + R * k);
            const size_t b0 = rc * ((j >> s) + rc * (k >> s));
            for (size_t bi = 0; bi < rc; bi++) {
                const size_t i0 = bi << s;
                const unsigned len = (unsigned)(R - i0 < bs ? R - i0 : bs);
                if (any_bits(g->bits, row + i0, len)) {
                    const size_t b = b0 + bi;
                    g->coarse[b >> 6] |= UINT64_C(1) << (b & 63);
                }
            }
        }
    }
    size_t occupied = 0;
    for (size_t w = 0; w < g->words; w++) {
        occupied += (size_t)__builtin_popcountll(g->bits[w]);
    }
    g->occupied = occupied;
}

void nerf__occupancy_reset(nerf__occupancy *g)
{
    memset(g->ema, 0, g->cells * sizeof(float));
    for (size_t w = 0; w < g->words; w++) {
        g->bits[w] = word_mask(g, w);
    }
    sync_coarse(g);
    g->updates = 0;
    g->mean = 0.0f;
    g->threshold = 0.0f;
    g->evaluated = 0;
}

/* The random stream of one cell in one update: draw 1 decides whether the
 * cell is sampled, draws 2 to 4 place its point. */
static nerf__rng cell_rng(uint64_t seed, uint64_t update, size_t cell)
{
    uint64_t key = nerf__mix64(seed ^ nerf__mix64(update ^ OCCUPANCY_STREAM));
    return nerf__rng_make(key, cell);
}

typedef struct update_job {
    nerf__occupancy *g;
    double p;     /* probability that an empty cell is sampled */
    size_t n;     /* cells in the current chunk */
} update_job;

/* Which cells to sample: every occupied one and a random share of the
 * others. */
static void select_block(void *ctx, size_t block)
{
    const update_job *j = ctx;
    nerf__occupancy *g = j->g;
    size_t w1 = (block + 1) * BLOCK_WORDS;
    w1 = w1 < g->words ? w1 : g->words;
    for (size_t w = block * BLOCK_WORDS; w < w1; w++) {
        const uint64_t valid = word_mask(g, w);
        uint64_t sel = g->bits[w];
        if (j->p >= 1.0) {
            sel = valid;
        } else if (j->p > 0.0) {
            uint64_t rest = valid & ~sel;
            while (rest) {
                int b = __builtin_ctzll(rest);
                rest &= rest - 1;
                nerf__rng r = cell_rng(g->opts.seed, g->updates, 64 * w + b);
                if (nerf__rng_uniform_d(&r) < j->p) {
                    sel |= UINT64_C(1) << b;
                }
            }
        }
        g->sel[w] = sel;
    }
}

static void place_points(void *ctx, size_t begin, size_t end)
{
    const update_job *j = ctx;
    nerf__occupancy *g = j->g;
    const size_t R = g->res;
    for (size_t i = begin; i < end; i++) {
        const size_t c = g->chunk_cells[i];
        const size_t ijk[3] = {c % R, (c / R) % R, c / (R * R)};
        nerf__rng r = cell_rng(g->opts.seed, g->updates, c);
        r.counter = 1; /* past the selection draw */
        for (int a = 0; a < 3; a++) {
            float u = (float)ijk[a] + nerf__rng_uniform(&r);
            g->chunk_xyz[3 * i + a] = g->lo[a] + u * g->cell_size[a];
        }
    }
}

/* Cells of a chunk are distinct, so the maxima are independent. */
static void apply_chunk(void *ctx, size_t begin, size_t end)
{
    const update_job *j = ctx;
    nerf__occupancy *g = j->g;
    const float decay = g->opts.decay;
    for (size_t i = begin; i < end; i++) {
        float *e = &g->ema[g->chunk_cells[i]];
        /* fmaxf ignores a NaN density. */
        *e = fmaxf(*e * decay, g->chunk_sigma[i]);
    }
}

/* Decay the cells not sampled (their new density is 0) and sum the EMA. */
static void decay_block(void *ctx, size_t block)
{
    const update_job *j = ctx;
    nerf__occupancy *g = j->g;
    const float decay = g->opts.decay;
    size_t c0 = block * BLOCK_CELLS, c1 = c0 + BLOCK_CELLS;
    c1 = c1 < g->cells ? c1 : g->cells;
    double sum = 0.0;
    for (size_t c = c0; c < c1; c++) {
        if (!((g->sel[c >> 6] >> (c & 63)) & 1u)) {
            g->ema[c] *= decay;
        }
        sum += g->ema[c];
    }
    g->block_sum[block] = sum;
}

static void sum_block(void *ctx, size_t block)
{
    const update_job *j = ctx;
    nerf__occupancy *g = j->g;
    size_t c0 = block * BLOCK_CELLS, c1 = c0 + BLOCK_CELLS;
    c1 = c1 < g->cells ? c1 : g->cells;
    double sum = 0.0;
    for (size_t c = c0; c < c1; c++) {
        sum += g->ema[c];
    }
    g->block_sum[block] = sum;
}

static void bits_block(void *ctx, size_t block)
{
    const update_job *j = ctx;
    nerf__occupancy *g = j->g;
    const float thr = g->threshold;
    size_t w1 = (block + 1) * BLOCK_WORDS;
    w1 = w1 < g->words ? w1 : g->words;
    for (size_t w = block * BLOCK_WORDS; w < w1; w++) {
        const size_t c0 = 64 * w;
        const size_t n = g->cells - c0 < 64 ? g->cells - c0 : 64;
        uint64_t bits = 0;
        for (size_t b = 0; b < n; b++) {
            bits |= (uint64_t)(g->ema[c0 + b] > thr) << b;
        }
        g->bits[w] = bits;
    }
}

/* The mean EMA from the block sums, added in block order so that it does
 * not depend on threads. */
static float block_mean(const nerf__occupancy *g)
{
    double sum = 0.0;
    for (size_t b = 0; b < g->blocks; b++) {
        sum += g->block_sum[b];
    }
    return (float)(sum / (double)g->cells);
}

/* Threshold and bits from the block sums. */
static void finish(nerf__occupancy *g, update_job *j)
{
    g->mean = block_mean(g);
    g->threshold = fminf(g->opts.density_threshold, g->mean);
    nerf__parallel_blocks(g->blocks, 4 * BLOCK_CELLS, bits_block, j);
    sync_coarse(g);
}

void nerf__occupancy_rebuild_bits(nerf__occupancy *g)
{
    update_job j = {.g = g};
    nerf__parallel_blocks(g->blocks, 2 * BLOCK_CELLS, sum_block, &j);
    if (g->updates == 0) {
        g->mean = block_mean(g);
        g->threshold = 0.0f;
        for (size_t w = 0; w < g->words; w++) {
            g->bits[w] = word_mask(g, w);
        }
        sync_coarse(g);
        return;
    }
    finish(g, &j);
}

int nerf__occupancy_restore(nerf__occupancy *g, const float *ema,
                            size_t ema_bytes, const uint64_t *bits,
                            size_t bits_bytes, uint64_t updates)
{
    if (ema_bytes != g->cells * sizeof(float) ||
        (bits && bits_bytes != g->words * sizeof(uint64_t))) {
        return nerf__error(NERF_EFORMAT, "occupancy grid: saved state of "
                           "%zu + %zu bytes does not fit a %u^3 grid",
                           ema_bytes, bits ? bits_bytes : 0, g->res);
    }
    memcpy(g->ema, ema, ema_bytes);
    g->updates = updates;
    if (bits == NULL) {
        nerf__occupancy_rebuild_bits(g);
        return NERF_OK;
    }
    for (size_t w = 0; w < g->words; w++) {
        g->bits[w] = bits[w] & word_mask(g, w);
    }
    /* The mean and threshold are figures of the EMA, as after an update. */
    update_job j = {.g = g};
    nerf__parallel_blocks(g->blocks, 2 * BLOCK_CELLS, sum_block, &j);
    g->mean = block_mean(g);
    g->threshold = updates ? fminf(g->opts.density_threshold, g->mean) : 0.0f;
    sync_coarse(g);
    return NERF_OK;
}

int nerf__occupancy_update(nerf__occupancy *g, nerf__density_fn density,
                           void *ctx, size_t n_random)
{
    update_job j = {.g = g};
    j.p = n_random >= g->cells ? 1.0 : (double)n_random / (double)g->cells;
    /* Each empty cell costs a draw of its own stream (two mixes and a
     * generator), and once the grid is carved most cells are empty, so
     * the selection is worth spreading over the pool (docs/perf-log/
     * 2026-11-27-0.10.4.md). */
    nerf__parallel_blocks(g->blocks, 32 * BLOCK_CELLS, select_block, &j);
    /* Walk the selection in cell order, a chunk at a time. */
    const size_t chunk = g->opts.chunk;
    size_t evaluated = 0;
    size_t w = 0;
    uint64_t pending = g->words ? g->sel[0] : 0;
    for (;;) {
        size_t n = 0;
        while (n < chunk && w < g->words) {
            if (pending == 0) {
                if (++w < g->words) {
                    pending = g->sel[w];
                }
                continue;
            }
            int b = __builtin_ctzll(pending);
            pending &= pending - 1;
            g->chunk_cells[n++] = (uint32_t)(64 * w + (size_t)b);
        }
        if (n == 0) {
            break;
        }
        j.n = n;
        nerf__parallel_for(n, 40, place_points, &j);
        int rc = density(ctx, n, g->chunk_xyz, g->chunk_sigma);
        if (rc != 0) {
            return rc;
        }
        nerf__parallel_for(n, 4, apply_chunk, &j);
        evaluated += n;
    }
    nerf__parallel_blocks(g->blocks, 4 * BLOCK_CELLS, decay_block, &j);
    finish(g, &j);
    g->evaluated = evaluated;
    g->updates++;
    return NERF_OK;
}

typedef struct zero_job {
    const nerf__occupancy *g;
    const float *points;
    float *sigma;
} zero_job;

static void zero_range(void *ctx, size_t begin, size_t end)
{
    const zero_job *j = ctx;
    for (size_t i = begin; i < end; i++) {
        if (!nerf__occupancy_occupied(j->g, j->points + 3 * i)) {
            j->sigma[i] = 0.0f;
        }
    }
}

void nerf__occupancy_zero_empty(const nerf__occupancy *g, size_t n,
                                const float *points, float *sigma)
{
    zero_job j = {g, points, sigma};
    nerf__parallel_for(n, 20, zero_range, &j);
}
