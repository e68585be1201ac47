#include "scene_image.h"

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
