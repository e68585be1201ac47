/*
 * What a render batch (render_batch.h) is asked for: the setup of a call
 * and the outputs of each pass.  Apart from the batch so that each of its
 * engines, stratified and marching, can name them.
 */
#ifndef NERF_RENDER_RENDER_SETUP_H
#define NERF_RENDER_RENDER_SETUP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "model.h"
#include "ndc.h"
#include "sampler.h"

/* Pass 0 is the coarse pass, pass 1 the fine one (absent when n_fine = 0). */
#define NERF__PASSES 2

typedef struct nerf__render_setup {
    const nerf_model *model;
    const nerf_sampler *sampler;
    /* Training: jittered and random samples (when the sampler's perturb is
     * set) and Gaussian noise of std noise_std on raw density.  Otherwise
     * everything is deterministic. */
    bool training;
    float noise_std;
    bool white_background;
    /* The NDC frustum, used when the sampler has ndc set. */
    float ndc_focal, ndc_width, ndc_height;
    /* Ray k draws from the streams of ray first_ray + k. */
    uint64_t first_ray;
    /* Draws supplied by the caller instead of the generator's (each may be
     * NULL): uniforms for the stratified jitter [n_rays, n_coarse] and the
     * hierarchical samples [n_rays, n_fine], and the values added to raw
     * density [n_rays, samples of the pass] (already scaled, used even if
     * noise_std is 0). */
    const float *u_coarse;
    const float *u_fine;
    const float *noise[NERF__PASSES];
    /* Keep activations, samples and weights for the backward pass. */
    bool keep;
    /* Training with nerf_trainer_options.batch_samples: take the first
     * rays of the batch whose samples reach this many (at least one ray;
     * 0: all).  The batch's n_rays says how many were taken. */
    size_t sample_budget;
    /* Training with nerf_trainer_options.random_background: ray k is
     * finished on the colour background + 3 k (both paths, forward and
     * backward) instead of white_background's.  It must stay unchanged
     * until the backward.  NULL: white_background. */
    const float *background;
    /* Rendering a model with appearance codes: the code its last pass's
     * colours are mapped by (model/appearance.h).  Training maps each
     * ray by its own image's code itself, and leaves this unset. */
    bool appearance;
    float code[NERF__CODE_FLOATS];
} nerf__render_setup;

/*
 * A batch's n rays (o, d) warped into NDC as the engines sample and march
 * them when the sampler has ndc set: the setup's frustum, with the near
 * plane at world depth 1 as in the reference.  Also for benchmarks that
 * replay a step's march.
 */
static inline void nerf__render_ndc_rays(const nerf__render_setup *s,
                                         size_t n, const float *o,
                                         const float *d, float *o_out,
                                         float *d_out)
{
    nerf__ndc_rays(s->ndc_focal, s->ndc_width, s->ndc_height, 1.0f, n, o, d,
                   o_out, d_out);
}

/* Outputs of one pass; any pointer may be NULL. */
typedef struct nerf__pass_out {
    float *rgb;       /* [n_rays, 3] */
    float *depth;     /* [n_rays] */
    float *disparity; /* [n_rays] */
    float *opacity;   /* [n_rays] */
} nerf__pass_out;

#endif
