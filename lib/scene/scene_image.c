#include "scene_image.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>

#include "jpeg_io.h"
#include "png_io.h"

int nerf__scene_image_check(const nerf_scene_options *o)
{
    if (o->image_format != NERF_IMAGE_FORMAT_PNG &&
        o->image_format != NERF_IMAGE_FORMAT_JPEG) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: image_format %u "
                           "is not NERF_IMAGE_FORMAT_PNG or _JPEG",
                           (unsigned)o->image_format);
    }
    if (o->jpeg_quality > 100) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: jpeg_quality %u "
                           "is outside 1..100 (0 = default)",
                           (unsigned)o->jpeg_quality);
    }
    return NERF_OK;
}

const char *nerf__scene_image_suffix(const nerf_scene_options *o)
{
    return o->image_format == NERF_IMAGE_FORMAT_JPEG ? ".jpg" : "";
}

/* c a + 255 (1 - a) in 8-bit arithmetic, rounded. */
static uint8_t over_white(uint8_t c, uint8_t a)
{
    return (uint8_t)(((unsigned)c * a + 255u * (255u - a) + 127u) / 255u);
}

const char *nerf__scene_image_extension(const nerf_scene_options *o)
{
    return o->image_format == NERF_IMAGE_FORMAT_JPEG ? ".jpg" : ".png";
}

int nerf__scene_image_write(const nerf__env *env, const char *stem,
                            const nerf_scene_options *o, uint32_t channels,
                            const uint8_t *px)
{
    char path[4200];
    bool jpeg = o->image_format == NERF_IMAGE_FORMAT_JPEG;
    snprintf(path, sizeof path, "%s%s", stem, nerf__scene_image_extension(o));
    if (!jpeg || channels == 3) {
        return jpeg ? nerf__jpeg_write8(env, path, o->width, o->height, 3, px,
                                        o->jpeg_quality)
                    : nerf__png_write8(env, path, o->width, o->height,
                                       channels, px);
    }
    const uint8_t *rgba = px;
    size_t pixels = (size_t)o->width * o->height;
    uint8_t *rgb = nerf__alloc(env, pixels * 3);
    if (rgb == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    for (size_t i = 0; i < pixels; i++) {
        for (int c = 0; c < 3; c++) {
            rgb[3 * i + c] = over_white(rgba[4 * i + c], rgba[4 * i + 3]);
        }
    }
    int rc = nerf__jpeg_write8(env, path, o->width, o->height, 3, rgb,
                               o->jpeg_quality);
    nerf__free(env, rgb);
    return rc;
}

bool nerf__scene_occluded(const nerf_scene_options *o, int split, uint32_t i)
{
    return o->occluders != 0 && split == 0 && i % 2 == 0;
}

void nerf__scene_paint_occluder(const nerf_scene_options *o, uint32_t i,
                                uint32_t channels, uint8_t *px,
                                uint8_t *mask)
{
    static const uint8_t colour[3] = {200, 30, 160};
    /* Golden-ratio steps spread the discs' places evenly over the middle
     * of the picture, where the solids are, whatever the view count. */
    const double fx = fmod(0.5 + i * 0.6180339887498949, 1.0);
    const double fy = fmod(0.5 + i * 0.7548776662466927, 1.0);
    const double side = o->width < o->height ? o->width : o->height;
    const double cx = o->width * (0.2 + 0.6 * fx);
    const double cy = o->height * (0.2 + 0.6 * fy);
    const double r = 0.2 * side;
    for (uint32_t y = 0; y < o->height; y++) {
        for (uint32_t x = 0; x < o->width; x++) {
            const double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
            const bool in = dx * dx + dy * dy <= r * r;
            const size_t at = (size_t)y * o->width + x;
            if (mask != NULL) {
                mask[at] = in ? 0 : 255;
            }
            if (in && px != NULL) {
                for (uint32_t c = 0; c < 3; c++) {
                    px[at * channels + c] = colour[c];
                }
                if (channels == 4) {
                    px[at * channels + 3] = 255;
                }
            }
        }
    }
}

int nerf__scene_mask_write(const nerf__env *env, const char *path,
                           const nerf_scene_options *o, const uint8_t *mask)
{
    return nerf__png_write8(env, path, o->width, o->height, 1, mask);
}
