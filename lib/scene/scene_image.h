/*
 * The files the scene writer stores its views in: RGBA PNG (the Blender
 * scenes' form) or RGB JPEG (a camera's), per nerf_scene_options.
 */
#ifndef NERF_SCENE_SCENE_IMAGE_H
#define NERF_SCENE_SCENE_IMAGE_H

#include <stdint.h>

#include "env.h"

/* NERF_EINVAL with a message for a bad image_format or jpeg_quality. */
int nerf__scene_image_check(const nerf_scene_options *o);

/* What file_path ends with: "" for PNG (bare, as the Blender scenes
 * write it, so that PNG output stays byte for byte what it was), ".jpg". */
const char *nerf__scene_image_suffix(const nerf_scene_options *o);

/* The extension of the files: ".png" or ".jpg". */
const char *nerf__scene_image_extension(const nerf_scene_options *o);

/*
 * Write one width x height view of 8-bit RGB or straight RGBA (channels 3
 * or 4) to stem plus the format's extension, atomically.  JPEG has no
 * alpha: RGBA is composited on white, as the Blender loader does by
 * default.
 */
int nerf__scene_image_write(const nerf__env *env, const char *stem,
                            const nerf_scene_options *o, uint32_t channels,
                            const uint8_t *px);

#endif
