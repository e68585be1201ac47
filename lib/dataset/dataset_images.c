/* Image storage shared by the loaders: compositing and area downscaling. */
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "dataset.h"
#include "image_read.h"

char *nerf__path_join(const nerf__env *env, const char *dir,
                      const char *name)
{
    size_t nd = strlen(dir), nn = strlen(name);
    bool slash = nd > 0 && dir[nd - 1] != '/';
    char *out = nerf__alloc(env, nd + nn + 2);
    if (out == NULL) {
        return NULL;
    }
    memcpy(out, dir, nd);
    if (slash) {
        out[nd++] = '/';
    }
    memcpy(out + nd, name, nn + 1);
    return out;
}

int nerf__dataset_reserve(nerf_dataset *ds, uint32_t count)
{
    ds->views = nerf__calloc(&ds->env, count, sizeof *ds->views);
    if (ds->views == NULL) {
        return NERF_ENOMEM;
    }
    ds->count = count;
    return NERF_OK;
}

/*
 * Composite each source pixel onto the background first and average
 * afterwards: the mean of what a camera would see over the block.  (The
 * reference resizes straight RGBA and composites afterwards, which gives a
 * slightly different colour at silhouette edges.)  Rows and columns beyond
 * a whole number of blocks are dropped.
 */
static void composite_box(const float *rgba, uint32_t src_w, uint32_t factor,
                          uint32_t w, uint32_t h, float bg, float *dst)
{
    double inv = 1.0 / ((double)factor * factor);
    for (uint32_t oy = 0; oy < h; oy++) {
        for (uint32_t ox = 0; ox < w; ox++) {
            double acc[3] = {0.0, 0.0, 0.0};
            for (uint32_t dy = 0; dy < factor; dy++) {
                const float *p = rgba + ((size_t)(oy * factor + dy) * src_w +
                                         (size_t)ox * factor) * 4;
                for (uint32_t dx = 0; dx < factor; dx++, p += 4) {
                    double a = p[3];
                    for (int c = 0; c < 3; c++) {
                        acc[c] += p[c] * a + bg * (1.0 - a);
                    }
                }
            }
            float *d = dst + ((size_t)oy * w + ox) * 3;
            for (int c = 0; c < 3; c++) {
                d[c] = (float)(acc[c] * inv);
            }
        }
    }
}

static bool has_transparency(const float *rgba, size_t pixels)
{
    for (size_t i = 0; i < pixels; i++) {
        if (rgba[4 * i + 3] < 1.0f) {
            return true;
        }
    }
    return false;
}

/* The mean alpha of each block, the same blocks composite_box() takes. */
static void coverage_box(const float *rgba, uint32_t src_w, uint32_t factor,
                         uint32_t w, uint32_t h, uint16_t *dst)
{
    double scale = 65535.0 / ((double)factor * factor);
    for (uint32_t oy = 0; oy < h; oy++) {
        for (uint32_t ox = 0; ox < w; ox++) {
            double acc = 0.0;
            for (uint32_t dy = 0; dy < factor; dy++) {
                const float *p = rgba + ((size_t)(oy * factor + dy) * src_w +
                                         (size_t)ox * factor) * 4;
                for (uint32_t dx = 0; dx < factor; dx++, p += 4) {
                    acc += p[3];
                }
            }
            double q = acc * scale + 0.5;
            dst[(size_t)oy * w + ox] = (uint16_t)(q > 65535.0 ? 65535.0 : q);
        }
    }
}

/*
 * Keep the coverage of image index.  Opaque scenes (LLFF photographs, RGB
 * files) never allocate the plane; the first image with a transparent
 * pixel allocates it for all, the images before it being opaque.
 */
static int store_alpha(nerf_dataset *ds, uint32_t index, const char *path,
                       const float *rgba, uint32_t factor)
{
    const size_t per_image = (size_t)ds->width * ds->height;
    const bool opaque = !has_transparency(
        rgba, (size_t)ds->src_width * ds->src_height);
    if (ds->alpha == NULL) {
        if (opaque) {
            return NERF_OK;
        }
        /* No overflow: first_image() checked per_image * 3 * count. */
        ds->alpha = nerf__alloc(&ds->env,
                                per_image * ds->count * sizeof *ds->alpha);
        if (ds->alpha == NULL) {
            return nerf__error_prefix(NERF_ENOMEM, path);
        }
        for (size_t i = 0; i < per_image * ds->count; i++) {
            ds->alpha[i] = 65535;
        }
    }
    uint16_t *dst = ds->alpha + per_image * index;
    if (opaque) {
        for (size_t i = 0; i < per_image; i++) {
            dst[i] = 65535;
        }
    } else {
        coverage_box(rgba, ds->src_width, factor, ds->width, ds->height, dst);
    }
    return NERF_OK;
}

/* The first image fixes the size of all: allocate the pixel store. */
static int first_image(nerf_dataset *ds, const char *path, uint32_t w,
                       uint32_t h, uint32_t factor)
{
    if (w < factor || h < factor) {
        return nerf__error(NERF_EINVAL, "%s: a %ux%u image cannot be "
                           "downscaled by %u", path, (unsigned)w,
                           (unsigned)h, (unsigned)factor);
    }
    ds->src_width = w;
    ds->src_height = h;
    ds->width = w / factor;
    ds->height = h / factor;
    size_t n;
    if (nerf__mul_size((size_t)ds->width * ds->height, 3, &n) != 0 ||
        nerf__mul_size(n, ds->count, &n) != 0) {
        return nerf__error(NERF_ENOMEM, "%s: %u images of %ux%u do not fit "
                           "in memory", path, (unsigned)ds->count,
                           (unsigned)ds->width, (unsigned)ds->height);
    }
    ds->pixels = nerf__calloc(&ds->env, n, sizeof *ds->pixels);
    return ds->pixels ? NERF_OK : nerf__error_prefix(NERF_ENOMEM, path);
}

/* An image of w x h beside the first one's size. */
static int check_size(const nerf_dataset *ds, const char *path, uint32_t w,
                      uint32_t h)
{
    if (w != ds->src_width || h != ds->src_height) {
        return nerf__error(NERF_EFORMAT, "%s: image is %ux%u but the images "
                           "before it are %ux%u", path, (unsigned)w,
                           (unsigned)h, (unsigned)ds->src_width,
                           (unsigned)ds->src_height);
    }
    return NERF_OK;
}

int nerf__dataset_load_image(nerf_dataset *ds, uint32_t index,
                             const char *path, uint32_t factor,
                             uint32_t white_background)
{
    uint32_t w, h;
    float *rgba;
    int rc = nerf__image_read_rgba(&ds->env, path, &w, &h, &rgba);
    if (rc != NERF_OK) {
        return rc;
    }
    if (ds->pixels == NULL) {
        rc = first_image(ds, path, w, h, factor);
    } else {
        rc = check_size(ds, path, w, h);
    }
    if (rc == NERF_OK) {
        size_t per_image = (size_t)ds->width * ds->height * 3;
        composite_box(rgba, w, factor, ds->width, ds->height,
                      white_background ? 1.0f : 0.0f,
                      ds->pixels + per_image * index);
        ds->alpha_bg = white_background ? 1.0f : 0.0f;
        rc = store_alpha(ds, index, path, rgba, factor);
    }
    nerf__free(&ds->env, rgba);
    return rc;
}

int nerf__dataset_check_image(const nerf_dataset *ds, const char *path)
{
    uint32_t w, h;
    int rc = nerf__image_read_size(&ds->env, path, &w, &h);
    return rc == NERF_OK ? check_size(ds, path, w, h) : rc;
}

/*
 * A block is kept only when all its source pixels are: a block that a
 * person covers in part holds some of the person's colour, which is what
 * the mask is there to keep out of training.  Every colour channel is
 * looked at, so grey, RGB and palette masks read alike; alpha is not (a
 * mask's transparency says nothing in any of the layouts' conventions).
 */
static void mask_box(const float *rgba, uint32_t src_w, uint32_t factor,
                     uint32_t w, uint32_t h, nerf__mask_rule rule,
                     uint8_t *dst)
{
    for (uint32_t oy = 0; oy < h; oy++) {
        for (uint32_t ox = 0; ox < w; ox++) {
            uint8_t keep = 1;
            for (uint32_t dy = 0; dy < factor; dy++) {
                const float *p = rgba + ((size_t)(oy * factor + dy) * src_w +
                                         (size_t)ox * factor) * 4;
                for (uint32_t dx = 0; dx < factor; dx++, p += 4) {
                    bool zero = p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f;
                    if (zero == (rule == NERF__MASK_ZERO_DROPS)) {
                        keep = 0;
                    }
                }
            }
            dst[(size_t)oy * w + ox] = keep;
        }
    }
}

int nerf__dataset_load_mask(nerf_dataset *ds, uint32_t index,
                            const char *path, const char *photo,
                            uint32_t factor, nerf__mask_rule rule)
{
    uint32_t w, h;
    float *rgba;
    int rc = nerf__image_read_rgba(&ds->env, path, &w, &h, &rgba);
    if (rc != NERF_OK) {
        char prefix[4200];
        snprintf(prefix, sizeof prefix, "mask of %s", photo);
        return nerf__error_prefix(rc, prefix);
    }
    const size_t per_image = (size_t)ds->width * ds->height;
    if (w != ds->src_width || h != ds->src_height) {
        rc = nerf__error(NERF_EFORMAT, "%s: mask is %ux%u but its photo %s "
                         "is %ux%u", path, (unsigned)w, (unsigned)h, photo,
                         (unsigned)ds->src_width, (unsigned)ds->src_height);
    } else if (ds->mask == NULL) {
        /* No overflow: first_image() checked per_image * 3 * count. */
        ds->mask = nerf__alloc(&ds->env, per_image * ds->count);
        if (ds->mask == NULL) {
            rc = nerf__error_prefix(NERF_ENOMEM, path);
        } else {
            memset(ds->mask, 1, per_image * ds->count);
        }
    }
    if (rc == NERF_OK) {
        mask_box(rgba, w, factor, ds->width, ds->height, rule,
                 ds->mask + per_image * index);
    }
    nerf__free(&ds->env, rgba);
    return rc;
}

int nerf__dataset_check_mask(const nerf_dataset *ds, const char *path,
                             const char *photo)
{
    uint32_t w, h;
    int rc = nerf__image_read_size(&ds->env, path, &w, &h);
    if (rc != NERF_OK) {
        char prefix[4200];
        snprintf(prefix, sizeof prefix, "mask of %s", photo);
        return nerf__error_prefix(rc, prefix);
    }
    if (w != ds->src_width || h != ds->src_height) {
        return nerf__error(NERF_EFORMAT, "%s: mask is %ux%u but its photo %s "
                           "is %ux%u", path, (unsigned)w, (unsigned)h, photo,
                           (unsigned)ds->src_width, (unsigned)ds->src_height);
    }
    return NERF_OK;
}
