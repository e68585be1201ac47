/*
 * The fast step's floor: what a training step on the last step's samples
 * must cost at least on this machine, part by part, measured rather than
 * taken from a data sheet.
 *
 *  - Encoding: every sample reads the 8 corners of its cell at each of
 *    the hash grid's levels and, going backward, adds a gradient to each.
 *    The floor is that many random reads (and read-modify-writes) of one
 *    entry, timed on the model's own tables level by level with every
 *    thread issuing independent accesses, so that the memory system keeps
 *    as many in flight as it can (memory-level parallelism, not
 *    bandwidth, bounds a random gather).  Corners that neighbouring
 *    samples share can come from cache, so a real step may beat this
 *    figure on coarse levels; on the hashed levels (2^19 entries of 8
 *    bytes, 4 MiB each) its accesses are as random as these.
 *  - MLP: the network's products, forward and the two backward ones (dX,
 *    dW), at the machine's peak multiply-add rate (nerf-bench-peak.c).
 *  - Optimiser: an Adam update of what the step touched.  The layers are
 *    dense, at the rate of a pass that streams them.  The hash entries
 *    with a gradient lie scattered over four arrays of the table's size
 *    (parameters, gradients, two moments) that no cache holds, so the
 *    unit of their cost is the 64-byte line, not the parameter: the
 *    floor is four random read-modify-writes of each line that holds a
 *    touched entry, timed like the encoding's on the table's gradient.
 *    (Streaming the whole table instead costs about as much: finding the
 *    touched lines without reading the others saves nothing.)
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
#define MAX_BLOCKS 64

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
    float sink[MAX_BLOCKS];
} access_job;

/* Independent reads (or read-modify-writes) of the listed entries. */
static void access_block(void *ctx, size_t block)
{
    access_job *j = ctx;
    const uint32_t *idx = j->idx + block * ACCESSES_PER_BLOCK;
    const uint32_t f = j->features;
    float *t = j->table;
    float s = 0.0f;
    if (j->write) {
        for (size_t i = 0; i < ACCESSES_PER_BLOCK; i++) {
            float *e = t + (size_t)idx[i] * f;
            for (uint32_t k = 0; k < f; k++) {
                e[k] += 1e-30f;
            }
        }
    } else {
        for (size_t i = 0; i < ACCESSES_PER_BLOCK; i++) {
            const float *e = t + (size_t)idx[i] * f;
            for (uint32_t k = 0; k < f; k++) {
                s += e[k];
            }
        }
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
    for (int run = 0; run < 3; run++) {
        double t0 = now();
        nerf__parallel_blocks(blocks, (size_t)1 << 30, access_block, &j);
        best = fmin(best, now() - t0);
    }
    return best / ((double)ACCESSES_PER_BLOCK * (double)blocks);
}

/* Floats of a cache line: the unit of a scattered update's traffic. */
#define LINE_FLOATS 16u

size_t touched_params(const nerf_model *m, size_t *lines)
{
    const nerf__network *net = &m->nets[0];
    const nerf__hashgrid *hg = &net->pos_enc.u.hash;
    const float *g = m->grads;
    const size_t table = net->pos_params, table_end = table + hg->count;
    size_t k = net->count - hg->count, last_line = SIZE_MAX;
    *lines = 0;
    for (size_t i = table; i < table_end; i += hg->features) {
        bool take = false;
        for (size_t f = 0; f < hg->features; f++) {
            take = take || g[i + f] != 0.0f;
        }
        k += take ? hg->features : 0;
        if (!take) {
            continue;
        }
        /* Entries come in memory order, so a line already counted is the
         * last one; an entry may straddle two (features need not divide
         * a line). */
        const size_t first = i / LINE_FLOATS;
        const size_t last = (i + hg->features - 1) / LINE_FLOATS;
        *lines += (first != last_line) + (last != first);
        last_line = last;
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
    double read_per_sample = 0.0, write_per_sample = 0.0;
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
        write_per_sample += 8.0 * w;
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
    fl->encoding = n * (read_per_sample + write_per_sample);

    const double peak = 1e9 * fl->peak_gflops;
    fl->mlp = n * 3.0 * nerf__network_flops_per_sample(net) / peak;

    fl->touched = bd->touched;
    fl->touched_lines = bd->touched_lines;
    const double layers = (double)(net->count - hg->count);
    fl->optimiser = time_dense_adam(m, net) * layers / (double)net->count +
                    4.0 * (double)fl->touched_lines * 1e-9 * fl->line_rmw_ns;

    const double cells = (double)bd->grid_cells_evaluated / NERF__GRID_EVERY;
    fl->grid = cells * (read_per_sample + density_flops(net) / peak);
    fl->sum = fl->encoding + fl->mlp + fl->optimiser + fl->grid;
    fl->ok = true;
    return 0;
}
