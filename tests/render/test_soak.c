/*
 * A long-running host: load a model from a checkpoint, render a small
 * image, free everything, thousands of times, as a server embedding
 * libnerf would.  Through the public API of the shared library only.
 *
 * What would fail: a leak on any of those paths (the sanitizer build's
 * leak check names it; the release build sees it as resident memory that
 * keeps growing), or state that survives a destroy and changes the next
 * render (every render must equal the first bit for bit).
 *
 * Resident memory (VmRSS of /proc/self/status) is read after a warm-up
 * and at the end; growth beyond SOAK_RSS_TOLERANCE_KB fails.  The warm-up
 * lets malloc's arenas, the BLAS's buffers and the thread stacks glibc
 * caches reach their steady size.  The tolerance is far below what
 * leaking one model per cycle costs (the second test checks the measure
 * sees that), and far above the few pages malloc's free lists drift by.
 * Under AddressSanitizer the growth is only printed: its quarantine holds
 * freed memory on purpose, and its leak check is the stronger test there.
 *
 * Bounded in time: SOAK_ITERATIONS cycles or SOAK_SECONDS, whichever
 * comes first, but at least SOAK_MIN_ITERATIONS cycles (unless
 * NERF_SOAK_ITERATIONS asks for fewer); NERF_SOAK_ITERATIONS and
 * NERF_SOAK_SECONDS override both bounds for a longer run by hand.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "nerf.h"

#if defined(__SANITIZE_ADDRESS__)
#define SOAK_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SOAK_ASAN 1
#endif
#endif
#ifndef SOAK_ASAN
#define SOAK_ASAN 0
#endif

#define SOAK_ITERATIONS 3000
#define SOAK_SECONDS 3.0
#define SOAK_WARMUP 32
/* Cycles run however long they take, so that a slow (sanitized) or busy
 * machine still tests enough of them rather than failing for want of
 * time. */
#define SOAK_MIN_ITERATIONS 200
#define SOAK_RSS_TOLERANCE_KB 2048L
/* Models held at once by the check that a leak shows: enough (about 17 MB
 * of tiny models) that they cannot all fit in the memory the soak's cycles
 * freed and the allocator kept, which runs to several MB. */
#define LEAK_MODELS 64

#define W 6
#define H 4
#define NPIX (W * H)

enum { KIND_TINY, KIND_HASHGRID, N_KINDS };
/* One cycle in HASHGRID_EVERY loads the hash-grid model, whose occupancy
 * grid (128^3 cells, fixed) costs ten times the tiny model's load. */
#define HASHGRID_EVERY 16

static char tmpdir[64];
static char paths[N_KINDS][128];
static float reference[N_KINDS][NPIX * 4];

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Resident set size in kB, or -1 where /proc/self/status has none. */
static long rss_kb(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (f == NULL) {
        return -1;
    }
    char line[256];
    long kb = -1;
    while (fgets(line, sizeof line, f) != NULL) {
        if (strncmp(line, "VmRSS:", 6) == 0) {
            kb = strtol(line + 6, NULL, 10);
            break;
        }
    }
    fclose(f);
    return kb;
}

static double env_number(const char *name, double fallback)
{
    const char *s = getenv(name);
    if (s == NULL || *s == '\0') {
        return fallback;
    }
    char *end = NULL;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || !(v > 0)) {
        printf("ignoring %s=%s (not a positive number)\n", name, s);
        return fallback;
    }
    return v;
}

/* The tiny preset and a hash-grid model small enough to load in a
 * millisecond: between them every loader and renderer path (two
 * networks with hierarchical sampling; one network with an occupancy
 * grid and ray marching). */
static void model_options(int kind, nerf_model_options *mo)
{
    NERF_MODEL_OPTIONS_INIT(mo);
    if (kind == KIND_TINY) {
        nerf_model_options_preset(mo, NERF_PRESET_TINY);
    } else {
        nerf_model_options_preset(mo, NERF_PRESET_FAST);
        mo->hash_levels = 4;
        mo->hash_log2_size = 10;
        mo->hash_max_resolution = 64;
    }
    mo->seed = 11 + (uint64_t)kind;
}

static void sampler_options(int kind, nerf_sampler_options *so)
{
    NERF_SAMPLER_OPTIONS_INIT(so);
    nerf_sampler_options_preset(so, kind == KIND_TINY ? NERF_PRESET_TINY
                                                      : NERF_PRESET_FAST);
    /* Few samples: the test is about what is allocated and freed, and
     * cheap cycles make thousands of them fit in seconds. */
    if (kind == KIND_TINY) {
        so->n_coarse = 16;
        so->n_fine = 16;
    } else {
        so->march_steps = 64;
        so->max_samples = 32;
    }
}

static void camera(nerf_camera *c)
{
    NERF_CAMERA_INIT(c);
    c->width = W;
    c->height = H;
    c->fx = c->fy = 0.5f * W / tanf(0.4f);
    c->cx = 0.5f * W;
    c->cy = 0.5f * H;
    const float eye[3] = {2.5f, -2.5f, 1.5f};
    const float target[3] = {0.0f, 0.0f, 0.0f};
    const float up[3] = {0.0f, 0.0f, 1.0f};
    nerf_camera_look_at(c, eye, target, up);
}

/* One cycle of the host: load, render into out (rgb, then opacity), free.
 * Returns the first failing status, after freeing what was made. */
static int cycle(int kind, float *out)
{
    nerf_model *m = NULL;
    nerf_sampler *s = NULL;
    nerf_renderer *r = NULL;
    nerf_sampler_options so;
    nerf_renderer_options ro;
    nerf_camera c;
    sampler_options(kind, &so);
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = 2;
    ro.chunk_rays = 64;
    camera(&c);
    int rc = nerf_model_load(&m, paths[kind], NULL);
    if (rc == NERF_OK) {
        rc = nerf_sampler_create(&s, &so);
    }
    if (rc == NERF_OK) {
        rc = nerf_renderer_create(&r, m, s, &ro);
    }
    if (rc == NERF_OK) {
        rc = nerf_renderer_render_image(r, &c, out, NULL, out + NPIX * 3,
                                        NPIX);
    }
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    return rc;
}

/* Runs one cycle and compares its image with the first one's.  Returns 0
 * once it has reported a failure, so the loops stop at the first. */
static int checked_cycle(long i)
{
    const int kind = i % HASHGRID_EVERY == HASHGRID_EVERY - 1 ? KIND_HASHGRID
                                                              : KIND_TINY;
    float out[NPIX * 4];
    int rc = cycle(kind, out);
    if (rc != NERF_OK) {
        FAILF("cycle %ld (model %d): status %d: %s", i, kind, rc,
              nerf_last_error());
        return 0;
    }
    if (memcmp(out, reference[kind], sizeof out) != 0) {
        FAILF("cycle %ld (model %d): the image differs from the first one",
              i, kind);
        return 0;
    }
    return 1;
}

TEST(first_renders)
{
    for (int kind = 0; kind < N_KINDS; kind++) {
        CHECK_OK(cycle(kind, reference[kind]));
        int lit = 0;
        for (int p = 0; p < NPIX; p++) {
            float o = reference[kind][NPIX * 3 + p];
            /* 32 samples a ray composited in either kind (sampler_options:
             * 16 + 16, or max_samples 32). */
            CHECK(o >= 0.0f && o <= float_opacity_max(32));
            lit += o > 1e-3f;
        }
        /* An untrained model is a faint fog: some opacity everywhere the
         * rays cross the scene, or the renders would compare nothing. */
        CHECK(lit > 0);
    }
}

TEST(soak)
{
    const long max_iter = (long)env_number("NERF_SOAK_ITERATIONS",
                                           SOAK_ITERATIONS);
    const double seconds = env_number("NERF_SOAK_SECONDS", SOAK_SECONDS);
    long i = 0;
    for (; i < SOAK_WARMUP; i++) {
        if (!checked_cycle(i)) {
            return;
        }
    }
    const long rss0 = rss_kb();
    const double t0 = now();
    long n = 0;
    while (n < max_iter &&
           (n < SOAK_MIN_ITERATIONS || now() - t0 < seconds)) {
        if (!checked_cycle(i)) {
            return;
        }
        i++;
        n++;
    }
    const double elapsed = now() - t0;
    const long rss1 = rss_kb();
    printf("  %ld cycles in %.2f s (%.2f ms each) after %d warm-up; "
           "VmRSS %ld kB -> %ld kB (%+ld kB, tolerance %ld kB%s)\n",
           n, elapsed, 1e3 * elapsed / (double)(n ? n : 1), SOAK_WARMUP,
           rss0, rss1, rss1 - rss0, SOAK_RSS_TOLERANCE_KB,
           SOAK_ASAN ? ", not applied under ASan" : "");
    if (rss0 < 0 || rss1 < 0) {
        printf("  no VmRSS in /proc/self/status: memory not compared\n");
    } else if (!SOAK_ASAN && rss1 - rss0 > SOAK_RSS_TOLERANCE_KB) {
        FAILF("resident memory grew by %ld kB over %ld cycles (tolerance "
              "%ld kB)", rss1 - rss0, n, SOAK_RSS_TOLERANCE_KB);
    }
}

/* The measure can fail: holding on to the models of LEAK_MODELS cycles,
 * as a host leaking one per cycle would, grows VmRSS past the tolerance. */
TEST(rss_sees_a_leak)
{
    nerf_model *held[LEAK_MODELS] = {0};
    const long rss0 = rss_kb();
    if (rss0 < 0) {
        printf("  no VmRSS in /proc/self/status: skipped\n");
        return;
    }
    float out[NPIX * 4];
    for (int k = 0; k < LEAK_MODELS; k++) {
        CHECK_OK(nerf_model_load(&held[k], paths[KIND_TINY], NULL));
        CHECK_OK(cycle(KIND_TINY, out));
    }
    const long rss1 = rss_kb();
    printf("  %d models held: VmRSS %ld kB -> %ld kB (%+ld kB)\n",
           LEAK_MODELS, rss0, rss1, rss1 - rss0);
    CHECK(rss1 - rss0 > SOAK_RSS_TOLERANCE_KB);
    for (int k = 0; k < LEAK_MODELS; k++) {
        nerf_model_destroy(held[k]);
    }
}

int main(void)
{
    snprintf(tmpdir, sizeof tmpdir, "/tmp/nerf-soak-XXXXXX");
    if (mkdtemp(tmpdir) == NULL) {
        printf("cannot create a temporary directory\n");
        return 1;
    }
    int ready = 1;
    for (int kind = 0; kind < N_KINDS; kind++) {
        nerf_model_options mo;
        model_options(kind, &mo);
        nerf_model *m = NULL;
        snprintf(paths[kind], sizeof paths[kind], "%s/model%d.nerf", tmpdir,
                 kind);
        if (nerf_model_create(&m, &mo) != NERF_OK ||
            nerf_model_save(m, paths[kind]) != NERF_OK) {
            printf("cannot make model %d: %s\n", kind, nerf_last_error());
            ready = 0;
        }
        nerf_model_destroy(m);
    }
    if (ready) {
        RUN(first_renders);
        RUN(soak);
        RUN(rss_sees_a_leak);
    } else {
        harness_failed = 1;
    }
    for (int kind = 0; kind < N_KINDS; kind++) {
        unlink(paths[kind]);
    }
    rmdir(tmpdir);
    HARNESS_EXIT();
}
