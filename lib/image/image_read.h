/*
 * The one way the loaders read a picture: PNG or JPEG, told apart by the
 * file's first bytes (not its name, which photo folders get wrong).
 */
#ifndef NERF_IMAGE_IMAGE_READ_H
#define NERF_IMAGE_IMAGE_READ_H

#include <stdint.h>

#include "env.h"

/*
 * Read the PNG (8 or 16 bits, any colour type; see nerf__png_read_rgba)
 * or JPEG (upright by its Exif orientation; see nerf__jpeg_read_rgba) at
 * path into width x height x 4 floats in [0, 1], row-major RGBA with
 * straight alpha (1 for JPEG).  The buffer comes from env.
 * Returns NERF_OK; NERF_ENOENT; NERF_EUNRECOGNISED (not a regular file:
 * a folder, a FIFO, a device, ...: refused without blocking); NERF_EIO;
 * NERF_EFORMAT ("not a PNG or JPEG file", truncated, corrupted, a header
 * claiming more pixels than the file holds, ...); NERF_ENOMEM.  Messages
 * start with the path.
 */
int nerf__image_read_rgba(const nerf__env *env, const char *path,
                          uint32_t *width_out, uint32_t *height_out,
                          float **rgba_out);

/*
 * The width and height nerf__image_read_rgba would give for path, from
 * the file's header alone: the checks it makes before decoding any pixel
 * (a regular file, PNG or JPEG, a header that decodes, with its Exif
 * orientation, within the size limits and the file's size), for a fraction
 * of the cost.  Returns as nerf__image_read_rgba.
 */
int nerf__image_read_size(const nerf__env *env, const char *path,
                          uint32_t *width_out, uint32_t *height_out);

#endif
