/*
 * bench_render: image rendering throughput (rays/s) of the reference and
 * tiny presets, with one worker thread and with one per core, and the
 * peak resident memory of an 800x800 render.  Prints figures; asserts
 * nothing.
 *
 *   bench_render [--quick] [--ref-rss-seconds S] [--no-rss]
 *                [--preset tiny|reference] [--side 100|400]
 *
 * --quick skips the reference preset at 400x400 (by far the longest part
 * of the run on a few cores) and cancels the reference memory run after
 * 10 s; --preset and --side restrict the throughput table.
 *
 * Sample counts: reference 64 + 128 (the paper's); tiny 32 + 64 (the tiny
 * sampler preset: half of each, enough for the small scenes tests and
 * quick trials use).  The model is untrained: rendering cost does not
 * depend on the weights, as nothing stops rays early.
 *
 * Peak memory is measured in a child process per configuration, forked
 * before this process touches the BLAS, so each figure is that render's
 * own ru_maxrss.  The reference preset renders 800x800 slowly on a small
 * machine, for many minutes (docs/performance.md): its child cancels
 * after --ref-rss-seconds (default 60) through the progress callback.
 * Memory does not grow with progress (workers allocate their scratch on
 * their first block and the output buffers are touched up front), so the
 * figure holds for the whole render; the rays rendered by then are
 * printed with it.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "nerf.h"
#include "nerf_internal.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct setup {
    nerf_model *m;
    nerf_sampler *s;
    double flops_per_ray;
} setup;

static int make(setup *st, int preset)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, preset);
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, preset);
    if (nerf_model_create(&st->m, &mo) != NERF_OK ||
        nerf_sampler_create(&st->s, &so) != NERF_OK) {
        fprintf(stderr, "bench_render: %s\n", nerf_last_error());
        return 1;
    }
    /* Coarse samples through the coarse network, all samples through the
     * fine one. */
    st->flops_per_ray = nerf__network_flops_per_sample(&st->m->nets[0]) *
                        (2.0 * so.n_coarse + so.n_fine);
    return 0;
}

static void release(setup *st)
{
    nerf_sampler_destroy(st->s);
    nerf_model_destroy(st->m);
}

/* A Blender-like view: as far from the origin and as wide as the built-in
 * scene's cameras. */
static void camera(nerf_camera *c, uint32_t side)
{
    NERF_CAMERA_INIT(c);
    c->width = c->height = side;
    c->fx = c->fy =
        0.5f * (float)side / tanf(0.5f * (float)NERF__SCENE_CAMERA_ANGLE_X);
    c->cx = c->cy = 0.5f * (float)side;
    /* Looking at the origin from (0, -2, 1)/|.| * radius, world z up. */
    const float e = 1.0f / sqrtf(5.0f);
    const float r = (float)NERF__SCENE_CAMERA_RADIUS;
    const float pose[12] = {1, 0, 0, 0,
                            0, e, -2 * e, -2 * r * e,
                            0, 2 * e, e, r * e};
    memcpy(c->c2w, pose, sizeof pose);
}

typedef struct budget {
    double seconds;
    uint64_t done;
} budget;

static int stop_after(const nerf_progress *p, void *user)
{
    budget *b = user;
    b->done = p->done;
    return p->elapsed > b->seconds;
}

/* Child process: render side x side, print ru_maxrss. */
static int rss_child(int preset, const char *name, uint32_t side,
                     double seconds)
{
    setup st;
    if (make(&st, preset)) {
        return 1;
    }
    nerf_renderer *r = NULL;
    if (nerf_renderer_create(&r, st.m, st.s, NULL) != NERF_OK) {
        fprintf(stderr, "bench_render: %s\n", nerf_last_error());
        return 1;
    }
    size_t pixels = (size_t)side * side;
    float *rgb = malloc(pixels * 3 * sizeof(float));
    float *depth = malloc(pixels * sizeof(float));
    float *opacity = malloc(pixels * sizeof(float));
    if (!rgb || !depth || !opacity) {
        return 1;
    }
    memset(rgb, 0, pixels * 3 * sizeof(float));
    memset(depth, 0, pixels * sizeof(float));
    memset(opacity, 0, pixels * sizeof(float));
    budget b = {seconds, 0};
    nerf_renderer_set_progress(r, stop_after, &b);
    nerf_camera cam;
    camera(&cam, side);
    double t0 = now();
    int rc = nerf_renderer_render_image(r, &cam, rgb, depth, opacity, pixels);
    double t = now() - t0;
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double out_mb = pixels * 5 * sizeof(float) / 1048576.0;
    if (rc == NERF_OK) {
        printf("%-9s %ux%u: peak RSS %.1f MB (outputs %.1f MB), "
               "%.1f s, %.0f rays/s\n", name, side, side,
               ru.ru_maxrss / 1024.0, out_mb, t, pixels / t);
    } else {
        printf("%-9s %ux%u: peak RSS %.1f MB (outputs %.1f MB), cancelled "
               "after %.1f s at %llu of %zu rays (%.0f rays/s: a full render "
               "takes about %.0f s)\n", name, side, side,
               ru.ru_maxrss / 1024.0, out_mb, t, (unsigned long long)b.done,
               pixels, b.done / t, pixels / (b.done / t));
    }
    nerf_renderer_destroy(r);
    release(&st);
    free(rgb);
    free(depth);
    free(opacity);
    return 0;
}

static void rss(int preset, const char *name, double seconds)
{
    fflush(stdout);
    pid_t pid = fork();
    if (pid == 0) {
        int rc = rss_child(preset, name, 800, seconds);
        fflush(stdout); /* _exit() does not flush */
        _exit(rc);
    }
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) < 0 || status != 0) {
        printf("%-9s 800x800: measurement failed\n", name);
    }
}

/* Rays per second of a side x side render with the given threads. */
static double throughput(const setup *st, uint32_t side, uint32_t threads)
{
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = threads;
    nerf_renderer *r = NULL;
    if (nerf_renderer_create(&r, st->m, st->s, &ro) != NERF_OK) {
        return 0.0;
    }
    size_t pixels = (size_t)side * side;
    float *rgb = malloc(pixels * 3 * sizeof(float));
    nerf_camera cam;
    camera(&cam, side);
    double t0 = now();
    int rc = nerf_renderer_render_image(r, &cam, rgb, NULL, NULL, pixels);
    double t = now() - t0;
    nerf_renderer_destroy(r);
    free(rgb);
    return rc == NERF_OK ? pixels / t : 0.0;
}

int main(int argc, char **argv)
{
    int quick = 0, no_rss = 0, only_preset = 0;
    uint32_t only_side = 0;
    double ref_seconds = 60.0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--quick") == 0) {
            quick = 1;
        } else if (strcmp(argv[i], "--no-rss") == 0) {
            no_rss = 1;
        } else if (strcmp(argv[i], "--ref-rss-seconds") == 0 && i + 1 < argc) {
            ref_seconds = atof(argv[++i]);
        } else if (strcmp(argv[i], "--preset") == 0 && i + 1 < argc) {
            i++;
            only_preset = strcmp(argv[i], "tiny") == 0 ? NERF_PRESET_TINY
                                                       : NERF_PRESET_REFERENCE;
        } else if (strcmp(argv[i], "--side") == 0 && i + 1 < argc) {
            only_side = (uint32_t)atoi(argv[++i]);
        } else {
            fprintf(stderr, "usage: %s [--quick] [--ref-rss-seconds S] "
                    "[--no-rss] [--preset tiny|reference] [--side N]\n",
                    argv[0]);
            return 2;
        }
    }
    const char *blas_threads = getenv("OPENBLAS_NUM_THREADS");
    uint32_t cores = nerf__cpu_count();
    printf("%s\n", nerf_build_info());
    printf("%u cores online, OPENBLAS_NUM_THREADS=%s", cores,
           blas_threads ? blas_threads : "(unset)");
    {
        setup st;
        nerf_renderer *r = NULL;
        if (make(&st, NERF_PRESET_TINY) == 0 &&
            nerf_renderer_create(&r, st.m, st.s, NULL) == NERF_OK) {
            printf(", default workers (threads = 0): %u, chunks of %zu rays",
                   r->threads, r->chunk);
        }
        nerf_renderer_destroy(r);
        release(&st);
    }
    printf("\n\n");

    if (!no_rss) {
        printf("peak resident memory (one child process each):\n");
        rss(NERF_PRESET_TINY, "tiny", 1e9);
        rss(NERF_PRESET_REFERENCE, "reference", quick ? 10.0 : ref_seconds);
    }

    printf("\n%-9s %8s %8s %11s %9s\n", "preset", "image", "threads",
           "rays/s", "GFLOP/s");
    static const int presets[2] = {NERF_PRESET_TINY, NERF_PRESET_REFERENCE};
    static const uint32_t sides[2] = {100, 400};
    for (int p = 0; p < 2; p++) {
        if (only_preset && presets[p] != only_preset) {
            continue;
        }
        setup st;
        if (make(&st, presets[p])) {
            return 1;
        }
        const char *name = p == 0 ? "tiny" : "reference";
        for (int s = 0; s < 2; s++) {
            if ((quick && p == 1 && s == 1) ||
                (only_side && sides[s] != only_side)) {
                continue;
            }
            uint32_t counts[2] = {1, cores};
            for (int k = 0; k < (cores > 1 ? 2 : 1); k++) {
                double rays = throughput(&st, sides[s], counts[k]);
                printf("%-9s %4ux%-3u %8u %11.0f %9.1f\n", name, sides[s],
                       sides[s], counts[k], rays,
                       rays * st.flops_per_ray * 1e-9);
                fflush(stdout);
            }
        }
        release(&st);
    }
    return 0;
}
