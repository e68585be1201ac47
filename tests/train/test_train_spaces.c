/*
 * The fast preset in the scene spaces beyond the box, on the built-in
 * scene's forward-facing and all-round captures (opaque, with a ground and
 * a backdrop 40 units away):
 * - forward-facing (LLFF layout): the grids over NDC space, the rays
 *   warped and marched there; it learns the held-out views;
 * - all-round: the grids over contracted space fit the training views
 *   better than the same model confined to a box, which cannot hold the
 *   backdrop;
 * - models and samplers of different spaces refuse to pair.
 * Small images, a small hash grid and few steps: what is checked is that
 * each space trains, by margins far from the noise of a short run.
 *
 * NERF_TEST_STEPS, NERF_TEST_CURVE (print the test PSNR every that many
 * steps) and NERF_TEST_SEED override the settings for experiments.
 */
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "train_fixture.h"

#define STEPS 200
#define STEPS_UNBOUNDED 400
#define BATCH 128
#define LEARNING_RATE 1e-2
/*
 * Test PSNR the forward-facing capture reaches, and what the contracted
 * model must gain over the boxed one in fitting the all-round capture's
 * training views.  A processor that rounds its products otherwise sends
 * training down another path, as another seed does, so the thresholds
 * sit below the spread over seeds: NERF_TEST_SEED=0..12 (2026-12, Intel
 * Xeon, 0.11.0) gave 17.95 to 19.59 dB forward-facing (mean 18.9, sd
 * 0.45, so mean - 4 sd 17.1), and a gain of 3.9 to 8.2 dB in 400 steps
 * (mean 6.2, sd 1.4).  In 200 steps the gain went down to 0.3 dB, and the
 * contracted model's test PSNR (14.7 to 22.2 dB in 400 steps) fell below
 * the boxed one's for 3 of the 13 seeds: held-out views of so small a
 * capture say little, so they are printed, not compared.
 */
#define MIN_PSNR_FORWARD 16.5
#define MIN_GAIN_UNBOUNDED 1.0
/* Steps across the grid's diagonal: a quarter of the preset's, which
 * images of 40 pixels do not miss, and a quarter of the samples. */
#define MARCH_STEPS 256

/* The capture written and both splits loaded. */
static int open_capture(fixture *f, uint32_t capture, uint32_t layout,
                        uint32_t w, uint32_t h, uint32_t n_train,
                        uint32_t n_test)
{
    memset(f, 0, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "%s", fx_make_temp_dir());
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = w;
    so.height = h;
    so.n_train = n_train;
    so.n_val = 0;
    so.n_test = n_test;
    so.capture = capture;
    so.layout = layout;
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    int rc = nerf_scene_write(f->dir, &so);
    if (rc == NERF_OK) {
        rc = nerf_dataset_load(&f->train, f->dir, &dopt);
    }
    dopt.split = NERF_SPLIT_TEST;
    if (rc == NERF_OK) {
        rc = nerf_dataset_load(&f->test, f->dir, &dopt);
    }
    return rc;
}

static nerf_model *space_model(uint32_t space, float bound)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_FAST);
    o.hash_log2_size = 15;
    o.hash_levels = 8;
    o.hash_max_resolution = 256;
    o.space = space;
    o.bound = bound;
    o.seed = fixture_seed();
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    return m;
}

/* A marching sampler: NDC with the frustum of the dataset's first
 * camera, or world rays from near to far. */
static nerf_sampler *space_sampler(const nerf_dataset *ds, bool ndc,
                                   float near, float far)
{
    nerf_sampler_options o;
    NERF_SAMPLER_OPTIONS_INIT(&o);
    CHECK_OK(nerf_sampler_options_preset(&o, NERF_PRESET_FAST));
    o.seed = fixture_seed();
    o.march_steps = MARCH_STEPS;
    o.t_near = near;
    o.t_far = far;
    if (ndc) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(ds, 0, &cam));
        o.ndc = 1;
        o.ndc_focal = cam.fx;
        o.ndc_width = cam.width;
        o.ndc_height = cam.height;
    }
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &o));
    return s;
}

/* Train m for the test's steps; returns the test PSNR after, and the
 * PSNR of renders of the training views in *train_psnr. */
static double train(nerf_model *m, nerf_sampler *s, const fixture *f,
                    const char *what, int default_steps, double *train_psnr)
{
    *train_psnr = -1.0;
    const int steps = fixture_env_int("NERF_TEST_STEPS", default_steps);
    const int curve = fixture_env_int("NERF_TEST_CURVE", 0);
    if (m == NULL || s == NULL) {
        return -1.0;
    }
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE,
                                  LEARNING_RATE));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE_FINAL,
                                  LEARNING_RATE / 10));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, steps));
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = BATCH;
    o.precrop_steps = 0;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, f->train, s, &o));
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    nerf_renderer *r = NULL;
    CHECK_OK(nerf_renderer_create(&r, m, s, &ro));
    if (t == NULL || r == NULL) {
        nerf_trainer_destroy(t);
        nerf_renderer_destroy(r);
        return -1.0;
    }
    const double before = fixture_renderer_psnr(r, f->test, NULL);
    nerf_train_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    double spr = 0.0;
    for (int i = 1; i <= steps; i++) {
        CHECK_OK(nerf_trainer_step(t, &st));
        spr += st.samples_per_ray;
        if (curve > 0 && i % curve == 0) {
            printf("  %s step %d: train %.2f, test %.2f dB, %.1f samples "
                   "per ray\n", what, i, st.psnr,
                   fixture_renderer_psnr(r, f->test, NULL),
                   st.samples_per_ray);
        }
    }
    const double after = fixture_renderer_psnr(r, f->test, NULL);
    *train_psnr = fixture_renderer_psnr(r, f->train, NULL);
    printf("  %s: %d steps, %.1f samples per ray, PSNR on the training "
           "views %.2f, test PSNR %.2f dB (untrained %.2f)\n", what, steps,
           spr / steps, *train_psnr, after, before);
    nerf_trainer_destroy(t);
    nerf_renderer_destroy(r);
    return after;
}

TEST(forward_facing_trains_in_ndc)
{
    fixture f;
    CHECK_OK(open_capture(&f, NERF_SCENE_CAPTURE_FORWARD,
                          NERF_SCENE_LAYOUT_LLFF, 40, 30, 28, 4));
    if (f.train == NULL || f.test == NULL) {
        fixture_close(&f);
        return;
    }
    uint32_t space = 99;
    float bound = 0.0f;
    CHECK_OK(nerf_dataset_space(f.train, &space, &bound));
    CHECK_EQ_INT(space, NERF_SPACE_NDC);
    nerf_model *m = space_model(space, bound);
    nerf_sampler *s = space_sampler(f.train, true, 0.0f, 1.0f);
    double fit;
    const double psnr = train(m, s, &f, "forward-facing, NDC", STEPS, &fit);
    CHECK(psnr >= MIN_PSNR_FORWARD);

    /* NDC rays into a box model's grid, or world rays into an NDC
     * model's, are refused by name. */
    nerf_model *box = space_model(NERF_SPACE_BOX, 1.5f);
    nerf_sampler *world = space_sampler(f.train, false, 0.5f, 6.0f);
    nerf_trainer *t = NULL;
    nerf_renderer *r = NULL;
    CHECK_EQ_INT(nerf_trainer_create(&t, box, f.train, s, NULL),
                 NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "NDC") != NULL);
    CHECK_EQ_INT(nerf_renderer_create(&r, m, world, NULL), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "ndc = 1") != NULL);
    nerf_model_destroy(box);
    nerf_sampler_destroy(world);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
    fixture_close(&f);
}

TEST(all_round_trains_better_contracted_than_boxed)
{
    fixture f;
    CHECK_OK(open_capture(&f, NERF_SCENE_CAPTURE_UNBOUNDED,
                          NERF_SCENE_LAYOUT_BLENDER, 32, 24, 60, 4));
    if (f.train == NULL || f.test == NULL) {
        fixture_close(&f);
        return;
    }
    /* aabb_scale 16 in its transforms files says: unbounded. */
    uint32_t space = 99;
    float bound = 0.0f, near = 0.0f, far = 0.0f;
    CHECK_OK(nerf_dataset_space(f.train, &space, &bound));
    CHECK_EQ_INT(space, NERF_SPACE_UNBOUNDED);
    CHECK(bound == 1.5f);
    CHECK_OK(nerf_dataset_bounds(f.train, &near, &far));
    CHECK(near < 0.1f && far > 1e3f);
    /* The backdrop is 40 units away; the cameras 2.2 to 3 from the
     * centre.  The boxed model gets the Blender scenes' bound and rays
     * through it; the contracted one rays to far beyond the backdrop. */
    nerf_model *unb = space_model(NERF_SPACE_UNBOUNDED, 1.5f);
    nerf_sampler *s_unb = space_sampler(f.train, false, 0.1f, 1e4f);
    double fit_unb, fit_box;
    const double p_unb = train(unb, s_unb, &f, "all-round, contracted",
                               STEPS_UNBOUNDED, &fit_unb);
    nerf_model *box = space_model(NERF_SPACE_BOX, 1.5f);
    nerf_sampler *s_box = space_sampler(f.train, false, 0.1f, 1e4f);
    const double p_box = train(box, s_box, &f, "all-round, boxed",
                               STEPS_UNBOUNDED, &fit_box);
    /* The box's fit of the views it was shown is what the backdrop
     * limits. */
    printf("  contracted against boxed: %+.2f dB on the training views, "
           "%+.2f on the test views\n", fit_unb - fit_box, p_unb - p_box);
    CHECK(fit_unb >= fit_box + MIN_GAIN_UNBOUNDED);
    /* Contracted models march world rays only. */
    nerf_sampler *ndc = space_sampler(f.train, true, 0.0f, 1.0f);
    nerf_renderer *r = NULL;
    CHECK_EQ_INT(nerf_renderer_create(&r, unb, ndc, NULL), NERF_EINVAL);
    nerf_sampler_destroy(ndc);
    nerf_model_destroy(unb);
    nerf_model_destroy(box);
    nerf_sampler_destroy(s_unb);
    nerf_sampler_destroy(s_box);
    fixture_close(&f);
}

/* A COLMAP model is unbounded too: its cameras fill the unit cube. */
TEST(colmap_models_are_unbounded)
{
    fixture f;
    memset(&f, 0, sizeof f);
    snprintf(f.dir, sizeof f.dir, "%s", fx_make_temp_dir());
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = 16;
    so.height = 12;
    so.n_train = 8;
    so.n_val = 0;
    so.n_test = 1;
    so.capture = NERF_SCENE_CAPTURE_UNBOUNDED;
    so.layout = NERF_SCENE_LAYOUT_COLMAP_TEXT;
    CHECK_OK(nerf_scene_write(f.dir, &so));
    CHECK_OK(nerf_dataset_load(&f.train, f.dir, NULL));
    uint32_t space = 99;
    float bound = 0.0f;
    if (f.train) {
        CHECK_OK(nerf_dataset_space(f.train, &space, &bound));
        CHECK_EQ_INT(space, NERF_SPACE_UNBOUNDED);
        CHECK(bound == 1.0f);
        /* Every camera inside the central cube. */
        for (uint32_t i = 0; i < nerf_dataset_count(f.train); i++) {
            nerf_camera cam;
            NERF_CAMERA_INIT(&cam);
            CHECK_OK(nerf_dataset_camera(f.train, i, &cam));
            for (int a = 0; a < 3; a++) {
                CHECK(fabsf(cam.c2w[4 * a + 3]) <= bound);
            }
        }
    }
    fixture_close(&f);
}

int main(void)
{
    RUN(forward_facing_trains_in_ndc);
    RUN(all_round_trains_better_contracted_than_boxed);
    RUN(colmap_models_are_unbounded);
    HARNESS_EXIT();
}
