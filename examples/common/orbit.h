/*
 * nerf-render's --path orbit: views circling the origin at 30 degrees of
 * elevation and a distance of 4, looking at it with the lego scene's field
 * of view, as the Blender scenes' cameras stand.  bench_render_model
 * renders the same views.
 */
#ifndef NERF_EXAMPLES_ORBIT_H
#define NERF_EXAMPLES_ORBIT_H

#include <nerf.h>

/* The lego scene's horizontal field of view, in radians: the orbit's, and
 * nerf-render's default for --poses files that carry no intrinsics. */
#define ORBIT_FOV 0.6911112070083618

/* View i of n around the orbit, width x height pixels. */
int orbit_camera(uint32_t i, uint32_t n, uint32_t width, uint32_t height,
                 nerf_camera *cam);

#endif
