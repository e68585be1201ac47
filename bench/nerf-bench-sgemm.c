/*
 * The sgemm bound of the presets without marching: what cblas_sgemm alone
 * achieves on the products of one training step, in this run and on this
 * machine, and hence the rays/s that training and rendering could reach
 * if the products were all they did.
 *
 * The products are listed here from the network's shapes, not taken from
 * the calls the library makes, and that is on purpose: the bound is a
 * yardstick for the shapes, and must not move when the library changes
 * how it calls the BLAS (fusing products, splitting them over its own
 * threads, going to bf16).  What the list reads from the library is the
 * shapes themselves; its FLOPs are checked against the library's count
 * (nerf__network_flops_per_sample).
 */
#include <cblas.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "nerf-bench.h"

#define MAX_CALLS 512

/*
 * One cblas_sgemm, row-major.  The list below is the natural
 * one-product-per-layer form of the network (samples as rows), with
 * the leading dimensions and betas of lib/mlp/network.c as written when
 * this bench was: the bound it gives belongs to the network's shapes, not
 * to however the library happens to call the BLAS.
 */
typedef struct gemm_call {
    bool ta, tb;
    int m, n, k;
    int lda, ldb, ldc;
    float beta;
    bool backward;
} gemm_call;

typedef struct gemm_list {
    gemm_call c[MAX_CALLS];
    int count;
} gemm_list;

static void push(gemm_list *l, gemm_call g)
{
    if (l->count < MAX_CALLS) {
        l->c[l->count++] = g;
    }
}

/* Y[n, out] = X[n, in] W^T, W a column block of rows of ldw floats. */
static void fwd(gemm_list *l, int n, int out, int in, int ldx, int ldw,
                float beta, int ldy)
{
    push(l, (gemm_call){false, true, n, out, in, ldx, ldw, ldy, beta, false});
}

/* dW[out, in] += dY[n, out]^T X[n, in]. */
static void wgrad(gemm_list *l, int n, int out, int in, int lddy, int ldx,
                  int lddw)
{
    push(l, (gemm_call){true, false, out, in, n, lddy, ldx, lddw, 1.0f, true});
}

/* dX[n, in] = dY[n, out] W. */
static void igrad(gemm_list *l, int n, int out, int in, int lddy, int ldw,
                  int lddx)
{
    push(l, (gemm_call){false, false, n, in, out, lddy, ldw, lddx, 0.0f, true});
}

static void network_forward(gemm_list *l, const nerf__network *net, int n)
{
    const int W = (int)net->width, Ep = (int)net->pos_width;
    const int HW = (int)nerf__network_head_width(net);
    for (uint32_t i = 0; i < net->depth; i++) {
        const int in = (int)net->trunk[i].in;
        if (i > 0 && i == net->skip) {
            /* [gamma(x), h]: one product per column block, never copied. */
            fwd(l, n, W, Ep, Ep, in, 0.0f, W);
            fwd(l, n, W, W, W, in, 1.0f, W);
        } else {
            fwd(l, n, W, in, i == 0 ? Ep : W, in, 0.0f, W);
        }
    }
    fwd(l, n, HW, W, W, W, 0.0f, HW);
    if (net->use_viewdirs) {
        const int V = (int)net->view_width, Ed = (int)net->dir_width;
        fwd(l, n, V, W, HW, W + Ed, 0.0f, V);
        fwd(l, n, V, Ed, Ed, W + Ed, 1.0f, V);
        fwd(l, n, 3, V, V, V, 0.0f, 3);
    }
}

/* Inputs that are encodings get no dX: nothing upstream learns. */
static void network_backward(gemm_list *l, const nerf__network *net, int n)
{
    const int W = (int)net->width, Ep = (int)net->pos_width;
    const int HW = (int)nerf__network_head_width(net);
    if (net->use_viewdirs) {
        const int V = (int)net->view_width, Ed = (int)net->dir_width;
        wgrad(l, n, 3, V, 3, V, V);
        igrad(l, n, 3, V, 3, V, V);
        wgrad(l, n, V, W, V, HW, W + Ed);
        wgrad(l, n, V, Ed, V, Ed, W + Ed);
        igrad(l, n, V, W, V, W + Ed, HW);
    }
    wgrad(l, n, HW, W, HW, W, W);
    igrad(l, n, HW, W, HW, W, W);
    for (uint32_t i = net->depth; i-- > 0;) {
        const int in = (int)net->trunk[i].in;
        if (i == 0) {
            wgrad(l, n, W, in, W, Ep, in);
            break;
        }
        if (i == net->skip) {
            wgrad(l, n, W, Ep, W, Ep, in);
        }
        wgrad(l, n, W, W, W, W, in);
        igrad(l, n, W, W, W, in, W);
    }
}

/*
 * The products of one training step of `rays` rays: the coarse network on
 * n_coarse samples per ray and the fine one on all samples, forward then
 * backward.  Rendering runs the same forward products.
 */
static void step_products(gemm_list *l, const nerf_model *m, int passes,
                          const int samples[2], int rays)
{
    const nerf__network *net[2] = {&m->nets[0], &m->nets[m->n_nets - 1]};
    l->count = 0;
    for (int p = 0; p < passes; p++) {
        network_forward(l, net[p], rays * samples[p]);
    }
    for (int p = passes; p-- > 0;) {
        network_backward(l, net[p], rays * samples[p]);
    }
}

static double list_flops(const gemm_list *l, bool forward, bool backward)
{
    double f = 0.0;
    for (int i = 0; i < l->count; i++) {
        const gemm_call *g = &l->c[i];
        if (g->backward ? backward : forward) {
            f += 2.0 * g->m * g->n * (double)g->k;
        }
    }
    return f;
}

static size_t elems(size_t rows, int ld)
{
    return rows * (size_t)ld;
}

/*
 * Run the list until `budget` seconds have passed (at least once), timing
 * each call so that forward and backward rates come from the same runs.
 */
static int time_products(const gemm_list *l, double budget, gemm_timing *out)
{
    size_t na = 0, nb = 0, nc = 0;
    for (int i = 0; i < l->count; i++) {
        const gemm_call *g = &l->c[i];
        size_t a = elems((size_t)(g->ta ? g->k : g->m), g->lda);
        size_t b = elems((size_t)(g->tb ? g->n : g->k), g->ldb);
        size_t c = elems((size_t)g->m, g->ldc);
        na = a > na ? a : na;
        nb = b > nb ? b : nb;
        nc = c > nc ? c : nc;
    }
    float *a = malloc(na * sizeof(float));
    float *b = malloc(nb * sizeof(float));
    float *c = calloc(nc, sizeof(float));
    if (!a || !b || !c) {
        free(a);
        free(b);
        free(c);
        return -1;
    }
    /* Written, not calloc'd zeros: untouched pages all map to one zero page
     * and would make the inputs look cache-resident. */
    for (size_t i = 0; i < na; i++) {
        a[i] = (float)(i % 251) * 1e-4f;
    }
    for (size_t i = 0; i < nb; i++) {
        b[i] = (float)(i % 241) * 1e-4f;
    }
    /* Wakes OpenBLAS's threads before the clock starts. */
    for (int i = 0; i < l->count && i < 2; i++) {
        const gemm_call *g = &l->c[i];
        cblas_sgemm(CblasRowMajor, g->ta ? CblasTrans : CblasNoTrans,
                    g->tb ? CblasTrans : CblasNoTrans, g->m, g->n, g->k, 1.0f,
                    a, g->lda, b, g->ldb, g->beta, c, g->ldc);
    }
    double t_fw = 0.0, t_bw = 0.0;
    int reps = 0;
    do {
        for (int i = 0; i < l->count; i++) {
            const gemm_call *g = &l->c[i];
            double t0 = now();
            cblas_sgemm(CblasRowMajor, g->ta ? CblasTrans : CblasNoTrans,
                        g->tb ? CblasTrans : CblasNoTrans, g->m, g->n, g->k,
                        1.0f, a, g->lda, b, g->ldb, g->beta, c, g->ldc);
            double t = now() - t0;
            if (g->backward) {
                t_bw += t;
            } else {
                t_fw += t;
            }
        }
        reps++;
    } while (t_fw + t_bw < budget);
    free(a);
    free(b);
    free(c);
    double f_fw = list_flops(l, true, false), f_bw = list_flops(l, false, true);
    out->reps = reps;
    out->seconds = t_fw + t_bw;
    out->gflops_step = reps * (f_fw + f_bw) / (t_fw + t_bw) * 1e-9;
    out->gflops_forward = reps * f_fw / t_fw * 1e-9;
    return 0;
}

/* FLOPs per ray: the products of a one-ray step. */
int sgemm_flops(const preset_setup *p, figures *f)
{
    gemm_list *l = malloc(sizeof *l);
    if (l == NULL) {
        return -1;
    }
    double lib_fw = nerf__network_flops_per_sample(&p->model->nets[0]);
    if (p->march) {
        /* A variable number of samples per ray, and products far from
         * the step's main cost: no sgemm bound, the step's breakdown
         * instead. */
        f->flops_sample_fw = lib_fw;
    } else {
        step_products(l, p->model, p->passes, p->samples, 1);
        f->flops_train_ray = list_flops(l, true, true);
        f->flops_render_ray = list_flops(l, true, false);
        f->flops_sample_fw =
            list_flops(l, true, false) /
            (p->samples[0] + (p->passes > 1 ? p->samples[1] : 0));
        if (fabs(lib_fw - f->flops_sample_fw) > 0.5) {
            fprintf(stderr,
                    "nerf-bench: warning: %s: %.0f forward FLOPs per "
                    "sample from the shapes, the library counts %.0f\n",
                    p->name, f->flops_sample_fw, lib_fw);
        }
    }
    free(l);
    return 0;
}

/* The products of a BATCH_RAYS-ray step, timed; calls: how many. */
int sgemm_time(const preset_setup *p, double budget, gemm_timing *out,
               int *calls)
{
    gemm_list *l = malloc(sizeof *l);
    if (l == NULL) {
        return -1;
    }
    step_products(l, p->model, p->passes, p->samples, (int)BATCH_RAYS);
    *calls = l->count;
    int rc = time_products(l, budget, out);
    free(l);
    return rc;
}

/*
 * cblas_sgemm on square side x side x side products, the shape BLAS
 * libraries are tuned for: the rate the step's own shapes could reach if
 * they were as friendly (issue 19, part 6).  Run for `budget` seconds.
 */
double sgemm_square_gflops(int side, double budget)
{
    gemm_list *l = malloc(sizeof *l);
    if (l == NULL) {
        return 0.0;
    }
    l->count = 0;
    push(l, (gemm_call){false, false, side, side, side, side, side, side,
                        0.0f, false});
    gemm_timing t;
    double rate = time_products(l, budget, &t) == 0 ? t.gflops_step : 0.0;
    free(l);
    return rate;
}

/* The rays/s the better sgemm rates allow: a step or a render that did
 * nothing but its products, at those rates. */
double train_bound(const figures *f)
{
    return f->gemm.gflops_step * 1e9 / f->flops_train_ray;
}

double render_bound(const figures *f)
{
    return f->gemm.gflops_forward * 1e9 / f->flops_render_ray;
}
