/*
 * A box sampled on a regular grid, and the scalar fields the geometry
 * code samples over it: the model's density (model_field.c) or, in the
 * tests, an analytic function.
 */
#ifndef NERF_GEOMETRY_GRID_BOX_H
#define NERF_GEOMETRY_GRID_BOX_H

#include <stddef.h>
#include <stdint.h>

/* Samples i = 0..cells[a] along axis a at lo[a] + i * step[a]: the cell
 * corners, both faces of the box included. */
typedef struct nerf__grid_box {
    float lo[3], hi[3];
    float step[3];
    uint32_t cells[3];
} nerf__grid_box;

/*
 * Lay a grid over [lo, hi] with `resolution` cells along the longest side
 * and as many along the others as keep the cells nearest to cubes (at
 * least one).  Returns NERF_EINVAL for resolution 0 or above 16384, a
 * non-finite box or one of zero volume, naming `who`.
 */
int nerf__grid_box_init(nerf__grid_box *g, const float lo[3],
                        const float hi[3], uint32_t resolution,
                        const char *who);

/*
 * A scalar field: density at n points (n x 3, world or the model's
 * space) into out[n].  Returns NERF_OK or a failure status with its
 * message.
 */
typedef struct nerf__field {
    int (*sample)(void *ctx, size_t n, const float *points, float *out);
    void *ctx;
} nerf__field;

/* Progress: called after each plane of samples with planes done and in
 * all; nonzero cancels the call (NERF_ECANCELLED). */
typedef struct nerf__geometry_progress {
    int (*fn)(void *ctx, uint64_t done, uint64_t total);
    void *ctx;
} nerf__geometry_progress;

#endif
