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

/* Coarse levels are dense and cheap, fine ones hashed and slow: blocks
 * pair them (0, L-1, 1, L-2, ...) so that contiguous ranges of blocks cost
 * about the same. */
static void backward_level(void *ctx, size_t block)
{
    const table_job *j = ctx;
    const uint32_t L = j->hg->levels;
    uint32_t level = block % 2 ? L - 1 - (uint32_t)(block / 2)
                               : (uint32_t)(block / 2);
    nerf__hashgrid_backward_level(j->hg, level, j->n, j->in, 3, j->d_out,
                                  j->stride, j->grad);
}

static void backward(const nerf__encoding *e, size_t n, const float *in,
                     const float *d_out, size_t d_stride, float *grad)
{
    table_job j = {.hg = &e->u.hash, .in = in, .d_out = d_out, .grad = grad,
                   .n = n, .stride = d_stride};
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
