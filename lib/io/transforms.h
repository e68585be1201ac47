/*
 * transforms.json files (Blender's transforms_<split>.json and instant-ngp's
 * transforms.json): the parts that the dataset loader and camera paths
 * share, so that both accept and refuse exactly the same files.  Every
 * error message starts with the file's path.
 */
#ifndef NERF_IO_TRANSFORMS_H
#define NERF_IO_TRANSFORMS_H

#include <cJSON.h>
#include <stddef.h>
#include <stdint.h>

#include "env.h"

/* Generous: a transforms file lists one small object per frame. */
#define NERF__TRANSFORMS_MAX_BYTES (64u << 20)

/*
 * What a usable camera looks like, beyond being finite (docs/formats.md,
 * "Camera sanity"): every entry of a pose and every intrinsic within
 * +-1e6 (scene units or pixels: a million times any scene's size, so only
 * garbage is refused); each column of the rotation part at least 1e-3
 * long, and the three not (nearly) coplanar: |det R| at least 1e-3 times
 * the product of their lengths (1 for a rotation); a focal length of at
 * least 1e-3 pixels (a field of view just short of 180 degrees).
 */
#define NERF__CAMERA_MAX_ABS 1e6
#define NERF__POSE_MIN_COLUMN 1e-3
#define NERF__POSE_MIN_DET_RATIO 1e-3
#define NERF__FOCAL_MIN 1e-3

/* Intrinsics fields, at top level or per frame; NAN when absent.  The
 * distortion coefficients k1, k2, p1, p2, k3 (nerf_camera's model) are
 * 0 when absent, as instant-ngp reads them. */
typedef struct nerf__intrinsics {
    double angle_x, angle_y, fl_x, fl_y, cx, cy, w, h;
    double k1, k2, p1, p2, k3;
} nerf__intrinsics;

/* instant-ngp's aabb_scale: a power of two up to this; 1 when absent. */
#define NERF__AABB_SCALE_MAX 128

/* All fields NAN, the distortion 0. */
void nerf__intrinsics_none(nerf__intrinsics *in);

/*
 * Read the file at path and parse it; free *root_out with cJSON_Delete.
 * Invalid JSON is NERF_EFORMAT naming the line.
 */
int nerf__transforms_parse(const nerf__env *env, const char *path,
                           cJSON **root_out);

/* The same for the file's bytes, already read; path names it in messages. */
int nerf__transforms_parse_text(const char *path, const unsigned char *text,
                                size_t size, cJSON **root_out);

/*
 * The top level: an object whose top-level intrinsics go to *top (fields
 * absent stay NAN) and whose 'frames' list goes to *frames_out.  Its
 * aabb_scale, a power of two 1..NERF__AABB_SCALE_MAX (1 when absent),
 * goes to *aabb_scale.
 */
int nerf__transforms_top(const char *path, const cJSON *root,
                         nerf__intrinsics *top, const cJSON **frames_out,
                         double *aabb_scale);

/*
 * How messages name frame idx: "frame 3", and its file_path when it has
 * one, "frame 3 (./train/r_3)" (cut short if long).
 */
void nerf__transforms_frame_name(const cJSON *frame, uint32_t idx, char *buf,
                                 size_t size);

/*
 * Overlay the intrinsics fields present in obj onto *in, refusing values
 * no camera has (angles outside (0, pi), focal lengths below
 * NERF__FOCAL_MIN, anything beyond NERF__CAMERA_MAX_ABS, distortion
 * beyond NERF__DISTORTION_MAX_ABS).  where prefixes
 * field names in messages ("frame 3: ", or "" at top level).
 */
int nerf__transforms_read_intrinsics(const char *path, const cJSON *obj,
                                     const char *where, nerf__intrinsics *in);

/* A frame's transform_matrix as a validated 3x4 row-major c2w; name is
 * the frame's (nerf__transforms_frame_name()). */
int nerf__transforms_read_matrix(const char *path, const cJSON *frame,
                                 const char *name, double c2w[12]);

/*
 * Focal lengths and principal point, {fx, fy, cx, cy}, of frame idx for an
 * image of w x h pixels: fl_x, else camera_angle_x; fl_y, else
 * camera_angle_y, else fx; cx, cy default to the centre.
 */
int nerf__transforms_focal(const char *path, const char *name,
                           const nerf__intrinsics *in, double w, double h,
                           double out[4]);

/*
 * Why a camera-to-world pose cannot be used ("has a NaN ...", written into
 * buf), or NULL if it can: c2w is its top 3x4 (row-major), last its bottom
 * row or NULL when it has none.  The limits are those above.
 */
const char *nerf__pose_problem(const double c2w[12], const double *last,
                               char *buf, size_t size);

#endif
