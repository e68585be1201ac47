/*
 * nerf-render's --path orbit: views circling the origin at 30 degrees of
 * elevation, looking at it, framed so that a Blender scene's object stays
 * whole in a frame of any aspect ratio.  bench_render_model renders views
 * of the same orbit.
 */
#ifndef NERF_EXAMPLES_ORBIT_H
#define NERF_EXAMPLES_ORBIT_H

#include <nerf.h>

/* The lego scene's horizontal field of view, in radians: the orbit's
 * field of view across the smaller side of its frames, and nerf-render's
 * default (horizontal) for --poses files that carry no intrinsics. */
#define ORBIT_FOV 0.6911112070083618

/* The orbit's elevation above the xy plane, in radians: 30 degrees. */
#define ORBIT_ELEVATION 0.5235987755982988

/*
 * The radius of the sphere about the origin that every orbit view keeps
 * whole: the bound of the box Blender scenes are placed in
 * (nerf_model_options.bound's default, 1.5), which holds their objects
 * (lego's silhouettes put it within 1.35 of the origin; the built-in
 * scene's bounding box reaches 1.48 at its corners).
 */
double orbit_bound(void);

/*
 * The orbit's distance from the origin, at which the sphere of
 * orbit_bound() fills ORBIT_FOV exactly: bound / sin(ORBIT_FOV / 2),
 * about 4.43.  That sphere's cone of view lies inside the frame's
 * smaller field of view, so it is whole at any aspect ratio.
 */
double orbit_distance(void);

/* View i of n around the orbit, width x height pixels, at
 * orbit_distance(). */
int orbit_camera(uint32_t i, uint32_t n, uint32_t width, uint32_t height,
                 nerf_camera *cam);

/* The same at another distance from the origin. */
int orbit_camera_at(uint32_t i, uint32_t n, uint32_t width, uint32_t height,
                    double distance, nerf_camera *cam);

#endif
