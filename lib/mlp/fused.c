#include "fused.h"

#include "bf16.h"
#include "multiversion.h"
#include "parallel.h"

/*
 * Forward passes split by rows.  Gradient passes also sum over rows, and
 * their sums must not depend on the thread count: the bias gradient
 * splits by columns, each summed over all rows in order; the ReLU backward
 * sums fixed row blocks (see below).  Column ranges are whole 64-byte
 * lines so that two threads never write one cache line.
 */
#define LINE 16

typedef struct fused_job {
    size_t cols;
    const float *y;
    size_t ldy;
    float *dy;
    size_t lddy;
    float *out;
    size_t ldout;
    const float *b;
    float *db;
    size_t n;
    const float *dy_in; /* the bf16 variant's input, kept as it is */
    uint16_t *dyb;
} fused_job;

NERF__CLONED(bias_relu_rows, (void *ctx, size_t begin, size_t end),
             (ctx, begin, end))
{
    const fused_job *j = ctx;
    for (size_t i = begin; i < end; i++) {
        float *row = j->out + i * j->ldout;
        for (size_t c = 0; c < j->cols; c++) {
            float v = row[c] + j->b[c];
            row[c] = v > 0.0f ? v : 0.0f;
        }
    }
}

void nerf__bias_relu(size_t n, size_t cols, float *y, size_t ld,
                     const float *b)
{
    fused_job j = {.cols = cols, .out = y, .ldout = ld, .b = b};
    nerf__parallel_for(n, 2 * cols, bias_relu_rows, &j);
}

NERF__CLONED(bias_add_rows, (void *ctx, size_t begin, size_t end),
             (ctx, begin, end))
{
    const fused_job *j = ctx;
    for (size_t i = begin; i < end; i++) {
        float *row = j->out + i * j->ldout;
        for (size_t c = 0; c < j->cols; c++) {
            row[c] += j->b[c];
        }
    }
}

void nerf__bias_add(size_t n, size_t cols, float *y, size_t ld,
                    const float *b)
{
    fused_job j = {.cols = cols, .out = y, .ldout = ld, .b = b};
    nerf__parallel_for(n, cols, bias_add_rows, &j);
}

static void column_span(const fused_job *j, size_t begin, size_t end,
                        size_t *c0, size_t *c1)
{
    *c0 = begin * LINE;
    *c1 = end * LINE < j->cols ? end * LINE : j->cols;
}

/*
 * The ReLU backward goes through whole rows: cutting rows into column
 * ranges, as the bias gradient below does, reads each row in pieces a row
 * apart, which the hardware prefetchers follow badly (docs/perf-log/
 * 2026-11-22-nerf-bench-reference-and-tiny.md, commit 9198f86).  Its bias
 * sums stay independent of the thread count another way: each fixed block
 * of NERF__RELU_ROWS rows sums into its own partial, and the partials are
 * added in block order.
 */
static void block_span(const fused_job *j, size_t block, size_t *r0,
                       size_t *r1)
{
    *r0 = block * NERF__RELU_ROWS;
    *r1 = *r0 + NERF__RELU_ROWS < j->n ? *r0 + NERF__RELU_ROWS : j->n;
}

NERF__CLONED(relu_backward_rows, (void *ctx, size_t block), (ctx, block))
{
    const fused_job *j = ctx;
    size_t r0, r1;
    block_span(j, block, &r0, &r1);
    float *restrict part = j->out + block * j->cols;
    for (size_t c = 0; c < j->cols; c++) {
        part[c] = 0.0f;
    }
    for (size_t i = r0; i < r1; i++) {
        const float *restrict yr = j->y + i * j->ldy;
        float *restrict dr = j->dy + i * j->lddy;
        for (size_t c = 0; c < j->cols; c++) {
            float g = yr[c] > 0.0f ? dr[c] : 0.0f;
            dr[c] = g;
            part[c] += g;
        }
    }
}

#define CHUNK 256

static NERF__BF16_WIDE void relu_backward_bf16_rows(void *ctx, size_t block)
{
    const fused_job *j = ctx;
    size_t r0, r1;
    block_span(j, block, &r0, &r1);
    float *restrict part = j->out + block * j->cols;
    float g[CHUNK];
    for (size_t c = 0; c < j->cols; c++) {
        part[c] = 0.0f;
    }
    for (size_t i = r0; i < r1; i++) {
        const float *restrict yr = j->y + i * j->ldy;
        const float *restrict dr = j->dy_in + i * j->lddy;
        uint16_t *restrict o = j->dyb + i * j->cols;
        for (size_t c0 = 0; c0 < j->cols; c0 += CHUNK) {
            const size_t m = j->cols - c0 < CHUNK ? j->cols - c0 : CHUNK;
            /* Two loops, each of which the compiler vectorises; fused into
             * one, neither is. */
            for (size_t c = 0; c < m; c++) {
                float v = yr[c0 + c] > 0.0f ? dr[c0 + c] : 0.0f;
                g[c] = v;
                part[c0 + c] += v;
            }
            for (size_t c = 0; c < m; c++) {
                o[c0 + c] = nerf__bf16_from_float(g[c]);
            }
        }
    }
}

NERF__CLONED(sum_partials_cols, (void *ctx, size_t begin, size_t end),
             (ctx, begin, end))
{
    const fused_job *j = ctx;
    size_t c0, c1;
    column_span(j, begin, end, &c0, &c1);
    const size_t blocks = (j->n + NERF__RELU_ROWS - 1) / NERF__RELU_ROWS;
    for (size_t b = 0; b < blocks; b++) {
        const float *p = j->out + b * j->cols;
        for (size_t c = c0; c < c1; c++) {
            j->db[c] += p[c];
        }
    }
}

/* Runs rows over fixed row blocks, then adds their partial sums to db. */
static void relu_backward_blocks(fused_job *j,
                                 void (*rows)(void *, size_t))
{
    const size_t blocks = (j->n + NERF__RELU_ROWS - 1) / NERF__RELU_ROWS;
    nerf__parallel_blocks(blocks, 4 * NERF__RELU_ROWS * j->cols, rows, j);
    nerf__parallel_for((j->cols + LINE - 1) / LINE, LINE * blocks,
                       sum_partials_cols, j);
}

void nerf__relu_backward_bias(size_t n, size_t cols, const float *y,
                              size_t ldy, float *dy, size_t lddy, float *db,
                              float *partial)
{
    fused_job j = {.cols = cols, .y = y, .ldy = ldy, .dy = dy, .lddy = lddy,
                   .db = db, .n = n, .out = partial};
    relu_backward_blocks(&j, relu_backward_rows);
}

void nerf__relu_backward_bias_bf16(size_t n, size_t cols, const float *y,
                                   size_t ldy, const float *dy, size_t lddy,
                                   float *db, uint16_t *dyb, float *partial)
{
    fused_job j = {.cols = cols, .y = y, .ldy = ldy, .dy_in = dy,
                   .lddy = lddy, .db = db, .n = n, .dyb = dyb,
                   .out = partial};
    relu_backward_blocks(&j, relu_backward_bf16_rows);
}

NERF__CLONED(bias_backward_cols, (void *ctx, size_t begin, size_t end),
             (ctx, begin, end))
{
    const fused_job *j = ctx;
    size_t c0, c1;
    column_span(j, begin, end, &c0, &c1);
    float *restrict db = j->db;
    for (size_t i = 0; i < j->n; i++) {
        const float *restrict dr = j->y + i * j->ldy;
        for (size_t c = c0; c < c1; c++) {
            db[c] += dr[c];
        }
    }
}

void nerf__bias_backward(size_t n, size_t cols, const float *dy, size_t ld,
                         float *db)
{
    fused_job j = {.cols = cols, .y = dy, .ldy = ld, .db = db, .n = n};
    nerf__parallel_for((cols + LINE - 1) / LINE, LINE * n,
                       bias_backward_cols, &j);
}
