/*
 * bench_render_model: seconds per frame of a saved model's renders, the
 * figure of "an 800x800 frame of a trained fast model".  Prints figures;
 * asserts nothing.
 *
 *   bench_render_model MODEL [--side N] [--frames N] [--threads N]
 *                      [--bake K]
 *
 * Renders --frames views (default 8) of --side pixels square (default
 * 800) along nerf-render's --path orbit at radius 4 (30 degrees up, the
 * lego scene's field of view), where its figures in docs/performance.md
 * were measured (nerf-render's orbit now stands at 4.43), with the renderer the model's own render
 * settings give, after one untimed frame in which the workers allocate
 * their scratch.  A marching model's cost depends on its weights (rays
 * stop where it is opaque), so the figure is only meaningful for a model
 * trained on a real scene.
 *
 * --bake K times the renders of the model baked at K subdivisions
 * (nerf_bake_create()) instead, after the bake itself, and scores each
 * against the networks' render of the same view (not timed).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nerf.h"
#include "orbit.h"

/* The orbit's radius when the figures were measured. */
#define BENCH_DISTANCE 4.0

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int compare(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    unsigned side = 800, frames = 8, threads = 0, bake_k = 0;
    for (int i = 1; i < argc; i++) {
        unsigned *v = strcmp(argv[i], "--side") == 0      ? &side
                      : strcmp(argv[i], "--frames") == 0  ? &frames
                      : strcmp(argv[i], "--threads") == 0 ? &threads
                      : strcmp(argv[i], "--bake") == 0    ? &bake_k
                                                          : NULL;
        if (v && i + 1 < argc) {
            *v = (unsigned)strtoul(argv[++i], NULL, 10);
        } else if (!v && argv[i][0] != '-' && path == NULL) {
            path = argv[i];
        } else {
            path = NULL;
            break;
        }
    }
    if (path == NULL || side == 0 || frames == 0 || frames > 1000 ||
        bake_k > 16) {
        fprintf(stderr, "usage: bench_render_model MODEL [--side N] "
                        "[--frames N (1-1000)] [--threads N] "
                        "[--bake K (1-16)]\n");
        return 2;
    }
    nerf_model *m = NULL;
    nerf_renderer *r = NULL;
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = threads;
    const size_t pixels = (size_t)side * side;
    float *rgb = malloc(3 * pixels * sizeof(float));
    float *net = malloc(3 * pixels * sizeof(float));
    double *t = malloc(frames * sizeof(double));
    int rc = rgb && net && t ? nerf_model_load(&m, path, NULL) : NERF_ENOMEM;
    if (rc == NERF_OK) {
        /* The model's background, which the bake composites on too. */
        rc = nerf_model_render_settings(m, NULL, &ro);
    }
    if (rc == NERF_OK) {
        rc = nerf_renderer_create(&r, m, NULL, &ro);
    }
    nerf_bake *bake = NULL;
    double psnr_sum = 0.0;
    if (rc == NERF_OK && bake_k > 0) {
        nerf_bake_options bo;
        NERF_BAKE_OPTIONS_INIT(&bo);
        bo.subdivisions = bake_k;
        const double t0 = now();
        rc = nerf_bake_create(&bake, m, &bo);
        nerf_bake_stats st;
        st.struct_size = sizeof st;
        if (rc == NERF_OK && nerf_bake_stats_get(bake, &st) == NERF_OK) {
            printf("baked at %u across in %.1f s: %llu bricks, %.0f MB\n",
                   st.resolution, now() - t0,
                   (unsigned long long)st.bricks, (double)st.bytes / 1e6);
        }
    }
    nerf_camera cam;
    for (unsigned i = 0; i <= frames && rc == NERF_OK; i++) {
        /* Frame 0 again first, untimed: the workers' scratch. */
        rc = orbit_camera_at(i == 0 ? 0 : i - 1, frames, side, side,
                             BENCH_DISTANCE, &cam);
        const double t0 = now();
        if (rc == NERF_OK) {
            rc = bake ? nerf_bake_render_image(bake, &cam, rgb, NULL, NULL,
                                               pixels)
                      : nerf_renderer_render_image(r, &cam, rgb, NULL, NULL,
                                                   pixels);
        }
        if (i > 0) {
            t[i - 1] = now() - t0;
        }
        if (rc == NERF_OK && bake && i > 0) {
            double p = 0.0;
            rc = nerf_renderer_render_image(r, &cam, net, NULL, NULL, pixels);
            if (rc == NERF_OK) {
                rc = nerf_psnr(rgb, net, 3 * pixels, &p);
            }
            psnr_sum += p;
        }
    }
    if (rc != NERF_OK) {
        fprintf(stderr, "bench_render_model: %s\n", nerf_last_error());
    } else {
        double sum = 0.0;
        for (unsigned i = 0; i < frames; i++) {
            sum += t[i];
        }
        qsort(t, frames, sizeof *t, compare);
        printf("%s\n%s: %u orbit frames of %ux%u: %.3f s a frame on "
               "average (median %.3f, fastest %.3f, slowest %.3f), "
               "%.0f rays/s\n", nerf_build_info(), path, frames, side, side,
               sum / frames, t[frames / 2], t[0], t[frames - 1],
               (double)pixels * frames / sum);
        if (bake) {
            printf("baked renders: %.2f dB against the networks' on "
                   "average\n", psnr_sum / frames);
        }
    }
    nerf_bake_destroy(bake);
    free(net);
    nerf_renderer_destroy(r);
    nerf_model_destroy(m);
    free(rgb);
    free(t);
    return rc == NERF_OK ? 0 : 1;
}
