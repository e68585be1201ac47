/*
 * nerf_density_grid_write(): the density sampled at cell centres, as a
 * float32 .npy, with a JSON sidecar recording the box it covers (NumPy
 * refuses keys of its own in the .npy header, so the box cannot go there).
 */
#include <cJSON.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "error.h"
#include "file_io.h"
#include "geometry_options.h"
#include "model_field.h"
#include "npy.h"
#include "space.h"

#define PATH_MAX_LEN 4096

typedef struct grid_paths {
    char json[PATH_MAX_LEN + 16];
    char rgb[PATH_MAX_LEN + 16];
} grid_paths;

/* "F.npy" -> "F.json" and "F_rgb.npy"; other names get the suffixes
 * appended. */
static int make_paths(const char *path, grid_paths *p)
{
    size_t n = strlen(path);
    if (n == 0 || n > PATH_MAX_LEN) {
        return nerf__error(NERF_EINVAL, "nerf_density_grid_write: the path "
                           "is empty or longer than %d bytes", PATH_MAX_LEN);
    }
    if (n > 4 && strcmp(path + n - 4, ".npy") == 0) {
        n -= 4;
    }
    snprintf(p->json, sizeof p->json, "%.*s.json", (int)n, path);
    snprintf(p->rgb, sizeof p->rgb, "%.*s_rgb.npy", (int)n, path);
    return NERF_OK;
}

static const char *space_name(const nerf_model *model)
{
    switch (nerf__model_space(model)->kind) {
    case NERF__SPACE_NDC:
        return "ndc";
    case NERF__SPACE_CONTRACT:
        return "world (unbounded model: its central cube)";
    default:
        return "world";
    }
}

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

static int write_sidecar(const nerf__env *env, const char *json_path,
                         const char *npy_path, const char *rgb_path,
                         const nerf__grid_box *g, const nerf_model *model)
{
    cJSON *root = cJSON_CreateObject();
    int ok = root != NULL;
    if (ok) {
        const double shape[3] = {g->cells[2], g->cells[1], g->cells[0]};
        const double lo[3] = {g->lo[0], g->lo[1], g->lo[2]};
        const double hi[3] = {g->hi[0], g->hi[1], g->hi[2]};
        const double step[3] = {g->step[0], g->step[1], g->step[2]};
        ok = cJSON_AddStringToObject(root, "format", "libnerf density grid") &&
             cJSON_AddNumberToObject(root, "version", 1) &&
             cJSON_AddStringToObject(root, "density", base_name(npy_path)) &&
             (rgb_path ? cJSON_AddStringToObject(root, "colour",
                                                 base_name(rgb_path)) != NULL
                       : cJSON_AddNullToObject(root, "colour") != NULL) &&
             cJSON_AddStringToObject(root, "order", "zyx") &&
             cJSON_AddItemToObject(root, "shape",
                                   cJSON_CreateDoubleArray(shape, 3)) &&
             cJSON_AddItemToObject(root, "box_min",
                                   cJSON_CreateDoubleArray(lo, 3)) &&
             cJSON_AddItemToObject(root, "box_max",
                                   cJSON_CreateDoubleArray(hi, 3)) &&
             cJSON_AddItemToObject(root, "spacing",
                                   cJSON_CreateDoubleArray(step, 3)) &&
             cJSON_AddStringToObject(root, "samples", "cell centres") &&
             cJSON_AddStringToObject(root, "space", space_name(model)) &&
             cJSON_AddNumberToObject(root, "model_step",
                                     (double)model->step);
    }
    char *text = ok ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    if (text == NULL) {
        return nerf__error(NERF_ENOMEM, "%s: out of memory building JSON",
                           json_path);
    }
    nerf__span part = {text, strlen(text)};
    int rc = nerf__file_write_atomic(env, json_path, &part, 1);
    cJSON_free(text);
    return rc;
}

/* Fill pts with the cell centres of plane k. */
static void plane_points(const nerf__grid_box *g, uint32_t k, float *pts)
{
    const float z = g->lo[2] + ((float)k + 0.5f) * g->step[2];
    for (uint32_t j = 0; j < g->cells[1]; j++) {
        const float y = g->lo[1] + ((float)j + 0.5f) * g->step[1];
        for (uint32_t i = 0; i < g->cells[0]; i++, pts += 3) {
            pts[0] = g->lo[0] + ((float)i + 0.5f) * g->step[0];
            pts[1] = y;
            pts[2] = z;
        }
    }
}

/* The colour of every sample seen down the density's gradient (central
 * differences over the grid, one-sided at its faces); straight down where
 * the density is flat. */
static int sample_colours(const nerf__grid_box *g, const float *sigma,
                          nerf__model_field *field, float *rgb, float *pts,
                          float *dirs, nerf__geometry_reporter *rep,
                          uint64_t done, uint64_t total)
{
    const size_t nx = g->cells[0], ny = g->cells[1], nz = g->cells[2];
    const size_t plane = nx * ny;
    const size_t stride[3] = {1, nx, plane};
    for (uint32_t k = 0; k < nz; k++) {
        plane_points(g, k, pts);
        for (size_t j = 0; j < ny; j++) {
            for (size_t i = 0; i < nx; i++) {
                const size_t at = k * plane + j * nx + i;
                const size_t idx[3] = {i, j, k}, n[3] = {nx, ny, nz};
                float d[3], len2 = 0.0f;
                for (int a = 0; a < 3; a++) {
                    const size_t lo = idx[a] > 0 ? at - stride[a] : at;
                    const size_t hi = idx[a] + 1 < n[a] ? at + stride[a] : at;
                    d[a] = (sigma[hi] - sigma[lo]) / g->step[a];
                    len2 += d[a] * d[a];
                }
                float *o = dirs + 3 * (j * nx + i);
                const float len = sqrtf(len2);
                if (len > 0.0f && isfinite(len)) {
                    o[0] = d[0] / len;
                    o[1] = d[1] / len;
                    o[2] = d[2] / len;
                } else {
                    o[0] = o[1] = 0.0f;
                    o[2] = -1.0f;
                }
            }
        }
        int rc = nerf__model_field_colour(field, plane, pts, dirs,
                                          rgb + 3 * k * plane);
        if (rc != NERF_OK) {
            return rc;
        }
        if (nerf__geometry_report(rep, done + k + 1, total)) {
            return nerf__error(NERF_ECANCELLED, "nerf_density_grid_write: "
                               "cancelled by the progress callback");
        }
    }
    return NERF_OK;
}

static int sample_grid(const nerf_model *model, const nerf_mesh_options *o,
                       const nerf__grid_box *g, float *sigma, float *rgb)
{
    const nerf__env *env = nerf__model_env(model);
    const size_t plane = (size_t)g->cells[0] * g->cells[1];
    nerf__model_field field;
    int rc = nerf__model_field_init(&field, model, o->threads);
    if (rc != NERF_OK) {
        return rc;
    }
    float *pts = nerf__alloc(env, 3 * plane * sizeof(float));
    float *dirs = rgb ? nerf__alloc(env, 3 * plane * sizeof(float)) : NULL;
    if (pts == NULL || (rgb && dirs == NULL)) {
        rc = NERF_ENOMEM;
    }
    nerf__geometry_reporter rep;
    nerf__geometry_reporter_init(&rep, o);
    const uint64_t total = (uint64_t)g->cells[2] * (rgb ? 2u : 1u);
    for (uint32_t k = 0; k < g->cells[2] && rc == NERF_OK; k++) {
        plane_points(g, k, pts);
        float *out = sigma + k * plane;
        rc = nerf__model_field_density(&field, plane, pts, out);
        for (size_t i = 0; rc == NERF_OK && i < plane; i++) {
            out[i] = isnan(out[i]) ? 0.0f : out[i];
        }
        if (rc == NERF_OK && nerf__geometry_report(&rep, k + 1u, total)) {
            rc = nerf__error(NERF_ECANCELLED, "nerf_density_grid_write: "
                             "cancelled by the progress callback");
        }
    }
    if (rc == NERF_OK && rgb) {
        rc = sample_colours(g, sigma, &field, rgb, pts, dirs, &rep,
                            g->cells[2], total);
    }
    nerf__free(env, pts);
    nerf__free(env, dirs);
    nerf__model_field_release(&field);
    return rc;
}

NERF_API int nerf_density_grid_write(const nerf_model *model,
                                     const char *path,
                                     const nerf_mesh_options *opts)
{
    const char *who = "nerf_density_grid_write";
    if (path == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL path", who);
    }
    nerf_mesh_options o;
    nerf__grid_box g;
    int rc = nerf__geometry_setup(model, opts, who, &o, &g);
    grid_paths p;
    if (rc == NERF_OK) {
        rc = make_paths(path, &p);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    const nerf__env *env = nerf__model_env(model);
    const int colour = o.colour != NERF_MESH_COLOUR_NONE;
    /* Unwritable outputs are found before the sampling, not after. */
    rc = nerf__file_check_writable(env, path);
    if (rc == NERF_OK) {
        rc = nerf__file_check_writable(env, p.json);
    }
    if (rc == NERF_OK && colour) {
        rc = nerf__file_check_writable(env, p.rgb);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    const size_t n = (size_t)g.cells[0] * g.cells[1] * g.cells[2];
    float *sigma = nerf__alloc(env, n * sizeof(float));
    float *rgb = colour ? nerf__alloc(env, 3 * n * sizeof(float)) : NULL;
    if (sigma == NULL || (colour && rgb == NULL)) {
        nerf__free(env, sigma);
        nerf__free(env, rgb);
        return nerf__error(NERF_ENOMEM, "%s: out of memory for a grid of "
                           "%u x %u x %u samples", who, g.cells[2],
                           g.cells[1], g.cells[0]);
    }
    rc = sample_grid(model, &o, &g, sigma, rgb);
    const size_t shape[4] = {g.cells[2], g.cells[1], g.cells[0], 3};
    if (rc == NERF_OK) {
        rc = nerf__npy_write_f4(env, path, sigma, shape, 3);
    }
    if (rc == NERF_OK && colour) {
        rc = nerf__npy_write_f4(env, p.rgb, rgb, shape, 4);
    }
    if (rc == NERF_OK) {
        rc = write_sidecar(env, p.json, path, colour ? p.rgb : NULL, &g,
                           model);
    }
    nerf__free(env, sigma);
    nerf__free(env, rgb);
    return rc;
}
