/*
 * What the scene writer's layouts share: the cameras of the built-in
 * dataset, the renderer of a view and folder creation.
 */
#ifndef NERF_SCENE_SCENE_INTERNAL_H
#define NERF_SCENE_SCENE_INTERNAL_H

#include <stdint.h>

#include "env.h"

/* Pose of view i of n of a split (0 train, 1 val, 2 test): size and
 * intrinsics of cam are the caller's. */
void nerf__scene_place_camera(int split, uint32_t i, uint32_t n,
                              uint64_t seed, nerf_camera *cam);

/* Render cam (straight RGBA, 8 bits) with up to threads threads. */
void nerf__scene_render_view(const nerf_camera *cam, uint32_t threads,
                             uint8_t *rgba);

/* mkdir -p; NERF_EIO naming the folder that cannot be made. */
int nerf__scene_make_dir(const char *path);

/* The COLMAP layouts (write_colmap.c); rgba holds one view. */
int nerf__scene_write_colmap(const char *dir, const nerf_scene_options *o,
                             const nerf__env *env, uint8_t *rgba);

#endif
