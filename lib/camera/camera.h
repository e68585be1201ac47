/* Cameras: validation of the public struct and ray generation. */
#ifndef NERF_CAMERA_CAMERA_H
#define NERF_CAMERA_CAMERA_H

#include <stddef.h>

#include "nerf.h"

/*
 * Read a caller's versioned camera into a full-size struct and validate it.
 * fn names the public call in error messages.
 */
int nerf__camera_read(nerf_camera *out, const nerf_camera *in, const char *fn);

/*
 * Copy a full-size camera into a caller's versioned struct, as many bytes
 * as its struct_size says, so that callers built against an older, smaller
 * nerf_camera keep working.  The caller's struct_size is kept.
 */
int nerf__camera_write(nerf_camera *out, const nerf_camera *cam,
                       const char *fn);

/*
 * Rays of pixels first .. first + n - 1 (row-major pixel index) of a
 * validated camera: origins and unnormalised directions, n x 3 each.
 */
void nerf__camera_rays(const nerf_camera *cam, size_t first, size_t n,
                       float *origins, float *directions);

#endif
