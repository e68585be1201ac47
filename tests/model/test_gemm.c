/*
 * The layer products, against sums in double: with OpenBLAS on one thread
 * (the products cut into blocks over libnerf's workers) and on two (one
 * call each), at shapes that cut along each dimension, with strides and
 * accumulation, on entries whose every sum a float holds exactly, so that
 * any kernel, order, blocking or thread split must give the exact value.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../harness.h"
#include "gemm.h"
#include "parallel.h"

#if defined(__GNUC__)
extern void openblas_set_num_threads(int n) __attribute__((weak));
#endif

static int set_blas_threads(int n)
{
#if defined(__GNUC__)
    if (openblas_set_num_threads) {
        openblas_set_num_threads(n);
        return nerf__blas_threads() == n;
    }
#endif
    (void)n;
    return 0;
}

static uint64_t state = 12345;

static float uniform(void)
{
    state = state * 6364136223846793005u + 1442695040888963407u;
    return (float)((state >> 40) / 16777216.0) * 2.0f - 1.0f;
}

static float *random_matrix(size_t rows, size_t ld)
{
    float *m = malloc(rows * ld * sizeof *m);
    for (size_t i = 0; i < rows * ld; i++) {
        m[i] = uniform();
    }
    return m;
}

/*
 * Entries j / 8 with |j| <= 8: every product of two is a multiple of 2^-6
 * at most 1 in magnitude, so every partial sum of the products here (at
 * most 4100 terms, the initial value included) is a multiple of 2^-6
 * below 2^13, which a float holds exactly (19 significant bits of its
 * 24).  Any summation order, blocking or fused multiply-add then gives
 * the exact sum, and a wrong element, row or operand shows.
 */
static float *exact_matrix(size_t rows, size_t ld)
{
    float *m = malloc(rows * ld * sizeof *m);
    for (size_t i = 0; i < rows * ld; i++) {
        m[i] = (float)(int)(uniform() * 8.5f) / 8.0f;
    }
    return m;
}

/* got == want, exactly (exact_matrix()). */
static int exactly(const float *got, const double *want, size_t rows,
                   size_t cols, size_t ld)
{
    for (size_t i = 0; i < rows; i++) {
        for (size_t j = 0; j < cols; j++) {
            if ((double)got[i * ld + j] != want[i * cols + j]) {
                FAILF("element (%zu, %zu): %.9g, want %.9g", i, j,
                      (double)got[i * ld + j], want[i * cols + j]);
                return 0;
            }
        }
    }
    return 1;
}

typedef struct shape {
    size_t n;
    uint32_t out, in;
} shape;

/* n large enough that the pool cuts it; out > in and out < in so that the
 * weight gradient is cut along rows and along columns. */
static const shape shapes[] = {
    {4099, 64, 32}, {3001, 3, 64}, {2048, 16, 1}, {5, 64, 64}, {1, 7, 9},
};

static void check_shape(const shape *s)
{
    const size_t n = s->n, out = s->out, in = s->in;
    const size_t ldx = in + 3, ldw = in + 5, ldy = out + 2;
    float *x = exact_matrix(n, ldx);
    float *w = exact_matrix(out, ldw);
    float *y = exact_matrix(n, ldy); /* beta = 1 adds to it */
    float *dy = exact_matrix(n, ldy);
    float *dw = exact_matrix(out, ldw); /* the gradient accumulates */
    float *dx = exact_matrix(n, ldx);
    double *want_y = malloc(n * out * sizeof *want_y);
    double *want_dw = malloc(out * in * sizeof *want_dw);
    double *want_dx = malloc(n * in * sizeof *want_dx);
    for (size_t i = 0; i < n; i++) {
        for (size_t o = 0; o < out; o++) {
            double acc = y[i * ldy + o];
            for (size_t k = 0; k < in; k++) {
                acc += (double)x[i * ldx + k] * w[o * ldw + k];
            }
            want_y[i * out + o] = acc;
        }
        for (size_t k = 0; k < in; k++) {
            double acc = 0.0;
            for (size_t o = 0; o < out; o++) {
                acc += (double)dy[i * ldy + o] * w[o * ldw + k];
            }
            want_dx[i * in + k] = acc;
        }
    }
    for (size_t o = 0; o < out; o++) {
        for (size_t k = 0; k < in; k++) {
            double acc = dw[o * ldw + k];
            for (size_t i = 0; i < n; i++) {
                acc += (double)dy[i * ldy + o] * x[i * ldx + k];
            }
            want_dw[o * in + k] = acc;
        }
    }
    nerf__gemm_forward(n, s->out, s->in, x, ldx, w, ldw, 1.0f, y, ldy);
    nerf__gemm_input_grad(n, s->out, s->in, dy, ldy, w, ldw, dx, ldx);
    nerf__gemm_weight_grad(n, s->out, s->in, dy, ldy, x, ldx, dw, ldw);
    CHECK(exactly(y, want_y, n, out, ldy));
    CHECK(exactly(dx, want_dx, n, in, ldx));
    CHECK(exactly(dw, want_dw, out, in, ldw));
    free(x);
    free(w);
    free(y);
    free(dy);
    free(dw);
    free(dx);
    free(want_y);
    free(want_dw);
    free(want_dx);
}

TEST(products_with_blas_threads)
{
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        check_shape(&shapes[i]);
    }
}

TEST(products_over_own_workers)
{
    if (!set_blas_threads(1)) {
        printf("SKIP: the BLAS is not OpenBLAS: its thread count cannot be "
               "set, so the products are never cut\n");
        return;
    }
    if (nerf__parallel_threads() < 2) {
        printf("note: one core: the products run as one call\n");
    }
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        check_shape(&shapes[i]);
    }
    set_blas_threads(2);
}

/* The three products of one shape, into y, dx, dw from the same inputs. */
typedef struct triple {
    const shape *s;
    const float *x, *w, *dy;
    float *y, *dx, *dw;
} triple;

static void run_triple(void *ctx, size_t begin, size_t end)
{
    const triple *t = ctx;
    const size_t in = t->s->in, out = t->s->out;
    if (begin != 0) {
        return;
    }
    (void)end;
    nerf__gemm_forward(t->s->n, t->s->out, t->s->in, t->x, in, t->w, in, 0.0f,
                       t->y, out);
    nerf__gemm_input_grad(t->s->n, t->s->out, t->s->in, t->dy, out, t->w, in,
                          t->dx, in);
    memset(t->dw, 0, out * in * sizeof(float));
    nerf__gemm_weight_grad(t->s->n, t->s->out, t->s->in, t->dy, out, t->x, in,
                           t->dw, in);
}

/*
 * Over a one-thread BLAS the products give the same bits whether the pool
 * spreads them or the caller runs them alone (as it does when the pool is
 * busy with another call): the calls are cut at fixed places (rows for
 * the forward and input gradient; one call per pool thread for a weight
 * gradient), because the BLAS may round a row by its call's size and its
 * place in the call
 * (OpenBLAS's small-matrix kernels, its Haswell and Zen tiles).  Shapes
 * whose halves would fall on tile boundaries that differ from the fixed
 * cuts', and one of few rows per call.
 */
TEST(products_same_whatever_the_split)
{
    if (!set_blas_threads(1)) {
        printf("SKIP: the BLAS's thread count cannot be set\n");
        return;
    }
    static const shape split[] = {{3001, 16, 64}, {2500, 3, 64},
                                  {1030, 64, 64}, {4099, 64, 32}};
    for (size_t i = 0; i < sizeof split / sizeof split[0]; i++) {
        const shape *s = &split[i];
        float *x = random_matrix(s->n, s->in);
        float *w = random_matrix(s->out, s->in);
        float *dy = random_matrix(s->n, s->out);
        float *a[3], *b[3];
        const size_t sizes[3] = {s->n * s->out, s->n * s->in,
                                 (size_t)s->out * s->in};
        for (int k = 0; k < 3; k++) {
            a[k] = calloc(sizes[k], sizeof(float));
            b[k] = calloc(sizes[k], sizeof(float));
        }
        triple spread = {s, x, w, dy, a[0], a[1], a[2]};
        triple alone = {s, x, w, dy, b[0], b[1], b[2]};
        run_triple(&spread, 0, 1);
        /* Inside the first of two ranges of the pool's (the other does
         * nothing), the pool is busy: every call the products make then
         * runs on this thread. */
        nerf__parallel_for(2, 1u << 30, run_triple, &alone);
        for (int k = 0; k < 3; k++) {
            if (memcmp(a[k], b[k], sizes[k] * sizeof(float)) != 0) {
                FAILF("%zu x %u x %u: product %d differs with the split",
                      s->n, (unsigned)s->out, (unsigned)s->in, k);
            }
            free(a[k]);
            free(b[k]);
        }
        free(x);
        free(w);
        free(dy);
    }
    set_blas_threads(2);
}

int main(void)
{
    RUN(products_with_blas_threads);
    RUN(products_over_own_workers);
    RUN(products_same_whatever_the_split);
    HARNESS_EXIT();
}
