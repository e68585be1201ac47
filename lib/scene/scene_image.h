/*
 * The files the scene writer stores its views in: RGBA PNG (the Blender
 * scenes' form) or RGB JPEG (a camera's), per nerf_scene_options.
 */
#ifndef NERF_SCENE_SCENE_IMAGE_H
#define NERF_SCENE_SCENE_IMAGE_H

#include <stdbool.h>
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

/* Whether view i of split (0 train) has the occluder painted into it
 * (nerf_scene_options.occluders). */
bool nerf__scene_occluded(const nerf_scene_options *o, int split, uint32_t i);

/*
 * Paint view i's occluder into px (channels 3 or 4, opaque in both) and
 * its mask into mask (width x height bytes, 0 where the disc is, 255
 * elsewhere: the nerfstudio and COLMAP convention), either may be NULL.
 */
void nerf__scene_paint_occluder(const nerf_scene_options *o, uint32_t i,
                                uint32_t channels, uint8_t *px,
                                uint8_t *mask);

/* Write a width x height mask of the options' size as a grey PNG at
 * path. */
int nerf__scene_mask_write(const nerf__env *env, const char *path,
                           const nerf_scene_options *o, const uint8_t *mask);

#endif
