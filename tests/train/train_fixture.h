/*
 * Shared set-up of the training tests: the built-in scene written once to
 * a temporary folder, loaded, and a tiny model, sampler and trainer.
 */
#ifndef NERF_TEST_TRAIN_FIXTURE_H
#define NERF_TEST_TRAIN_FIXTURE_H

#include <stdlib.h>

#include "../data/data_fixtures.h"
#include "../harness.h"
#include "nerf.h"

typedef struct fixture {
    char dir[512];
    nerf_dataset *train;
    nerf_dataset *test;
} fixture;

/* An integer from the environment variable name, else fallback: the
 * tests' overrides for experiments (NERF_TEST_STEPS, ...). */
static inline int fixture_env_int(const char *name, int fallback)
{
    const char *v = getenv(name);
    return v ? atoi(v) : fallback;
}

/* The built-in scene's options at width x width, n_train training and
 * n_test test views, no validation views. */
static inline void fixture_scene_options(nerf_scene_options *so,
                                         uint32_t width, uint32_t n_train,
                                         uint32_t n_test)
{
    NERF_SCENE_OPTIONS_INIT(so);
    so->width = so->height = width;
    so->n_train = n_train;
    so->n_val = 0;
    so->n_test = n_test;
}

/* Write the built-in scene at width x width and load both splits. */
static inline int fixture_open(fixture *f, uint32_t width, uint32_t n_train,
                               uint32_t n_test)
{
    memset(f, 0, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "%s", fx_make_temp_dir());
    nerf_scene_options so;
    fixture_scene_options(&so, width, n_train, n_test);
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    int rc = nerf_scene_write(f->dir, &so);
    if (rc == NERF_OK) {
        rc = nerf_dataset_load(&f->train, f->dir, &dopt);
    }
    dopt.split = NERF_SPLIT_TEST;
    if (rc == NERF_OK && n_test > 0) {
        rc = nerf_dataset_load(&f->test, f->dir, &dopt);
    }
    return rc;
}

/* Mean PSNR of a renderer's images of the views of test; the renders go
 * to rgb[n_test][w h 3] when it is set. */
static inline double fixture_renderer_psnr(nerf_renderer *r,
                                           nerf_dataset *test, float *rgb)
{
    uint32_t w, h;
    nerf_dataset_image_size(test, &w, &h);
    const size_t px = (size_t)w * h;
    float *own = rgb ? NULL : malloc(px * 3 * sizeof(float));
    double sum = 0.0;
    uint32_t n = nerf_dataset_count(test);
    for (uint32_t i = 0; i < n; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        const float *truth;
        double p = 0.0;
        float *out = rgb ? rgb + i * px * 3 : own;
        CHECK_OK(nerf_dataset_camera(test, i, &cam));
        CHECK_OK(nerf_dataset_image(test, i, &truth));
        CHECK_OK(nerf_renderer_render_image(r, &cam, out, NULL, NULL, px));
        CHECK_OK(nerf_psnr(out, truth, px * 3, &p));
        sum += p;
    }
    free(own);
    return sum / n;
}

/* Mean PSNR of a model's renders (on white) of the views of test; -1 if
 * no renderer could be made. */
static inline double fixture_test_psnr(nerf_model *m, nerf_sampler *s,
                                       nerf_dataset *test)
{
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.white_background = 1;
    nerf_renderer *r = NULL;
    if (nerf_renderer_create(&r, m, s, &ro) != NERF_OK) {
        return -1.0;
    }
    double psnr = fixture_renderer_psnr(r, test, NULL);
    nerf_renderer_destroy(r);
    return psnr;
}

static inline void fixture_close(fixture *f)
{
    nerf_dataset_destroy(f->train);
    nerf_dataset_destroy(f->test);
    fx_remove_tree(f->dir);
}

/* The step of the checkpoint at path; -1 when none can be loaded. */
static inline int64_t fixture_saved_step(const char *path)
{
    nerf_model *saved = NULL;
    if (nerf_model_load(&saved, path, NULL) != NERF_OK) {
        return -1;
    }
    int64_t step = (int64_t)nerf_model_step(saved);
    nerf_model_destroy(saved);
    return step;
}

/*
 * The seed of the convergence tests' models and samplers: 0, or
 * NERF_TEST_SEED, with which a sweep over seeds measures the spread of
 * the PSNR a test reaches (a processor that rounds its products another
 * way sends training down another path, as another seed does, so the
 * thresholds sit well below that spread: docs/dispatch.md).
 */
static inline uint64_t fixture_seed(void)
{
    const char *v = getenv("NERF_TEST_SEED");
    return v ? strtoull(v, NULL, 10) : 0;
}

/* The fast preset with a smaller hash grid than its own (`levels` levels
 * of 2^log2_size entries, up to max_resolution cells across), as the
 * tests that train it take one to stay cheap; NULL on failure, said. */
static inline nerf_model *fixture_fast_model(uint64_t seed, uint32_t levels,
                                             uint32_t log2_size,
                                             uint32_t max_resolution)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_FAST);
    o.hash_levels = levels;
    o.hash_log2_size = log2_size;
    o.hash_max_resolution = max_resolution;
    o.seed = seed;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    return m;
}

/* The fast preset's marching sampler. */
static inline nerf_sampler *fixture_fast_sampler(uint64_t seed)
{
    nerf_sampler_options o;
    NERF_SAMPLER_OPTIONS_INIT(&o);
    CHECK_OK(nerf_sampler_options_preset(&o, NERF_PRESET_FAST));
    o.seed = seed;
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &o));
    return s;
}

static inline nerf_model *tiny_model(uint64_t seed)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    o.seed = seed;
    nerf_model *m = NULL;
    if (nerf_model_create(&m, &o) != NERF_OK) {
        printf("  nerf_model_create: %s\n", nerf_last_error());
    }
    return m;
}

static inline nerf_sampler *tiny_sampler(uint64_t seed)
{
    nerf_sampler_options o;
    NERF_SAMPLER_OPTIONS_INIT(&o);
    nerf_sampler_options_preset(&o, NERF_PRESET_TINY);
    o.seed = seed;
    nerf_sampler *s = NULL;
    if (nerf_sampler_create(&s, &o) != NERF_OK) {
        printf("  nerf_sampler_create: %s\n", nerf_last_error());
    }
    return s;
}

#endif
