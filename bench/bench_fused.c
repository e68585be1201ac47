/*
 * bench_fused: the fused small-MLP path (lib/mlp/network_fused.h) against
 * the per-layer sgemm path, in one process, passes alternating so that a
 * shared machine's load falls on both alike.  For the fast preset's
 * network (its hash grid, and the same layers on a cheap frequency
 * encoding so that the layers dominate), it times forward with kept
 * activations, backward, forward without them (rendering) and density,
 * each the fastest of its rounds, in wall time and in the process's CPU
 * time (both threads; steadier when others share the cores).  Then the
 * kernels alone, one thread, on a 128 x 64 x 64 product.  Prints figures;
 * asserts nothing.
 *
 *   bench_fused [--samples N] [--rounds R]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nerf.h"
#include "nerf_internal.h"

#if defined(__GNUC__)
extern void openblas_set_num_threads(int n) __attribute__((weak));
#endif

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

enum { FWD, BWD, RENDER, DENSITY, PASSES };
static const char *pass_names[PASSES] = {"forward", "backward", "render",
                                         "density"};

typedef struct timing {
    double wall[PASSES], cpu[PASSES];
} timing;

static void keep_min(double *best, double v, int first)
{
    if (first || v < *best) {
        *best = v;
    }
}

static void run_model(const char *title, nerf_model_options *o, size_t n,
                      int rounds)
{
    nerf_model *m = NULL;
    if (nerf_model_create(&m, o) != NERF_OK) {
        fprintf(stderr, "bench_fused: %s\n", nerf_last_error());
        return;
    }
    const int k = nerf__model_network(m, NERF_NETWORK_COARSE);
    const nerf__network *net = &m->nets[k];
    float *pos = malloc(3 * n * sizeof(float));
    float *dir = malloc(3 * n * sizeof(float));
    float *rgb = malloc(3 * n * sizeof(float));
    float *sigma = malloc(n * sizeof(float));
    float *d_rgb = malloc(3 * n * sizeof(float));
    float *d_sigma = malloc(n * sizeof(float));
    nerf__rng r = nerf__rng_make(3, 1);
    for (size_t i = 0; i < 3 * n; i++) {
        pos[i] = 0.9f * o->bound * (2.0f * nerf__rng_uniform(&r) - 1.0f);
        dir[i] = i % 3 == 2 ? 1.0f : 0.0f;
        d_rgb[i] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
    }
    for (size_t i = 0; i < n; i++) {
        d_sigma[i] = 0.01f * (2.0f * nerf__rng_uniform(&r) - 1.0f);
    }
    const int paths[2] = {NERF__SMM_OFF, nerf__smm_best()};
    timing t[2];
    memset(t, 0, sizeof t);
    nerf__workspace train, render, density;
    memset(&train, 0, sizeof train);
    memset(&render, 0, sizeof render);
    memset(&density, 0, sizeof density);
    for (int round = 0; round <= rounds; round++) {
        for (int p = 0; p < 2; p++) {
            nerf__smm_use(paths[p]);
            double w[PASSES + 1], c[PASSES + 1];
            w[0] = clock_s(CLOCK_MONOTONIC);
            c[0] = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            nerf__model_forward(m, k, &train, n, pos, dir, rgb, sigma);
            w[1] = clock_s(CLOCK_MONOTONIC);
            c[1] = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            nerf__model_backward(m, k, &train, d_rgb, d_sigma);
            w[2] = clock_s(CLOCK_MONOTONIC);
            c[2] = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            nerf__model_evaluate(m, k, &render, n, pos, dir, rgb, sigma);
            w[3] = clock_s(CLOCK_MONOTONIC);
            c[3] = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            nerf__model_density(m, k, &density, n, pos, sigma);
            w[4] = clock_s(CLOCK_MONOTONIC);
            c[4] = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            if (round == 0) {
                continue; /* warm-up: buffers, pages, caches */
            }
            for (int q = 0; q < PASSES; q++) {
                keep_min(&t[p].wall[q], w[q + 1] - w[q], round == 1);
                keep_min(&t[p].cpu[q], c[q + 1] - c[q], round == 1);
            }
        }
    }
    /* The gradients only grew: leave the model as it was for nobody. */
    nerf__model_zero_grad(m);
    printf("%s: %zu samples, %.0f FLOPs/sample forward, fused path %s\n",
           title, n, nerf__network_flops_per_sample(net),
           nerf__fused_fits(net) ? "fits" : "does not fit");
    printf("  %-9s %12s %12s %12s %12s %9s\n", "pass", "sgemm wall",
           "fused wall", "sgemm cpu", "fused cpu", "cpu ratio");
    for (int q = 0; q < PASSES; q++) {
        printf("  %-9s %9.2f ms %9.2f ms %9.2f ms %9.2f ms %9.2f\n",
               pass_names[q], 1e3 * t[0].wall[q], 1e3 * t[1].wall[q],
               1e3 * t[0].cpu[q], 1e3 * t[1].cpu[q],
               t[1].cpu[q] / t[0].cpu[q]);
    }
    nerf__smm_use(nerf__smm_default());
    nerf__workspace_release(&m->env, &train);
    nerf__workspace_release(&m->env, &render);
    nerf__workspace_release(&m->env, &density);
    free(pos);
    free(dir);
    free(rgb);
    free(sigma);
    free(d_rgb);
    free(d_sigma);
    nerf_model_destroy(m);
}

static void run_kernels(void)
{
    enum { M = 128, N = 64, K = 64, REPS = 4000 };
    float *a = malloc(M * K * sizeof(float));
    float *b = malloc(K * N * sizeof(float));
    float *c = malloc(M * N * sizeof(float));
    float *bias = malloc(N * sizeof(float));
    for (int i = 0; i < M * K; i++) {
        a[i] = 0.01f * (float)(i % 7);
    }
    for (int i = 0; i < K * N; i++) {
        b[i] = 0.02f * (float)(i % 5) - 0.04f;
    }
    for (int i = 0; i < N; i++) {
        bias[i] = 0.1f;
    }
    static const char *names[] = {"", "portable", "avx2", "avx512"};
    printf("kernels, one thread, thread CPU time, %dx%dx%d:\n", M, N, K);
    for (int v = NERF__SMM_AVX512; v >= NERF__SMM_PORTABLE; v--) {
        if (nerf__smm_use(v) != 0) {
            printf("  %-8s not on this processor\n", names[v]);
            continue;
        }
        const nerf__smm_seg rows = {a, K, 1, K}, cols = {a, 1, K, M};
        const double flops = 2.0 * M * N * K * REPS;
        double t0 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        for (int i = 0; i < REPS; i++) { /* X W^T + b, ReLU */
            nerf__smm(M, N, &rows, 1, b, N, bias, NERF__SMM_RELU, c, N);
        }
        double t1 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        for (int i = 0; i < REPS; i++) { /* dW += dY^T X */
            nerf__smm(K, N, &cols, 1, c, N, NULL, NERF__SMM_ADD, b, N);
        }
        double t2 = clock_s(CLOCK_THREAD_CPUTIME_ID);
        printf("  %-8s forward %6.1f GFLOP/s, weight gradient %6.1f GFLOP/s\n",
               names[v], flops / (t1 - t0) * 1e-9, flops / (t2 - t1) * 1e-9);
    }
    nerf__smm_use(nerf__smm_default());
    free(a);
    free(b);
    free(c);
    free(bias);
}

int main(int argc, char **argv)
{
    size_t n = 44000; /* a fast-preset training step's samples */
    int rounds = 5;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--samples") == 0 && i + 1 < argc) {
            n = strtoul(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--rounds") == 0 && i + 1 < argc) {
            rounds = atoi(argv[++i]);
        } else {
            fprintf(stderr, "usage: %s [--samples N] [--rounds R]\n", argv[0]);
            return 2;
        }
    }
    if (n == 0 || rounds < 1) {
        fprintf(stderr, "bench_fused: --samples and --rounds must be > 0\n");
        return 2;
    }
#if defined(__GNUC__)
    /* As the programs do (examples/common/cli.c): the sgemm path then
     * spreads its products over libnerf's workers. */
    if (openblas_set_num_threads && getenv("OPENBLAS_NUM_THREADS") == NULL) {
        openblas_set_num_threads(1);
    }
#endif
    printf("%s\n", nerf_build_info());
    printf("kernels chosen at load: %d (0 off, 1 portable, 2 avx2, 3 "
           "avx512)\n", nerf__smm_default());
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_FAST);
    run_model("fast preset", &o, n, rounds);
    o.encoding = NERF_ENCODING_FREQUENCY;
    o.pos_frequencies = 5;
    run_model("fast preset's layers on a frequency encoding", &o, n, rounds);
    run_kernels();
    return 0;
}
