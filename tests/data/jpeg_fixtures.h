/*
 * JPEG test files written with libjpeg directly, not through libnerf, so
 * that the reader is checked against an independent writer: any colour
 * space, progressive or arithmetic coding, and an APP1 marker of the
 * test's choosing (Exif blocks built by fx_exif below).
 */
#ifndef NERF_TEST_JPEG_FIXTURES_H
#define NERF_TEST_JPEG_FIXTURES_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>

#define FX_JPEG_PROGRESSIVE 0x1
#define FX_JPEG_ARITHMETIC 0x2

/*
 * Write w x h pixels of `space` (JCS_RGB, JCS_GRAYSCALE, JCS_CMYK; that
 * many interleaved 8-bit samples each) at quality, full-resolution chroma
 * (so that solid 8x8 blocks decode to their colour), with app1[0..app1_n)
 * as an APP1 marker when app1_n > 0.  libjpeg's default error handler
 * exits the test on failure.
 */
static inline void fx_write_jpeg(const char *path, uint32_t w, uint32_t h,
                                 J_COLOR_SPACE space, const uint8_t *px,
                                 int quality, int flags, const uint8_t *app1,
                                 size_t app1_n)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        fprintf(stderr, "fx_write_jpeg: cannot create %s\n", path);
        exit(1);
    }
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr err;
    c.err = jpeg_std_error(&err);
    jpeg_create_compress(&c);
    jpeg_stdio_dest(&c, f);
    c.image_width = w;
    c.image_height = h;
    c.in_color_space = space;
    c.input_components = space == JCS_GRAYSCALE ? 1 : space == JCS_CMYK ? 4
                                                                        : 3;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, quality, TRUE);
    for (int i = 0; i < c.num_components; i++) {
        c.comp_info[i].h_samp_factor = 1;
        c.comp_info[i].v_samp_factor = 1;
    }
    if (flags & FX_JPEG_PROGRESSIVE) {
        jpeg_simple_progression(&c);
    }
    if (flags & FX_JPEG_ARITHMETIC) {
        c.arith_code = TRUE;
    }
    jpeg_start_compress(&c, TRUE);
    if (app1_n > 0) {
        jpeg_write_marker(&c, JPEG_APP0 + 1, app1, (unsigned)app1_n);
    }
    size_t stride = (size_t)w * (size_t)c.input_components;
    while (c.next_scanline < h) {
        JSAMPROW row = (JSAMPROW)(uintptr_t)(px + c.next_scanline * stride);
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    fclose(f);
}

/*
 * An Exif APP1 body into out (at least 64 bytes): "Exif\0\0", a TIFF
 * header in Intel (II) or Motorola (MM) byte order, and IFD0 with a Make
 * entry before an Orientation entry of the given type and value.
 * Returns its length.
 */
static inline size_t fx_exif(uint8_t *out, int big_endian,
                             uint32_t orientation, uint32_t type)
{
    size_t n = 0;
    memcpy(out, "Exif\0\0", 6);
    n = 6;
    uint8_t *t = out + n;
#define FX_PUT16(at, v)                                                     \
    do {                                                                    \
        uint32_t v_ = (v);                                                  \
        t[(at) + (big_endian ? 0 : 1)] = (uint8_t)(v_ >> 8);                \
        t[(at) + (big_endian ? 1 : 0)] = (uint8_t)v_;                       \
    } while (0)
#define FX_PUT32(at, v)                                                     \
    do {                                                                    \
        uint32_t w_ = (v);                                                  \
        FX_PUT16((at) + (big_endian ? 0 : 2), w_ >> 16);                    \
        FX_PUT16((at) + (big_endian ? 2 : 0), w_ & 0xffff);                 \
    } while (0)
    t[0] = t[1] = big_endian ? 'M' : 'I';
    FX_PUT16(2, 42);
    FX_PUT32(4, 8);         /* IFD0 right after the header */
    FX_PUT16(8, 2);         /* two entries */
    FX_PUT16(10, 0x010f);   /* Make, ASCII, 4 bytes inline */
    FX_PUT16(12, 2);
    FX_PUT32(14, 4);
    memcpy(t + 18, "cam", 4);
    FX_PUT16(22, 0x0112);   /* Orientation */
    FX_PUT16(24, type);
    FX_PUT32(26, 1);
    FX_PUT32(30, 0);
    FX_PUT16(30, orientation);
    FX_PUT32(34, 0);        /* no IFD1 */
#undef FX_PUT16
#undef FX_PUT32
    return n + 38;
}

#endif
