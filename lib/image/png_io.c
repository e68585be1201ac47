#include "png_io.h"

#include <png.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "deflate_bound.h"
#include "file_io.h"

/*
 * libpng's message is the only detail we have; an empty one (which the
 * simplified API should never leave) still gets a readable sentence.
 */
static const char *png_message(const png_image *img)
{
    return img->message[0] != '\0' ? img->message : "unknown libpng error";
}

/*
 * A libpng failure on a stream that reported a read error is an I/O
 * problem; anything else means the bytes themselves are bad.
 */
static int read_failure(const char *path, FILE *f, const png_image *img)
{
    if (ferror(f)) {
        return nerf__error(NERF_EIO, "%s: read error (%s)", path,
                           png_message(img));
    }
    return nerf__error(NERF_EFORMAT, "%s: not a valid PNG file: %s", path,
                       png_message(img));
}

/* A true division: the result is the float nearest k / 255, which
 * callers can compare exactly. */
static void to_float_8bit(const uint8_t *src, size_t n, float *dst)
{
    for (size_t i = 0; i < n; i++) {
        dst[i] = (float)src[i] / 255.0f;
    }
}

/*
 * libpng hands linear data back with associated (premultiplied) alpha;
 * divide it out so that both bit depths give the same straight-alpha
 * layout.  Fully transparent pixels have no recoverable colour: 0.
 */
static void to_float_16bit(const uint16_t *src, size_t pixels, float *dst)
{
    for (size_t p = 0; p < pixels; p++) {
        const uint16_t *s = src + 4 * p;
        float *d = dst + 4 * p;
        double a = s[3];
        for (int c = 0; c < 3; c++) {
            double v = a > 0.0 ? s[c] / a : 0.0;
            d[c] = (float)(v > 1.0 ? 1.0 : v);
        }
        d[3] = (float)(a / 65535.0);
    }
}

/* Decode an image whose header is already in img; frees img's state. */
static int decode(const nerf__env *env, const char *path, FILE *f,
                  png_image *img, float **rgba_out)
{
    bool linear = (img->format & PNG_FORMAT_FLAG_LINEAR) != 0;
    img->format = linear ? PNG_FORMAT_LINEAR_RGB_ALPHA : PNG_FORMAT_RGBA;
    size_t pixels = (size_t)img->width * img->height;
    size_t raw_size = pixels * 4 * (linear ? 2 : 1);
    void *raw = nerf__alloc(env, raw_size);
    float *rgba = raw ? nerf__calloc(env, pixels * 4, sizeof *rgba) : NULL;
    if (rgba == NULL) {
        png_image_free(img);
        nerf__free(env, raw);
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    if (!png_image_finish_read(img, NULL, raw, 0, NULL)) {
        int rc = read_failure(path, f, img);
        png_image_free(img);
        nerf__free(env, raw);
        nerf__free(env, rgba);
        return rc;
    }
    if (img->warning_or_error & PNG_IMAGE_WARNING) {
        nerf__log(env, NERF_LOG_WARN, "%s: libpng: %s", path,
                  png_message(img));
    }
    if (linear) {
        to_float_16bit(raw, pixels, rgba);
    } else {
        to_float_8bit(raw, pixels * 4, rgba);
    }
    nerf__free(env, raw);
    *rgba_out = rgba;
    return NERF_OK;
}

/*
 * The least a PNG of w x h pixels can take: a pixel is at least 1 bit
 * (gray or palette at bit depth 1; the filter byte of each row left out),
 * and deflate packs at most NERF__DEFLATE_MAX_RATIO bytes into one.
 */
static uint64_t png_min_bytes(uint32_t w, uint32_t h)
{
    return (uint64_t)w * h / 8 / NERF__DEFLATE_MAX_RATIO;
}

/*
 * Read the header of the PNG open as f (file_size bytes) into img, and
 * refuse a size above the limit or more pixels than the file can hold,
 * before anything is allocated for them.  On failure img is freed.
 */
static int begin(const char *path, FILE *f, uint64_t file_size,
                 png_image *img)
{
    memset(img, 0, sizeof *img);
    img->version = PNG_IMAGE_VERSION;
    int rc = NERF_OK;
    if (!png_image_begin_read_from_stdio(img, f)) {
        rc = read_failure(path, f, img);
    } else if (img->width == 0 || img->height == 0 ||
               img->width > NERF__PNG_MAX_SIDE ||
               img->height > NERF__PNG_MAX_SIDE) {
        rc = nerf__error(NERF_EFORMAT, "%s: image is %ux%u pixels; the "
                         "limit is %u per side", path, (unsigned)img->width,
                         (unsigned)img->height, NERF__PNG_MAX_SIDE);
    } else if (file_size < png_min_bytes(img->width, img->height)) {
        rc = nerf__error(NERF_EFORMAT, "%s: the header claims %ux%u pixels, "
                         "more than its %llu bytes can hold (a PNG of that "
                         "size takes at least %llu)", path,
                         (unsigned)img->width, (unsigned)img->height,
                         (unsigned long long)file_size,
                         (unsigned long long)png_min_bytes(img->width,
                                                           img->height));
    }
    if (rc != NERF_OK) {
        png_image_free(img);
    }
    return rc;
}

int nerf__png_stream_size(const char *path, FILE *f, uint64_t file_size,
                          uint32_t *width_out, uint32_t *height_out)
{
    png_image img;
    int rc = begin(path, f, file_size, &img);
    if (rc == NERF_OK) {
        *width_out = img.width;
        *height_out = img.height;
        png_image_free(&img);
    }
    return rc;
}

int nerf__png_stream_read_rgba(const nerf__env *env, const char *path,
                               FILE *f, uint64_t file_size,
                               uint32_t *width_out, uint32_t *height_out,
                               float **rgba_out)
{
    *rgba_out = NULL;
    *width_out = 0;
    *height_out = 0;
    png_image img;
    int rc = begin(path, f, file_size, &img);
    if (rc == NERF_OK) {
        uint32_t w = img.width, h = img.height;
        rc = decode(env, path, f, &img, rgba_out);
        if (rc == NERF_OK) {
            *width_out = w;
            *height_out = h;
        }
    }
    return rc;
}

int nerf__png_read_rgba(const nerf__env *env, const char *path,
                        uint32_t *width_out, uint32_t *height_out,
                        float **rgba_out)
{
    *rgba_out = NULL;
    *width_out = 0;
    *height_out = 0;
    FILE *f;
    uint64_t size;
    int rc = nerf__file_fopen_read(path, &f, &size);
    if (rc == NERF_OK) {
        rc = nerf__png_stream_read_rgba(env, path, f, size, width_out,
                                        height_out, rgba_out);
        fclose(f);
    }
    return rc;
}

int nerf__png_write8(const nerf__env *env, const char *path, uint32_t width,
                     uint32_t height, uint32_t channels,
                     const uint8_t *pixels)
{
    if (path == NULL || pixels == NULL) {
        return nerf__error(NERF_EINVAL, "PNG write: NULL path or pixels");
    }
    if (width == 0 || height == 0 || width > NERF__PNG_MAX_SIDE ||
        height > NERF__PNG_MAX_SIDE) {
        return nerf__error(NERF_EINVAL, "%s: cannot write a %ux%u image "
                           "(each side must be 1..%u)", path,
                           (unsigned)width, (unsigned)height,
                           NERF__PNG_MAX_SIDE);
    }
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    img.width = width;
    img.height = height;
    switch (channels) {
    case 1: img.format = PNG_FORMAT_GRAY; break;
    case 3: img.format = PNG_FORMAT_RGB; break;
    case 4: img.format = PNG_FORMAT_RGBA; break;
    default:
        return nerf__error(NERF_EINVAL, "%s: cannot write %u channels "
                           "(1, 3 or 4)", path, (unsigned)channels);
    }
    /*
     * Encode to memory first: the atomic writer then owns all file
     * handling, and a failed encode never touches the disk.
     */
    png_alloc_size_t size = 0;
    if (!png_image_write_get_memory_size(img, size, 0, pixels, 0, NULL)) {
        int rc = nerf__error(NERF_ERROR, "%s: PNG encoding failed: %s", path,
                             png_message(&img));
        png_image_free(&img);
        return rc;
    }
    void *buf = nerf__alloc(env, size);
    if (buf == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    if (!png_image_write_to_memory(&img, buf, &size, 0, pixels, 0, NULL)) {
        int rc = nerf__error(NERF_ERROR, "%s: PNG encoding failed: %s", path,
                             png_message(&img));
        png_image_free(&img);
        nerf__free(env, buf);
        return rc;
    }
    nerf__span span = {buf, size};
    int rc = nerf__file_write_atomic(env, path, &span, 1);
    nerf__free(env, buf);
    return rc;
}
