/*
 * Normalised device coordinates for forward-facing scenes, as the
 * reference implementation defines them: the frustum of a camera looking
 * down -z, with its near plane at z = -near, becomes a cube in which depth
 * runs from 0 (the near plane) to 1 (infinity).
 */
#ifndef NERF_CAMERA_NDC_H
#define NERF_CAMERA_NDC_H

#include <stddef.h>

/*
 * Warp n rays (origins o and directions d, n x 3 each) into o_out and
 * d_out (which may alias them).  The frustum is that of an image of
 * width x height pixels with focal length focal (one focal for both axes).
 * Each origin is first moved along its ray to the plane z = -near_plane.
 * Rays must point into the scene (d_z < 0); others give non-finite values.
 */
void nerf__ndc_rays(float focal, float width, float height, float near_plane,
                    size_t n, const float *o, const float *d, float *o_out,
                    float *d_out);

#endif
