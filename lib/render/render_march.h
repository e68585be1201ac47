/*
 * The marching engine of a render batch (render_batch.h says when it
 * runs): samples marched through the model's occupancy grid (march.h),
 * a variable number per ray, packed; the network on the packed samples;
 * compositing with early termination (composite_packed.h).  Only pass 0
 * is used.
 */
#ifndef NERF_RENDER_RENDER_MARCH_H
#define NERF_RENDER_RENDER_MARCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "composite_packed.h"
#include "march.h"
#include "model.h"
#include "occupancy.h"
#include "opacity_cut.h"
#include "render_setup.h"

/* The batch whose part nerf__march_state is (render_batch.h). */
struct nerf__batch;

/*
 * For tests that compare skipping with references, not a setting of the
 * setup: place samples in empty cells too (everywhere), and give the
 * samples in empty cells density 0 (zero_empty), which is what skipping
 * them amounts to.  All false unless a test sets them, through
 * nerf__batch_set_march_test() or nerf__renderer_set_march_test().
 */
typedef struct nerf__march_test {
    bool everywhere;
    bool zero_empty;
} nerf__march_test;

/*
 * The marching engine's part of a batch.  Buffers grow on demand and are
 * reused.  After a batch that took this engine the fields up to `private`
 * describe it.
 */
typedef struct nerf__march_state {
    /* The packed samples of the last batch (with keep, each ray's up to
     * where it turns opaque; otherwise the last piece's), and their
     * points, view directions, colours and densities. */
    nerf__march_samples samples;
    float *points;                  /* [samples.total, 3] */
    float *dirs, *rgb, *sigma;      /* [samples.total, 3 / 3 / 1] */
    /* With keep: what the backward composites, and the gradients of the
     * samples' colours and densities it gives the network. */
    nerf__packed_batch packed;
    float *d_rgb, *d_sigma;         /* [samples.total, 3 / 1] */
    nerf__opacity_cut cut;          /* a training batch's */
    /* private */
    nerf__march_test test;
    float bg[3];                    /* white, for white_background */
    size_t cap_packed, cap_rays;
    bool cap_packed_keep;
    void *packed_block, *ray_block;
    /* Rendering in pieces: each ray's composite so far, where its march
     * resumes and its samples so far [n_rays]; the rays still going, and
     * where each resumes [n_rays], their origins, directions and view
     * directions [n_rays, 3]. */
    nerf__composite_state *ray_state;
    uint32_t *ray_first, *ray_count;
    uint32_t *active, *active_first;
    float *active_o, *active_d, *active_view;
} nerf__march_state;

void nerf__march_state_init(nerf__march_state *st, const nerf__env *env);
/* Free what st holds (env: the batch's allocator, which made it). */
void nerf__march_state_release(nerf__march_state *st, const nerf__env *env);
/* Start the model-bound scratch (the opacity cut's) afresh with the
 * allocator of another model. */
void nerf__march_state_bind(nerf__march_state *st,
                            const nerf__env *model_env);

/* Tests: b marches with *t from now on, until its release (NULL: as
 * outside tests). */
void nerf__batch_set_march_test(struct nerf__batch *b,
                                const nerf__march_test *t);

/*
 * The engine, which nerf__render_batch() and its backward hand over to
 * when the sampler marches.  The rays have been checked.
 */
int nerf__render_march(struct nerf__batch *b, const nerf__render_setup *s,
                       size_t n_rays, const float *origins,
                       const float *directions,
                       const nerf__pass_out out[NERF__PASSES]);
int nerf__render_march_backward(struct nerf__batch *b, nerf_model *m,
                                const float *d_rgb, const float *d_depth,
                                const float *d_opacity);

/*
 * What the engine hands the marcher for setup s: its settings for the
 * sampler and grid g (training jitters, and empty cells are skipped
 * unless a test says otherwise), and the n_rays rays with the sampler's
 * bounds and s's ray numbering.  Exposed so that a benchmark replays a
 * step's march with the step's own settings.
 */
void nerf__render_march_options(const nerf__render_setup *s,
                                const nerf__occupancy *g,
                                nerf__march_options *mo);
nerf__march_rays nerf__render_march_rays(const nerf__render_setup *s,
                                         size_t n_rays, const float *origins,
                                         const float *directions);

#endif
