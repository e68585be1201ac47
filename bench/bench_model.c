/*
 * bench_model: throughput of the reference network's forward and
 * forward+backward passes, against the time the same sgemm calls take
 * alone (the sgemm-bound limit).  Prints figures; asserts nothing.
 *
 *   bench_model [--preset reference|tiny] [--seconds S]
 */
#include <cblas.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nerf.h"
#include "nerf_internal.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* One sgemm of the network: C[M, N] = A[M, K] B[K, N] in some layout. */
typedef struct shape {
    int m, n, k;
    int trans_a, trans_b;
} shape;

typedef struct shape_list {
    shape s[128];
    int count;
} shape_list;

static void add(shape_list *l, int m, int n, int k, int ta, int tb)
{
    l->s[l->count++] = (shape){m, n, k, ta, tb};
}

/* Forward: Y[n,out] = X[n,in] W^T; backward: dW[out,in] = dY^T X and
 * dX[n,in] = dY W, for each column block the network multiplies. */
static void linear_shapes(shape_list *fw, shape_list *bw, int n, int out,
                          int in, int need_dx)
{
    add(fw, n, out, in, 0, 1);
    add(bw, out, in, n, 1, 0);
    if (need_dx) {
        add(bw, n, in, out, 0, 0);
    }
}

static void network_shapes(const nerf__network *net, int n, shape_list *fw,
                           shape_list *bw)
{
    int W = (int)net->width, Ep = (int)net->pos_width;
    for (uint32_t i = 0; i < net->depth; i++) {
        if (i > 0 && i == net->skip) {
            linear_shapes(fw, bw, n, W, Ep, 0);
            linear_shapes(fw, bw, n, W, W, 1);
        } else {
            linear_shapes(fw, bw, n, W, (int)net->trunk[i].in, i > 0);
        }
    }
    linear_shapes(fw, bw, n, (int)net->head.out, W, 1);
    if (net->use_viewdirs) {
        int V = (int)net->view_width;
        linear_shapes(fw, bw, n, V, W, 1);
        linear_shapes(fw, bw, n, V, (int)net->dir_width, 0);
        linear_shapes(fw, bw, n, 3, V, 1);
    }
}

static double shape_flops(const shape_list *l)
{
    double f = 0.0;
    for (int i = 0; i < l->count; i++) {
        f += 2.0 * l->s[i].m * l->s[i].n * l->s[i].k;
    }
    return f;
}

/* Seconds per run of the listed sgemm calls, on scratch matrices. */
static double time_shapes(const shape_list *l, float *a, float *b, float *c,
                          double budget)
{
    int reps = 0;
    double t0 = now(), t;
    do {
        for (int i = 0; i < l->count; i++) {
            const shape *s = &l->s[i];
            cblas_sgemm(CblasRowMajor, s->trans_a ? CblasTrans : CblasNoTrans,
                        s->trans_b ? CblasTrans : CblasNoTrans, s->m, s->n,
                        s->k, 1.0f, a, s->trans_a ? s->m : s->k, b,
                        s->trans_b ? s->k : s->n, 0.0f, c, s->n);
        }
        reps++;
        t = now() - t0;
    } while (t < budget || reps < 2);
    return t / reps;
}

int main(int argc, char **argv)
{
    int preset = NERF_PRESET_REFERENCE;
    double budget = 1.0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--preset") == 0 && i + 1 < argc) {
            i++;
            preset = strcmp(argv[i], "tiny") == 0 ? NERF_PRESET_TINY
                                                  : NERF_PRESET_REFERENCE;
        } else if (strcmp(argv[i], "--seconds") == 0 && i + 1 < argc) {
            budget = atof(argv[++i]);
        } else {
            fprintf(stderr, "usage: %s [--preset reference|tiny] [--seconds S]\n",
                    argv[0]);
            return 2;
        }
    }
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, preset);
    nerf_model *m = NULL;
    if (nerf_model_create(&m, &o) != NERF_OK) {
        fprintf(stderr, "bench_model: %s\n", nerf_last_error());
        return 1;
    }
    const nerf__network *net = &m->nets[0];
    const char *threads = getenv("OPENBLAS_NUM_THREADS");
    printf("%s\n", nerf_build_info());
    printf("preset %s, %.0f FLOPs/sample forward, OPENBLAS_NUM_THREADS=%s\n",
           preset == NERF_PRESET_TINY ? "tiny" : "reference",
           nerf__network_flops_per_sample(net), threads ? threads : "(unset)");
    printf("%8s %-9s %12s %9s %12s %9s %8s\n", "samples", "pass", "samples/s",
           "GFLOP/s", "sgemm-bound", "GFLOP/s", "share");

    static const size_t sizes[] = {4096, 16384, 65536};
    for (size_t si = 0; si < 3; si++) {
        size_t n = sizes[si];
        float *pos = malloc(n * 3 * sizeof(float));
        float *dir = malloc(n * 3 * sizeof(float));
        float *drgb = malloc(n * 3 * sizeof(float));
        float *dsig = malloc(n * sizeof(float));
        for (size_t i = 0; i < n * 3; i++) {
            pos[i] = (float)((i * 7919) % 1000) / 500.0f - 1.0f;
            dir[i] = i % 3 == 2 ? 1.0f : 0.0f;
            drgb[i] = 1e-3f;
        }
        for (size_t i = 0; i < n; i++) {
            dsig[i] = 1e-3f;
        }
        nerf__workspace ws;
        memset(&ws, 0, sizeof ws);

        shape_list fw = {0}, bw = {0};
        network_shapes(net, (int)n, &fw, &bw);
        size_t big = n * 512;
        float *a = calloc(big, sizeof(float)), *b = calloc(big, sizeof(float));
        float *c = calloc(big, sizeof(float));
        double gemm_fw = time_shapes(&fw, a, b, c, budget);
        shape_list both = fw;
        for (int i = 0; i < bw.count; i++) {
            both.s[both.count++] = bw.s[i];
        }
        double gemm_both = time_shapes(&both, a, b, c, budget);
        free(a);
        free(b);
        free(c);

        for (int pass = 0; pass < 2; pass++) {
            int reps = 0;
            nerf__model_forward(m, 0, &ws, n, pos, dir, NULL, NULL); /* warm */
            double t0 = now(), t;
            do {
                nerf__model_forward(m, 0, &ws, n, pos, dir, NULL, NULL);
                if (pass == 1) {
                    nerf__model_backward(m, 0, &ws, drgb, dsig);
                }
                reps++;
                t = now() - t0;
            } while (t < budget || reps < 2);
            double per = t / reps;
            double flops = pass ? shape_flops(&both) : shape_flops(&fw);
            double bound = pass ? gemm_both : gemm_fw;
            printf("%8zu %-9s %12.0f %9.1f %12.0f %9.1f %7.1f%%\n", n,
                   pass ? "fwd+bwd" : "forward", n / per, flops / per * 1e-9,
                   n / bound, flops / bound * 1e-9, 100.0 * bound / per);
        }
        nerf__workspace_release(&m->env, &ws);
        free(pos);
        free(dir);
        free(drgb);
        free(dsig);
    }
    nerf_model_destroy(m);
    return 0;
}
