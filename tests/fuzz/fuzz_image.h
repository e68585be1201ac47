/*
 * What the image targets (fuzz_png, fuzz_jpeg) require of the loaders'
 * image reader, whatever the file: through an allocator capped at 16 MB
 * (a header may ask for any size; the cap keeps the fuzzer's memory
 * bounded, and a refused allocation must be reported, not crash), an image
 * it accepts has the size its header and the downscale factor say and
 * every value in [0, 1].
 */
#ifndef NERF_FUZZ_IMAGE_H
#define NERF_FUZZ_IMAGE_H

#include <stdint.h>
#include <stdlib.h>

#include <nerf.h>

#include "dataset.h"

#define FUZZ_IMAGE_ALLOC_CAP ((size_t)16 << 20)

static void *fuzz_capped_alloc(size_t size, void *user)
{
    (void)user;
    return size > FUZZ_IMAGE_ALLOC_CAP ? NULL : malloc(size);
}

static void fuzz_plain_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

/* Load path as image 0 of a dataset, by factor and onto white or black,
 * and check what comes back; aborts on a broken promise. */
static void fuzz_load_image(const char *path, uint32_t factor, uint32_t white)
{
    nerf_hooks hooks;
    if (NERF_HOOKS_INIT(&hooks) != NERF_OK) {
        abort();
    }
    hooks.alloc = fuzz_capped_alloc;
    hooks.free = fuzz_plain_free;
    nerf__env env;
    if (nerf__env_from_hooks(&env, &hooks) != NERF_OK) {
        abort();
    }
    nerf_dataset *ds = nerf__calloc(&env, 1, sizeof *ds);
    if (ds == NULL) {
        return;
    }
    ds->env = env;
    if (nerf__dataset_reserve(ds, 1) == NERF_OK &&
        nerf__dataset_load_image(ds, 0, path, factor, white) == NERF_OK) {
        if (ds->width != ds->src_width / factor || ds->width == 0 ||
            ds->height != ds->src_height / factor || ds->height == 0) {
            abort();
        }
        const size_t n = (size_t)ds->width * ds->height * 3;
        for (size_t i = 0; i < n; i++) {
            if (!(ds->pixels[i] >= 0.0f && ds->pixels[i] <= 1.0f)) {
                abort();
            }
        }
    }
    nerf_dataset_destroy(ds);
}

#endif
