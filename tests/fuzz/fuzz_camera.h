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
#include <stdlib.h>

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

/*
 * Load the scene in dir and hold the loader to its contract: a dataset
 * exactly when it says NERF_OK, and every camera a trainer would ask for
 * usable.  Aborts otherwise; returns the dataset (NULL on a refusal).
 */
static inline nerf_dataset *fuzz_load_dataset(const char *dir,
                                              const nerf_dataset_options *o)
{
    nerf_dataset *ds = NULL;
    int rc = nerf_dataset_load(&ds, dir, o);
    if ((rc == NERF_OK) != (ds != NULL)) {
        abort();
    }
    for (uint32_t i = 0; ds != NULL && i < nerf_dataset_count(ds); i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        if (nerf_dataset_camera(ds, i, &cam) != NERF_OK ||
            !fuzz_camera_usable(&cam)) {
            abort();
        }
    }
    return ds;
}

#endif
