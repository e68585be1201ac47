/*
 * Marching cubes over a field sampled on a grid, one layer of cells at a
 * time: memory holds two planes of samples and the vertex indices of the
 * edges of one layer, never the whole grid.  Vertices on a grid edge are
 * made once and shared by every cube around the edge, so a surface that
 * stays inside the box comes out closed (every edge of the mesh in
 * exactly two triangles), with triangles wound counter-clockwise seen
 * from the side of lower density.
 */
#ifndef NERF_GEOMETRY_MARCHING_CUBES_H
#define NERF_GEOMETRY_MARCHING_CUBES_H

#include "grid_box.h"
#include "mesh.h"

/*
 * Append to `mesh` the surface where `field` crosses `threshold` over the
 * grid g.  Samples that are not finite count as empty (below any
 * threshold).  Returns NERF_OK; NERF_ENOMEM; NERF_ECANCELLED (progress);
 * the field's failures.
 */
int nerf__marching_cubes(const nerf__grid_box *g, const nerf__field *field,
                         float threshold,
                         const nerf__geometry_progress *progress,
                         nerf_mesh *mesh);

#endif
