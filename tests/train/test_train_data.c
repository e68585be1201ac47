/*
 * The trainer's records of its data and its batch: a model trained on one
 * dataset and trained on another warns (through the hooks, naming what
 * differs and both datasets), as does one trained on at another batch;
 * the same data and batch, a fresh model, or a checkpoint without a
 * record (older files) does not; and the records travel in checkpoints.
 */
#include <stdio.h>
#include <string.h>

#include "model.h"
#include "train_fixture.h"

static fixture a, b;
static char warnings[4096];
static int n_warnings;

static void keep_warnings(int level, const char *msg, void *user)
{
    (void)user;
    if (level == NERF_LOG_WARN) {
        n_warnings++;
        snprintf(warnings, sizeof warnings, "%s", msg);
    }
}

/* A trainer for m on ds at `rays` and `samples` a step (its warnings
 * counted afresh), made and dropped after a step: creating it is what
 * records and compares the data and the batch. */
static void train_batch(nerf_model *m, nerf_dataset *ds, uint32_t rays,
                        uint32_t samples)
{
    nerf_hooks h;
    NERF_HOOKS_INIT(&h);
    h.log_cb = keep_warnings;
    h.log_level = NERF_LOG_WARN;
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = rays;
    o.batch_samples = samples;
    o.hooks = &h;
    nerf_sampler *s = tiny_sampler(1);
    nerf_trainer *t = NULL;
    n_warnings = 0;
    warnings[0] = '\0';
    CHECK_OK(nerf_trainer_create(&t, m, ds, s, &o));
    if (t) {
        nerf_train_stats st;
        memset(&st, 0, sizeof st);
        st.struct_size = sizeof st;
        CHECK_OK(nerf_trainer_step(t, &st));
    }
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
}

static void train_on(nerf_model *m, nerf_dataset *ds)
{
    train_batch(m, ds, 32, 0);
}

static nerf_model *save_and_load(nerf_model *m)
{
    char path[600];
    snprintf(path, sizeof path, "%s/m.nerf", a.dir);
    CHECK_OK(nerf_model_save(m, path));
    nerf_model_destroy(m);
    nerf_model *back = NULL;
    CHECK_OK(nerf_model_load(&back, path, NULL));
    remove(path);
    return back;
}

TEST(recorded_and_saved)
{
    nerf_model *m = tiny_model(1);
    CHECK(m && !m->data.known);
    char said[256] = "x";
    CHECK_OK(nerf_model_training_data(m, said, sizeof said));
    CHECK_EQ_INT((int)strlen(said), 0);
    CHECK_EQ_INT(nerf_model_contents(m) & NERF_MODEL_HAS_DATA_RECORD, 0);
    train_on(m, a.train);
    CHECK_EQ_INT(n_warnings, 0);
    CHECK(m->data.known);
    CHECK_EQ_INT(nerf_model_contents(m) & NERF_MODEL_HAS_DATA_RECORD,
                 NERF_MODEL_HAS_DATA_RECORD);
    CHECK_OK(nerf_model_training_data(m, said, sizeof said));
    CHECK(strncmp(said, "4 images of 16x16 (blender", 26) == 0);
    CHECK_OK(nerf_model_training_data(m, said, 8)); /* truncated */
    CHECK_EQ_INT((int)strlen(said), 7);
    CHECK_EQ_INT(nerf_model_training_data(m, said, 0), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_training_data(NULL, said, 8), NERF_EINVAL);
    CHECK_EQ_INT(m->data.count, 4);
    CHECK_EQ_INT(m->data.width, 16);
    CHECK_EQ_INT(m->data.kind, NERF__FINGERPRINT_BLENDER);
    CHECK(m->data.mean_rgb[0] > 0.0f && m->data.mean_rgb[0] < 1.0f);
    m = save_and_load(m);
    CHECK(m && m->data.known && m->data.count == 4);
    /* Resumed on the same data: nothing to say. */
    train_on(m, a.train);
    CHECK_EQ_INT(n_warnings, 0);
    nerf_model_destroy(m);
}

TEST(other_data_warns)
{
    nerf_model *m = tiny_model(1);
    train_on(m, a.train);
    m = save_and_load(m);
    train_on(m, b.train);
    CHECK_EQ_INT(n_warnings, 1);
    printf("  %s\n", warnings);
    CHECK(strstr(warnings, "image count, image size") != NULL);
    CHECK(strstr(warnings, "trained on 4 images of 16x16 (blender") != NULL);
    CHECK(strstr(warnings, "this dataset has 6 of 24x24 (blender") != NULL);
    /* The model now records what it was trained on last. */
    CHECK_EQ_INT(m->data.count, 6);
    nerf_model_destroy(m);
}

TEST(no_record_no_warning)
{
    /* As a checkpoint written before the record existed. */
    nerf_model *m = save_and_load(tiny_model(1));
    CHECK(m && !m->data.known);
    train_on(m, b.train);
    CHECK_EQ_INT(n_warnings, 0);
    nerf_model_destroy(m);
}

static void check_batch(const nerf_model *m, uint32_t rays, uint32_t samples)
{
    uint32_t r = 7, s = 7;
    CHECK_OK(nerf_model_training_batch(m, &r, &s));
    CHECK_EQ_INT((int)r, (int)rays);
    CHECK_EQ_INT((int)s, (int)samples);
    CHECK_EQ_INT(nerf_model_contents(m) & NERF_MODEL_HAS_BATCH_RECORD,
                 rays > 0 ? NERF_MODEL_HAS_BATCH_RECORD : 0);
}

TEST(batch_recorded_and_saved)
{
    nerf_model *m = tiny_model(1);
    check_batch(m, 0, 0);
    uint32_t r = 0;
    CHECK_EQ_INT(nerf_model_training_batch(NULL, &r, &r), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_training_batch(m, NULL, &r), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_training_batch(m, &r, NULL), NERF_EINVAL);
    train_batch(m, a.train, 48, 300);
    CHECK_EQ_INT(n_warnings, 0);
    check_batch(m, 48, 300);
    m = save_and_load(m);
    check_batch(m, 48, 300);
    /* Resumed at the same batch: nothing to say. */
    train_batch(m, a.train, 48, 300);
    CHECK_EQ_INT(n_warnings, 0);
    nerf_model_destroy(m);
}

TEST(other_batch_warns)
{
    nerf_model *m = save_and_load(tiny_model(1));
    train_batch(m, a.train, 48, 0);
    m = save_and_load(m);
    train_batch(m, a.train, 32, 0);
    CHECK_EQ_INT(n_warnings, 1);
    printf("  %s\n", warnings);
    CHECK(strstr(warnings, "trained at 48 rays a step (batch_samples 0) "
                           "and this trainer takes 32 (batch_samples 0)") !=
          NULL);
    check_batch(m, 32, 0);
    /* The sample budget is part of the batch. */
    train_batch(m, a.train, 32, 500);
    CHECK_EQ_INT(n_warnings, 1);
    check_batch(m, 32, 500);
    nerf_model_destroy(m);
}

TEST(batch_no_record_no_warning)
{
    /* A model with steps from a checkpoint written before the record. */
    nerf_model *m = tiny_model(1);
    train_on(m, a.train);
    m->batch_rays = m->batch_samples = 0;
    m = save_and_load(m);
    check_batch(m, 0, 0);
    train_batch(m, a.train, 64, 0);
    CHECK_EQ_INT(n_warnings, 0);
    check_batch(m, 64, 0);
    nerf_model_destroy(m);
}

int main(void)
{
    if (fixture_open(&a, 16, 4, 0) != NERF_OK ||
        fixture_open(&b, 24, 6, 0) != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    RUN(recorded_and_saved);
    RUN(other_data_warns);
    RUN(no_record_no_warning);
    RUN(batch_recorded_and_saved);
    RUN(other_batch_warns);
    RUN(batch_no_record_no_warning);
    fixture_close(&a);
    fixture_close(&b);
    HARNESS_EXIT();
}
