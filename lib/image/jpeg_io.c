#include "jpeg_io.h"

#include <setjmp.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>
#include <jerror.h>

#include "exif.h"
#include "file_io.h"
#include "png_io.h"

/*
 * libjpeg reports errors by calling error_exit, which must not return:
 * we jump back to the function that started the work, after turning the
 * message into text.  Its warnings go through emit_message.
 */
typedef struct jpeg_fail {
    struct jpeg_error_mgr pub;
    jmp_buf jump;
    const nerf__env *env;
    const char *path;
    bool warning; /* the jump came from a corrupt-data warning */
    char message[JMSG_LENGTH_MAX];
} jpeg_fail;

static void on_error(j_common_ptr cinfo)
{
    jpeg_fail *f = (jpeg_fail *)cinfo->err;
    cinfo->err->format_message(cinfo, f->message);
    f->warning = false;
    longjmp(f->jump, 1);
}

/*
 * Warnings about the data (a premature end, a bad Huffman or arithmetic
 * code, a marker inside entropy data) mean libjpeg went on with made-up
 * pixels (grey for a truncated file): for training data that is an error.
 * Header oddities that leave the pixels alone are only logged.
 */
static void on_message(j_common_ptr cinfo, int level)
{
    if (level >= 0) {
        return; /* trace messages */
    }
    jpeg_fail *f = (jpeg_fail *)cinfo->err;
    cinfo->err->format_message(cinfo, f->message);
    switch (cinfo->err->msg_code) {
    case JWRN_ADOBE_XFORM:
    case JWRN_EXTRANEOUS_DATA:
    case JWRN_JFIF_MAJOR:
    case JWRN_BOGUS_ICC:
        nerf__log(f->env, NERF_LOG_WARN, "%s: libjpeg: %s", f->path,
                  f->message);
        return;
    default:
        f->warning = true;
        longjmp(f->jump, 1);
    }
}

static void fail_init(jpeg_fail *f, const nerf__env *env, const char *path)
{
    memset(f, 0, sizeof *f);
    jpeg_std_error(&f->pub);
    f->pub.error_exit = on_error;
    f->pub.emit_message = on_message;
    f->env = env;
    f->path = path;
}

/*
 * Everything a decode owns, kept by the caller of the function that calls
 * setjmp: after a longjmp these are still valid (a local of the jumping
 * function changed after setjmp would not be).
 */
typedef struct decode_state {
    struct jpeg_decompress_struct cinfo;
    jpeg_fail fail;
    bool created;
    uint8_t *rgb; /* the stored (not yet oriented) pixels */
    float *rgba;
    uint32_t orientation;
} decode_state;

static int exif_orientation(const char *path, decode_state *s)
{
    s->orientation = 1;
    for (jpeg_saved_marker_ptr m = s->cinfo.marker_list; m; m = m->next) {
        if (m->marker != JPEG_APP0 + 1 ||
            !nerf__exif_is_exif(m->data, m->data_length)) {
            continue;
        }
        char why[160];
        if (nerf__exif_orientation(m->data, m->data_length, &s->orientation,
                                   why, sizeof why) != 0) {
            return nerf__error(NERF_EFORMAT, "%s: %s", path, why);
        }
        return NERF_OK; /* the first Exif block is the camera's */
    }
    return NERF_OK;
}

/*
 * Where upright pixel (x, y) of a w x h picture comes from in the stored
 * image of sw x sh pixels, for each Exif orientation: 2 mirrors left-right,
 * 3 turns half way, 4 mirrors top-bottom, 5 transposes, 6 is stored turned
 * a quarter counter-clockwise (shown turned clockwise), 7 is the
 * transverse, 8 is stored turned clockwise.
 */
static size_t source_pixel(uint32_t orientation, uint32_t x, uint32_t y,
                           uint32_t sw, uint32_t sh)
{
    uint32_t sx, sy;
    switch (orientation) {
    case 2: sx = sw - 1 - x; sy = y; break;
    case 3: sx = sw - 1 - x; sy = sh - 1 - y; break;
    case 4: sx = x; sy = sh - 1 - y; break;
    case 5: sx = y; sy = x; break;
    case 6: sx = y; sy = sh - 1 - x; break;
    case 7: sx = sw - 1 - y; sy = sh - 1 - x; break;
    case 8: sx = sw - 1 - y; sy = x; break;
    default: sx = x; sy = y; break;
    }
    return (size_t)sy * sw + sx;
}

static void orient(const uint8_t *rgb, uint32_t sw, uint32_t sh,
                   uint32_t orientation, float *rgba)
{
    bool swap = orientation >= 5;
    uint32_t w = swap ? sh : sw, h = swap ? sw : sh;
    for (uint32_t y = 0; y < h; y++) {
        for (uint32_t x = 0; x < w; x++) {
            const uint8_t *s = rgb + 3 * source_pixel(orientation, x, y,
                                                      sw, sh);
            float *d = rgba + 4 * ((size_t)y * w + x);
            for (int c = 0; c < 3; c++) {
                d[c] = (float)s[c] / 255.0f;
            }
            d[3] = 1.0f;
        }
    }
}

/*
 * The least a JPEG with the blocks of c's components can take.  Huffman
 * coding spends at least 1 bit on every 8x8 block of every component (its
 * DC difference: no Huffman code is shorter), so blocks / 8 bytes.
 * Arithmetic coding spends less on a decision it has learnt to expect,
 * but not nothing: T.81's least probability estimate is Qe = 1 in an
 * interval of at most 0x10000, so a decision costs at least
 * -log2(1 - 2^-16) > 1 / 45426 bit, and a block takes at least one.
 */
static uint64_t jpeg_min_bytes(const struct jpeg_decompress_struct *c)
{
    uint64_t blocks = 0;
    for (int i = 0; i < c->num_components; i++) {
        blocks += (uint64_t)c->comp_info[i].width_in_blocks *
                  c->comp_info[i].height_in_blocks;
    }
    return c->arith_code ? blocks / (8u * 45426u) : blocks / 8u;
}

/*
 * The header up to the first scan, judged before anything is allocated
 * for the pixels: colour space, size, pixels the file can hold, and the
 * Exif orientation.  Runs under the caller's setjmp.
 */
static int read_header(const char *path, uint64_t file_size,
                       decode_state *s)
{
    struct jpeg_decompress_struct *c = &s->cinfo;
    jpeg_save_markers(c, JPEG_APP0 + 1, 0xFFFF);
    jpeg_read_header(c, TRUE);
    if (c->jpeg_color_space == JCS_CMYK || c->jpeg_color_space == JCS_YCCK) {
        return nerf__error(NERF_EFORMAT, "%s: CMYK JPEGs are not supported "
                           "(convert the file to RGB)", path);
    }
    if (c->image_width == 0 || c->image_height == 0 ||
        c->image_width > NERF__PNG_MAX_SIDE ||
        c->image_height > NERF__PNG_MAX_SIDE) {
        return nerf__error(NERF_EFORMAT, "%s: image is %ux%u pixels; the "
                           "limit is %u per side", path,
                           (unsigned)c->image_width,
                           (unsigned)c->image_height, NERF__PNG_MAX_SIDE);
    }
    uint64_t least = jpeg_min_bytes(c);
    if (file_size < least) {
        return nerf__error(NERF_EFORMAT, "%s: the header claims %ux%u "
                           "pixels, more than its %llu bytes can hold (a "
                           "JPEG of that size takes at least %llu)", path,
                           (unsigned)c->image_width,
                           (unsigned)c->image_height,
                           (unsigned long long)file_size,
                           (unsigned long long)least);
    }
    return exif_orientation(path, s);
}

/* The message of a libjpeg failure that jumped back to setjmp. */
static int jpeg_failure(const char *path, const decode_state *s)
{
    return nerf__error(NERF_EFORMAT, s->fail.warning
                       ? "%s: corrupted or truncated JPEG: %s"
                       : "%s: not a valid JPEG file: %s",
                       path, s->fail.message);
}

static int decode(const nerf__env *env, const char *path,
                  const uint8_t *data, size_t size, decode_state *s)
{
    if (setjmp(s->fail.jump)) {
        return jpeg_failure(path, s);
    }
    s->cinfo.err = &s->fail.pub;
    jpeg_create_decompress(&s->cinfo);
    s->created = true;
    jpeg_mem_src(&s->cinfo, data, (unsigned long)size);
    int rc = read_header(path, size, s);
    if (rc != NERF_OK) {
        return rc;
    }
    struct jpeg_decompress_struct *c = &s->cinfo;
    c->out_color_space = JCS_RGB;
    jpeg_start_decompress(c);
    if (c->output_components != 3) {
        return nerf__error(NERF_EFORMAT, "%s: JPEG decodes to %d components, "
                           "not RGB", path, c->output_components);
    }
    uint32_t w = c->output_width, h = c->output_height;
    size_t pixels = (size_t)w * h;
    s->rgb = nerf__alloc(env, pixels * 3);
    s->rgba = s->rgb ? nerf__alloc(env, pixels * 4 * sizeof *s->rgba) : NULL;
    if (s->rgba == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    while (c->output_scanline < h) {
        JSAMPROW row = s->rgb + (size_t)c->output_scanline * w * 3;
        jpeg_read_scanlines(c, &row, 1);
    }
    jpeg_finish_decompress(c);
    orient(s->rgb, w, h, s->orientation, s->rgba);
    return NERF_OK;
}

/* The upright size of the header read into s. */
static void upright_size(const decode_state *s, uint32_t *width_out,
                         uint32_t *height_out)
{
    bool swap = s->orientation >= 5;
    *width_out = swap ? s->cinfo.image_height : s->cinfo.image_width;
    *height_out = swap ? s->cinfo.image_width : s->cinfo.image_height;
}

int nerf__jpeg_decode_rgba(const nerf__env *env, const char *path,
                           const uint8_t *data, size_t size,
                           uint32_t *width_out, uint32_t *height_out,
                           float **rgba_out)
{
    *rgba_out = NULL;
    *width_out = 0;
    *height_out = 0;
    decode_state *s = nerf__calloc(env, 1, sizeof *s);
    if (s == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    fail_init(&s->fail, env, path);
    int rc = decode(env, path, data, size, s);
    if (rc == NERF_OK) {
        upright_size(s, width_out, height_out);
        *rgba_out = s->rgba;
        s->rgba = NULL;
    }
    if (s->created) {
        jpeg_destroy_decompress(&s->cinfo);
    }
    nerf__free(env, s->rgb);
    nerf__free(env, s->rgba);
    nerf__free(env, s);
    return rc;
}

static int header_only(const char *path, FILE *f, uint64_t file_size,
                       decode_state *s)
{
    if (setjmp(s->fail.jump)) {
        return jpeg_failure(path, s);
    }
    s->cinfo.err = &s->fail.pub;
    jpeg_create_decompress(&s->cinfo);
    s->created = true;
    jpeg_stdio_src(&s->cinfo, f);
    return read_header(path, file_size, s);
}

int nerf__jpeg_stream_size(const nerf__env *env, const char *path, FILE *f,
                           uint64_t file_size, uint32_t *width_out,
                           uint32_t *height_out)
{
    *width_out = 0;
    *height_out = 0;
    decode_state *s = nerf__calloc(env, 1, sizeof *s);
    if (s == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    fail_init(&s->fail, env, path);
    int rc = header_only(path, f, file_size, s);
    if (rc == NERF_OK) {
        upright_size(s, width_out, height_out);
    }
    if (s->created) {
        jpeg_destroy_decompress(&s->cinfo);
    }
    nerf__free(env, s);
    return rc;
}

int nerf__jpeg_read_rgba(const nerf__env *env, const char *path,
                         uint32_t *width_out, uint32_t *height_out,
                         float **rgba_out)
{
    *rgba_out = NULL;
    *width_out = 0;
    *height_out = 0;
    unsigned char *data = NULL;
    size_t size = 0;
    int rc = nerf__file_read(env, path, NERF__JPEG_MAX_FILE_SIZE, &data,
                             &size);
    if (rc == NERF_OK) {
        rc = nerf__jpeg_decode_rgba(env, path, data, size, width_out,
                                    height_out, rgba_out);
    }
    nerf__free(env, data);
    return rc;
}

/* As decode_state, for an encode. */
typedef struct encode_state {
    struct jpeg_compress_struct cinfo;
    jpeg_fail fail;
    bool created;
    unsigned char *out; /* malloc'd by libjpeg's memory destination */
    unsigned long out_size;
} encode_state;

static int encode(const char *path, uint32_t width, uint32_t height,
                  uint32_t channels, const uint8_t *pixels, uint32_t quality,
                  encode_state *s)
{
    if (setjmp(s->fail.jump)) {
        return nerf__error(NERF_ERROR, "%s: JPEG encoding failed: %s", path,
                           s->fail.message);
    }
    s->cinfo.err = &s->fail.pub;
    jpeg_create_compress(&s->cinfo);
    s->created = true;
    struct jpeg_compress_struct *c = &s->cinfo;
    jpeg_mem_dest(c, &s->out, &s->out_size);
    c->image_width = width;
    c->image_height = height;
    c->input_components = (int)channels;
    c->in_color_space = channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
    jpeg_set_defaults(c);
    jpeg_set_quality(c, (int)quality, TRUE);
    if (quality >= 90) {
        /* Full-resolution colour: at high quality, halving the chroma
         * would be the largest error left (coloured edges bleed). */
        for (int i = 0; i < c->num_components; i++) {
            c->comp_info[i].h_samp_factor = 1;
            c->comp_info[i].v_samp_factor = 1;
        }
    }
    jpeg_start_compress(c, TRUE);
    while (c->next_scanline < height) {
        /* libjpeg's prototype is not const, but it only reads the rows. */
        JSAMPROW row = (JSAMPROW)(uintptr_t)(pixels + (size_t)c->next_scanline *
                                             width * channels);
        jpeg_write_scanlines(c, &row, 1);
    }
    jpeg_finish_compress(c);
    return NERF_OK;
}

int nerf__jpeg_write8(const nerf__env *env, const char *path, uint32_t width,
                      uint32_t height, uint32_t channels,
                      const uint8_t *pixels, uint32_t quality)
{
    if (path == NULL || pixels == NULL) {
        return nerf__error(NERF_EINVAL, "JPEG write: NULL path or pixels");
    }
    if (width == 0 || height == 0 || width > NERF__PNG_MAX_SIDE ||
        height > NERF__PNG_MAX_SIDE) {
        return nerf__error(NERF_EINVAL, "%s: cannot write a %ux%u image "
                           "(each side must be 1..%u)", path,
                           (unsigned)width, (unsigned)height,
                           NERF__PNG_MAX_SIDE);
    }
    if (channels != 1 && channels != 3) {
        return nerf__error(NERF_EINVAL, "%s: cannot write %u channels as "
                           "JPEG (1 or 3)", path, (unsigned)channels);
    }
    if (quality > 100) {
        return nerf__error(NERF_EINVAL, "%s: JPEG quality %u is outside "
                           "1..100", path, (unsigned)quality);
    }
    if (quality == 0) {
        quality = NERF__JPEG_DEFAULT_QUALITY;
    }
    encode_state *s = nerf__calloc(env, 1, sizeof *s);
    if (s == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    fail_init(&s->fail, env, path);
    int rc = encode(path, width, height, channels, pixels, quality, s);
    if (rc == NERF_OK) {
        nerf__span span = {s->out, s->out_size};
        rc = nerf__file_write_atomic(env, path, &span, 1);
    }
    if (s->created) {
        jpeg_destroy_compress(&s->cinfo);
    }
    free(s->out);
    nerf__free(env, s);
    return rc;
}
