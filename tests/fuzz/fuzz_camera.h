/*
 * What the loader targets require of every camera a parser hands out: a
 * renderer or trainer takes it as it is, so it must be finite, with a
 * positive focal length and a non-empty image.
 */
#ifndef NERF_FUZZ_CAMERA_H
#define NERF_FUZZ_CAMERA_H

#include <math.h>

#include <nerf.h>

static inline int fuzz_camera_usable(const nerf_camera *cam)
{
    if (cam->width == 0 || cam->height == 0 ||
        !(isfinite(cam->fx) && cam->fx > 0.0f) ||
        !(isfinite(cam->fy) && cam->fy > 0.0f) ||
        !isfinite(cam->cx) || !isfinite(cam->cy)) {
        return 0;
    }
    for (int k = 0; k < 12; k++) {
        if (!isfinite(cam->c2w[k])) {
            return 0;
        }
    }
    return 1;
}

#endif
