/*
 * The hash grid as an encoding: its table is the encoding's parameters,
 * forward runs by ranges of samples over the thread pool and backward by
 * levels (each level's part of the gradient written by one thread in
 * sample order, so the sums do not depend on the split).
 */
#include <string.h>

#include "encoding.h"
#include "nerf.h"
#include "parallel.h"

static uint32_t width(const nerf__encoding *e)
{
    return nerf__hashgrid_width(&e->u.hash);
}

static size_t params(const nerf__encoding *e)
{
    return e->u.hash.count;
}

static void init(const nerf__encoding *e, float *table, uint64_t seed,
                 uint64_t stream_base)
{
    nerf__hashgrid_init(&e->u.hash, table, seed, stream_base);
}

typedef struct table_job {
    const nerf__hashgrid *hg;
    const float *table, *in, *d_out;
    float *out, *grad;
    size_t n, stride;
} table_job;

static void forward_rows(void *ctx, size_t begin, size_t end)
{
    const table_job *j = ctx;
    nerf__hashgrid_forward_range(j->hg, j->table, begin, end, j->in, 3,
                                 j->out, j->stride);
}

static void forward(const nerf__encoding *e, const float *table, size_t n,
                    const float *in, float *out, size_t out_stride)
{
    table_job j = {.hg = &e->u.hash, .table = table, .in = in, .out = out,
                   .stride = out_stride};
    nerf__parallel_for(n, 50 * e->u.hash.levels, forward_rows, &j);
}

typedef struct backward_job {
    table_job t;
    uint32_t order[NERF__HASHGRID_MAX_LEVELS]; /* block -> level */
} backward_job;

static void backward_level(void *ctx, size_t block)
{
    const backward_job *j = ctx;
    nerf__hashgrid_backward_level(j->t.hg, j->order[block], j->t.n, j->t.in,
                                  3, j->t.d_out, j->t.stride, j->t.grad);
}

/*
 * A level's cost grows with its resolution, and the pool gives each
 * thread a contiguous range of blocks: so the levels are dealt to the
 * threads back and forth (for two: 0, 3, 4, 7, ... to the first, 1, 2,
 * 5, 6, ... to the second), each thread's in a row.  Pairing the
 * coarsest with the finest instead left one of two threads waiting a
 * quarter of the backward on lego.  Levels write disjoint parts of the
 * gradient, so the order changes no value.
 */
static void deal_levels(uint32_t L, uint32_t *order)
{
    uint32_t T = nerf__parallel_threads();
    T = T < L ? T : L;
    uint32_t k = 0;
    for (uint32_t t = 0; t < T; t++) {
        for (uint32_t l = 0; l < L; l++) {
            const uint32_t lane = l % T;
            if ((l / T % 2 ? T - 1 - lane : lane) == t) {
                order[k++] = l;
            }
        }
    }
}

static void backward(const nerf__encoding *e, size_t n, const float *in,
                     const float *d_out, size_t d_stride, float *grad)
{
    backward_job j = {.t = {.hg = &e->u.hash, .in = in, .d_out = d_out,
                            .grad = grad, .n = n, .stride = d_stride}};
    deal_levels(e->u.hash.levels, j.order);
    nerf__parallel_blocks(e->u.hash.levels, 200 * n, backward_level, &j);
}

static const nerf__encoding_ops hashgrid_ops = {
    .width = width, .params = params, .init = init, .forward = forward,
    .backward = backward};

void nerf__encoding_hashgrid(nerf__encoding *e, const nerf__hashgrid *hg)
{
    memset(e, 0, sizeof *e);
    e->kind = NERF_ENCODING_HASHGRID;
    e->ops = &hashgrid_ops;
    e->u.hash = *hg;
}
