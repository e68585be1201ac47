/*
 * A run as nerf-train sets it up (lib/train/run_setup.c): the presets'
 * learning rates, the fastest fp32 products, a march set finer or back,
 * the sampler for a model and a dataset (forward-facing and all-round
 * scenes training in a coarser march), the trainer's settings for a
 * model, and the march a trainer records for rendering.  The programs'
 * agreement with these calls is examples/test-same-run.sh's.
 */
#include <math.h>
#include <string.h>

#include "train_fixture.h"

enum { SIDE = 16, IMAGES = 3 };

static fixture fx;

/* A fast-preset model with a small hash grid, in space: the options that
 * matter here are its encoding, space and marching, not its size. */
static nerf_model *small_fast_in(uint32_t space)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
    o.hash_levels = 4;
    o.hash_log2_size = 12;
    o.hash_max_resolution = 64;
    o.space = space;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    return m;
}

static nerf_model *small_fast(void)
{
    return small_fast_in(NERF_SPACE_BOX);
}

static double param(const nerf_model *m, int p)
{
    double v = -1.0;
    CHECK_OK(nerf_model_get_param(m, p, &v));
    return v;
}

TEST(preset_learning_rates)
{
    static const struct {
        int preset;
        double lr;
    } want[] = {{NERF_PRESET_REFERENCE, 5e-4},
                {NERF_PRESET_TINY, 5e-3},
                {NERF_PRESET_FAST, 1e-2}};
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        CHECK_OK(nerf_model_options_preset(&o, want[i].preset));
        CHECK(o.learning_rate == want[i].lr);
    }
    /* Applied at creation, the last rate a tenth of the first (computed
     * as nerf-train computes it, so exactly equal); the options then
     * report 0, the rate being a parameter. */
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_TINY));
    o.learning_rate = 2.5e-3;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m) {
        CHECK(param(m, NERF_PARAM_LEARNING_RATE) == 2.5e-3);
        CHECK(param(m, NERF_PARAM_LEARNING_RATE_FINAL) == 2.5e-3 / 10);
        nerf_model_options got;
        NERF_MODEL_OPTIONS_INIT(&got);
        CHECK_OK(nerf_model_get_options(m, &got));
        CHECK(got.learning_rate == 0.0);
    }
    nerf_model_destroy(m);
    /* 0: the model kind's, as before 0.12. */
    NERF_MODEL_OPTIONS_INIT(&o);
    m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m) {
        CHECK(param(m, NERF_PARAM_LEARNING_RATE) == 5e-4);
        CHECK(param(m, NERF_PARAM_LEARNING_RATE_FINAL) == 5e-5);
    }
    nerf_model_destroy(m);
}

TEST(bad_learning_rates_refused)
{
    const double bad[] = {-1e-3, 1.5, NAN, INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        o.learning_rate = bad[i];
        nerf_model *m = NULL;
        CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
        CHECK(m == NULL);
        CHECK(strstr(nerf_last_error(), "learning_rate") != NULL);
    }
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.reserved2 = 1;
    nerf_model *m = NULL;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "reserved2") != NULL);
}

TEST(fastest_products_chosen_and_recorded)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_TINY));
    o.matmul = NERF_MATMUL_FP32_FASTEST;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    nerf_model_options got;
    NERF_MODEL_OPTIONS_INIT(&got);
    if (m) {
        CHECK_OK(nerf_model_get_options(m, &got));
        CHECK_EQ_INT((int)got.matmul,
                     nerf_matmul_supported(NERF_MATMUL_FP32_ONEDNN)
                         ? NERF_MATMUL_FP32_ONEDNN
                         : NERF_MATMUL_FP32);
    }
    nerf_model_destroy(m);
    /* Hash-grid networks run fastest on the library's own kernels. */
    NERF_MODEL_OPTIONS_INIT(&o);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
    o.hash_levels = 2;
    o.hash_log2_size = 10;
    o.matmul = NERF_MATMUL_FP32_FASTEST;
    m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m) {
        CHECK_OK(nerf_model_get_options(m, &got));
        CHECK_EQ_INT((int)got.matmul, NERF_MATMUL_FP32);
    }
    nerf_model_destroy(m);
    o.matmul = NERF_MATMUL_FP32_FASTEST + 1;
    m = NULL;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
}

TEST(march_set_finer_and_back)
{
    nerf_sampler_options o;
    NERF_SAMPLER_OPTIONS_INIT(&o);
    CHECK_OK(nerf_sampler_options_preset(&o, NERF_PRESET_FAST));
    CHECK_EQ_INT((int)o.march_steps, 1024);
    CHECK_EQ_INT((int)o.max_samples, 1024);
    /* The cap is a distance in steps: 1280 steps reach as far in 1280. */
    CHECK_OK(nerf_sampler_options_set_march(&o, 1280));
    CHECK_EQ_INT((int)o.march_steps, 1280);
    CHECK_EQ_INT((int)o.max_samples, 1280);
    CHECK_OK(nerf_sampler_options_set_march(&o, 1024));
    CHECK_EQ_INT((int)o.max_samples, 1024);
    /* Within the sampler's range at both ends. */
    CHECK_OK(nerf_sampler_options_set_march(&o, 65536));
    CHECK_EQ_INT((int)o.max_samples, 65536);
    CHECK_OK(nerf_sampler_options_set_march(&o, 1));
    CHECK_EQ_INT((int)o.max_samples, 1);
    CHECK_EQ_INT(nerf_sampler_options_set_march(&o, 0), NERF_EINVAL);
    CHECK_EQ_INT(nerf_sampler_options_set_march(&o, 65537), NERF_EINVAL);
    CHECK_EQ_INT((int)o.march_steps, 1);
    /* Options that do not march are left as they are. */
    NERF_SAMPLER_OPTIONS_INIT(&o);
    CHECK_OK(nerf_sampler_options_set_march(&o, 1280));
    CHECK_EQ_INT((int)o.march_steps, 0);
    CHECK_EQ_INT(nerf_sampler_options_set_march(NULL, 1280), NERF_EINVAL);
}

TEST(trainer_options_for_a_model)
{
    nerf_model *fast = small_fast();
    nerf_model *tiny = tiny_model(0);
    nerf_trainer_options o;
    if (fast == NULL || tiny == NULL) {
        goto done;
    }
    NERF_TRAINER_OPTIONS_INIT(&o);
    CHECK_OK(nerf_trainer_options_for(&o, fast));
    CHECK_EQ_INT((int)o.batch_rays, 2048);
    CHECK_EQ_INT((int)o.batch_samples, 131072);
    CHECK_EQ_INT((int)o.precrop_steps, 0);
    CHECK_EQ_INT(o.random_background, 1);
    CHECK_EQ_INT((int)o.render_march_steps, 1280);
    CHECK(o.checkpoint_seconds == 0.0); /* no path: no timed saves */

    NERF_TRAINER_OPTIONS_INIT(&o);
    o.checkpoint_path = "model.nerf";
    CHECK_OK(nerf_trainer_options_for(&o, tiny));
    CHECK_EQ_INT((int)o.batch_rays, 1024);
    CHECK_EQ_INT((int)o.batch_samples, 0);
    CHECK_EQ_INT((int)o.precrop_steps, 500); /* the reference's */
    CHECK_EQ_INT(o.random_background, 0);
    CHECK_EQ_INT((int)o.render_march_steps, 0);
    CHECK(o.checkpoint_seconds == 120.0);
    /* Saves by steps, when asked for, stay the only ones. */
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.checkpoint_path = "model.nerf";
    o.checkpoint_every = 50;
    CHECK_OK(nerf_trainer_options_for(&o, tiny));
    CHECK(o.checkpoint_seconds == 0.0);
    CHECK_EQ_INT(nerf_trainer_options_for(NULL, tiny), NERF_EINVAL);
    CHECK_EQ_INT(nerf_trainer_options_for(&o, NULL), NERF_EINVAL);
done:
    nerf_model_destroy(fast);
    nerf_model_destroy(tiny);
}

/* A trainer records the march render_march_steps says, its cap scaled;
 * the model then trains on in the preset's march and renders in its own,
 * and keeps the batch it was trained at. */
TEST(render_march_recorded_and_sampler_for_each_use)
{
    nerf_model *m = small_fast();
    nerf_sampler *s = NULL;
    nerf_trainer *t = NULL;
    nerf_sampler_options so;
    nerf_trainer_options to;
    if (m == NULL) {
        goto done;
    }
    NERF_SAMPLER_OPTIONS_INIT(&so);
    so.seed = 77;
    CHECK_OK(nerf_sampler_options_for(&so, m, fx.train,
                                      NERF_SAMPLER_FOR_TRAINING));
    CHECK_EQ_INT((int)so.march_steps, 1024);
    CHECK(so.seed == 77); /* the caller's */
    float near = 0.0f, far = 0.0f;
    CHECK_OK(nerf_dataset_bounds(fx.train, &near, &far));
    CHECK(so.t_near == near && so.t_far == far);
    CHECK_OK(nerf_sampler_create(&s, &so));
    NERF_TRAINER_OPTIONS_INIT(&to);
    CHECK_OK(nerf_trainer_options_for(&to, m));
    to.batch_rays = 32;
    to.batch_samples = 0;
    to.render_march_steps = 65537;
    CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &to), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "render_march_steps") != NULL);
    to.render_march_steps = 1280;
    CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &to));
    if (t == NULL) {
        goto done;
    }
    CHECK_OK(nerf_trainer_step(t, NULL));

    nerf_sampler_options rec;
    NERF_SAMPLER_OPTIONS_INIT(&rec);
    CHECK_OK(nerf_model_render_settings(m, &rec, NULL));
    CHECK_EQ_INT((int)rec.march_steps, 1280);
    CHECK_EQ_INT((int)rec.max_samples, 1280);
    NERF_SAMPLER_OPTIONS_INIT(&so);
    CHECK_OK(nerf_sampler_options_for(&so, m, fx.test,
                                      NERF_SAMPLER_FOR_RENDERING));
    CHECK_EQ_INT((int)so.march_steps, 1280);
    CHECK_EQ_INT((int)so.max_samples, 1280);
    NERF_SAMPLER_OPTIONS_INIT(&so);
    CHECK_OK(nerf_sampler_options_for(&so, m, NULL,
                                      NERF_SAMPLER_FOR_TRAINING));
    CHECK_EQ_INT((int)so.march_steps, 1024);
    CHECK_EQ_INT((int)so.max_samples, 1024);
    CHECK(so.t_near == rec.t_near && so.t_far == rec.t_far);

    /* The batch the model records outranks its preset's. */
    NERF_TRAINER_OPTIONS_INIT(&to);
    CHECK_OK(nerf_trainer_options_for(&to, m));
    CHECK_EQ_INT((int)to.batch_rays, 32);
    CHECK_EQ_INT((int)to.batch_samples, 0);

    CHECK_EQ_INT(nerf_sampler_options_for(&so, m, NULL, 2), NERF_EINVAL);
    CHECK_EQ_INT(nerf_sampler_options_for(NULL, m, NULL, 0), NERF_EINVAL);
done:
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* Forward-facing and all-round scenes train in a quarter of the box's
 * march, its cap cut with it, and render in the march they record (or,
 * without a recording, in the fast preset's). */
TEST(open_spaces_train_in_a_coarser_march)
{
    static const struct {
        uint32_t space;
        int train_steps;
    } want[] = {{NERF_SPACE_BOX, 1024},
                {NERF_SPACE_NDC, 256},
                {NERF_SPACE_UNBOUNDED, 256}};
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        nerf_model *m = small_fast_in(want[i].space);
        if (m == NULL) {
            continue;
        }
        nerf_sampler_options so;
        NERF_SAMPLER_OPTIONS_INIT(&so);
        CHECK_OK(nerf_sampler_options_for(&so, m, NULL,
                                          NERF_SAMPLER_FOR_TRAINING));
        CHECK_EQ_INT((int)so.march_steps, want[i].train_steps);
        CHECK_EQ_INT((int)so.max_samples, want[i].train_steps);
        NERF_SAMPLER_OPTIONS_INIT(&so);
        CHECK_OK(nerf_sampler_options_for(&so, m, NULL,
                                          NERF_SAMPLER_FOR_RENDERING));
        CHECK_EQ_INT((int)so.march_steps, 1024);
        CHECK_EQ_INT((int)so.max_samples, 1024);
        nerf_model_destroy(m);
    }
}

TEST(sampler_for_a_preset_without_a_model)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    CHECK_OK(nerf_sampler_options_preset(&so, NERF_PRESET_TINY));
    CHECK_OK(nerf_sampler_options_for(&so, NULL, fx.train,
                                      NERF_SAMPLER_FOR_RENDERING));
    CHECK_EQ_INT((int)so.n_coarse, 32);
    CHECK_EQ_INT((int)so.n_fine, 64);
    CHECK_EQ_INT((int)so.ndc, 0);
    float near = 0.0f, far = 0.0f;
    CHECK_OK(nerf_dataset_bounds(fx.train, &near, &far));
    CHECK(so.t_near == near && so.t_far == far);
}

TEST(model_placed_in_the_dataset)
{
    uint32_t space = 99;
    float bound = 0.0f;
    CHECK_OK(nerf_dataset_space(fx.train, &space, &bound));
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
    o.bound = 7.0f;
    CHECK_OK(nerf_model_options_for_dataset(&o, fx.train));
    CHECK(o.space == space && o.bound == bound);
    /* The frequency encoding reads coordinates anywhere: nothing to
     * place. */
    NERF_MODEL_OPTIONS_INIT(&o);
    o.bound = 7.0f;
    CHECK_OK(nerf_model_options_for_dataset(&o, fx.train));
    CHECK(o.bound == 7.0f && o.space == NERF_SPACE_BOX);
    CHECK_EQ_INT(nerf_model_options_for_dataset(NULL, fx.train), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_options_for_dataset(&o, NULL), NERF_EINVAL);
}

int main(void)
{
    int rc = fixture_open(&fx, SIDE, IMAGES, 1);
    if (rc != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    RUN(preset_learning_rates);
    RUN(bad_learning_rates_refused);
    RUN(fastest_products_chosen_and_recorded);
    RUN(march_set_finer_and_back);
    RUN(trainer_options_for_a_model);
    RUN(render_march_recorded_and_sampler_for_each_use);
    RUN(open_spaces_train_in_a_coarser_march);
    RUN(sampler_for_a_preset_without_a_model);
    RUN(model_placed_in_the_dataset);
    fixture_close(&fx);
    HARNESS_EXIT();
}
