/*
 * bench_march: rays/s and samples per ray of the occupancy-grid ray
 * marcher (count and fill passes) on a 128^3 grid of a ball, for camera
 * rays as a Blender scene has them (bound [-1.5, 1.5]^3, cameras at radius
 * 4); marching without skipping for comparison; the same rays in batches
 * of a training step's rays, counted and filled or walked once
 * (nerf__march_run); the grid update and the packed compositing as well.  Uses the thread pool (every core).  Prints
 * figures; asserts nothing.
 *
 *   bench_march [--rays N] [--res R] [--radius r] [--seconds S]
 */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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

typedef struct ball {
    float r, value;
} ball;

static int ball_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    const ball *b = ctx;
    for (size_t i = 0; i < n; i++) {
        const float *p = xyz + 3 * i;
        float d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        sigma[i] = d2 < b->r * b->r ? b->value : 0.0f;
    }
    return 0;
}

typedef struct bench {
    const nerf__occupancy *g;
    nerf__march_options o;
    nerf__march_rays rays;
    size_t *offsets;
    float *t, *dt, *rgb, *sigma, *out_rgb, *d_out, *d_rgb, *d_sigma;
    uint32_t *used;
    size_t total;
    nerf__march_samples walk;
} bench;

/* Rays a batch of run_batches() takes: a fast training step's. */
#define BATCH_RAYS 2048

/* The rays in batches of BATCH_RAYS, each numbered on from the last;
 * walk: by nerf__march_run(), else count and fill. */
static void run_batches(bench *b, bool walk)
{
    nerf__march_rays part = b->rays;
    for (size_t at = 0; at < b->rays.n; at += part.n) {
        const size_t left = b->rays.n - at;
        part.n = left < BATCH_RAYS ? left : BATCH_RAYS;
        part.origins = b->rays.origins + 3 * at;
        part.dirs = b->rays.dirs + 3 * at;
        part.first_ray = at;
        if (walk) {
            nerf__march_run(b->g, &b->o, &part, &b->walk);
        } else {
            nerf__march_count(b->g, &b->o, &part, b->offsets);
            nerf__march_fill(b->g, &b->o, &part, b->offsets, b->t, b->dt,
                             NULL);
        }
    }
}

static void run_batches_walked(bench *b)
{
    run_batches(b, true);
}

static void run_batches_counted(bench *b)
{
    run_batches(b, false);
}

static void run_count(bench *b)
{
    b->total = nerf__march_count(b->g, &b->o, &b->rays, b->offsets);
}

static void run_fill(bench *b)
{
    nerf__march_fill(b->g, &b->o, &b->rays, b->offsets, b->t, b->dt, NULL);
}

static void run_march(bench *b)
{
    run_count(b);
    run_fill(b);
}

static nerf__packed_batch packed(const bench *b)
{
    static const float white[3] = {1.0f, 1.0f, 1.0f};
    nerf__packed_batch pb = {.n_rays = b->rays.n, .offsets = b->offsets,
                             .t = b->t, .dt = b->dt, .rgb = b->rgb,
                             .sigma = b->sigma, .bg = white,
                             .eps = NERF__COMPOSITE_EPS_DEFAULT};
    return pb;
}

static void run_composite(bench *b)
{
    nerf__packed_batch pb = packed(b);
    nerf__packed_out out = {.rgb = b->out_rgb, .used = b->used};
    nerf__composite_packed(&pb, &out);
}

static void run_composite_backward(bench *b)
{
    nerf__packed_batch pb = packed(b);
    nerf__composite_packed_backward(&pb, b->d_out, NULL, NULL, b->d_rgb,
                                    b->d_sigma);
}

typedef struct timing {
    double wall, cpu; /* seconds per run, best of the runs */
} timing;

/* Best of repeated runs over at least `seconds` (3 runs at least): the
 * machine is shared, and the best run is the least disturbed.  The
 * process CPU time is kept too: on a loaded machine it shows the work
 * done apart from the time spent waiting for a core. */
static timing best_time(void (*fn)(bench *), bench *b, double seconds)
{
    timing best = {1e300, 1e300};
    double start = now();
    for (int runs = 0; runs < 3 || now() - start < seconds; runs++) {
        double t0 = now(), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
        fn(b);
        double t = now() - t0, c = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
        best.wall = t < best.wall ? t : best.wall;
        best.cpu = c < best.cpu ? c : best.cpu;
    }
    return best;
}

int main(int argc, char **argv)
{
    size_t n = (size_t)1 << 16;
    uint32_t res = 128;
    float radius = 0.8f;
    double seconds = 2.0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--rays") == 0 && i + 1 < argc) {
            n = (size_t)strtoull(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--res") == 0 && i + 1 < argc) {
            res = (uint32_t)strtoul(argv[++i], NULL, 10);
        } else if (strcmp(argv[i], "--radius") == 0 && i + 1 < argc) {
            radius = strtof(argv[++i], NULL);
        } else if (strcmp(argv[i], "--seconds") == 0 && i + 1 < argc) {
            seconds = strtod(argv[++i], NULL);
        } else {
            fprintf(stderr, "usage: %s [--rays N] [--res R] [--radius r] "
                    "[--seconds S]\n", argv[0]);
            return 2;
        }
    }
    nerf__env env;
    nerf__env_default(&env);
    const float lo[3] = {-1.5f, -1.5f, -1.5f}, hi[3] = {1.5f, 1.5f, 1.5f};
    nerf__occupancy_options go;
    nerf__occupancy_defaults(&go, lo, hi);
    go.resolution = res;
    nerf__occupancy *g = NULL;
    if (nerf__occupancy_create(&env, &go, &g) != NERF_OK) {
        fprintf(stderr, "%s\n", nerf_last_error());
        return 1;
    }
    ball scene = {radius, 50.0f};
    double t0 = now();
    nerf__occupancy_update(g, ball_density, &scene, g->cells);
    double t_full = now() - t0;
    t0 = now();
    nerf__occupancy_update(g, ball_density, &scene, g->cells / 4);
    double t_part = now() - t0;
    size_t part_evaluated = g->evaluated;
    printf("grid %u^3 over [-1.5, 1.5]^3, ball of radius %.2f: %zu cells "
           "occupied (%.2f%%); %u threads\n", res, (double)radius,
           g->occupied, 100.0 * (double)g->occupied / (double)g->cells,
           nerf__parallel_threads());
    printf("update (analytic density): all cells %.1f ms, a quarter + "
           "occupied (%zu cells) %.1f ms\n", t_full * 1e3, part_evaluated,
           t_part * 1e3);

    /* Pinhole cameras on a sphere of radius 4 looking at the centre, 40
     * degrees of view, as the Blender scenes have them; one camera per
     * 4096 rays. */
    float *o = malloc(3 * n * sizeof(float)), *d = malloc(3 * n * sizeof(float));
    nerf__rng r = nerf__rng_make(1, 0);
    float cam[3] = {0, 0, 0}, fwd[3] = {0, 0, 0}, right[3] = {0, 0, 0};
    float up[3] = {0, 0, 0};
    for (size_t k = 0; k < n; k++) {
        if (k % 4096 == 0) {
            float len = 0.0f;
            for (int a = 0; a < 3; a++) {
                cam[a] = (float)nerf__rng_normal(&r);
                len += cam[a] * cam[a];
            }
            len = sqrtf(len);
            for (int a = 0; a < 3; a++) {
                cam[a] *= 4.0f / len;
                fwd[a] = -cam[a] / 4.0f;
            }
            /* right = fwd x z (or x when looking along z), up = right x fwd */
            float z[3] = {0, 0, 1};
            if (fabsf(fwd[2]) > 0.9f) {
                z[0] = 1;
                z[2] = 0;
            }
            right[0] = fwd[1] * z[2] - fwd[2] * z[1];
            right[1] = fwd[2] * z[0] - fwd[0] * z[2];
            right[2] = fwd[0] * z[1] - fwd[1] * z[0];
            float rl = sqrtf(right[0] * right[0] + right[1] * right[1] +
                             right[2] * right[2]);
            for (int a = 0; a < 3; a++) {
                right[a] /= rl;
            }
            up[0] = right[1] * fwd[2] - right[2] * fwd[1];
            up[1] = right[2] * fwd[0] - right[0] * fwd[2];
            up[2] = right[0] * fwd[1] - right[1] * fwd[0];
        }
        const float half = tanf(20.0f * 3.14159265f / 180.0f);
        float u = (2.0f * nerf__rng_uniform(&r) - 1.0f) * half;
        float v = (2.0f * nerf__rng_uniform(&r) - 1.0f) * half;
        for (int a = 0; a < 3; a++) {
            o[3 * k + a] = cam[a];
            d[3 * k + a] = fwd[a] + u * right[a] + v * up[a];
        }
    }
    bench b = {.g = g};
    nerf__march_samples_init(&b.walk, &env);
    nerf__march_defaults(&b.o, g);
    b.o.jitter = true;
    b.rays = (nerf__march_rays){.n = n, .origins = o, .dirs = d,
                                .near_all = 2.0f, .far_all = 6.0f};
    b.offsets = malloc((n + 1) * sizeof(size_t));
    /* Capacity for the march without skipping. */
    b.o.skip_empty = false;
    size_t cap = nerf__march_count(g, &b.o, &b.rays, b.offsets) + 1;
    b.t = malloc(cap * sizeof(float));
    b.dt = malloc(cap * sizeof(float));
    b.rgb = malloc(3 * cap * sizeof(float));
    b.sigma = malloc(cap * sizeof(float));
    b.d_rgb = malloc(3 * cap * sizeof(float));
    b.d_sigma = malloc(cap * sizeof(float));
    b.out_rgb = malloc(3 * n * sizeof(float));
    b.d_out = malloc(3 * n * sizeof(float));
    b.used = malloc(n * sizeof(uint32_t));
    for (size_t i = 0; i < 3 * n; i++) {
        b.d_out[i] = 0.1f;
    }
    printf("%zu rays, step %.5f (%u across the diagonal), jittered\n", n,
           (double)b.o.step, NERF__MARCH_STEPS_DEFAULT);
    for (int skip = 1; skip >= 0; skip--) {
        b.o.skip_empty = skip;
        timing tc = best_time(run_count, &b, seconds / 2);
        timing tf = best_time(run_fill, &b, seconds / 2);
        timing tm = best_time(run_march, &b, seconds);
        printf("%-16s %6.2f samples/ray: march %6.2f Mrays/s, %6.1f "
               "Msamples/s (%.1f ms: count %.1f, fill %.1f); CPU %.0f ns/ray "
               "(count %.0f, fill %.0f)\n",
               skip ? "skipping empty:" : "not skipping:",
               (double)b.total / (double)n, n / tm.wall * 1e-6,
               (double)b.total / tm.wall * 1e-6, tm.wall * 1e3,
               tc.wall * 1e3, tf.wall * 1e3, tm.cpu / n * 1e9,
               tc.cpu / n * 1e9, tf.cpu / n * 1e9);
        timing tb = best_time(run_batches_counted, &b, seconds / 2);
        timing tw = best_time(run_batches_walked, &b, seconds / 2);
        printf("  in batches of %d rays: count and fill %.1f ms, one walk "
               "%.1f ms (CPU %.0f and %.0f ns/ray)\n", BATCH_RAYS,
               tb.wall * 1e3, tw.wall * 1e3, tb.cpu / n * 1e9,
               tw.cpu / n * 1e9);
    }
    /* Compositing the skipping march's samples, the ball opaque. */
    b.o.skip_empty = true;
    run_march(&b);
    float *xyz = malloc(3 * (b.total + 1) * sizeof(float));
    nerf__march_points(&b.o, &b.rays, b.offsets, b.t, xyz);
    ball_density(&scene, b.total, xyz, b.sigma);
    for (size_t i = 0; i < 3 * b.total; i++) {
        b.rgb[i] = 0.5f;
    }
    timing tcf = best_time(run_composite, &b, seconds / 2);
    timing tcb = best_time(run_composite_backward, &b, seconds / 2);
    size_t used = 0;
    for (size_t k = 0; k < n; k++) {
        used += b.used[k];
    }
    printf("composite (eps 1e-4): %.2f of %.2f samples/ray used; forward "
           "%.1f ms (%.1f Mrays/s, CPU %.0f ns/ray), backward %.1f ms (%.1f "
           "Mrays/s, CPU %.0f ns/ray)\n",
           (double)used / (double)n, (double)b.total / (double)n,
           tcf.wall * 1e3, n / tcf.wall * 1e-6, tcf.cpu / n * 1e9,
           tcb.wall * 1e3, n / tcb.wall * 1e-6, tcb.cpu / n * 1e9);
    free(xyz);
    free(o);
    free(d);
    free(b.offsets);
    free(b.t);
    free(b.dt);
    free(b.rgb);
    free(b.sigma);
    free(b.d_rgb);
    free(b.d_sigma);
    free(b.out_rgb);
    free(b.d_out);
    free(b.used);
    nerf__march_samples_release(&b.walk);
    nerf__occupancy_destroy(g);
    return 0;
}
