/*
 * What the parts of the scene writer share: rendering a view of the field,
 * the cameras of each capture, and the layouts written in files of their
 * own (scene_writer.c holds the options and the Blender layout).
 */
#ifndef NERF_SCENE_INTERNAL_H
#define NERF_SCENE_INTERNAL_H

#include <cJSON.h>
#include <stdbool.h>
#include <stdint.h>

#include "env.h"
#include "field.h"
#include "nerf.h"

/* How a capture looks at the field. */
typedef struct nerf__scene_look {
    nerf__scene_world world;
    float near, far;   /* the stretch of each camera ray integrated */
    uint32_t channels; /* 4: straight RGBA (the object); 3: opaque RGB */
} nerf__scene_look;

/* The look of the options' capture and texture (already checked). */
nerf__scene_look nerf__scene_look_of(const nerf_scene_options *o);

/*
 * Render one view into px (width x height x look->channels bytes) with up
 * to `threads` threads splitting its rows; zdepth (width x height floats,
 * or NULL) receives each pixel's expected depth along the optical axis.
 */
void nerf__scene_render_view(const nerf_camera *cam,
                             const nerf__scene_look *look, uint32_t threads,
                             uint8_t *px, float *zdepth);

/* mkdir -p: the folder and any missing parents. */
int nerf__scene_make_dir(const char *path);

/*
 * Camera i of n of a split (0 train, 1 val, 2 test) of a capture, with the
 * options' image size: FORWARD, UNBOUNDED and WALK (captures.c); OBJECT stays in
 * scene_writer.c.
 */
void nerf__scene_forward_camera(const nerf_scene_options *o, int split,
                                uint32_t i, uint32_t n, nerf_camera *cam);
void nerf__scene_unbounded_camera(const nerf_scene_options *o, int split,
                                  uint32_t i, uint32_t n, nerf_camera *cam);
void nerf__scene_walk_camera(const nerf_scene_options *o, int split,
                             uint32_t i, uint32_t n, nerf_camera *cam);

/* The horizontal field of view (radians) of FORWARD and UNBOUNDED. */
#define NERF__SCENE_WIDE_ANGLE_X 1.0

/* "train", "val", "test": the splits, numbered 0..2. */
extern const char *const nerf__scene_split_names[3];

/* A 3x4 pose as a transform_matrix, 4 rows. */
cJSON *nerf__scene_matrix_json(const float c2w[12]);

/* Add k1, k2, p1, p2, k3 to obj: always, or only when one is non-zero. */
void nerf__scene_lens_json(cJSON *obj, const nerf_scene_options *o,
                           bool always);

/* Print root and write it to path atomically. */
int nerf__scene_write_json(const nerf__env *env, const char *path,
                           const cJSON *root);

/* NERF_SCENE_LAYOUT_TRANSFORMS into dir (which exists); px holds one view
 * of 4 channels (scene_transforms.c). */
int nerf__scene_write_transforms(const char *dir, const nerf_scene_options *o,
                                 const nerf__env *env, uint8_t *px);

/* Camera i of n of a split of the options' capture, any of them, through
 * the options' lens. */
void nerf__scene_capture_camera(const nerf_scene_options *o, int split,
                                uint32_t i, uint32_t n, nerf_camera *cam);

/* nerf_scene_options.appearance (appearance_changes.c): the gains of the
 * channels of view i of a split (all 1 but for varied training views),
 * and a rendered view of `channels` bytes a pixel changed by them. */
void nerf__scene_appearance_gains(const nerf_scene_options *o, int split,
                                  uint32_t i, double gains[3]);
void nerf__scene_vary_view(const nerf_scene_options *o, int split,
                           uint32_t i, uint32_t channels, uint8_t *px);

/* The COLMAP layouts, text or binary (write_colmap.c); px holds one view
 * of 4 channels. */
int nerf__scene_write_colmap(const char *dir, const nerf_scene_options *o,
                             const nerf__env *env, uint8_t *px);

/* The LLFF layout of a FORWARD capture (layout_llff.c). */
int nerf__scene_write_llff(const char *dir, const nerf_scene_options *o,
                           const nerf__env *env, uint8_t *px);

#endif
