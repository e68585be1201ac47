/* The trainer: determinism, exact resume, checkpoints, cancellation and
 * allocation failures. */
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../fail_alloc.h"
#include "model.h"
#include "occupancy.h"
#include "train_fixture.h"
#include "trainer.h"

static fixture fx;

static nerf_trainer *make_trainer(nerf_model *m, nerf_sampler *s,
                                  uint32_t batch, const nerf_hooks *hooks)
{
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = batch;
    o.precrop_steps = 2; /* so that both kinds of step run */
    o.hooks = hooks;
    nerf_trainer *t = NULL;
    int rc = nerf_trainer_create(&t, m, fx.train, s, &o);
    if (rc != NERF_OK && rc != NERF_ENOMEM) {
        printf("  nerf_trainer_create: %s\n", nerf_last_error());
    }
    return t;
}

static void check_grids(const nerf__occupancy *a, const nerf__occupancy *b)
{
    CHECK(a->updates == b->updates);
    CHECK(memcmp(a->ema, b->ema, a->cells * sizeof(float)) == 0);
    CHECK(memcmp(a->bits, b->bits, a->words * sizeof(uint64_t)) == 0);
}

static void train(nerf_model *m, nerf_sampler *s, int steps)
{
    nerf_trainer *t = make_trainer(m, s, 64, NULL);
    CHECK(t != NULL);
    for (int i = 0; t && i < steps; i++) {
        nerf_train_stats st;
        st.struct_size = sizeof st;
        CHECK_OK(nerf_trainer_step(t, &st));
        CHECK(st.step == nerf_model_step(m));
        CHECK(st.loss > 0.0 && st.psnr > 0.0);
    }
    nerf_trainer_destroy(t);
}

TEST(same_seed_same_weights)
{
    nerf_sampler *s = tiny_sampler(3);
    nerf_model *a = tiny_model(1), *b = tiny_model(1);
    train(a, s, 4);
    train(b, s, 4);
    CHECK(memcmp(a->params, b->params, a->n_params * sizeof(float)) == 0);
    CHECK(memcmp(a->adam_v, b->adam_v, a->n_params * sizeof(float)) == 0);
    nerf_model *c = tiny_model(2);
    train(c, s, 4);
    CHECK(memcmp(a->params, c->params, a->n_params * sizeof(float)) != 0);
    nerf_model_destroy(a);
    nerf_model_destroy(b);
    nerf_model_destroy(c);
    nerf_sampler_destroy(s);
}

TEST(resume_is_bit_identical)
{
    char path[600];
    snprintf(path, sizeof path, "%s/resume.nerf", fx.dir);
    nerf_sampler *s = tiny_sampler(5);
    nerf_model *whole = tiny_model(9), *first = tiny_model(9);
    train(whole, s, 6);
    train(first, s, 3);
    CHECK_OK(nerf_model_save(first, path));
    nerf_model_destroy(first);
    nerf_model *resumed = NULL;
    CHECK_OK(nerf_model_load(&resumed, path, NULL));
    if (resumed) {
        CHECK_EQ_INT(nerf_model_step(resumed), 3);
        train(resumed, s, 3);
        CHECK_EQ_INT(nerf_model_step(resumed), 6);
        CHECK(memcmp(whole->params, resumed->params,
                     whole->n_params * sizeof(float)) == 0);
        CHECK(memcmp(whole->adam_m, resumed->adam_m,
                     whole->n_params * sizeof(float)) == 0);
    }
    nerf_model_destroy(resumed);
    nerf_model_destroy(whole);
    nerf_sampler_destroy(s);
}

static void train_fast(nerf_model *m, nerf_sampler *s, int steps)
{
    nerf_trainer *t = make_trainer(m, s, 32, NULL);
    CHECK(t != NULL);
    for (int i = 0; t && i < steps; i++) {
        nerf_train_stats st;
        st.struct_size = sizeof st;
        CHECK_OK(nerf_trainer_step(t, &st));
        CHECK(st.samples_per_ray > 0.0 && st.samples_per_ray <= 1024.0);
    }
    nerf_trainer_destroy(t);
}

/*
 * Marching: the occupancy grid is training state too.  Steps 0 and 16
 * update it, so a run cut at step 10 resumes with the grid of the first
 * update (restored from the checkpoint, bits rebuilt from the EMA) and
 * must then march, update and train exactly as the unbroken run.
 */
TEST(fast_resume_is_bit_identical)
{
    char path[600];
    snprintf(path, sizeof path, "%s/fast.nerf", fx.dir);
    nerf_sampler *s = fixture_fast_sampler(5);
    nerf_model *whole = fixture_fast_model(9, 4, 12, 64);
    nerf_model *first = fixture_fast_model(9, 4, 12, 64);
    if (!whole || !first || !s) {
        return;
    }
    train_fast(whole, s, 20);
    CHECK_EQ_INT(whole->grid->updates, 2);
    CHECK(whole->grid->occupied < whole->grid->cells);
    train_fast(first, s, 10);
    CHECK_OK(nerf_model_save(first, path));
    nerf_model *resumed = NULL;
    CHECK_OK(nerf_model_load(&resumed, path, NULL));
    if (resumed) {
        check_grids(resumed->grid, first->grid);
        train_fast(resumed, s, 10);
        CHECK_EQ_INT(nerf_model_step(resumed), 20);
        CHECK(memcmp(whole->params, resumed->params,
                     whole->n_params * sizeof(float)) == 0);
        CHECK(memcmp(whole->adam_v, resumed->adam_v,
                     whole->n_params * sizeof(float)) == 0);
        check_grids(resumed->grid, whole->grid);
    }
    /* A new trainer on the same model continues the same way too. */
    train_fast(first, s, 10);
    CHECK(memcmp(whole->params, first->params,
                 whole->n_params * sizeof(float)) == 0);
    nerf_model_destroy(resumed);
    nerf_model_destroy(first);
    nerf_model_destroy(whole);
    nerf_sampler_destroy(s);
}

/* Grid updates every 16 steps through the warm-up, every 32 after. */
TEST(grid_schedule)
{
    int due = 0;
    for (uint64_t k = 0; k < 1024; k++) {
        due += nerf__grid_due(k);
    }
    CHECK_EQ_INT(due, 256 / 16 + (1024 - 256) / 32);
    CHECK(nerf__grid_due(0) && nerf__grid_due(240) && nerf__grid_due(256));
    CHECK(!nerf__grid_due(272) && nerf__grid_due(288));
    CHECK(!nerf__grid_due(1u << 20 | 16) && nerf__grid_due(1u << 20));
}

TEST(marching_needs_a_grid)
{
    nerf_sampler *s = fixture_fast_sampler(1);
    nerf_model *m = tiny_model(1);
    nerf_trainer *t = NULL;
    CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, NULL), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "occupancy grid") != NULL);
    CHECK(t == NULL);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

static int stop_after_two(const nerf_progress *p, void *user)
{
    int *calls = user;
    ++*calls;
    if (p->kind != NERF_PROGRESS_TRAIN || p->total != 10 || !(p->loss > 0.0)) {
        return -100; /* marks a bad report: the test sees calls stop */
    }
    return p->done >= 2;
}

TEST(run_progress_cancel_and_checkpoints)
{
    char path[600];
    snprintf(path, sizeof path, "%s/run.nerf", fx.dir);
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(4);
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 32;
    o.checkpoint_every = 1;
    o.checkpoint_path = path;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &o));
    int calls = 0;
    CHECK_OK(nerf_trainer_set_progress(t, stop_after_two, &calls));
    nerf_train_stats st;
    st.struct_size = sizeof st;
    CHECK_EQ_INT(nerf_trainer_run(t, 10, &st), NERF_ECANCELLED);
    CHECK_EQ_INT(calls, 2);
    CHECK_EQ_INT(st.step, 2);
    CHECK_EQ_INT(fixture_saved_step(path), 2);
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/* What the checkpoint at a path held after each step: its step, or -1
 * when there was none yet. */
typedef struct saves_seen {
    const char *path;
    int64_t at[4];
    int calls;
} saves_seen;

static int note_saved_step(const nerf_progress *p, void *user)
{
    (void)p;
    saves_seen *w = user;
    if (w->calls < 4) {
        w->at[w->calls] = fixture_saved_step(w->path);
    }
    w->calls++;
    return 0;
}

/*
 * checkpoint_seconds saves once that much time has passed since the last
 * save: a tiny interval saves after every step (and the run's end adds no
 * second save of the last step), a long one only at the end.  Refused
 * without a path, or negative, infinite or NaN.
 */
TEST(timed_checkpoints)
{
    char path[600];
    snprintf(path, sizeof path, "%s/timed.nerf", fx.dir);
    nerf_sampler *s = tiny_sampler(1);
    const double every[2] = {1e-9, 1e6};
    for (int k = 0; k < 2; k++) {
        unlink(path);
        nerf_model *m = tiny_model(4);
        nerf_trainer_options o;
        NERF_TRAINER_OPTIONS_INIT(&o);
        CHECK(o.checkpoint_seconds == 0.0);
        o.batch_rays = 32;
        o.checkpoint_path = path;
        o.checkpoint_seconds = every[k];
        nerf_trainer *t = NULL;
        CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &o));
        saves_seen w = {.path = path};
        CHECK_OK(nerf_trainer_set_progress(t, note_saved_step, &w));
        CHECK_OK(nerf_trainer_run(t, 3, NULL));
        CHECK_EQ_INT(w.calls, 3);
        for (int i = 0; i < 3; i++) {
            CHECK_EQ_INT(w.at[i], k == 0 ? i + 1 : -1);
        }
        CHECK_EQ_INT(fixture_saved_step(path), 3);
        nerf_trainer_destroy(t);
        nerf_model_destroy(m);
    }
    unlink(path);
    nerf_model *m = tiny_model(1);
    const double bad[] = {-1.0, INFINITY, NAN};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        nerf_trainer_options o;
        NERF_TRAINER_OPTIONS_INIT(&o);
        o.checkpoint_path = path;
        o.checkpoint_seconds = bad[i];
        nerf_trainer *t = NULL;
        CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &o),
                     NERF_EINVAL);
        CHECK(strstr(nerf_last_error(), "checkpoint_seconds") != NULL);
        CHECK(t == NULL);
    }
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.checkpoint_seconds = 60.0;
    nerf_trainer *t = NULL;
    CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "checkpoint_path") != NULL);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/* A checkpoint path that cannot be written is refused by create, naming
 * it, before any training. */
static void expect_unwritable(nerf_model *m, nerf_sampler *s,
                              const char *path, const char *why)
{
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.checkpoint_path = path;
    nerf_trainer *t = (nerf_trainer *)&o;
    int rc = nerf_trainer_create(&t, m, fx.train, s, &o);
    if (rc != NERF_EIO || t != NULL ||
        strstr(nerf_last_error(), path) == NULL ||
        strstr(nerf_last_error(), why) == NULL) {
        FAILF("%s: status %d, '%s' (want EIO and '%s')", path, rc,
              nerf_last_error(), why);
    }
    if (rc == NERF_OK) {
        nerf_trainer_destroy(t);
    }
}

TEST(unwritable_checkpoint_path)
{
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(4);
    char path[700], file[600], inner[720];
    snprintf(path, sizeof path, "%s/no-such-folder/run.nerf", fx.dir);
    expect_unwritable(m, s, path, "No such file or directory");
    snprintf(file, sizeof file, "%s/a-file", fx.dir);
    FILE *f = fopen(file, "w");
    CHECK(f != NULL);
    if (f) {
        fclose(f);
    }
    snprintf(path, sizeof path, "%s/run.nerf", file);
    expect_unwritable(m, s, path, "Not a directory");
    unlink(file);
    expect_unwritable(m, s, fx.dir, "it is a folder");
    if (geteuid() == 0) {
        printf("  (skipped a read-only folder: root writes into any)\n");
    } else {
        snprintf(path, sizeof path, "%s/read-only", fx.dir);
        mkdir(path, 0555);
        snprintf(inner, sizeof inner, "%s/run.nerf", path);
        expect_unwritable(m, s, inner, "Permission denied");
        rmdir(path);
    }
    /* The check leaves nothing behind, and a good path still works. */
    snprintf(path, sizeof path, "%s/ok.nerf", fx.dir);
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.checkpoint_path = path;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &o));
    CHECK(access(path, F_OK) != 0);
    DIR *d = opendir(fx.dir);
    for (struct dirent *e = d ? readdir(d) : NULL; e; e = readdir(d)) {
        if (strstr(e->d_name, ".tmp.") != NULL) {
            FAILF("left behind: %s", e->d_name);
        }
    }
    if (d) {
        closedir(d);
    }
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/* Takes the checkpoint's folder away after step 4 and stops the run. */
typedef struct swap_dir {
    const char *dir, *moved;
} swap_dir;

static int swap_after_four(const nerf_progress *p, void *user)
{
    const swap_dir *sw = user;
    if (p->done < 4) {
        return 0;
    }
    /* A regular file where the folder was: the final save cannot create
     * its temporary file, whoever runs the test. */
    if (rename(sw->dir, sw->moved) == 0) {
        FILE *f = fopen(sw->dir, "w");
        if (f) {
            fclose(f);
        }
    }
    return 1;
}

/* A run stopped by its callback whose final save fails reports the save
 * (EIO), not the cancellation; the last good checkpoint stays. */
TEST(failed_final_save_is_reported)
{
    char dir[600], moved[620], path[700], kept[700];
    snprintf(dir, sizeof dir, "%s/ckpt", fx.dir);
    snprintf(moved, sizeof moved, "%s/ckpt-moved", fx.dir);
    snprintf(path, sizeof path, "%s/run.nerf", dir);
    snprintf(kept, sizeof kept, "%s/run.nerf", moved);
    mkdir(dir, 0755);
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(4);
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 32;
    o.checkpoint_every = 3;
    o.checkpoint_path = path;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &o));
    swap_dir sw = {dir, moved};
    CHECK_OK(nerf_trainer_set_progress(t, swap_after_four, &sw));
    CHECK_EQ_INT(nerf_trainer_run(t, 10, NULL), NERF_EIO);
    CHECK(strstr(nerf_last_error(), path) != NULL);
    CHECK_EQ_INT(nerf_model_step(m), 4);
    CHECK_EQ_INT(fixture_saved_step(kept), 3);
    nerf_trainer_destroy(t);
    unlink(dir);
    unlink(kept);
    rmdir(moved);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

TEST(bad_arguments)
{
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(1);
    nerf_trainer *t = NULL;
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    CHECK_EQ_INT(nerf_trainer_create(&t, NULL, fx.train, s, &o), NERF_EINVAL);
    o.batch_rays = 0;
    CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "batch_rays") != NULL);
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.checkpoint_every = 5;
    CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &o), NERF_EINVAL);
    CHECK(t == NULL);
    CHECK_EQ_INT(nerf_trainer_step(NULL, NULL), NERF_EINVAL);
    nerf_trainer_destroy(NULL);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/*
 * Without marching every ray has the same samples, so a budget is a number
 * of rays: the fewest whose samples reach it.  They are the batch's first
 * rays, drawn as without a budget, so the loss is that of those rays alone:
 * a batch_rays of exactly that many gives the same step.
 */
TEST(batch_samples_without_marching)
{
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *a = tiny_model(1), *b = tiny_model(1);
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, NERF_PRESET_TINY);
    const uint32_t per_ray = so.n_coarse + so.n_coarse + so.n_fine;
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 64;
    o.precrop_steps = 0;
    o.batch_samples = 20 * per_ray + 1; /* 21 rays */
    nerf_trainer *ta = NULL, *tb = NULL;
    CHECK_OK(nerf_trainer_create(&ta, a, fx.train, s, &o));
    o.batch_samples = 0;
    o.batch_rays = 21;
    CHECK_OK(nerf_trainer_create(&tb, b, fx.train, s, &o));
    for (int k = 0; ta && tb && k < 2; k++) {
        nerf_train_stats sa, sb;
        memset(&sa, 0, sizeof sa);
        memset(&sb, 0, sizeof sb);
        sa.struct_size = sb.struct_size = sizeof sa;
        CHECK_OK(nerf_trainer_step(ta, &sa));
        CHECK_OK(nerf_trainer_step(tb, &sb));
        CHECK_EQ_INT(sa.rays, 21);
        CHECK_EQ_INT(sb.rays, 21);
        CHECK(sa.samples_per_ray == (double)per_ray);
        /* The first step draws the same rays; later ones do not (ray
         * numbers run on from batch_rays per step). */
        if (k == 0) {
            CHECK(sa.loss == sb.loss);
        }
    }
    nerf_trainer_destroy(ta);
    nerf_trainer_destroy(tb);
    nerf_model_destroy(a);
    nerf_model_destroy(b);
    nerf_sampler_destroy(s);
}

TEST(allocation_failures)
{
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(1);
    nerf_hooks hooks;
    fail_alloc f;
    fail_alloc_hooks(&hooks, &f);
    int succeeded_at = 0;
    for (int k = 1; k < 40 && !succeeded_at; k++) {
        f = (fail_alloc){0, k, 0};
        nerf_trainer *t = make_trainer(m, s, 16, &hooks);
        int rc = t ? nerf_trainer_step(t, NULL) : NERF_ENOMEM;
        if (t && rc == NERF_OK) {
            succeeded_at = k;
        } else {
            CHECK_EQ_INT(rc, NERF_ENOMEM);
        }
        nerf_trainer_destroy(t);
        CHECK_EQ_INT(f.live, 0);
    }
    CHECK(succeeded_at > 2);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/*
 * A dataset photographed through a lens trains on its pixels' true rays:
 * every ray a step draws is, bit for bit, the ray nerf_dataset_camera()'s
 * camera (lens included) gives some pixel, and its target is that pixel.
 */
TEST(rays_go_through_the_lens)
{
    char *dir = fx_make_temp_dir();
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = 16;
    so.height = 12;
    so.n_train = 3;
    so.n_val = 0;
    so.n_test = 0;
    so.k1 = -0.4f;
    so.k2 = 0.1f;
    so.p2 = 0.01f;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_scene_write(dir, &so));
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(1);
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 64;
    o.precrop_steps = 0;
    nerf_trainer *t = NULL;
    if (ds) {
        CHECK_OK(nerf_trainer_create(&t, m, ds, s, &o));
    }
    enum { N = 3 * 16 * 12 };
    static float org[N * 3], dir_[N * 3], pinhole[N * 3];
    const float *img[3] = {NULL, NULL, NULL};
    for (uint32_t i = 0; t && i < 3; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(ds, i, &cam));
        CHECK(cam.k1 == so.k1 && cam.k2 == so.k2 && cam.p2 == so.p2);
        CHECK_OK(nerf_camera_rays(&cam, 0, 192, org + i * 576,
                                  dir_ + i * 576));
        cam.k1 = cam.k2 = cam.p2 = 0.0f;
        CHECK_OK(nerf_camera_rays(&cam, 0, 192, org + i * 576,
                                  pinhole + i * 576));
        CHECK_OK(nerf_dataset_image(ds, i, &img[i]));
    }
    int found = 0, targets = 0, as_pinhole = 0;
    for (uint64_t step = 0; t && step < 4; step++) {
        nerf__trainer_pick_rays(t, step);
        for (uint32_t r = 0; r < o.batch_rays; r++) {
            const float *d = t->directions + 3 * r;
            for (int k = 0; k < N; k++) {
                if (memcmp(d, dir_ + 3 * k, 3 * sizeof(float)) == 0 &&
                    memcmp(t->origins + 3 * r, org + 3 * k,
                           3 * sizeof(float)) == 0) {
                    found++;
                    const float *px = img[k / 192] + 3 * (k % 192);
                    targets += memcmp(px, t->targets + 3 * r,
                                      3 * sizeof(float)) == 0;
                    break;
                }
            }
            for (int k = 0; k < N; k++) {
                if (memcmp(d, pinhole + 3 * k, 3 * sizeof(float)) == 0 &&
                    k % 16 != 8 && (k % 192) / 16 != 6) {
                    as_pinhole++; /* off the axes the lens bends rays */
                }
            }
        }
    }
    CHECK_EQ_INT(found, 4 * 64);
    CHECK_EQ_INT(targets, 4 * 64);
    CHECK_EQ_INT(as_pinhole, 0);
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
    nerf_dataset_destroy(ds);
    fx_remove_tree(dir);
}

int main(void)
{
    if (fixture_open(&fx, 24, 6, 0) != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    RUN(same_seed_same_weights);
    RUN(resume_is_bit_identical);
    RUN(fast_resume_is_bit_identical);
    RUN(grid_schedule);
    RUN(marching_needs_a_grid);
    RUN(run_progress_cancel_and_checkpoints);
    RUN(timed_checkpoints);
    RUN(unwritable_checkpoint_path);
    RUN(failed_final_save_is_reported);
    RUN(bad_arguments);
    RUN(batch_samples_without_marching);
    RUN(allocation_failures);
    RUN(rays_go_through_the_lens);
    fixture_close(&fx);
    HARNESS_EXIT();
}
