/* The public mesh calls: extraction from a model, accessors, files. */
#include <string.h>
#include <strings.h>

#include "error.h"
#include "geometry_options.h"
#include "marching_cubes.h"
#include "mesh.h"
#include "mesh_colour.h"
#include "mesh_write.h"
#include "model_field.h"

/*
 * An NDC model's vertices back to world space, when its render settings
 * carry the NDC frustum: the inverse of the warp (camera/ndc.c) with the
 * near plane at depth 1.  The map reverses orientation, so faces are
 * rewound.  Returns whether it mapped.
 */
static int ndc_to_world(const nerf_model *model, nerf_mesh *m)
{
    const nerf_sampler_options *s = &model->render_sampler;
    if (nerf__model_space(model)->kind != NERF__SPACE_NDC ||
        !model->has_render || !s->ndc || !(s->ndc_focal > 0.0f)) {
        return 0;
    }
    const double sx = -2.0 * s->ndc_focal / s->ndc_width;
    const double sy = -2.0 * s->ndc_focal / s->ndc_height;
    for (size_t i = 0; i < m->n_vertices; i++) {
        float *p = m->vertices + 3 * i;
        /* z_ndc = 1 is infinitely far: keep such vertices far, finite. */
        const double zn = p[2] < 0.999999 ? p[2] : 0.999999;
        const double z = 2.0 / (zn - 1.0);
        p[0] = (float)(p[0] * z / sx);
        p[1] = (float)(p[1] * z / sy);
        p[2] = (float)z;
    }
    for (size_t f = 0; f < m->n_faces; f++) {
        uint32_t *t = m->faces + 3 * f;
        const uint32_t k = t[1];
        t[1] = t[2];
        t[2] = k;
    }
    return 1;
}

static int extract(nerf_mesh *mesh, const nerf_model *model,
                   const nerf_mesh_options *o, const nerf__grid_box *grid)
{
    nerf__model_field field;
    int rc = nerf__model_field_init(&field, model, o->threads);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__geometry_reporter reporter;
    nerf__geometry_reporter_init(&reporter, o);
    const nerf__field f = {nerf__model_field_density, &field};
    const nerf__geometry_progress progress = {nerf__geometry_report, &reporter};
    rc = nerf__marching_cubes(grid, &f, o->threshold, &progress, mesh);
    if (rc == NERF_OK) {
        rc = nerf__mesh_filter_components(mesh, (int)o->keep_largest,
                                          o->min_component_faces);
    }
    /* Colours are queried where the networks work (NDC points for an NDC
     * model), seen along the world normals, as the renderer's view
     * directions are world directions. */
    float *model_points = NULL;
    if (rc == NERF_OK && o->colour != NERF_MESH_COLOUR_NONE &&
        nerf__model_space(model)->kind == NERF__SPACE_NDC) {
        const size_t bytes = 3 * mesh->n_vertices * sizeof(float);
        model_points = nerf__alloc(&mesh->env, bytes + 1);
        if (model_points == NULL) {
            rc = NERF_ENOMEM;
        } else if (bytes) {
            memcpy(model_points, mesh->vertices, bytes);
        }
    }
    if (rc == NERF_OK && nerf__model_space(model)->kind == NERF__SPACE_NDC &&
        !ndc_to_world(model, mesh)) {
        nerf__log(&mesh->env, NERF_LOG_WARN, "mesh: the NDC model has no "
                  "recorded NDC frustum: vertices stay in NDC space");
    }
    if (rc == NERF_OK) {
        rc = nerf__mesh_compute_normals(mesh);
    }
    if (rc == NERF_OK && o->colour != NERF_MESH_COLOUR_NONE) {
        rc = nerf__mesh_colour(mesh, &field, model_points);
    }
    nerf__free(&mesh->env, model_points);
    nerf__model_field_release(&field);
    return rc;
}

NERF_API int nerf_mesh_extract(nerf_mesh **out, const nerf_model *model,
                               const nerf_mesh_options *opts)
{
    if (out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_mesh_extract: out is NULL");
    }
    *out = NULL;
    nerf_mesh_options o;
    nerf__grid_box grid;
    int rc = nerf__geometry_setup(model, opts, "nerf_mesh_extract", &o, &grid);
    nerf__env env;
    if (rc == NERF_OK) {
        rc = nerf__env_from_hooks(&env, o.hooks);
    }
    nerf_mesh *mesh = NULL;
    if (rc == NERF_OK) {
        rc = nerf__mesh_create(&env, &mesh);
    }
    if (rc == NERF_OK) {
        nerf__log(&env, NERF_LOG_DEBUG, "mesh: %u x %u x %u cells, threshold "
                  "%g", grid.cells[0], grid.cells[1], grid.cells[2],
                  (double)o.threshold);
        rc = extract(mesh, model, &o, &grid);
    }
    if (rc != NERF_OK) {
        nerf_mesh_destroy(mesh);
        return rc;
    }
    *out = mesh;
    return NERF_OK;
}

NERF_API void nerf_mesh_destroy(nerf_mesh *mesh)
{
    if (mesh == NULL) {
        return;
    }
    nerf__env env = mesh->env;
    nerf__free(&env, mesh->vertices);
    nerf__free(&env, mesh->faces);
    nerf__free(&env, mesh->normals);
    nerf__free(&env, mesh->colours);
    nerf__free(&env, mesh);
}

NERF_API size_t nerf_mesh_vertex_count(const nerf_mesh *mesh)
{
    return mesh ? mesh->n_vertices : 0;
}

NERF_API size_t nerf_mesh_face_count(const nerf_mesh *mesh)
{
    return mesh ? mesh->n_faces : 0;
}

NERF_API const float *nerf_mesh_vertices(const nerf_mesh *mesh)
{
    return mesh && mesh->n_vertices ? mesh->vertices : NULL;
}

NERF_API const uint32_t *nerf_mesh_faces(const nerf_mesh *mesh)
{
    return mesh && mesh->n_faces ? mesh->faces : NULL;
}

NERF_API const float *nerf_mesh_normals(const nerf_mesh *mesh)
{
    return mesh && mesh->n_vertices ? mesh->normals : NULL;
}

NERF_API const uint8_t *nerf_mesh_colours(const nerf_mesh *mesh)
{
    return mesh && mesh->n_vertices ? mesh->colours : NULL;
}

static int ends_with(const char *s, const char *tail)
{
    const size_t n = strlen(s), k = strlen(tail);
    return n >= k && strcasecmp(s + n - k, tail) == 0;
}

NERF_API int nerf_mesh_write(const nerf_mesh *mesh, const char *path,
                             int format)
{
    if (mesh == NULL || path == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_mesh_write: NULL mesh or path");
    }
    if (format == NERF_MESH_FORMAT_AUTO) {
        if (ends_with(path, ".ply")) {
            format = NERF_MESH_FORMAT_PLY;
        } else if (ends_with(path, ".obj")) {
            format = NERF_MESH_FORMAT_OBJ;
        } else {
            return nerf__error(NERF_EINVAL, "%s: cannot tell the mesh format "
                               "from the extension (use .ply or .obj)", path);
        }
    }
    const nerf__mesh_arrays a = {mesh->n_vertices, mesh->n_faces,
                                 mesh->vertices, mesh->normals,
                                 mesh->colours, mesh->faces,
                                 "libnerf mesh"};
    switch (format) {
    case NERF_MESH_FORMAT_PLY:
        return nerf__mesh_write_ply(&mesh->env, path, &a, 0);
    case NERF_MESH_FORMAT_PLY_ASCII:
        return nerf__mesh_write_ply(&mesh->env, path, &a, 1);
    case NERF_MESH_FORMAT_OBJ:
        return nerf__mesh_write_obj(&mesh->env, path, &a);
    default:
        return nerf__error(NERF_EINVAL, "nerf_mesh_write: format %d is not a "
                           "nerf_mesh_format", format);
    }
}
