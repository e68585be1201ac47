/*
 * Triangle meshes and point clouds to files: PLY (binary little-endian or
 * ASCII) and Wavefront OBJ, from plain arrays, through
 * nerf__file_write_atomic.  A point cloud is a mesh without faces.
 */
#ifndef NERF_IO_MESH_WRITE_H
#define NERF_IO_MESH_WRITE_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"

typedef struct nerf__mesh_arrays {
    size_t n_vertices, n_faces;
    const float *vertices;  /* n_vertices x 3 */
    const float *normals;   /* n_vertices x 3, or NULL */
    const uint8_t *colours; /* n_vertices x 3, or NULL */
    const uint32_t *faces;  /* n_faces x 3; NULL: a point cloud */
    const char *comment;    /* the header's comment line */
} nerf__mesh_arrays;

/* PLY: vertex x y z (float), nx ny nz (float) and red green blue (uchar)
 * when given; face vertex_indices (list uchar uint), no face element for
 * a point cloud.  ASCII floats have 9 significant digits, which give a
 * float back.  Returns NERF_OK; NERF_EIO naming path; NERF_ENOMEM. */
int nerf__mesh_write_ply(const nerf__env *env, const char *path,
                         const nerf__mesh_arrays *m, int ascii);

/* OBJ: "v x y z [r g b]" (colours in [0, 1], the common extension),
 * "vn" when normals are given, faces "f a//a b//b c//c" (1-based). */
int nerf__mesh_write_obj(const nerf__env *env, const char *path,
                         const nerf__mesh_arrays *m);

#endif
