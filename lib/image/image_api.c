/* The public image functions: thin checks around png_io and image_read. */
#include "env.h"
#include "image_read.h"
#include "png_io.h"

NERF_API void nerf_free(void *ptr)
{
    /* Buffers handed to callers come from the default environment. */
    nerf__free(NULL, ptr);
}

NERF_API int nerf_image_read_png(const char *path, uint32_t *width_out,
                                 uint32_t *height_out, float **rgba_out)
{
    if (rgba_out != NULL) {
        *rgba_out = NULL;
    }
    if (path == NULL || width_out == NULL || height_out == NULL ||
        rgba_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_image_read_png: NULL argument");
    }
    return nerf__png_read_rgba(NULL, path, width_out, height_out, rgba_out);
}

NERF_API int nerf_image_read(const char *path, uint32_t *width_out,
                             uint32_t *height_out, float **rgba_out)
{
    if (rgba_out != NULL) {
        *rgba_out = NULL;
    }
    if (path == NULL || width_out == NULL || height_out == NULL ||
        rgba_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_image_read: NULL argument");
    }
    return nerf__image_read_rgba(NULL, path, width_out, height_out, rgba_out);
}

NERF_API int nerf_image_write_png8(const char *path, uint32_t width,
                                   uint32_t height, uint32_t channels,
                                   const uint8_t *pixels)
{
    return nerf__png_write8(NULL, path, width, height, channels, pixels);
}

/* Round to the nearest 8-bit level; NaN becomes 0 rather than undefined. */
static uint8_t quantize(float v)
{
    if (!(v > 0.0f)) {
        return 0;
    }
    if (v >= 1.0f) {
        return 255;
    }
    return (uint8_t)(v * 255.0f + 0.5f);
}

NERF_API int nerf_image_write_png(const char *path, uint32_t width,
                                  uint32_t height, uint32_t channels,
                                  const float *pixels)
{
    if (path == NULL || pixels == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_image_write_png: NULL path or "
                           "pixels");
    }
    /* Let the 8-bit writer judge sizes and channels before we allocate. */
    if (width == 0 || height == 0 || width > NERF__PNG_MAX_SIDE ||
        height > NERF__PNG_MAX_SIDE ||
        (channels != 1 && channels != 3 && channels != 4)) {
        return nerf__png_write8(NULL, path, width, height, channels,
                                (const uint8_t *)pixels);
    }
    size_t n = (size_t)width * height * channels;
    uint8_t *bytes = nerf__alloc(NULL, n);
    if (bytes == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    for (size_t i = 0; i < n; i++) {
        bytes[i] = quantize(pixels[i]);
    }
    int rc = nerf__png_write8(NULL, path, width, height, channels, bytes);
    nerf__free(NULL, bytes);
    return rc;
}
