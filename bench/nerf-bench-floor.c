/*
 * The fast step's floor: what a training step on the last step's samples
 * must cost at least on this machine, part by part, measured rather than
 * taken from a data sheet.
 *
 *  - Encoding: every sample reads the 8 corners of its cell at each of
 *    the hash grid's levels and, going backward, adds a gradient to each.
 *    Neighbouring samples share corners, so the floor counts each
 *    distinct corner of the step (an entry its gradient reached) once at
 *    the cost of a random read and read-modify-write of one entry, timed
 *    on the model's own tables level by level with every thread issuing
 *    independent accesses, so that the memory system keeps as many in
 *    flight as it can (memory-level parallelism, not bandwidth, bounds a
 *    random gather), and the other accesses at the cost of one that hits
 *    the cache.  Counting all 8 at the random cost, as this file did
 *    first, came out above the measured encoding on an AMD EPYC.
 *  - MLP: the network's products, forward and the two backward ones (dX,
 *    dW), at the machine's peak multiply-add rate (nerf-bench-peak.c).
 *  - Optimiser: an Adam update of what the step touched.  The layers are
 *    dense, at the rate of a pass that streams them.  The hash entries
 *    with a gradient lie scattered over the arrays of the table's size
 *    that the update reads and writes, which no cache holds: parameters,
 *    gradients and two moments, and with updates corrected by each
 *    entry's own count (the fast preset's) the two powers of the betas
 *    as well, six in all.  So the unit of their cost is the 64-byte
 *    line, not the parameter: the cost of updating them alone is one
 *    random read-modify-write of each array's line that holds a touched
 *    entry, timed like the encoding's on the table's gradient.
 *    Streaming those arrays whole is the other way, and the floor is the
 *    cheaper of the two: about the same on an Intel Xeon, while on an
 *    AMD EPYC the lines alone came to two to three times the stream.
 *    (Until 2026-12-03 the floor counted four arrays for the corrected
 *    update too, and so put it a third too low.)
 *  - Grid refresh: the density of the cells a refresh evaluates (per
 *    step: a sixteenth of them), as encoding reads plus the density
 *    layers' products.
 * Compositing and ray drawing get no floor: they are a few percent of the
 * step.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nerf-bench.h"

#define ACCESSES_PER_BLOCK ((size_t)1 << 20)
/* Passes over a block's indices in one timed run: a cached access costs
 * a fraction of a nanosecond, and one pass (a fraction of a millisecond)
 * would time the pool's wake-up as much as the accesses (the figure
 * moved 1.8-fold between runs). */
#define PASSES 8
/* Entries a thread's cached accesses are drawn from: 8 KiB at 2 floats,
 * inside any level-1 data cache, and enough that two adds in flight
 * seldom meet on one entry. */
#define CACHED_ENTRIES 1024u
#define MAX_BLOCKS 64

const char floor_method[] =
    "the hash grid's distinct corners of the step, each read and given a "
    "gradient add at the random-access cost measured on the model's own "
    "tables with every thread issuing independent accesses, and the rest "
    "of the 8 reads and adds per sample and level at a cached access's "
    "cost; the network's forward, dX and dW products at the measured fp32 "
    "FMA peak; Adam: the layers at a streaming pass's rate, and the table "
    "at the lesser of a random 64-byte line update in each array the "
    "update moves (parameters, gradients, moments, and with corrected "
    "updates the betas' powers: 4 or 6) for each line holding a touched "
    "entry and a streaming pass over those arrays; a refresh's density "
    "queries per step";

static uint64_t next_random(uint64_t *s)
{
    /* xorshift64*: the bench's own stream, independent of the library's. */
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * UINT64_C(2685821657736338717);
}

typedef struct access_job {
    float *table;       /* a level's entries, `features` floats each */
    uint32_t features;
    const uint32_t *idx; /* ACCESSES_PER_BLOCK entry indices per block */
    bool write;
    bool pairs; /* the loop written for 2 features an entry */
    float sink[MAX_BLOCKS];
} access_job;

static float entry_sum(const float *e, uint32_t f, bool pairs)
{
    if (pairs) {
        return e[0] + e[1];
    }
    float s = 0.0f;
    for (uint32_t k = 0; k < f; k++) {
        s += e[k];
    }
    return s;
}

static void entry_add(float *e, uint32_t f, bool pairs)
{
    if (pairs) {
        e[0] += 1e-30f;
        e[1] += 1e-30f;
        return;
    }
    for (uint32_t k = 0; k < f; k++) {
        e[k] += 1e-30f;
    }
}

/*
 * Independent reads (or read-modify-writes) of the listed entries.  The
 * reads go to four sums: with one, each read waits for the add before it.
 * A loop over a run-time feature count read cached entries much more
 * slowly on an AMD EPYC than the one written for pairs (docs/perf-log/
 * 2026-11-26-fused-small-mlp-and-step-floor.md, "On an AMD EPYC"), so both
 * are timed and the better kept: the floor is the memory's cost, not a
 * loop's.
 */
static void access_block(void *ctx, size_t block)
{
    access_job *j = ctx;
    const uint32_t *idx = j->idx + block * ACCESSES_PER_BLOCK;
    const uint32_t f = j->features;
    const bool pairs = j->pairs;
    float *t = j->table;
    float s = 0.0f;
    for (int pass = 0; pass < PASSES; pass++) {
        if (j->write) {
            for (size_t i = 0; i < ACCESSES_PER_BLOCK; i++) {
                entry_add(t + (size_t)idx[i] * f, f, pairs);
            }
            continue;
        }
        float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f, s3 = 0.0f;
        for (size_t i = 0; i < ACCESSES_PER_BLOCK; i += 4) {
            s0 += entry_sum(t + (size_t)idx[i] * f, f, pairs);
            s1 += entry_sum(t + (size_t)idx[i + 1] * f, f, pairs);
            s2 += entry_sum(t + (size_t)idx[i + 2] * f, f, pairs);
            s3 += entry_sum(t + (size_t)idx[i + 3] * f, f, pairs);
        }
        s += s0 + s1 + s2 + s3;
    }
    j->sink[block % MAX_BLOCKS] = s;
}

/*
 * Seconds per access, all threads together, on `entries` entries of
 * `table`: the best of three runs.  Block b draws its entries from the
 * b-th contiguous part of the table, so that concurrent writes never meet,
 * not even in one cache line (the library's backward gives each level to
 * one thread).
 */
static double time_accesses(float *table, uint32_t entries, uint32_t features,
                            bool write, uint32_t *idx, size_t blocks,
                            uint64_t *seed)
{
    const uint32_t per = entries / (uint32_t)blocks;
    if (per == 0) {
        return 0.0;
    }
    for (size_t b = 0; b < blocks; b++) {
        for (size_t i = 0; i < ACCESSES_PER_BLOCK; i++) {
            uint32_t e = (uint32_t)(next_random(seed) % per);
            idx[b * ACCESSES_PER_BLOCK + i] = (uint32_t)b * per + e;
        }
    }
    access_job j;
    memset(&j, 0, sizeof j);
    j.table = table;
    j.features = features;
    j.idx = idx;
    j.write = write;
    double best = INFINITY;
    for (int run = 0; run < 3 * (1 + (features == 2)); run++) {
        j.pairs = run >= 3;
        double t0 = now();
        nerf__parallel_blocks(blocks, (size_t)1 << 30, access_block, &j);
        best = fmin(best, now() - t0);
    }
    return best / ((double)PASSES * ACCESSES_PER_BLOCK * (double)blocks);
}

/* Floats of a cache line: the unit of a scattered update's traffic. */
#define LINE_FLOATS 16u

static bool has_gradient(const float *g, uint32_t features)
{
    bool any = false;
    for (uint32_t f = 0; f < features; f++) {
        any = any || g[f] != 0.0f;
    }
    return any;
}

size_t touched_params(const nerf_model *m, size_t *lines,
                      size_t level_entries[NERF__HASHGRID_MAX_LEVELS])
{
    const nerf__network *net = &m->nets[0];
    const nerf__hashgrid *hg = &net->pos_enc.u.hash;
    const uint32_t nf = hg->features;
    size_t k = net->count - hg->count, last_line = SIZE_MAX;
    *lines = 0;
    for (uint32_t l = 0; l < hg->levels; l++) {
        const size_t at = net->pos_params + hg->offset[l];
        level_entries[l] = 0;
        for (uint32_t e = 0; e < hg->entries[l]; e++) {
            const size_t i = at + (size_t)e * nf;
            if (!has_gradient(m->grads + i, nf)) {
                continue;
            }
            level_entries[l]++;
            k += nf;
            /* Entries come in memory order, so a line already counted is
             * the last one; an entry may straddle two (features need not
             * divide a line). */
            const size_t first = i / LINE_FLOATS;
            const size_t last = (i + nf - 1) / LINE_FLOATS;
            *lines += (first != last_line) + (last != first);
            last_line = last;
        }
    }
    return k;
}

/*
 * Seconds of a dense Adam pass over all of network 0's parameters, in
 * memory order on every thread: the best of three, after an untimed pass.
 * The layers' share of it is their floor: the same bytes per parameter,
 * at the rate of a pass that streams them.  (A dense pass costs the same
 * whatever the gradients hold.)
 */
static double time_dense_adam(nerf_model *m, const nerf__network *net)
{
    const double lr = nerf__adam_rate(&m->adam, m->step);
    const size_t at = net->offset;
    double best = INFINITY;
    for (int run = 0; run < 4; run++) {
        double t0 = now();
        /* The library's own dense update (flags 0), on its thread pool. */
        nerf__adam_update(&m->adam, m->step + 1, lr, net->count,
                          m->params + at, m->grads + at, m->adam_m + at,
                          m->adam_v + at, 0);
        if (run > 0) {
            best = fmin(best, now() - t0);
        }
    }
    return best;
}

/* FLOPs of the density layers alone (trunk and head), per sample. */
static double density_flops(const nerf__network *net)
{
    double f = 2.0 * net->head.in * net->head.out;
    for (uint32_t i = 0; i < net->depth; i++) {
        f += 2.0 * net->trunk[i].in * net->trunk[i].out;
    }
    return f;
}

int measure_floor(nerf_trainer *t, const step_breakdown *bd, fast_floor *fl)
{
    memset(fl, 0, sizeof *fl);
    nerf_model *m = t->model;
    const nerf__network *net = &m->nets[0];
    if (!bd->ok || net->pos_enc.kind != NERF_ENCODING_HASHGRID) {
        return -1;
    }
    const nerf__hashgrid *hg = &net->pos_enc.u.hash;
    const size_t blocks = nerf__parallel_threads() < MAX_BLOCKS
                              ? nerf__parallel_threads()
                              : MAX_BLOCKS;
    const double n = (double)bd->samples;
    fl->threads = (uint32_t)blocks;
    fl->peak_gflops = peak_gflops(&fl->isa);

    /* The encoding's reads and adds, level by level on the real tables
     * (the gradients are cleared below). */
    uint32_t *idx = malloc(blocks * ACCESSES_PER_BLOCK * sizeof *idx);
    if (idx == NULL) {
        return -1;
    }
    uint64_t seed = UINT64_C(0x9E3779B97F4A7C15);
    /* A repeated corner: the same loop on a few KiB a thread. */
    const size_t at0 = net->pos_params + hg->offset[0];
    const uint32_t cached = hg->entries[0] < blocks * CACHED_ENTRIES
                                ? hg->entries[0]
                                : (uint32_t)blocks * CACHED_ENTRIES;
    fl->cached_read_ns = 1e9 * time_accesses(m->params + at0, cached,
                                             hg->features, false, idx, blocks,
                                             &seed);
    fl->cached_write_ns = 1e9 * time_accesses(m->grads + at0, cached,
                                              hg->features, true, idx, blocks,
                                              &seed);
    const double hit = 1e-9 * (fl->cached_read_ns + fl->cached_write_ns);
    double read_per_sample = 0.0;
    fl->levels = hg->levels;
    for (uint32_t l = 0; l < hg->levels; l++) {
        const size_t at = net->pos_params + hg->offset[l];
        const double r = time_accesses(m->params + at, hg->entries[l],
                                       hg->features, false, idx, blocks, &seed);
        const double w = time_accesses(m->grads + at, hg->entries[l],
                                       hg->features, true, idx, blocks, &seed);
        fl->level_read_ns[l] = 1e9 * r;
        fl->level_write_ns[l] = 1e9 * w;
        read_per_sample += 8.0 * r;
        /* Each distinct corner of the step once at the level's random
         * cost, its other accesses at a cache hit's (or at the level's,
         * where that measured lower). */
        const double corners = 8.0 * n;
        const double distinct = fmin((double)bd->level_entries[l], corners);
        fl->encoding += distinct * (r + w) +
                        (corners - distinct) * fmin(hit, r + w);
    }
    /* The optimiser's unit: a random read-modify-write of a whole line,
     * on an array of the table's size. */
    float *g = m->grads + net->pos_params;
    const uint32_t lines = (uint32_t)(hg->count / LINE_FLOATS);
    fl->line_rmw_ns = 1e9 * time_accesses(g, lines, LINE_FLOATS, true, idx,
                                          blocks, &seed);
    free(idx);
    /* The adds above went behind the model's back: it believes its
     * gradients zero since the breakdown's last Adam step. */
    memset(g, 0, hg->count * sizeof(float));

    const double peak = 1e9 * fl->peak_gflops;
    fl->mlp = n * 3.0 * nerf__network_flops_per_sample(net) / peak;

    const double dense = time_dense_adam(m, net);
    const double table = (double)hg->count / (double)net->count;
    /* The dense pass moves 4 arrays; a corrected update of the table 6. */
    fl->table_arrays = m->corrected ? 6 : 4;
    fl->table_lines = fl->table_arrays * (double)bd->touched_lines * 1e-9 *
                      fl->line_rmw_ns;
    fl->table_stream = dense * table * fl->table_arrays / 4.0;
    fl->optimiser = dense * (1.0 - table) +
                    fmin(fl->table_lines, fl->table_stream);

    const double cells = (double)bd->grid_cells_evaluated / NERF__GRID_EVERY;
    fl->grid = cells * (read_per_sample + density_flops(net) / peak);
    fl->sum = fl->encoding + fl->mlp + fl->optimiser + fl->grid;
    fl->ok = true;
    return 0;
}

void floor_parts(const step_breakdown *bd, const fast_floor *fl,
                 bool by_gap, floor_part parts[FLOOR_PARTS])
{
    const step_shares sh = shares_of(bd);
    /* The encoding's floor is the hash grid's reads and adds: it is set
     * beside the hash forward and backward alone, without the SH. */
    const floor_part in_order[FLOOR_PARTS] = {
        [FLOOR_ENCODING] = {"encoding", bd->hash_fw + bd->hash_bw,
                            fl->encoding},
        [FLOOR_MLP] = {"MLP", sh.mlp, fl->mlp},
        [FLOOR_OPTIMISER] = {"optimiser", sh.optimiser, fl->optimiser},
        [FLOOR_GRID] = {"grid refresh", sh.grid, fl->grid},
    };
    for (int i = 0; i < FLOOR_PARTS; i++) {
        const floor_part q = in_order[i];
        int k = i;
        for (; by_gap && k > 0 &&
               parts[k - 1].measured - parts[k - 1].floor <
                   q.measured - q.floor;
             k--) {
            parts[k] = parts[k - 1];
        }
        parts[k] = q;
    }
}
