/*
 * bench_hashgrid: samples/s of the hash-grid encoding's forward and
 * backward (and of the SH direction encoding) at the paper's defaults.
 * Two position layouts: uniformly random in the bound (the worst case for
 * the caches) and consecutive samples along random rays (what a training
 * batch looks like).  Prints figures; asserts nothing.
 *
 *   bench_hashgrid [--samples N] [--threads T] [--seconds S] [--huge]
 */
/* madvise and MADV_HUGEPAGE are not POSIX. */
#define _DEFAULT_SOURCE 1

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

#include "nerf.h"
#include "nerf_internal.h"

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double now(void)
{
    return clock_s(CLOCK_MONOTONIC);
}

typedef struct bench {
    const nerf__hashgrid *hg;
    float *table, *grad, *pos, *out;
    size_t n;
    uint32_t threads;
} bench;

typedef struct timing {
    double wall, cpu; /* seconds per run, best of the runs */
} timing;

/* Best of repeated runs over at least `seconds` (3 runs at least): the
 * machine is shared, and the best run is the one least disturbed.  The
 * process CPU time is kept too: on a loaded machine it shows the work
 * done apart from the time spent waiting for a core. */
static timing best_time(void (*fn)(const bench *), const bench *b,
                        double seconds)
{
    timing best = {1e300, 1e300};
    double start = now();
    int runs = 0;
    while (runs < 3 || now() - start < seconds) {
        double t0 = now(), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
        fn(b);
        double t = now() - t0, c = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
        best.wall = t < best.wall ? t : best.wall;
        best.cpu = c < best.cpu ? c : best.cpu;
        runs++;
    }
    return best;
}

static void run_forward(const bench *b)
{
    nerf__hashgrid_forward(b->hg, b->table, b->n, b->pos, 3, b->out,
                           nerf__hashgrid_width(b->hg), b->threads);
}

static void run_backward(const bench *b)
{
    nerf__hashgrid_backward(b->hg, b->n, b->pos, 3, b->out,
                            nerf__hashgrid_width(b->hg), b->grad, b->threads);
}

static void run_zero(const bench *b)
{
    memset(b->grad, 0, b->hg->count * sizeof(float));
}

static void run_sh(const bench *b)
{
    nerf__sh_forward(4, b->n, b->pos, 3, b->out, 16);
}

/*
 * The tables are large and read at random, so with 4 KiB pages most reads
 * also miss the TLB.  Where the kernel gives transparent huge pages only
 * on request (the Debian default), --huge requests them.
 */
static float *alloc_table(size_t count, int huge)
{
    size_t bytes = count * sizeof(float);
    const size_t page = (size_t)2 << 20;
    bytes = (bytes + page - 1) / page * page;
    void *p = NULL;
    if (posix_memalign(&p, page, bytes) != 0) {
        return NULL;
    }
#ifdef MADV_HUGEPAGE
    if (huge) {
        (void)madvise(p, bytes, MADV_HUGEPAGE);
    }
#else
    (void)huge;
#endif
    memset(p, 0, bytes);
    return p;
}

static void fill_random(float *pos, size_t n, const float lo[3],
                        const float hi[3])
{
    nerf__rng r = nerf__rng_make(1, 1);
    for (size_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            pos[3 * i + a] = lo[a] + (hi[a] - lo[a]) * nerf__rng_uniform(&r);
        }
    }
}

/* Rays from random points on a sphere of radius 4 towards random points
 * near the centre, `per` samples evenly spaced over the 3 units of each
 * ray around the centre, as a sampler inside a [-1.5, 1.5]^3 bound
 * places them. */
static void fill_rays(float *pos, size_t n, size_t per)
{
    nerf__rng r = nerf__rng_make(1, 2);
    for (size_t i = 0; i < n; i += per) {
        float o[3], d[3], len = 0.0f, dl = 0.0f;
        for (int a = 0; a < 3; a++) {
            o[a] = (float)nerf__rng_normal(&r);
            len += o[a] * o[a];
        }
        len = sqrtf(len);
        for (int a = 0; a < 3; a++) {
            o[a] *= 4.0f / len;
            d[a] = 0.5f * (nerf__rng_uniform(&r) - 0.5f) - o[a];
            dl += d[a] * d[a];
        }
        dl = sqrtf(dl);
        for (size_t k = 0; k < per && i + k < n; k++) {
            float s = 2.5f + 3.0f * (float)k / (float)per;
            for (int a = 0; a < 3; a++) {
                pos[3 * (i + k) + a] = o[a] + s * d[a] / dl;
            }
        }
    }
}

int main(int argc, char **argv)
{
    size_t n = (size_t)1 << 18;
    uint32_t threads = 0;
    double seconds = 2.0;
    int huge = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--samples") == 0 && i + 1 < argc) {
            n = (size_t)strtoull(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
            threads = (uint32_t)strtoul(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--seconds") == 0 && i + 1 < argc) {
            seconds = strtod(argv[++i], NULL);
        } else if (strcmp(argv[i], "--huge") == 0) {
            huge = 1;
        } else {
            fprintf(stderr,
                    "usage: %s [--samples N] [--threads T] [--seconds S] "
                    "[--huge]\n",
                    argv[0]);
            return 2;
        }
    }
    const float lo[3] = {-1.5f, -1.5f, -1.5f}, hi[3] = {1.5f, 1.5f, 1.5f};
    nerf__hashgrid hg;
    if (nerf__hashgrid_defaults(&hg, lo, hi) != NERF_OK) {
        fprintf(stderr, "%s\n", nerf_last_error());
        return 1;
    }
    uint32_t W = nerf__hashgrid_width(&hg);
    nerf__env env;
    nerf__env_default(&env);
    bench b = {&hg, NULL, NULL, NULL, NULL, n, 1};
    b.table = alloc_table(hg.count, huge);
    b.grad = alloc_table(hg.count, huge);
    b.pos = nerf__alloc(&env, n * 3 * sizeof(float));
    b.out = nerf__alloc(&env, n * (W > 16 ? W : 16) * sizeof(float));
    if (!b.table || !b.grad || !b.pos || !b.out) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    nerf__hashgrid_init(&hg, b.table, 1, 0);
    uint32_t dense = 0;
    for (uint32_t l = 0; l < hg.levels; l++) {
        dense += hg.dense[l];
    }
    printf("hash grid: L %u, F %u, T 2^%u, N %u..%u (%u dense levels), "
           "%zu parameters (%.1f MiB); %zu samples\n",
           hg.levels, hg.features, hg.log2_table, hg.min_resolution,
           hg.max_resolution, dense, hg.count,
           (double)hg.count * 4.0 / 1048576.0, n);
    uint32_t tlist[2] = {1, 2};
    int tcount = 2;
    if (threads) {
        tlist[0] = threads;
        tcount = 1;
    }
    for (int layout = 0; layout < 2; layout++) {
        if (layout == 0) {
            fill_random(b.pos, n, lo, hi);
        } else {
            fill_rays(b.pos, n, 128);
        }
        for (int k = 0; k < tcount; k++) {
            b.threads = tlist[k];
            timing tf = best_time(run_forward, &b, seconds);
            timing tb = best_time(run_backward, &b, seconds);
            printf("%-6s threads %u: forward %6.2f Msamples/s (%6.1f ms, "
                   "%6.1f ms CPU), backward %6.2f Msamples/s (%6.1f ms, "
                   "%6.1f ms CPU)\n",
                   layout == 0 ? "random" : "rays", b.threads,
                   n / tf.wall * 1e-6, tf.wall * 1e3, tf.cpu * 1e3,
                   n / tb.wall * 1e-6, tb.wall * 1e3, tb.cpu * 1e3);
        }
    }
    timing tz = best_time(run_zero, &b, seconds / 4);
    printf("zeroing the gradient table: %.2f ms\n", tz.wall * 1e3);
    timing ts = best_time(run_sh, &b, seconds / 4);
    printf("SH degree 4 forward, 1 thread: %.2f Msamples/s (%.2f ms)\n",
           n / ts.wall * 1e-6, ts.wall * 1e3);
    free(b.table);
    free(b.grad);
    nerf__free(&env, b.pos);
    nerf__free(&env, b.out);
    return 0;
}
