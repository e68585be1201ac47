/*
 * Weights that are not finite, as a run that diverged leaves them: every
 * call that would make something of them refuses them with a message
 * saying so (not black images, no surface, or a checkpoint written over a
 * good one), a renderer made before they turned too, and a trainer says
 * that its run diverged, where the first such weight is, and keeps its
 * last checkpoint.  A query still runs: the model can be inspected.
 */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "model.h"
#include "train_fixture.h"

static fixture fx;

static void mentions(const char *part, const char *call)
{
    if (strstr(nerf_last_error(), part) == NULL) {
        FAILF("%s: '%s' lacks '%s'", call, nerf_last_error(), part);
    }
}

/* What a step since has made of weight i. */
static void spoil(nerf_model *m, size_t i)
{
    m->params[i] = NAN;
    nerf__model_weights_changed(m);
}

static nerf_trainer *make_trainer(nerf_model *m, nerf_sampler *s,
                                  const char *checkpoint)
{
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 32;
    o.checkpoint_path = checkpoint;
    o.checkpoint_every = checkpoint ? 1 : 0;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &o));
    return t;
}

TEST(every_use_refuses_them)
{
    nerf_model *m = tiny_model(3);
    nerf_sampler *s = tiny_sampler(3);
    nerf_renderer *r = NULL;
    CHECK_OK(nerf_renderer_create(&r, m, s, NULL));
    if (m == NULL || s == NULL || r == NULL) {
        goto out;
    }
    char path[600];
    snprintf(path, sizeof path, "%s/good.nerf", fx.dir);
    CHECK_OK(nerf_model_save(m, path));
    size_t before_size = 0;
    unsigned char *before = fx_slurp(path, &before_size);

    spoil(m, m->nets[1].trunk[2].b + 4);
    const char *where = "the fine network's trunk layer 2 bias [4]";
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_dataset_camera(fx.train, 0, &cam));
    float rgb[16 * 16 * 3];
    /* The renderer was made while the weights were finite. */
    CHECK_EQ_INT(nerf_renderer_render_image(r, &cam, rgb, NULL, NULL,
                                            16 * 16), NERF_EINVAL);
    mentions(where, "nerf_renderer_render_image");
    mentions("not finite", "nerf_renderer_render_image");
    float o[3] = {0, -4, 0}, d[3] = {0, 1, 0};
    CHECK_EQ_INT(nerf_renderer_render_rays(r, 1, o, d, rgb, NULL, NULL),
                 NERF_EINVAL);
    mentions(where, "nerf_renderer_render_rays");
    nerf_renderer *r2 = NULL;
    CHECK_EQ_INT(nerf_renderer_create(&r2, m, s, NULL), NERF_EINVAL);
    mentions("nerf_renderer_create: the model's weights are not finite (1 "
             "of ", "nerf_renderer_create");
    CHECK(r2 == NULL);
    nerf_trainer *t = NULL;
    nerf_trainer_options to;
    NERF_TRAINER_OPTIONS_INIT(&to);
    CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &to), NERF_EINVAL);
    mentions(where, "nerf_trainer_create");
    CHECK(t == NULL);
    nerf_mesh *mesh = NULL;
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, NULL), NERF_EINVAL);
    mentions(where, "nerf_mesh_extract");
    char grid[600];
    snprintf(grid, sizeof grid, "%s/grid.npy", fx.dir);
    CHECK_EQ_INT(nerf_density_grid_write(m, grid, NULL), NERF_EINVAL);
    CHECK(access(grid, F_OK) != 0);
    /* The good file stays as it was. */
    CHECK_EQ_INT(nerf_model_save(m, path), NERF_EINVAL);
    mentions(path, "nerf_model_save");
    mentions(where, "nerf_model_save");
    size_t after_size = 0;
    unsigned char *after = fx_slurp(path, &after_size);
    CHECK(before && after && before_size == after_size &&
          memcmp(before, after, before_size) == 0);
    free(before);
    free(after);
    /* Inspection still works. */
    float pos[3] = {0.1f, 0.2f, 0.3f}, dir[3] = {0, 0, 1}, c[3], sigma;
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_FINE, 1, pos, dir, c, &sigma));
    CHECK(nerf_model_contents(m) & NERF_MODEL_HAS_NONFINITE_WEIGHTS);
out:
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* The loss turns NaN: the trainer says the weights are not finite, and
 * where, rather than only "the loss is nan". */
TEST(a_step_says_the_weights_diverged)
{
    nerf_model *m = tiny_model(4);
    nerf_sampler *s = tiny_sampler(4);
    nerf_trainer *t = m && s ? make_trainer(m, s, NULL) : NULL;
    if (t == NULL) {
        goto out;
    }
    CHECK_OK(nerf_trainer_step(t, NULL));
    const uint64_t k = nerf_model_step(m);
    /* Every sample's coarse colour is NaN, and so the loss. */
    spoil(m, m->nets[0].rgb.b + 1);
    CHECK_EQ_INT(nerf_trainer_step(t, NULL), NERF_ERROR);
    mentions("training diverged by step", "nerf_trainer_step");
    mentions("the coarse network's rgb layer bias [1]", "nerf_trainer_step");
    CHECK(nerf_model_step(m) == k);
out:
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* Weights a step made NaN with a finite loss (a trunk weight whose unit
 * the ReLU then silences, say) are found by the next checkpoint, which is
 * not written over the last good one, or by the run's end without one. */
TEST(a_run_keeps_its_last_good_checkpoint)
{
    nerf_model *m = tiny_model(5);
    nerf_sampler *s = tiny_sampler(5);
    char path[600];
    snprintf(path, sizeof path, "%s/run.nerf", fx.dir);
    nerf_trainer *t = m && s ? make_trainer(m, s, path) : NULL;
    if (t == NULL) {
        goto out;
    }
    CHECK_OK(nerf_trainer_run(t, 1, NULL));
    size_t before_size = 0;
    unsigned char *before = fx_slurp(path, &before_size);
    CHECK_EQ_INT(fixture_saved_step(path), 1);
    spoil(m, m->nets[0].trunk[0].w + 3);
    CHECK_EQ_INT(nerf_trainer_run(t, 2, NULL), NERF_ERROR);
    mentions("training diverged by step", "nerf_trainer_run");
    mentions("the coarse network's trunk layer 0 weights [row 0, column 3]",
             "nerf_trainer_run");
    mentions(path, "nerf_trainer_run");
    size_t after_size = 0;
    unsigned char *after = fx_slurp(path, &after_size);
    CHECK(before && after && before_size == after_size &&
          memcmp(before, after, before_size) == 0);
    free(before);
    free(after);
    nerf_trainer_destroy(t);

    /* No checkpoint to save: the run's end says it. */
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 32;
    t = NULL;
    CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &o), NERF_EINVAL);
    nerf_model_destroy(m);
    m = tiny_model(5);
    t = m ? make_trainer(m, s, NULL) : NULL;
    if (t == NULL) {
        goto out;
    }
    spoil(m, m->nets[0].trunk[0].w + 3);   /* after the trainer's check */
    CHECK_EQ_INT(nerf_trainer_run(t, 1, NULL), NERF_ERROR);
    mentions("the weights are not finite", "nerf_trainer_run");
out:
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

int main(void)
{
    if (fixture_open(&fx, 16, 3, 0) != NERF_OK) {
        printf("cannot set up: %s\n", nerf_last_error());
        return 1;
    }
    RUN(every_use_refuses_them);
    RUN(a_step_says_the_weights_diverged);
    RUN(a_run_keeps_its_last_good_checkpoint);
    fixture_close(&fx);
    HARNESS_EXIT();
}
