/*
 * Where each ray of a marched training batch turns opaque, from the
 * densities alone, evaluated in rounds of a few samples a ray so that
 * the samples behind that point are mostly never evaluated.
 */
#ifndef NERF_RENDER_OPACITY_CUT_H
#define NERF_RENDER_OPACITY_CUT_H

#include <stddef.h>
#include <stdint.h>

#include "march.h"
#include "model.h"
#include "network.h"
#include "occupancy.h"

/* Scratch of the rounds; buffers grow on demand and are reused. */
typedef struct nerf__opacity_cut {
    nerf__env env;          /* the model's: its workspace's allocator */
    nerf__workspace ws;     /* the rounds' density workspace */
    size_t cap_rays, cap_samples;
    void *ray_block, *sample_block;
    float *trans;           /* [rays] transmittance so far */
    uint32_t *active;       /* [rays] the rays going */
    size_t *start;          /* [rays + 1] each going ray's rows in a round */
    float *pos;             /* [samples, 3] a round's points */
    float *sigma;           /* [samples] a round's densities */
    /* Samples the last run evaluated, all rounds. */
    size_t evaluated;
    uint32_t rounds;
} nerf__opacity_cut;

void nerf__opacity_cut_init(nerf__opacity_cut *c, const nerf__env *env);
void nerf__opacity_cut_release(nerf__opacity_cut *c);

/*
 * For each ray k of ms, with its samples' points (points: [ms->total, 3]),
 * count[k] receives how many of its samples nerf__composite_packed_ray()
 * uses with eps, as nerf__composite_packed_ray_used() counts them over all
 * of its densities.  Densities come from network 0 of m (in cells that
 * zero_in marks empty, 0; zero_in NULL: as they are).  enc (NULL: not
 * wanted; else [ms->total, pos_width]) receives at each counted sample's
 * row its position encoding as that density used it.  The densities the
 * network computes for a sample do not depend on the other samples it is
 * given, so the counts are those of a single pass over every sample.
 */
int nerf__opacity_cut_run(nerf__opacity_cut *c, const nerf_model *m,
                          const nerf__march_samples *ms, const float *points,
                          const nerf__occupancy *zero_in, float eps,
                          uint32_t *count, float *enc);

#endif
