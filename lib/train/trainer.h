/*
 * The struct behind nerf_trainer: what one optimisation step needs besides
 * the model, whose step counter and weights are the whole training state.
 * Every random draw of step k is keyed by k (and the model's seed), so a
 * run resumed from a checkpoint at step k continues exactly as an
 * uninterrupted one.
 */
#ifndef NERF_TRAIN_TRAINER_H
#define NERF_TRAIN_TRAINER_H

#include <stdatomic.h>

#include "render_batch.h"

struct nerf_trainer {
    nerf__env env;
    nerf_trainer_options opts; /* as created; hooks NULL, path copied */
    char *checkpoint_path;     /* owned copy, or NULL */
    nerf_model *model;
    const nerf_dataset *dataset;
    const nerf_sampler *sampler;
    nerf_camera *cameras;      /* one per image, validated */
    uint32_t n_images, width, height;
    bool white;
    float noise_std;
    nerf__render_setup setup;
    nerf__batch batch;
    /* [batch_rays, 3] each: the rays and target colours of the step, and
     * the loss gradient of each pass's colours. */
    float *origins, *directions, *targets;
    float *rgb[NERF__PASSES], *d_rgb[NERF__PASSES];
    nerf_progress_cb progress;
    void *progress_user;
    atomic_int cancel;
};

/* Fill the trainer's rays and targets for step `step`. */
void nerf__trainer_pick_rays(nerf_trainer *t, uint64_t step);

#endif
