/*
 * Pose arithmetic of LLFF scenes, following the reference NeRF protocol:
 * axis reordering, rescaling by the bounds, recentring on the average pose
 * and the spiral render path.  Poses are 3x4 camera-to-world matrices,
 * row-major, 12 doubles each.
 */
#ifndef NERF_DATASET_LLFF_POSES_H
#define NERF_DATASET_LLFF_POSES_H

#include <stddef.h>
#include <stdint.h>

#include "dataset.h"

/* Columns in a row of poses_bounds.npy: a 3x5 [R | t | hwf] and 2 bounds. */
#define NERF__LLFF_ROW 17

/*
 * The pose of one row in NeRF axes: LLFF stores the rotation's columns as
 * [down, right, back]; the result is [right, up, back] = [c1, -c0, c2].
 */
void nerf__llff_row_pose(const double *row, double c2w[12]);

/*
 * Scale all n poses and their bounds (n x 2: near, far) so that the
 * smallest bound becomes 1/0.75, then recentre the poses on their average
 * pose.  Returns the scale factor.
 */
double nerf__llff_normalize(double *poses, double *bounds, size_t n);

/* The average pose as the reference defines it (see llff_poses.c). */
void nerf__llff_average_pose(const double *poses, size_t n, double out[12]);

/*
 * Spiral parameters from the normalised poses and bounds.  scratch holds n
 * doubles (for the percentile).
 */
void nerf__llff_spiral_setup(const double *poses, const double *bounds,
                             size_t n, double *scratch, nerf__spiral *out);

/*
 * Pose index of n_views along the spiral: 2 turns, the depth wobbling at
 * half the angular rate, looking at the focus point.
 */
void nerf__llff_spiral_pose(const nerf__spiral *s, uint32_t index,
                            uint32_t n_views, double c2w[12]);

#endif
