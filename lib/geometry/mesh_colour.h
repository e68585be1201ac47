/*
 * Vertex colours from the radiance field: each vertex gets the model's
 * colour at the vertex for the view direction minus its normal, what a
 * camera looking at the surface head on would see there.
 */
#ifndef NERF_GEOMETRY_MESH_COLOUR_H
#define NERF_GEOMETRY_MESH_COLOUR_H

#include "mesh.h"
#include "model_field.h"

/*
 * Fill mesh->colours (allocating it).  points: where to query the model
 * (the vertices in the model's space: NULL means mesh->vertices);
 * mesh->normals must be set.  A vertex without a normal is seen from
 * above (view direction -z).
 */
int nerf__mesh_colour(nerf_mesh *mesh, nerf__model_field *field,
                      const float *points);

#endif
