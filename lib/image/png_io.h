/*
 * PNG files through libpng's simplified API.  This pair is the only place
 * in libnerf that includes <png.h>; everything else sees float or 8-bit
 * pixel arrays.  Every error message starts with the path.
 */
#ifndef NERF_IMAGE_PNG_IO_H
#define NERF_IMAGE_PNG_IO_H

#include <stdint.h>
#include <stdio.h>

#include "env.h"

/* Largest width or height accepted on read and write. */
#define NERF__PNG_MAX_SIDE 16384u

/*
 * Read any PNG (gray, gray+alpha, RGB, RGBA, palette; 8 or 16 bits) into
 * width x height x 4 floats in [0, 1], row-major RGBA with straight (not
 * premultiplied) alpha; opaque files get alpha 1.  The buffer comes from
 * env (free with nerf__free).
 *
 * 8-bit files keep their stored values (v / 255).  16-bit files are read
 * through libpng's linear format: without a gAMA/sRGB chunk that is the
 * stored v / 65535; with one, libpng converts to linear light.
 *
 * The header is judged before any pixel is allocated: a side above
 * NERF__PNG_MAX_SIDE, or more pixels than the file's size can hold (a
 * pixel takes at least 1 bit, deflated at most NERF__DEFLATE_MAX_RATIO
 * times), is refused.
 *
 * Returns NERF_OK; NERF_ENOENT; NERF_EUNRECOGNISED (not a regular file:
 * nerf__file_open_read); NERF_EIO (cannot open or read); NERF_EFORMAT
 * (not a PNG, truncated, corrupted, too large, or a header claiming more
 * than the file holds); NERF_ENOMEM.
 */
int nerf__png_read_rgba(const nerf__env *env, const char *path,
                        uint32_t *width_out, uint32_t *height_out,
                        float **rgba_out);

/* As nerf__png_read_rgba, from f, open on the file_size bytes of path. */
int nerf__png_stream_read_rgba(const nerf__env *env, const char *path,
                               FILE *f, uint64_t file_size,
                               uint32_t *width_out, uint32_t *height_out,
                               float **rgba_out);

/*
 * The width and height of the PNG open as f, from its header alone (read
 * up to the image data, which is not decoded), judged as
 * nerf__png_read_rgba judges them.  Returns as it does.
 */
int nerf__png_stream_size(const char *path, FILE *f, uint64_t file_size,
                          uint32_t *width_out, uint32_t *height_out);

/*
 * Encode width x height pixels of channels (1 gray, 3 RGB, 4 RGBA) 8-bit
 * samples, row-major and interleaved, and write them to path atomically
 * (temporary file beside it, then rename).
 * Returns NERF_OK; NERF_EINVAL; NERF_EIO; NERF_ENOMEM.
 */
int nerf__png_write8(const nerf__env *env, const char *path, uint32_t width,
                     uint32_t height, uint32_t channels,
                     const uint8_t *pixels);

#endif
