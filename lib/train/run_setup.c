/*
 * A run as nerf-train sets it up: the choices beyond the library's
 * defaults (which are the reference implementation's) that nerf-train
 * makes for a model and a dataset.  They live here, not in the program, so
 * that a C or Python caller who asks for the same preset trains the same
 * bits.  docs/api-notes.md, "A run as nerf-train sets it up", says why
 * each is what it is.
 */
#include <stdbool.h>

#include "error.h"
#include "occupancy.h"
#include "options.h"
#include "trainer.h"

/* 2048 rays a step for a fresh hash-grid model, and the most samples they
 * may take: 64 a ray, where a lego ray takes about 40 once the grid is
 * carved.  While the grid is still uncarved a ray marches hundreds, and
 * the cap keeps the first steps as cheap as the later ones, so that the
 * grid, refreshed every 16 steps at first, is carved sooner. */
#define HASH_BATCH_RAYS 2048u
#define HASH_BATCH_SAMPLES 131072u

/* The march a marching model records for rendering: lego's thirty-minute
 * models scored higher rendered in 1280 steps than in the 1024 they train
 * in, for a little more time a frame, and nearly as high as in 2048. */
#define RENDER_MARCH_STEPS 1280u

/* The march a marching model trains in, in steps of its grid's diagonal.
 * A box keeps the fast preset's, instant-ngp's 1024: its rays cross empty
 * space, which the grid skips, to hard surfaces, and ten minutes of lego
 * in 512 and 256 made more steps but scored 0.28 and 1.87 dB less
 * (docs/perf-log/2026-12-03-lego-march-and-the-optimiser.md).  A
 * forward-facing (NDC) or contracted scene's rays cross occupied cells
 * from their first sample to their last, through densities that a young
 * model spreads over tens of samples: a quarter of the steps takes a
 * quarter of the samples, so that a step trains more rays or takes less
 * time, and in five minutes fern and the built-in all-round capture
 * scored higher in 512 steps than in 1024, and higher again in 256
 * (docs/perf-log/2026-12-03-training-march-of-real-captures.md).
 * Renders keep the finer march the trainer records. */
#define TRAIN_MARCH_STEPS_BOX NERF__MARCH_STEPS_DEFAULT
#define TRAIN_MARCH_STEPS_OPEN (NERF__MARCH_STEPS_DEFAULT / 4u)

/* Timed saves: a hash-grid model's checkpoint is large and takes seconds
 * to write, so saves every few hundred steps would cost a large share of
 * a run; one every two minutes loses little when a run is killed. */
#define CHECKPOINT_SECONDS 120.0

/* model's options into mo; false for a NULL model or one that has none. */
static bool options_of(const nerf_model *model, nerf_model_options *mo)
{
    nerf_model_options_init(mo, sizeof *mo);
    return model != NULL && nerf_model_get_options(model, mo) == NERF_OK;
}

static bool hash_grid(const nerf_model *model)
{
    nerf_model_options mo;
    return options_of(model, &mo) && mo.encoding == NERF_ENCODING_HASHGRID;
}

static uint32_t train_march_steps(const nerf_model *model)
{
    nerf_model_options mo;
    const bool coarse = options_of(model, &mo) &&
                        mo.encoding == NERF_ENCODING_HASHGRID &&
                        (mo.space == NERF_SPACE_NDC ||
                         mo.space == NERF_SPACE_UNBOUNDED);
    return coarse ? TRAIN_MARCH_STEPS_OPEN : TRAIN_MARCH_STEPS_BOX;
}

NERF_API int nerf_model_options_for_dataset(nerf_model_options *opts,
                                            const nerf_dataset *dataset)
{
    if (opts == NULL || dataset == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_options_for_dataset: "
                           "NULL argument");
    }
    nerf_model_options o;
    nerf_model_options_init(&o, sizeof o);
    int rc = nerf__options_read(&o, sizeof o, opts, "nerf_model_options");
    if (rc == NERF_OK && o.encoding == NERF_ENCODING_HASHGRID) {
        rc = nerf_dataset_space(dataset, &o.space, &o.bound);
    }
    if (rc == NERF_OK) {
        nerf__options_write(opts, &o, sizeof o);
    }
    return rc;
}

/* The dataset's part of nerf_sampler_options_for(). */
static int sample_dataset(nerf_sampler_options *o, const nerf_model *model,
                          const nerf_dataset *dataset)
{
    const float model_far = o->t_far;
    int rc = nerf_dataset_bounds(dataset, &o->t_near, &o->t_far);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf_model_options mo;
    if (options_of(model, &mo) && mo.space == NERF_SPACE_UNBOUNDED) {
        /* A contracted scene is marched as far as the model reaches, past
         * the farthest point the capture's cameras placed. */
        o->t_far = model_far;
    }
    o->ndc = (uint32_t)nerf_dataset_is_ndc(dataset);
    o->ndc_focal = 0.0f;
    o->ndc_width = o->ndc_height = 0;
    nerf_camera cam;
    nerf_camera_init(&cam, sizeof cam);
    if (o->ndc && nerf_dataset_camera(dataset, 0, &cam) == NERF_OK) {
        /* One NDC frustum for every view, that of the training images,
         * so renders at other sizes see the same warped scene. */
        o->ndc_focal = cam.fx;
        o->ndc_width = cam.width;
        o->ndc_height = cam.height;
    }
    return NERF_OK;
}

NERF_API int nerf_sampler_options_for(nerf_sampler_options *opts,
                                      const nerf_model *model,
                                      const nerf_dataset *dataset, int use)
{
    if (opts == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_options_for: NULL "
                           "options");
    }
    if (use != NERF_SAMPLER_FOR_RENDERING && use != NERF_SAMPLER_FOR_TRAINING) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_options_for: use %d is "
                           "not a nerf_sampler_use", use);
    }
    nerf_sampler_options o;
    nerf_sampler_options_init(&o, sizeof o);
    int rc = nerf__options_read(&o, sizeof o, opts, "nerf_sampler_options");
    if (rc == NERF_OK && model != NULL) {
        rc = nerf_model_render_settings(model, &o, NULL);
    }
    if (rc == NERF_OK && model != NULL && use == NERF_SAMPLER_FOR_TRAINING &&
        o.march_steps > 0) {
        /* Trained in the march of its space whatever finer one the model
         * records, so that a resumed run goes on as it began. */
        rc = nerf_sampler_options_set_march(&o, train_march_steps(model));
    }
    if (rc == NERF_OK && dataset != NULL) {
        rc = sample_dataset(&o, model, dataset);
    }
    if (rc == NERF_OK) {
        nerf__options_write(opts, &o, sizeof o);
    }
    return rc;
}

NERF_API int nerf_trainer_options_for(nerf_trainer_options *opts,
                                      const nerf_model *model)
{
    if (opts == NULL || model == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_options_for: NULL "
                           "argument");
    }
    nerf_trainer_options o;
    nerf_trainer_options_init(&o, sizeof o);
    int rc = nerf__options_read(&o, sizeof o, opts, "nerf_trainer_options");
    if (rc != NERF_OK) {
        return rc;
    }
    const bool hash = hash_grid(model);
    uint32_t rays = 0, samples = 0;
    nerf_model_training_batch(model, &rays, &samples);
    if (rays == 0) {
        /* Not recorded: a new model, or one trained before libnerf 0.8
         * recorded batches, at its 1024 rays. */
        const bool fresh = nerf_model_step(model) == 0;
        rays = hash && fresh ? HASH_BATCH_RAYS : 1024u;
        samples = hash && fresh ? HASH_BATCH_SAMPLES : 0u;
    }
    o.batch_rays = rays;
    o.batch_samples = samples;
    if (hash) {
        /* As Mueller et al.  During a central crop the occupancy grid
         * keeps the untrained rim occupied (on the built-in scene a run
         * with crop steps scored a lower test PSNR than one without); and
         * against a background the images do not show, density must
         * vanish wherever they are transparent, which is also what lets
         * marching skip it. */
        o.precrop_steps = 0;
        o.random_background = 1;
    }
    nerf_sampler_options so;
    nerf_sampler_options_init(&so, sizeof so);
    if (nerf_model_render_settings(model, &so, NULL) == NERF_OK &&
        so.march_steps > 0) {
        o.render_march_steps = RENDER_MARCH_STEPS;
    }
    if (o.checkpoint_path != NULL && o.checkpoint_every == 0) {
        o.checkpoint_seconds = CHECKPOINT_SECONDS;
    }
    nerf__options_write(opts, &o, sizeof o);
    return NERF_OK;
}
