/*
 * The trainer's record of its data: a model trained on one dataset and
 * trained on another warns (through the hooks, naming what differs and
 * both datasets); the same data, a fresh model, or a checkpoint without a
 * record (older files) does not; and the record travels in checkpoints.
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

/* A trainer for m on ds (its warnings counted afresh), made and dropped:
 * creating it is what records and compares the data. */
static void train_on(nerf_model *m, nerf_dataset *ds)
{
    nerf_hooks h;
    NERF_HOOKS_INIT(&h);
    h.log_cb = keep_warnings;
    h.log_level = NERF_LOG_WARN;
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 32;
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
    fixture_close(&a);
    fixture_close(&b);
    HARNESS_EXIT();
}
