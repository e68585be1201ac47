/*
 * The struct behind nerf_mesh: growable arrays of vertices, triangles and
 * the optional per-vertex normals and colours, through the caller's
 * allocator.
 */
#ifndef NERF_GEOMETRY_MESH_H
#define NERF_GEOMETRY_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"

struct nerf_mesh {
    nerf__env env;
    size_t n_vertices, n_faces;
    size_t cap_vertices, cap_faces;
    float *vertices;   /* n_vertices x 3 */
    uint32_t *faces;   /* n_faces x 3, counter-clockwise seen from outside */
    float *normals;    /* n_vertices x 3, or NULL */
    uint8_t *colours;  /* n_vertices x 3, or NULL */
};

/* An empty mesh.  Returns NERF_OK or NERF_ENOMEM. */
int nerf__mesh_create(const nerf__env *env, nerf_mesh **out);

/* Append a vertex; *index receives its index.  Fails with NERF_ENOMEM, or
 * NERF_EINVAL past 2^32 - 1 vertices (faces index them with 32 bits). */
int nerf__mesh_add_vertex(nerf_mesh *m, const float p[3], uint32_t *index);

int nerf__mesh_add_face(nerf_mesh *m, uint32_t a, uint32_t b, uint32_t c);

/* Fill m->normals (allocating it) with the area-weighted mean of the
 * normals of the faces about each vertex, unit length (0 0 0 for a vertex
 * of no face of non-zero area). */
int nerf__mesh_compute_normals(nerf_mesh *m);

/*
 * Keep the faces whose connected component (faces sharing a vertex) has
 * at least min_faces faces, and with keep_largest only those of the
 * component with the most faces (the first found of equal ones); then
 * drop the vertices no face uses.  Normals and colours follow.
 */
int nerf__mesh_filter_components(nerf_mesh *m, int keep_largest,
                                 size_t min_faces);

#endif
