#include "mesh_colour.h"

#include <math.h>

int nerf__mesh_colour(nerf_mesh *mesh, nerf__model_field *field,
                      const float *points)
{
    const size_t n = mesh->n_vertices;
    const nerf__env *env = &mesh->env;
    float *dirs = nerf__alloc(env, 3 * n * sizeof(float) + 1);
    float *rgb = nerf__alloc(env, 3 * n * sizeof(float) + 1);
    mesh->colours = nerf__alloc(env, 3 * n + 1);
    if (dirs == NULL || rgb == NULL || mesh->colours == NULL) {
        nerf__free(env, dirs);
        nerf__free(env, rgb);
        return NERF_ENOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        const float *nv = mesh->normals + 3 * i;
        float *d = dirs + 3 * i;
        const int none = nv[0] == 0.0f && nv[1] == 0.0f && nv[2] == 0.0f;
        d[0] = none ? 0.0f : -nv[0];
        d[1] = none ? 0.0f : -nv[1];
        d[2] = none ? -1.0f : -nv[2];
    }
    int rc = nerf__model_field_colour(field, n,
                                      points ? points : mesh->vertices, dirs,
                                      rgb);
    for (size_t i = 0; rc == 0 && i < 3 * n; i++) {
        const float c = rgb[i] > 0.0f ? (rgb[i] < 1.0f ? rgb[i] : 1.0f) : 0.0f;
        mesh->colours[i] = (uint8_t)lrintf(255.0f * c);
    }
    nerf__free(env, dirs);
    nerf__free(env, rgb);
    return rc;
}
