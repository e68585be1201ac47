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
 * calls would each wake the BLAS's threads and oversubscribe the cores. */
static int split_over_pool(void)
{
    return nerf__blas_threads() == 1 && nerf__parallel_threads() > 1;
}

typedef struct product {
    uint32_t out, in;
    size_t n;
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

void nerf__gemm_forward(size_t n, uint32_t out, uint32_t in, const float *x,
                        size_t ldx, const float *w, size_t ldw, float beta,
                        float *y, size_t ldy)
{
    product p = {out, in, n, x, w, ldx, ldw, beta, y, ldy};
    if (split_over_pool()) {
        nerf__parallel_for(n, item_cost(out, in), forward_rows, &p);
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

void nerf__gemm_input_grad(size_t n, uint32_t out, uint32_t in, const float *dy,
                           size_t lddy, const float *w, size_t ldw, float *dx,
                           size_t lddx)
{
    product p = {out, in, n, dy, w, lddy, ldw, 0.0f, dx, lddx};
    if (split_over_pool()) {
        nerf__parallel_for(n, item_cost(out, in), input_grad_rows, &p);
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

void nerf__gemm_weight_grad(size_t n, uint32_t out, uint32_t in,
                            const float *dy, size_t lddy, const float *x,
                            size_t ldx, float *dw, size_t lddw)
{
    product p = {out, in, n, dy, x, lddy, ldx, 1.0f, dw, lddw};
    if (!split_over_pool()) {
        weight_grad_rows(&p, 0, out);
    } else if (out >= in) {
        nerf__parallel_for(out, item_cost(n, in), weight_grad_rows, &p);
    } else {
        nerf__parallel_for(in, item_cost(n, out), weight_grad_cols, &p);
    }
}
