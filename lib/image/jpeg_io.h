/*
 * JPEG files through libjpeg-turbo.  This pair is the only place in
 * libnerf that includes <jpeglib.h>.  Every error message starts with the
 * path.
 */
#ifndef NERF_IMAGE_JPEG_IO_H
#define NERF_IMAGE_JPEG_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "env.h"

/* The default quality of nerf__jpeg_write8 and the scene writer. */
#define NERF__JPEG_DEFAULT_QUALITY 95u

/* Larger files are refused before they are read: no photo comes near. */
#define NERF__JPEG_MAX_FILE_SIZE ((uint64_t)1 << 30)

/*
 * Read a baseline, progressive or arithmetic-coded JPEG (YCbCr, RGB or
 * grayscale; CMYK and YCCK are refused) into width x height x 4 floats in
 * [0, 1], row-major RGBA with alpha 1, v / 255 of the decoded 8-bit
 * samples.  The Exif Orientation (APP1) is applied, so width and height
 * are those of the upright picture (swapped for orientations 5 to 8).
 * Corrupt-data warnings of libjpeg (a truncated file, a bad Huffman code)
 * are errors: the decoder would otherwise invent the missing pixels.  A
 * malformed Exif block or an Orientation outside 1..8 is an error, since
 * the upright picture cannot be known.  The buffer comes from env.
 *
 * The header is judged before any pixel is allocated: a side above
 * NERF__PNG_MAX_SIDE, or more 8x8 blocks than the file's size can hold
 * (at least 1 bit per block with Huffman coding, 1/45426 bit with
 * arithmetic coding), is refused.
 *
 * Returns NERF_OK; NERF_ENOENT; NERF_EUNRECOGNISED (not a regular file);
 * NERF_EIO (cannot open or read); NERF_EFORMAT (not a JPEG, truncated,
 * corrupted, CMYK, bad Exif, too large, a header claiming more than the
 * file holds); NERF_ENOMEM.
 */
int nerf__jpeg_read_rgba(const nerf__env *env, const char *path,
                         uint32_t *width_out, uint32_t *height_out,
                         float **rgba_out);

/* As nerf__jpeg_read_rgba, from size bytes already in memory. */
int nerf__jpeg_decode_rgba(const nerf__env *env, const char *path,
                           const uint8_t *data, size_t size,
                           uint32_t *width_out, uint32_t *height_out,
                           float **rgba_out);

/*
 * The upright width and height of the JPEG open as f (file_size bytes),
 * from its markers up to the first scan (no pixel is decoded), judged as
 * nerf__jpeg_read_rgba judges them.  Returns as it does.
 */
int nerf__jpeg_stream_size(const nerf__env *env, const char *path, FILE *f,
                           uint64_t file_size, uint32_t *width_out,
                           uint32_t *height_out);

/*
 * Encode width x height 8-bit samples of channels (1 gray, 3 RGB),
 * row-major and interleaved, at quality 1..100 (0 = the default) and write
 * them to path atomically.  JPEG has no alpha: callers composite first.
 * Returns NERF_OK; NERF_EINVAL; NERF_EIO; NERF_ENOMEM; NERF_ERROR.
 */
int nerf__jpeg_write8(const nerf__env *env, const char *path, uint32_t width,
                      uint32_t height, uint32_t channels,
                      const uint8_t *pixels, uint32_t quality);

#endif
