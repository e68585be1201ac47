/*
 * Masks in training: the trainer never draws a masked pixel, its draws
 * depend only on the seed and the step, and on the built-in scene with a
 * moving occluder painted into half the training views, training with the
 * masks scores as training on the capture without the occluder, and
 * training without them clearly worse.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dataset.h"
#include "model.h"
#include "train_fixture.h"
#include "trainer.h"

/*
 * The fast preset with test_train_fast's smaller hash grid, on a 48x48
 * scene, as there.  NERF_TEST_STEPS, NERF_TEST_WIDTH and NERF_TEST_SEED
 * override the settings for experiments.
 */
#define WIDTH 48
#define N_TRAIN 60
#define N_TEST 8
#define STEPS 400
#define BATCH 256
#define PRECROP 50
#define LEARNING_RATE 1e-2

/*
 * Two claims, each with its own check.
 *
 * The occluder has no influence at all: trained with the masks, the
 * occluded capture trains exactly as the clean capture given the same
 * masks, step for step and bit for bit, because no ray is ever drawn at a
 * masked pixel and every other pixel holds the clean capture's colour.
 * That holds on any machine by construction, so the check is equality.
 *
 * Masks recover what the occluder costs: trained without them, the
 * occluded capture scores far below the clean one (the model paints the
 * magenta discs into the scene: -3.31 dB from seed 0 and -3.42 dB from
 * seed 1 at these settings), and WORSE_DB sits well below that.  Trained
 * with them, it scores near the clean capture trained on every pixel, but
 * not within a fixed bound at a test's budget: the masks take 6% of the
 * training pixels away, and at this size losing them costs about 0.5 dB
 * on average, as losing as many pixels at random does, with any change
 * of a run's rays moving its test PSNR by about what another seed does
 * (sd 0.8 dB over seeds at 400 steps, test_train_fast.c; seeds 0 and 1
 * gave -0.84 and -0.50 dB here).  bench/bench_captures.c measures it
 * over seeds and on a larger capture, where the masked runs came within
 * 0.1 dB of the clean one or above it
 * (docs/api-notes.md, "Masks").  So the test prints the figure and checks
 * only that the masked run is nearer the clean capture than the unmasked
 * one.
 */
#define WORSE_DB 1.5
#define EXACT_STEPS 60

static char clean_dir[512], occluded_dir[512];
static nerf_dataset *clean_train, *masked_train, *unmasked_train, *test;

static int write_scene(char *dir, size_t cap, uint32_t occluders)
{
    snprintf(dir, cap, "%s", fx_make_temp_dir());
    nerf_scene_options so;
    fixture_scene_options(&so,
                          (uint32_t)fixture_env_int("NERF_TEST_WIDTH", WIDTH),
                          N_TRAIN, N_TEST);
    so.occluders = occluders;
    return nerf_scene_write(dir, &so);
}

static nerf_dataset *load(const char *dir, uint32_t split, uint32_t ignore)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = split;
    o.ignore_masks = ignore;
    nerf_dataset *ds = NULL;
    if (nerf_dataset_load(&ds, dir, &o) != NERF_OK) {
        printf("  %s: %s\n", dir, nerf_last_error());
    }
    return ds;
}

static nerf_trainer *make_trainer(nerf_model *m, nerf_sampler *s,
                                  const nerf_dataset *ds)
{
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = BATCH;
    o.precrop_steps = PRECROP;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, ds, s, &o));
    return t;
}

/* The loaders read the masks as the scene writer wrote them. */
TEST(datasets_say_whether_they_have_masks)
{
    uint32_t w, h;
    const uint8_t *mask = (const uint8_t *)"x";
    CHECK(!nerf_dataset_has_masks(clean_train));
    CHECK_OK(nerf_dataset_mask(clean_train, 0, &mask));
    CHECK(mask == NULL);
    CHECK(!nerf_dataset_has_masks(unmasked_train));
    CHECK(nerf_dataset_has_masks(masked_train));
    CHECK(!nerf_dataset_has_masks(test));
    CHECK(nerf_dataset_mask(masked_train, N_TRAIN, &mask) == NERF_EINVAL);
    CHECK(nerf_dataset_mask(masked_train, 0, NULL) == NERF_EINVAL);
    nerf_dataset_image_size(masked_train, &w, &h);
    const size_t px = (size_t)w * h;
    for (uint32_t i = 0; i < 4; i++) {
        const float *rgb, *clean;
        CHECK_OK(nerf_dataset_mask(masked_train, i, &mask));
        CHECK_OK(nerf_dataset_image(masked_train, i, &rgb));
        CHECK_OK(nerf_dataset_image(clean_train, i, &clean));
        size_t dropped = 0, differ = 0, differ_kept = 0;
        for (size_t p = 0; p < px; p++) {
            bool same = memcmp(rgb + 3 * p, clean + 3 * p,
                               3 * sizeof *rgb) == 0;
            dropped += mask[p] == 0;
            differ += !same;
            differ_kept += !same && mask[p] != 0;
        }
        /* Even views carry the disc (an eighth of the picture), odd ones
         * nothing; a kept pixel is the clean capture's. */
        if (i % 2 == 0) {
            CHECK(dropped > px / 10 && dropped < px / 6);
            CHECK(differ > 0);
        } else {
            CHECK(dropped == 0);
        }
        CHECK(differ_kept == 0);
    }
}

/* Over many steps (precrop ones too), no ray of the trainer is drawn at a
 * masked pixel, and a step's draws depend only on the step: a trainer
 * created afresh (as on resume) draws the same rays. */
TEST(the_trainer_never_draws_a_masked_pixel)
{
    nerf_model *m = fixture_fast_model(fixture_seed(), 8, 15, 256);
    nerf_sampler *s = fixture_fast_sampler(fixture_seed());
    nerf_trainer *a = make_trainer(m, s, masked_train);
    nerf_trainer *b = make_trainer(m, s, masked_train);
    if (a == NULL || b == NULL) {
        FAILF("no trainer");
        return;
    }
    size_t masked = 0, redrawn_same = 0;
    for (uint64_t step = 0; step < 200; step++) {
        nerf__trainer_pick_rays(a, step);
        nerf__trainer_pick_rays(b, 199 - step);
        for (uint32_t r = 0; r < BATCH; r++) {
            masked += masked_train->mask[a->picked[r]] == 0;
        }
    }
    for (uint64_t step = 0; step < 200; step++) {
        size_t keep[BATCH];
        nerf__trainer_pick_rays(a, step);
        memcpy(keep, a->picked, sizeof keep);
        nerf__trainer_pick_rays(b, step);
        redrawn_same += memcmp(keep, b->picked, sizeof keep) == 0;
    }
    printf("  %zu of %d rays at masked pixels; %zu of 200 steps drawn "
           "alike by two trainers\n", masked, 200 * BATCH, redrawn_same);
    CHECK(masked == 0);
    CHECK(redrawn_same == 200);
    nerf_trainer_destroy(a);
    nerf_trainer_destroy(b);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* Train a fresh model from the test's seed on train for steps steps;
 * each step's train PSNR into curve (when set); the test PSNR. */
static void train_steps(nerf_model *m, nerf_sampler *s,
                        const nerf_dataset *ds, int steps)
{
    nerf_trainer *t = make_trainer(m, s, ds);
    for (int i = 0; t && i < steps; i++) {
        CHECK_OK(nerf_trainer_step(t, NULL));
    }
    nerf_trainer_destroy(t);
}

/* With masks, a run saved at step 10 and resumed is bit for bit the
 * unbroken run: the masked rays' redraws are keyed by the step too. */
TEST(a_masked_run_resumes_bit_for_bit)
{
    char path[600];
    snprintf(path, sizeof path, "%s/resume.nerf", occluded_dir);
    nerf_sampler *s = fixture_fast_sampler(fixture_seed());
    nerf_model *whole = fixture_fast_model(fixture_seed(), 8, 15, 256);
    nerf_model *first = fixture_fast_model(fixture_seed(), 8, 15, 256);
    if (!whole || !first || !s) {
        return;
    }
    train_steps(whole, s, masked_train, 20);
    train_steps(first, s, masked_train, 10);
    CHECK_OK(nerf_model_save(first, path));
    nerf_model *resumed = NULL;
    CHECK_OK(nerf_model_load(&resumed, path, NULL));
    if (resumed) {
        train_steps(resumed, s, masked_train, 10);
        CHECK_EQ_INT(nerf_model_step(resumed), 20);
        CHECK(memcmp(whole->params, resumed->params,
                     whole->n_params * sizeof(float)) == 0);
        CHECK(memcmp(whole->adam_v, resumed->adam_v,
                     whole->n_params * sizeof(float)) == 0);
    }
    nerf_model_destroy(resumed);
    nerf_model_destroy(first);
    nerf_model_destroy(whole);
    nerf_sampler_destroy(s);
}

static double train_and_score(const nerf_dataset *train, int steps,
                              double *curve)
{
    nerf_model *m = fixture_fast_model(fixture_seed(), 8, 15, 256);
    nerf_sampler *s = fixture_fast_sampler(fixture_seed());
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE,
                                  LEARNING_RATE));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE_FINAL,
                                  LEARNING_RATE / 10));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, steps));
    nerf_trainer *t = make_trainer(m, s, train);
    nerf_train_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    for (int i = 0; t && i < steps; i++) {
        CHECK_OK(nerf_trainer_step(t, &st));
        if (curve != NULL) {
            curve[i] = st.psnr;
        }
    }
    double psnr = fixture_test_psnr(m, s, test);
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    return psnr;
}

/* The clean capture's training split with the occluded one's masks. */
static nerf_dataset *clean_with_masks(void)
{
    nerf_dataset *ds = load(clean_dir, NERF_SPLIT_TRAIN, 0);
    if (ds == NULL) {
        return NULL;
    }
    size_t n = (size_t)ds->count * ds->width * ds->height;
    ds->mask = nerf__alloc(&ds->env, n);
    if (ds->mask != NULL) {
        memcpy(ds->mask, masked_train->mask, n);
    }
    return ds;
}

TEST(the_occluder_has_no_influence_with_masks)
{
    nerf_dataset *clean_masked = clean_with_masks();
    if (clean_masked == NULL || clean_masked->mask == NULL) {
        FAILF("no dataset");
        nerf_dataset_destroy(clean_masked);
        return;
    }
    double a[EXACT_STEPS], b[EXACT_STEPS];
    double pa = train_and_score(masked_train, EXACT_STEPS, a);
    double pb = train_and_score(clean_masked, EXACT_STEPS, b);
    printf("  %d steps: occluded with masks %.4f dB, clean with the same "
           "masks %.4f dB\n", EXACT_STEPS, pa, pb);
    CHECK(memcmp(a, b, sizeof a) == 0);
    CHECK(pa == pb);
    nerf_dataset_destroy(clean_masked);
}

TEST(masks_recover_what_the_occluder_costs)
{
    const int steps = fixture_env_int("NERF_TEST_STEPS", STEPS);
    double clean = train_and_score(clean_train, steps, NULL);
    double masked = train_and_score(masked_train, steps, NULL);
    double unmasked = train_and_score(unmasked_train, steps, NULL);
    printf("  %d steps, test PSNR: clean capture %.2f dB; occluded with "
           "masks %.2f (%+.2f); without masks %.2f (%+.2f)\n", steps, clean,
           masked, masked - clean, unmasked, unmasked - clean);
    CHECK(unmasked < clean - WORSE_DB);
    CHECK(fabs(masked - clean) < clean - unmasked);
}

int main(void)
{
    int rc = write_scene(clean_dir, sizeof clean_dir, 0);
    if (rc == NERF_OK) {
        rc = write_scene(occluded_dir, sizeof occluded_dir, 1);
    }
    if (rc != NERF_OK) {
        printf("scene: %s\n", nerf_last_error());
        return 1;
    }
    clean_train = load(clean_dir, NERF_SPLIT_TRAIN, 0);
    masked_train = load(occluded_dir, NERF_SPLIT_TRAIN, 0);
    unmasked_train = load(occluded_dir, NERF_SPLIT_TRAIN, 1);
    test = load(clean_dir, NERF_SPLIT_TEST, 0);
    if (!clean_train || !masked_train || !unmasked_train || !test) {
        return 1;
    }
    RUN(datasets_say_whether_they_have_masks);
    RUN(the_trainer_never_draws_a_masked_pixel);
    RUN(a_masked_run_resumes_bit_for_bit);
    RUN(the_occluder_has_no_influence_with_masks);
    /* NERF_TEST_QUICK: the sanitizer run (scripts/test.sh). */
    if (!getenv("NERF_TEST_SKIP_TRAINING") && !getenv("NERF_TEST_QUICK")) {
        RUN(masks_recover_what_the_occluder_costs);
    }
    nerf_dataset_destroy(clean_train);
    nerf_dataset_destroy(masked_train);
    nerf_dataset_destroy(unmasked_train);
    nerf_dataset_destroy(test);
    fx_remove_tree(clean_dir);
    fx_remove_tree(occluded_dir);
    HARNESS_EXIT();
}
