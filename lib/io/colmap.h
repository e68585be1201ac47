/*
 * COLMAP sparse models (cameras, images, points3D) in COLMAP's text and
 * binary forms, parsed from memory so that the fuzz targets can feed them
 * directly.  Only what a NeRF loader needs is kept: intrinsics, poses,
 * names, point positions and the images of each point's track (the 2D
 * observations are checked for size and skipped).  docs/formats.md has
 * the layouts.
 */
#ifndef NERF_IO_COLMAP_H
#define NERF_IO_COLMAP_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"

/* COLMAP's camera model ids (colmap/src/base/camera_models.h order). */
enum {
    NERF__COLMAP_SIMPLE_PINHOLE = 0,
    NERF__COLMAP_PINHOLE = 1,
    NERF__COLMAP_SIMPLE_RADIAL = 2,
    NERF__COLMAP_RADIAL = 3,
    NERF__COLMAP_OPENCV = 4,
    NERF__COLMAP_N_MODELS = 11 /* ids 5..10: known, not supported */
};

/* Models files this large are refused (a million-point model is ~100 MB). */
#define NERF__COLMAP_MAX_BYTES (1ull << 30)

typedef struct nerf__colmap_camera {
    uint32_t id;
    int model;               /* one of the supported ids above */
    uint32_t width, height;  /* of the images COLMAP saw, 1..65536 */
    /* The model's parameters mapped onto the OpenCV ones; 0 where the
     * model has none (fy = fx for single-focal models). */
    double fx, fy, cx, cy, k1, k2, p1, p2, k3;
} nerf__colmap_camera;

typedef struct nerf__colmap_image {
    uint32_t id, camera_id;
    double q[4];             /* world-to-camera rotation qw qx qy qz,
                                normalised */
    double t[3];             /* world-to-camera translation */
    char *name;              /* relative to the images folder */
} nerf__colmap_image;

typedef struct nerf__colmap_point {
    double xyz[3];
    size_t track_first;      /* into nerf__colmap_model.track */
    size_t track_len;
} nerf__colmap_point;

typedef struct nerf__colmap_model {
    nerf__colmap_camera *cameras; /* sorted by id */
    size_t n_cameras;
    nerf__colmap_image *images;   /* in file order */
    size_t n_images;
    nerf__colmap_point *points;
    size_t n_points;
    uint32_t *track;              /* image ids of every point's track */
    size_t n_track;
} nerf__colmap_model;

/* COLMAP's name of model id ("PINHOLE", ...), NULL for an unknown id. */
const char *nerf__colmap_model_name(int model);
/* Parameter count of model id, -1 for an unknown id. */
int nerf__colmap_model_param_count(int model);

/*
 * Parse one file of a model into m; binary selects the .bin layout.
 * path names the file in messages.  Cameras come first: images must name
 * a camera that m already has.  Every problem is NERF_EFORMAT with the
 * file, the record and the reason; NERF_ENOMEM.  On failure m keeps what
 * it had and whatever was parsed (free it with nerf__colmap_free).
 */
int nerf__colmap_parse_cameras(const nerf__env *env, const char *path,
                               const unsigned char *data, size_t size,
                               int binary, nerf__colmap_model *m);
int nerf__colmap_parse_images(const nerf__env *env, const char *path,
                              const unsigned char *data, size_t size,
                              int binary, nerf__colmap_model *m);
int nerf__colmap_parse_points(const nerf__env *env, const char *path,
                              const unsigned char *data, size_t size,
                              int binary, nerf__colmap_model *m);

/* The camera with this id, or NULL. */
const nerf__colmap_camera *nerf__colmap_find_camera(
    const nerf__colmap_model *m, uint32_t id);

void nerf__colmap_free(const nerf__env *env, nerf__colmap_model *m);

#endif
