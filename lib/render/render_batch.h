/*
 * One batch of rays through the whole method: sampling, the coarse
 * network, compositing, hierarchical sampling, the fine network and
 * compositing again.  The image renderer calls it on blocks of pixels; the
 * trainer calls it on its batch of random rays with `keep` set, then calls
 * nerf__render_batch_backward() with the loss gradients of its outputs.
 *
 * With a marching sampler (march_steps > 0) the batch takes the fast path
 * instead (render_march.c): one pass of samples marched through the
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

#include "composite_packed.h"
#include "march.h"
#include "model.h"
#include "opacity_cut.h"
#include "render_setup.h"
#include "sampler.h"

/*
 * Scratch and state of one batch.  Buffers grow on demand and are reused,
 * so a caller that keeps one batch per worker allocates only on its first
 * call.  After nerf__render_batch() the fields below describe the batch
 * (t and weights stay valid until the next call).
 */
typedef struct nerf__batch {
    nerf__env env;
    size_t n_rays;                  /* as asked, or fewer (sample_budget) */
    uint32_t n_pass;
    uint32_t n_samples[NERF__PASSES];
    int net[NERF__PASSES];          /* network index of each pass */
    float *t[NERF__PASSES];         /* [n_rays, n_samples] */
    float *weights[NERF__PASSES];   /* [n_rays, n_samples] */
    float *rgb[NERF__PASSES];       /* [n_rays * n_samples, 3] */
    float *sigma[NERF__PASSES];     /* [n_rays * n_samples], noise added */
    float *dir_norm;                /* [n_rays], |d| of the sampled rays */
    /* Network evaluations of the last batch, all passes and pieces (with
     * marching and keep, the density pass's: every marched sample). */
    size_t n_evaluated;
    /* Marching: the packed samples of the last batch (with keep, each
     * ray's up to where it turns opaque; otherwise the last piece's), and
     * their points. */
    nerf__march_samples march;
    float *march_points;            /* [march.total, 3] */
    /* private */
    const nerf_model *model;
    bool white, kept;
    const float *ray_bg;            /* setup's background */
    size_t cap_rays;
    uint32_t cap_c, cap_f;
    bool cap_keep;
    void *block;
    float *ray_o, *ray_d, *viewdir, *points, *dirs, *scratch;
    float *d_rgb, *d_sigma;
    nerf__env ws_env;
    nerf__workspace ws[NERF__PASSES];
    /* private, marching (render_march.c) */
    bool marched;                   /* the last batch took this path */
    nerf__packed_batch packed;      /* what the backward composites */
    float bg[3];
    size_t cap_packed, cap_march_rays;
    bool cap_packed_keep;
    void *packed_block, *march_block;
    float *m_dirs, *m_rgb, *m_sigma, *m_d_rgb, *m_d_sigma;
    nerf__composite_state *m_state;      /* [n_rays] */
    uint32_t *m_first, *m_count, *m_active, *m_act_first; /* [n_rays] */
    float *m_o, *m_d, *m_view;           /* [n_rays, 3], rays going */
    nerf__opacity_cut cut;               /* a training batch's */
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
 * The marching path (render_march.c), which nerf__render_batch() and its
 * backward hand over to when the sampler marches; only pass 0 is used.
 * The rays have been checked and b sized for n_rays per-ray values.
 */
int nerf__render_march(nerf__batch *b, const nerf__render_setup *s,
                       size_t n_rays, const float *origins,
                       const float *directions,
                       const nerf__pass_out out[NERF__PASSES]);
int nerf__render_march_backward(nerf__batch *b, nerf_model *m,
                                const float *d_rgb, const float *d_depth,
                                const float *d_opacity);
void nerf__render_march_release(nerf__batch *b);

/*
 * What the marching path hands the marcher for setup s: its settings for
 * the sampler and grid g (training jitters, and skips empty cells unless
 * march_everywhere), and the n_rays rays with the sampler's bounds and
 * s's ray numbering.  Exposed so that a benchmark replays a step's march
 * with the step's own settings.
 */
void nerf__render_march_options(const nerf__render_setup *s,
                                const nerf__occupancy *g,
                                nerf__march_options *mo);
nerf__march_rays nerf__render_march_rays(const nerf__render_setup *s,
                                         size_t n_rays, const float *origins,
                                         const float *directions);

/* Check, at renderer or trainer creation, that the sampler can work with
 * the model (a marching sampler needs the model's occupancy grid). */
int nerf__render_check_pair(const nerf_model *m, const nerf_sampler *s,
                            const char *fn);

#endif
