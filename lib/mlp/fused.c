#include "fused.h"

#include "multiversion.h"
#include "parallel.h"

/*
 * Forward passes split by rows.  Gradient passes that also sum over rows
 * split by columns instead: every bias gradient is then summed over the
 * rows in the same order whatever the thread count, so results never
 * depend on it.  Column ranges are whole 64-byte lines so that two threads
 * never write one cache line.
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
} fused_job;

NERF__MULTIVERSION static void bias_relu_rows(void *ctx, size_t begin,
                                              size_t end)
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

NERF__MULTIVERSION static void bias_add_rows(void *ctx, size_t begin,
                                             size_t end)
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

NERF__MULTIVERSION static void relu_backward_cols(void *ctx, size_t begin,
                                                  size_t end)
{
    const fused_job *j = ctx;
    size_t c0, c1;
    column_span(j, begin, end, &c0, &c1);
    float *restrict db = j->db;
    for (size_t i = 0; i < j->n; i++) {
        const float *restrict yr = j->y + i * j->ldy;
        float *restrict dr = j->dy + i * j->lddy;
        for (size_t c = c0; c < c1; c++) {
            float g = yr[c] > 0.0f ? dr[c] : 0.0f;
            dr[c] = g;
            db[c] += g;
        }
    }
}

void nerf__relu_backward_bias(size_t n, size_t cols, const float *y,
                              size_t ldy, float *dy, size_t lddy, float *db)
{
    fused_job j = {.cols = cols, .y = y, .ldy = ldy, .dy = dy, .lddy = lddy,
                   .db = db, .n = n};
    nerf__parallel_for((cols + LINE - 1) / LINE, 3 * LINE * n,
                       relu_backward_cols, &j);
}

NERF__MULTIVERSION static void bias_backward_cols(void *ctx, size_t begin,
                                                  size_t end)
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
