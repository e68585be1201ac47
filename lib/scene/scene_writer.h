/*
 * What the layouts of nerf_scene_write() share: the views' cameras and
 * renders, folders and JSON.  scene_writer.c writes the Blender layout,
 * each other layout has its own file.
 */
#ifndef NERF_SCENE_SCENE_WRITER_H
#define NERF_SCENE_SCENE_WRITER_H

#include <cJSON.h>
#include <stdbool.h>
#include <stdint.h>

#include "env.h"
#include "nerf.h"

/* "train", "val", "test": the splits, numbered 0..2. */
extern const char *const nerf__scene_split_names[3];

/* The camera of view i of n of a split (0..2): size, focal, lens, pose. */
void nerf__scene_camera(const nerf_scene_options *o, int split, uint32_t i,
                        uint32_t n, nerf_camera *cam);

/* Render a view into straight RGBA, rows split over up to threads
 * threads. */
void nerf__scene_render_view(const nerf_camera *cam, uint32_t threads,
                             uint8_t *rgba);

/* mkdir -p: the folder and any missing parents. */
int nerf__scene_make_dir(const char *path);

/* A 3x4 pose as a transform_matrix, 4 rows. */
cJSON *nerf__scene_matrix_json(const float c2w[12]);

/* Add k1, k2, p1, p2, k3 to obj: always, or only when one is non-zero. */
void nerf__scene_lens_json(cJSON *obj, const nerf_scene_options *o,
                           bool always);

/* Print root and write it to path atomically. */
int nerf__scene_write_json(const nerf__env *env, const char *path,
                           const cJSON *root);

/* NERF_SCENE_LAYOUT_TRANSFORMS into dir (which exists); rgba holds one
 * view. */
int nerf__scene_write_transforms(const char *dir, const nerf_scene_options *o,
                                 const nerf__env *env, uint8_t *rgba);

#endif
