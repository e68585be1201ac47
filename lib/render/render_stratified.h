/*
 * The stratified engine of a render batch (render_batch.h says when it
 * runs), the reference's method: stratified coarse samples, the coarse
 * network, compositing, hierarchical fine samples, the fine network and
 * compositing again.  Every ray of a pass has the same number of samples,
 * so its arrays are rows [n_rays, n_samples of the pass].
 */
#ifndef NERF_RENDER_RENDER_STRATIFIED_H
#define NERF_RENDER_RENDER_STRATIFIED_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "model.h"
#include "render_setup.h"

/* The batch whose part nerf__stratified_state is (render_batch.h). */
struct nerf__batch;

/*
 * The stratified engine's part of a batch.  Buffers grow on demand and
 * are reused.  After a batch that took this engine the fields up to
 * `private` describe it (t and weights stay valid until the next call).
 */
typedef struct nerf__stratified_state {
    float *t[NERF__PASSES];         /* [n_rays, n_samples] */
    float *weights[NERF__PASSES];   /* [n_rays, n_samples] */
    float *rgb[NERF__PASSES];       /* [n_rays * n_samples, 3] */
    float *sigma[NERF__PASSES];     /* [n_rays * n_samples], noise added */
    /* With keep: the gradients of the last pass the backward ran, of its
     * samples' colours and densities, as it gave them the network. */
    float *d_rgb, *d_sigma;         /* [n_rays * n_samples, 3 / 1] */
    /* private */
    size_t cap_rays;
    uint32_t cap_c, cap_f;
    bool cap_keep;
    void *block;
    float *points, *dirs, *scratch;
} nerf__stratified_state;

/* Free what st holds (env: the batch's allocator, which made it). */
void nerf__stratified_release(nerf__stratified_state *st,
                              const nerf__env *env);

/*
 * The engine, which nerf__render_batch() and its backward hand over to
 * when the sampler does not march.  The rays have been checked.
 */
int nerf__render_stratified(struct nerf__batch *b,
                            const nerf__render_setup *s, size_t n_rays,
                            const float *origins, const float *directions,
                            const nerf__pass_out out[NERF__PASSES]);
int nerf__render_stratified_backward(
    struct nerf__batch *b, nerf_model *m,
    const float *const d_rgb[NERF__PASSES],
    const float *const d_depth[NERF__PASSES],
    const float *const d_opacity[NERF__PASSES]);

#endif
