/*
 * What the loader targets require of every camera a parser hands out: a
 * renderer or trainer takes it as it is, so it must be finite, with a
 * positive focal length, a non-empty image and a lens the camera accepts,
 * and the rays of its corners and centre (through the lens's inverse)
 * must be finite.
 */
#ifndef NERF_FUZZ_CAMERA_H
#define NERF_FUZZ_CAMERA_H

#include <math.h>
#include <stddef.h>

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
    const size_t w = cam->width, h = cam->height;
    const size_t pixels[5] = {0, w - 1, (h - 1) * w, h * w - 1,
                              (h / 2) * w + w / 2};
    for (int p = 0; p < 5; p++) {
        float o[3], d[3];
        if (nerf_camera_rays(cam, pixels[p], 1, o, d) != NERF_OK) {
            return 0;
        }
        for (int c = 0; c < 3; c++) {
            if (!isfinite(o[c]) || !isfinite(d[c])) {
                return 0;
            }
        }
    }
    return 1;
}

#endif
