#include "hashgrid.h"

#include <math.h>
#include <pthread.h>
#include <string.h>

#include "error.h"
#include "multiversion.h"
#include "prefetch.h"
#include "rng.h"

/*
 * Work is done in tiles of TILE samples for one level at a time: a first
 * pass computes the 8 corner entries and weights of every sample of the
 * tile (straight-line arithmetic the compiler vectorises), a second
 * gathers or scatters them.  The second pass is bound by the latency of
 * the hashed tables, which live in L3 (a default level is 4 MiB, the
 * whole table 46 MiB), and takes most of the time.  Its loads are
 * independent from sample to sample, and the out-of-order core overlaps
 * some of them; prefetching the corners of the sample AHEAD places on
 * overlaps more.  bench_hashgrid chose the distance: 16 ahead gained more
 * than 8 in both directions, 64 nothing in the backward (docs/perf-log/
 * 2026-11-26-fused-small-mlp-and-step-floor.md).  Huge pages were no
 * faster.
 *
 * Levels are the outer loop over a block of BLOCK samples, so a level's
 * table keeps the core's cache to itself while the block visits it
 * instead of sharing it with 15 others.  On random samples one level at a
 * time over blocks of 2^16 or more samples was faster than over 2^14, and
 * faster still than all levels per tile.  A tile (19 KiB) stays in L1.
 */
#ifndef TILE
#  define TILE 256
#endif
#ifndef BLOCK
#  define BLOCK 65536
#endif
#define AHEAD 16

/* Below this many samples (or levels) per thread, threads cost more than
 * they save. */
#define MIN_SAMPLES_PER_THREAD 4096


/* ---- configuration ------------------------------------------------------ */

int nerf__hashgrid_defaults(nerf__hashgrid *hg, const float bound_min[3],
                            const float bound_max[3])
{
    memset(hg, 0, sizeof *hg);
    hg->levels = 16;
    hg->features = 2;
    hg->log2_table = 19;
    hg->min_resolution = 16;
    hg->max_resolution = 2048;
    for (int a = 0; a < 3; a++) {
        hg->bound_min[a] = bound_min[a];
        hg->bound_max[a] = bound_max[a];
    }
    return nerf__hashgrid_layout(hg);
}

int nerf__hashgrid_layout(nerf__hashgrid *hg)
{
    const uint32_t L = hg->levels;
    if (L < 1 || L > NERF__HASHGRID_MAX_LEVELS) {
        return nerf__error(NERF_EINVAL, "hash grid: levels %u outside 1..%u", L,
                           NERF__HASHGRID_MAX_LEVELS);
    }
    if (hg->features < 1 || hg->features > NERF__HASHGRID_MAX_FEATURES) {
        return nerf__error(NERF_EINVAL, "hash grid: features %u outside 1..%u",
                           hg->features, NERF__HASHGRID_MAX_FEATURES);
    }
    if (hg->log2_table < 1 || hg->log2_table > NERF__HASHGRID_MAX_LOG2_TABLE) {
        return nerf__error(NERF_EINVAL,
                           "hash grid: log2 table size %u outside 1..%u",
                           hg->log2_table, NERF__HASHGRID_MAX_LOG2_TABLE);
    }
    if (hg->min_resolution < 1 || hg->max_resolution < hg->min_resolution ||
        hg->max_resolution > NERF__HASHGRID_MAX_RESOLUTION) {
        return nerf__error(NERF_EINVAL,
                           "hash grid: resolutions %u..%u not within "
                           "1..%u in increasing order",
                           hg->min_resolution, hg->max_resolution,
                           NERF__HASHGRID_MAX_RESOLUTION);
    }
    for (int a = 0; a < 3; a++) {
        float lo = hg->bound_min[a], hi = hg->bound_max[a];
        float inv = 1.0f / (hi - lo);
        if (!(isfinite(lo) && isfinite(hi) && hi > lo && isfinite(inv))) {
            return nerf__error(NERF_EINVAL,
                               "hash grid: bound [%g, %g] of axis %d "
                               "is empty or not finite",
                               (double)lo, (double)hi, a);
        }
        hg->inv_extent[a] = inv;
    }
    const uint64_t T = UINT64_C(1) << hg->log2_table;
    const double nmin = hg->min_resolution, nmax = hg->max_resolution;
    const double log_b =
        L > 1 ? (log(nmax) - log(nmin)) / (double)(L - 1) : 0.0;
    size_t offset = 0;
    for (uint32_t l = 0; l < L; l++) {
        /* The relative nudge keeps floor() from landing one below an exact
         * integer (N_max itself at the last level) through rounding of
         * exp; it is far below any real gap between resolutions. */
        double v = nmin * exp((double)l * log_b);
        double r = floor(v * (1.0 + 1e-12));
        if (r < nmin) {
            r = nmin;
        }
        if (r > nmax) {
            r = nmax;
        }
        uint32_t res = (uint32_t)r;
        uint64_t side = (uint64_t)res + 1;
        uint64_t dense = side * side * side;
        hg->resolution[l] = res;
        hg->dense[l] = dense <= T;
        hg->entries[l] = (uint32_t)(dense <= T ? dense : T);
        hg->offset[l] = offset;
        offset += (size_t)hg->entries[l] * hg->features;
    }
    for (uint32_t l = L; l < NERF__HASHGRID_MAX_LEVELS; l++) {
        hg->resolution[l] = 0;
        hg->entries[l] = 0;
        hg->dense[l] = false;
        hg->offset[l] = offset;
    }
    hg->count = offset;
    return NERF_OK;
}

uint32_t nerf__hashgrid_index(const nerf__hashgrid *hg, uint32_t level,
                              uint32_t x, uint32_t y, uint32_t z)
{
    if (hg->dense[level]) {
        uint32_t side = hg->resolution[level] + 1;
        return x + side * (y + side * z);
    }
    return nerf__hashgrid_hash(x, y, z, hg->log2_table);
}

void nerf__hashgrid_init(const nerf__hashgrid *hg, float *table, uint64_t seed,
                         uint64_t stream_base)
{
    for (uint32_t l = 0; l < hg->levels; l++) {
        nerf__rng rng = nerf__rng_make(seed, stream_base + l);
        float *t = table + hg->offset[l];
        size_t m = (size_t)hg->entries[l] * hg->features;
        for (size_t i = 0; i < m; i++) {
            t[i] = (2.0f * nerf__rng_uniform(&rng) - 1.0f) * 1e-4f;
        }
    }
}

/* ---- kernels ------------------------------------------------------------ */

typedef struct tile {
    float u[3][TILE];      /* positions in the unit cube, clamped */
    uint32_t idx[8][TILE]; /* corner c = bx + 2 by + 4 bz, entry index */
    float w[8][TILE];      /* its trilinear weight */
} tile;

/*
 * Positions of samples [0, m) of `in` into t->u.  Each clamp is its own
 * comparison so that the compiler can use the SIMD min and max, whose
 * handling of NaN (the second operand wins) sends NaN to 0.
 */
static NERF__ALWAYS_INLINE void load_positions(const nerf__hashgrid *hg,
                                         size_t m, const float *restrict in,
                                         size_t in_stride, tile *restrict t)
{
    for (int a = 0; a < 3; a++) {
        const float lo = hg->bound_min[a], inv = hg->inv_extent[a];
        float *restrict u = t->u[a];
        for (size_t s = 0; s < m; s++) {
            float v = (in[s * in_stride + a] - lo) * inv;
            v = v > 0.0f ? v : 0.0f;
            v = v < 1.0f ? v : 1.0f;
            u[s] = v;
        }
    }
}

/*
 * Cell and weights of each position at resolution N.  A position at the
 * far face (u = 1) is placed in the last cell with weight 1 on its far
 * corners, so vertex N is read and nothing beyond it.  Signed integers
 * throughout: they convert to and from float in SIMD registers, and
 * positions are at most 2^20.
 */
static inline void cell(float u, float N, int32_t last, int32_t *i, float *f)
{
    float p = u * N;
    int32_t k = (int32_t)p;
    k = k < last ? k : last;
    *i = k;
    *f = p - (float)k;
}

static inline void weights(tile *restrict t, size_t s, float fx, float fy,
                           float fz)
{
    float gx = 1.0f - fx, gy = 1.0f - fy, gz = 1.0f - fz;
    float w00 = gy * gz, w10 = fy * gz, w01 = gy * fz, w11 = fy * fz;
    t->w[0][s] = gx * w00;
    t->w[1][s] = fx * w00;
    t->w[2][s] = gx * w10;
    t->w[3][s] = fx * w10;
    t->w[4][s] = gx * w01;
    t->w[5][s] = fx * w01;
    t->w[6][s] = gx * w11;
    t->w[7][s] = fx * w11;
}

/* Corner entries and weights at level l of the m positions in t->u. */
static NERF__ALWAYS_INLINE void corners(const nerf__hashgrid *hg, uint32_t l,
                                  size_t m, tile *restrict t)
{
    const float N = (float)hg->resolution[l];
    const int32_t last = (int32_t)hg->resolution[l] - 1;
    const float *restrict ux = t->u[0], *restrict uy = t->u[1],
                          *restrict uz = t->u[2];
    if (hg->dense[l]) {
        const int32_t side = (int32_t)hg->resolution[l] + 1;
        const int32_t plane = side * side;
        for (size_t s = 0; s < m; s++) {
            int32_t ix, iy, iz;
            float fx, fy, fz;
            cell(ux[s], N, last, &ix, &fx);
            cell(uy[s], N, last, &iy, &fy);
            cell(uz[s], N, last, &iz, &fz);
            weights(t, s, fx, fy, fz);
            uint32_t b = (uint32_t)(ix + side * iy + plane * iz);
            t->idx[0][s] = b;
            t->idx[1][s] = b + 1;
            t->idx[2][s] = b + (uint32_t)side;
            t->idx[3][s] = b + (uint32_t)side + 1;
            t->idx[4][s] = b + (uint32_t)plane;
            t->idx[5][s] = b + (uint32_t)plane + 1;
            t->idx[6][s] = b + (uint32_t)(plane + side);
            t->idx[7][s] = b + (uint32_t)(plane + side) + 1;
        }
        return;
    }
    const uint32_t mask = (1u << hg->log2_table) - 1u;
    for (size_t s = 0; s < m; s++) {
        int32_t ix, iy, iz;
        float fx, fy, fz;
        cell(ux[s], N, last, &ix, &fx);
        cell(uy[s], N, last, &iy, &fy);
        cell(uz[s], N, last, &iz, &fz);
        weights(t, s, fx, fy, fz);
        uint32_t x0 = (uint32_t)ix, x1 = x0 + 1;
        uint32_t hy0 = (uint32_t)iy * NERF__HASHGRID_PRIME_Y;
        uint32_t hy1 = hy0 + NERF__HASHGRID_PRIME_Y;
        uint32_t hz0 = (uint32_t)iz * NERF__HASHGRID_PRIME_Z;
        uint32_t hz1 = hz0 + NERF__HASHGRID_PRIME_Z;
        uint32_t a00 = hy0 ^ hz0, a10 = hy1 ^ hz0, a01 = hy0 ^ hz1,
                 a11 = hy1 ^ hz1;
        t->idx[0][s] = (x0 ^ a00) & mask;
        t->idx[1][s] = (x1 ^ a00) & mask;
        t->idx[2][s] = (x0 ^ a10) & mask;
        t->idx[3][s] = (x1 ^ a10) & mask;
        t->idx[4][s] = (x0 ^ a01) & mask;
        t->idx[5][s] = (x1 ^ a01) & mask;
        t->idx[6][s] = (x0 ^ a11) & mask;
        t->idx[7][s] = (x1 ^ a11) & mask;
    }
}

/* F is a constant in each instantiation below, so the feature loops
 * unroll. */
static NERF__ALWAYS_INLINE void gather(const tile *restrict t, size_t m,
                                 const float *restrict table, uint32_t F,
                                 float *restrict out, size_t out_stride)
{
    for (size_t s = 0; s < m; s++) {
        for (int c = 0; c < 8 && s + AHEAD < m; c++) {
            NERF__PREFETCH(table + (size_t)t->idx[c][s + AHEAD] * F, 0, 3);
        }
        float acc[NERF__HASHGRID_MAX_FEATURES];
        for (uint32_t f = 0; f < F; f++) {
            acc[f] = 0.0f;
        }
        for (int c = 0; c < 8; c++) {
            const float *e = table + (size_t)t->idx[c][s] * F;
            const float w = t->w[c][s];
            for (uint32_t f = 0; f < F; f++) {
                acc[f] += w * e[f];
            }
        }
        float *o = out + s * out_stride;
        for (uint32_t f = 0; f < F; f++) {
            o[f] = acc[f];
        }
    }
}

static NERF__ALWAYS_INLINE void scatter(const tile *restrict t, size_t m,
                                  float *restrict grad, uint32_t F,
                                  const float *restrict d, size_t d_stride)
{
    for (size_t s = 0; s < m; s++) {
        for (int c = 0; c < 8 && s + AHEAD < m; c++) {
            NERF__PREFETCH(grad + (size_t)t->idx[c][s + AHEAD] * F, 1, 3);
        }
        float g[NERF__HASHGRID_MAX_FEATURES];
        const float *ds = d + s * d_stride;
        for (uint32_t f = 0; f < F; f++) {
            g[f] = ds[f];
        }
        for (int c = 0; c < 8; c++) {
            float *e = grad + (size_t)t->idx[c][s] * F;
            const float w = t->w[c][s];
            for (uint32_t f = 0; f < F; f++) {
                e[f] += w * g[f];
            }
        }
    }
}

static NERF__ALWAYS_INLINE void gather_any(const tile *t, size_t m,
                                     const float *table, uint32_t F,
                                     float *out, size_t out_stride)
{
    switch (F) {
    case 1: gather(t, m, table, 1, out, out_stride); break;
    case 2: gather(t, m, table, 2, out, out_stride); break;
    case 4: gather(t, m, table, 4, out, out_stride); break;
    case 8: gather(t, m, table, 8, out, out_stride); break;
    default: gather(t, m, table, F, out, out_stride); break;
    }
}

static NERF__ALWAYS_INLINE void
scatter_any(const tile *t, size_t m, float *grad,
            uint32_t F, const float *d,
            size_t d_stride)
{
    switch (F) {
    case 1: scatter(t, m, grad, 1, d, d_stride); break;
    case 2: scatter(t, m, grad, 2, d, d_stride); break;
    case 4: scatter(t, m, grad, 4, d, d_stride); break;
    case 8: scatter(t, m, grad, 8, d, d_stride); break;
    default: scatter(t, m, grad, F, d, d_stride); break;
    }
}

NERF__CLONED(forward_range,
             (const nerf__hashgrid *hg, const float *table, size_t begin,
              size_t end, const float *in, size_t in_stride, float *out,
              size_t out_stride),
             (hg, table, begin, end, in, in_stride, out, out_stride))
{
    tile t;
    const uint32_t F = hg->features;
    for (size_t b0 = begin; b0 < end; b0 += BLOCK) {
        size_t b1 = end - b0 < BLOCK ? end : b0 + BLOCK;
        for (uint32_t l = 0; l < hg->levels; l++) {
            const float *tl = table + hg->offset[l];
            for (size_t s0 = b0; s0 < b1; s0 += TILE) {
                size_t m = b1 - s0 < TILE ? b1 - s0 : TILE;
                load_positions(hg, m, in + s0 * in_stride, in_stride, &t);
                corners(hg, l, m, &t);
                gather_any(&t, m, tl, F, out + s0 * out_stride + (size_t)l * F,
                           out_stride);
            }
        }
    }
}

/*
 * One level over all samples in order, without blocking: the level's
 * table then gets the cache to itself for the whole pass (measured as
 * fast as blocking by BLOCK at 2^18 samples), and the order of the adds
 * into each entry is fixed by the samples alone.
 */
NERF__CLONED(backward_level,
             (const nerf__hashgrid *hg, uint32_t level, size_t n,
              const float *in, size_t in_stride, const float *d_out,
              size_t d_stride, float *grad),
             (hg, level, n, in, in_stride, d_out, d_stride, grad))
{
    tile t;
    const uint32_t F = hg->features;
    float *gl = grad + hg->offset[level];
    for (size_t s0 = 0; s0 < n; s0 += TILE) {
        size_t m = n - s0 < TILE ? n - s0 : TILE;
        load_positions(hg, m, in + s0 * in_stride, in_stride, &t);
        corners(hg, level, m, &t);
        scatter_any(&t, m, gl, F, d_out + s0 * d_stride + (size_t)level * F,
                    d_stride);
    }
}

void nerf__hashgrid_forward_range(const nerf__hashgrid *hg, const float *table,
                                  size_t begin, size_t end, const float *in,
                                  size_t in_stride, float *out,
                                  size_t out_stride)
{
    forward_range(hg, table, begin, end, in, in_stride, out, out_stride);
}

void nerf__hashgrid_backward_level(const nerf__hashgrid *hg, uint32_t level,
                                   size_t n, const float *in, size_t in_stride,
                                   const float *d_out, size_t d_stride,
                                   float *grad)
{
    backward_level(hg, level, n, in, in_stride, d_out, d_stride, grad);
}

/* ---- threads ------------------------------------------------------------ */

#define MAX_THREADS 64

typedef struct job {
    const nerf__hashgrid *hg;
    const float *table; /* forward */
    float *grad;        /* backward */
    size_t n, begin, end;
    const float *in;
    size_t in_stride;
    float *out;
    const float *d_out;
    size_t stride; /* of out or d_out */
    bool mine[NERF__HASHGRID_MAX_LEVELS];
} job;

static void *forward_job(void *arg)
{
    job *j = arg;
    nerf__hashgrid_forward_range(j->hg, j->table, j->begin, j->end, j->in,
                                 j->in_stride, j->out, j->stride);
    return NULL;
}

static void *backward_job(void *arg)
{
    job *j = arg;
    for (uint32_t l = 0; l < j->hg->levels; l++) {
        if (j->mine[l]) {
            nerf__hashgrid_backward_level(j->hg, l, j->n, j->in, j->in_stride,
                                          j->d_out, j->stride, j->grad);
        }
    }
    return NULL;
}

/*
 * Run fn on jobs[1..k) in new threads and jobs[0] in this one.  A thread
 * that cannot be created has its job run here instead: each job's result
 * does not depend on which thread runs it.
 */
static void run_jobs(job *jobs, uint32_t k, void *(*fn)(void *))
{
    pthread_t tid[MAX_THREADS];
    bool started[MAX_THREADS];
    for (uint32_t i = 1; i < k; i++) {
        started[i] = pthread_create(&tid[i], NULL, fn, &jobs[i]) == 0;
    }
    fn(&jobs[0]);
    for (uint32_t i = 1; i < k; i++) {
        if (started[i]) {
            pthread_join(tid[i], NULL);
        } else {
            fn(&jobs[i]);
        }
    }
}

void nerf__hashgrid_forward(const nerf__hashgrid *hg, const float *table,
                            size_t n, const float *in, size_t in_stride,
                            float *out, size_t out_stride, uint32_t threads)
{
    size_t k = threads < 1 ? 1 : threads > MAX_THREADS ? MAX_THREADS : threads;
    if (k > n / MIN_SAMPLES_PER_THREAD) {
        k = n / MIN_SAMPLES_PER_THREAD;
    }
    if (k <= 1) {
        nerf__hashgrid_forward_range(hg, table, 0, n, in, in_stride, out,
                                     out_stride);
        return;
    }
    job jobs[MAX_THREADS];
    /* Chunks in whole tiles so that threads do not share the cache lines
     * of each other's output rows more than they must. */
    size_t per = (n + k - 1) / k;
    per = (per + TILE - 1) / TILE * TILE;
    for (size_t i = 0; i < k; i++) {
        job *j = &jobs[i];
        memset(j, 0, sizeof *j);
        j->hg = hg;
        j->table = table;
        j->in = in;
        j->in_stride = in_stride;
        j->out = out;
        j->stride = out_stride;
        j->begin = i * per < n ? i * per : n;
        j->end = (i + 1) * per < n ? (i + 1) * per : n;
    }
    run_jobs(jobs, (uint32_t)k, forward_job);
}

void nerf__hashgrid_backward(const nerf__hashgrid *hg, size_t n,
                             const float *in, size_t in_stride,
                             const float *d_out, size_t d_stride, float *grad,
                             uint32_t threads)
{
    const uint32_t L = hg->levels;
    uint32_t k = threads < 1             ? 1
                 : threads > MAX_THREADS ? MAX_THREADS
                                         : threads;
    if (k > L) {
        k = L;
    }
    if (n < MIN_SAMPLES_PER_THREAD) {
        k = 1;
    }
    job jobs[MAX_THREADS];
    /*
     * Levels are dealt finest first to the thread with the least work so
     * far, a hashed level counting as twice a dense one (whose table sits
     * in cache).  Which thread owns a level changes nothing in its
     * gradients, only the balance.
     */
    uint32_t load[MAX_THREADS] = {0};
    for (uint32_t i = 0; i < k; i++) {
        job *j = &jobs[i];
        memset(j, 0, sizeof *j);
        j->hg = hg;
        j->grad = grad;
        j->n = n;
        j->in = in;
        j->in_stride = in_stride;
        j->d_out = d_out;
        j->stride = d_stride;
    }
    for (uint32_t l = L; l-- > 0;) {
        uint32_t best = 0;
        for (uint32_t i = 1; i < k; i++) {
            if (load[i] < load[best]) {
                best = i;
            }
        }
        jobs[best].mine[l] = true;
        load[best] += hg->dense[l] ? 1 : 2;
    }
    run_jobs(jobs, k, backward_job);
}
