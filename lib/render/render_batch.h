/*
 * One batch of rays through the whole method.  The image renderer calls it
 * on blocks of pixels; the trainer calls it on its batch of random rays
 * with `keep` set, then calls nerf__render_batch_backward() with the loss
 * gradients of its outputs.
 *
 * Two engines do the work, each with its own part of the batch beside the
 * part they share.  The stratified one (render_stratified.h) is the
 * reference's method: sampling, the coarse network, compositing,
 * hierarchical sampling, the fine network and compositing again.  With a
 * marching sampler (march_steps > 0) the batch takes the marching one
 * instead (render_march.h): one pass of samples marched through the
 * model's occupancy grid, packed (a variable number per ray), the network
 * on the packed samples, and compositing with early termination.  With
 * `keep` (training) every ray is marched in full at once, a density pass
 * finds where each turns opaque, and one forward of the samples before
 * that holds everything the backward needs; without it (rendering) the
 * rays are marched a few samples at a time and each stops being marched
 * once it is opaque, so the network sees few samples past the surfaces.
 */
#ifndef NERF_RENDER_BATCH_H
#define NERF_RENDER_BATCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "model.h"
#include "render_march.h"
#include "render_setup.h"
#include "render_stratified.h"
#include "sampler.h"

/*
 * Scratch and state of one batch: a part both engines share and each
 * engine's own.  Buffers grow on demand and are reused, so a caller that
 * keeps one batch per worker allocates only on its first call.  After
 * nerf__render_batch() the fields up to `private` describe the batch, and
 * so does the part of the engine it took (marched says which).
 */
typedef struct nerf__batch {
    nerf__env env;
    size_t n_rays;                  /* as asked, or fewer (sample_budget) */
    uint32_t n_pass;
    uint32_t n_samples[NERF__PASSES]; /* per ray; 0 when marched */
    int net[NERF__PASSES];          /* network index of each pass */
    float *dir_norm;                /* [n_rays], |d| of the sampled rays */
    /* Network evaluations of the last batch, all passes and pieces (with
     * marching and keep, the density pass's: every marched sample). */
    size_t n_evaluated;
    bool marched;                   /* the last batch took marching */
    bool kept;                      /* and kept its state for a backward */
    /* The network's workspace of each pass (marching: ws[0] alone). */
    nerf__workspace ws[NERF__PASSES];
    nerf__stratified_state stratified; /* render_stratified.h */
    nerf__march_state marching;        /* render_march.h */
    /* private, both engines */
    const nerf_model *model;
    nerf__env ws_env;               /* the model's, the workspaces' */
    bool white;
    const float *ray_bg;            /* setup's background */
    size_t cap_rays;
    void *ray_block;
    float *ray_o, *ray_d, *viewdir; /* [n_rays, 3] */
    float *opacity;                 /* [n_rays]: for the appearance map
                                       when the caller asks for none */
} nerf__batch;

void nerf__batch_init(nerf__batch *b, const nerf__env *env);
void nerf__batch_release(nerf__batch *b);

/*
 * Render n_rays rays (origins, directions: [n_rays, 3], world space,
 * directions unnormalised) into out[0] (coarse) and out[1] (fine; ignored
 * without a fine pass).  The fine pass runs the model's fine network, or
 * its coarse one if it has none (as the reference does).  Each pass is one
 * network call over all its samples, so the caller chooses the batch size
 * that bounds memory; the results of a ray depend only on the rays of its
 * batch through the matrix products.
 */
int nerf__render_batch(nerf__batch *b, const nerf__render_setup *s,
                       size_t n_rays, const float *origins,
                       const float *directions,
                       const nerf__pass_out out[NERF__PASSES]);

/*
 * Backward of the last nerf__render_batch(), which must have had keep set:
 * given dL/d(rgb) [n_rays, 3], dL/d(depth) and dL/d(opacity) [n_rays] of
 * each pass (any may be NULL for zero), accumulate the gradients of both
 * networks into m->grads via nerf__model_backward().  m must be the model
 * the forward used.  Sampling is not differentiated (the samples are
 * constants, as in the reference).
 */
int nerf__render_batch_backward(nerf__batch *b, nerf_model *m,
                                const float *const d_rgb[NERF__PASSES],
                                const float *const d_depth[NERF__PASSES],
                                const float *const d_opacity[NERF__PASSES]);

/*
 * For the engines: size the per-ray arrays for n_rays rays, bind b to s's
 * model, and record the batch's rays and background.
 */
int nerf__batch_begin(nerf__batch *b, const nerf__render_setup *s,
                      size_t n_rays);

/* Check, at renderer or trainer creation, that the sampler can work with
 * the model (a marching sampler needs the model's occupancy grid). */
int nerf__render_check_pair(const nerf_model *m, const nerf_sampler *s,
                            const char *fn);

#endif
