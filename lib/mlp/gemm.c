#include <cblas.h>

#include "gemm.h"
#include "parallel.h"

/* Weak, so that BLAS providers other than OpenBLAS link without it. */
#if defined(__GNUC__)
extern int openblas_get_num_threads(void) __attribute__((weak));
#endif

int nerf__blas_threads(void)
{
#if defined(__GNUC__)
    if (openblas_get_num_threads) {
        return openblas_get_num_threads();
    }
#endif
    return 0;
}

/* Split only over a one-thread BLAS: on a threaded one, our workers'
 * calls would each wake the BLAS's threads and oversubscribe the cores.
 * Split even where the pool has one thread, so that the calls, and with
 * them the results, are the same for every thread count. */
static int split_over_pool(void)
{
    return nerf__blas_threads() == 1;
}

/*
 * The BLAS's result for a row of a product can depend on how many rows
 * its call holds and on where the row sits in it: OpenBLAS 0.3.21 sends
 * small products (rows x out x in up to 10^6, or fewer than 1200 rows x
 * out) to other kernels on SkylakeX and later cores, and its Haswell and
 * Zen kernels round a row by its place in the tile.  So a split over the
 * pool never cuts where the pool's threads happen to be free:
 *  - forward and input-gradient products are cut at fixed rows,
 *    ROWS_PER_CALL apart from the first, the same calls for any thread
 *    count and however busy the pool is;
 *  - a weight gradient, each of whose calls sums over all the samples
 *    and packs all of one operand, is cut into as many calls as the pool
 *    has threads (not as many as are free): finer cuts pack that operand
 *    again for each, which made the reference preset's step slower with
 *    32-row cuts on two cores.  Its results are deterministic for a
 *    given thread count, as oneDNN's weight gradients are.
 * ROWS_PER_CALL is large enough that each call runs at the BLAS's full
 * rate, and small enough that a render's coarse pass (64 rays of 64
 * samples) still spreads over the cores: 4096 made the reference
 * preset's render slower on two cores.
 */
#define ROWS_PER_CALL 1024

static size_t calls(size_t n, size_t per_call)
{
    return (n + per_call - 1) / per_call;
}

typedef struct product {
    uint32_t out, in;
    size_t n;
    size_t per_call; /* rows or columns of dW a weight-gradient call takes */
    const float *a, *b;
    size_t lda, ldb;
    float beta;
    float *c;
    size_t ldc;
} product;

static void forward_rows(void *ctx, size_t begin, size_t end)
{
    const product *p = ctx;
    cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasTrans, (int)(end - begin),
                (int)p->out, (int)p->in, 1.0f, p->a + begin * p->lda,
                (int)p->lda, p->b, (int)p->ldb, p->beta, p->c + begin * p->ldc,
                (int)p->ldc);
}

/* The pool's cost of one row of a product whose rows are a x b. */
static size_t item_cost(size_t a, size_t b)
{
    return 2 * a * b / NERF__FLOPS_PER_OP;
}

/* Block b of a split product's rows, or of its units (weight gradient). */
static void block_range(size_t b, size_t per_call, size_t n, size_t *begin,
                        size_t *end)
{
    *begin = b * per_call;
    *end = n - *begin < per_call ? n : *begin + per_call;
}

static void forward_block(void *ctx, size_t b)
{
    const product *p = ctx;
    size_t begin, end;
    block_range(b, ROWS_PER_CALL, p->n, &begin, &end);
    forward_rows(ctx, begin, end);
}

void nerf__gemm_forward(size_t n, uint32_t out, uint32_t in, const float *x,
                        size_t ldx, const float *w, size_t ldw, float beta,
                        float *y, size_t ldy)
{
    product p = {out, in, n, 0, x, w, ldx, ldw, beta, y, ldy};
    if (split_over_pool()) {
        nerf__parallel_blocks(calls(n, ROWS_PER_CALL),
                              ROWS_PER_CALL * item_cost(out, in),
                              forward_block, &p);
    } else {
        forward_rows(&p, 0, n);
    }
}

static void input_grad_rows(void *ctx, size_t begin, size_t end)
{
    const product *p = ctx;
    cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, (int)(end - begin),
                (int)p->in, (int)p->out, 1.0f, p->a + begin * p->lda,
                (int)p->lda, p->b, (int)p->ldb, 0.0f, p->c + begin * p->ldc,
                (int)p->ldc);
}

static void input_grad_block(void *ctx, size_t b)
{
    const product *p = ctx;
    size_t begin, end;
    block_range(b, ROWS_PER_CALL, p->n, &begin, &end);
    input_grad_rows(ctx, begin, end);
}

void nerf__gemm_input_grad(size_t n, uint32_t out, uint32_t in, const float *dy,
                           size_t lddy, const float *w, size_t ldw, float *dx,
                           size_t lddx)
{
    product p = {out, in, n, 0, dy, w, lddy, ldw, 0.0f, dx, lddx};
    if (split_over_pool()) {
        nerf__parallel_blocks(calls(n, ROWS_PER_CALL),
                              ROWS_PER_CALL * item_cost(out, in),
                              input_grad_block, &p);
    } else {
        input_grad_rows(&p, 0, n);
    }
}

/* The weight gradient sums over the samples, so it is cut along dW's own
 * rows (output units) or columns (inputs), whichever is longer: each
 * element is still one call's sum over all n samples. */
static void weight_grad_rows(void *ctx, size_t begin, size_t end)
{
    const product *p = ctx;
    cblas_sgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)(end - begin),
                (int)p->in, (int)p->n, 1.0f, p->a + begin, (int)p->lda, p->b,
                (int)p->ldb, 1.0f, p->c + begin * p->ldc, (int)p->ldc);
}

static void weight_grad_cols(void *ctx, size_t begin, size_t end)
{
    const product *p = ctx;
    cblas_sgemm(CblasRowMajor, CblasTrans, CblasNoTrans, (int)p->out,
                (int)(end - begin), (int)p->n, 1.0f, p->a, (int)p->lda,
                p->b + begin, (int)p->ldb, 1.0f, p->c + begin, (int)p->ldc);
}

static void weight_grad_row_block(void *ctx, size_t b)
{
    const product *p = ctx;
    size_t begin, end;
    block_range(b, p->per_call, p->out, &begin, &end);
    weight_grad_rows(ctx, begin, end);
}

static void weight_grad_col_block(void *ctx, size_t b)
{
    const product *p = ctx;
    size_t begin, end;
    block_range(b, p->per_call, p->in, &begin, &end);
    weight_grad_cols(ctx, begin, end);
}

void nerf__gemm_weight_grad(size_t n, uint32_t out, uint32_t in,
                            const float *dy, size_t lddy, const float *x,
                            size_t ldx, float *dw, size_t lddw)
{
    product p = {out, in, n, 0, dy, x, lddy, ldx, 1.0f, dw, lddw};
    const size_t parts = nerf__parallel_threads();
    if (!split_over_pool() || parts < 2) {
        weight_grad_rows(&p, 0, out);
    } else if (out >= in) {
        p.per_call = calls(out, parts);
        nerf__parallel_blocks(calls(out, p.per_call),
                              p.per_call * item_cost(n, in),
                              weight_grad_row_block, &p);
    } else {
        p.per_call = calls(in, parts);
        nerf__parallel_blocks(calls(in, p.per_call),
                              p.per_call * item_cost(n, out),
                              weight_grad_col_block, &p);
    }
}
