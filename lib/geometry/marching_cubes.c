#include "marching_cubes.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "error.h"
#include "mc_table.h"

#define NONE UINT32_MAX

typedef struct layer {
    size_t nx, ny;     /* samples per row and rows per plane */
    float *points;     /* one plane of sample positions */
    float *plane[2];   /* samples at z = k and k + 1 */
    /* Vertex indices of the edges: x edges ([ny][nx - 1]) and y edges
     * ([ny - 1][nx]) of both planes, z edges ([ny][nx]) between them. */
    uint32_t *xe[2], *ye[2], *ze;
} layer;

static void layer_free(const nerf__env *env, layer *l)
{
    nerf__free(env, l->points);
    for (int i = 0; i < 2; i++) {
        nerf__free(env, l->plane[i]);
        nerf__free(env, l->xe[i]);
        nerf__free(env, l->ye[i]);
    }
    nerf__free(env, l->ze);
}

static int layer_alloc(const nerf__env *env, layer *l, size_t nx, size_t ny)
{
    memset(l, 0, sizeof *l);
    l->nx = nx;
    l->ny = ny;
    const size_t n = nx * ny;
    l->points = nerf__alloc(env, 3 * n * sizeof(float));
    l->ze = nerf__alloc(env, n * sizeof(uint32_t));
    int ok = l->points && l->ze;
    for (int i = 0; i < 2; i++) {
        l->plane[i] = nerf__alloc(env, n * sizeof(float));
        l->xe[i] = nerf__alloc(env, n * sizeof(uint32_t));
        l->ye[i] = nerf__alloc(env, n * sizeof(uint32_t));
        ok = ok && l->plane[i] && l->xe[i] && l->ye[i];
    }
    if (!ok) {
        layer_free(env, l);
        return NERF_ENOMEM;
    }
    return NERF_OK;
}

static void fill_none(uint32_t *a, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        a[i] = NONE;
    }
}

/* Sample plane k of the grid into out. */
static int sample_plane(const nerf__grid_box *g, const nerf__field *field,
                        layer *l, uint32_t k, float *out)
{
    const float z = k == g->cells[2] ? g->hi[2]
                                     : g->lo[2] + (float)k * g->step[2];
    float *p = l->points;
    for (size_t j = 0; j < l->ny; j++) {
        const float y = j == g->cells[1] ? g->hi[1]
                                         : g->lo[1] + (float)j * g->step[1];
        for (size_t i = 0; i < l->nx; i++, p += 3) {
            p[0] = i == g->cells[0] ? g->hi[0]
                                    : g->lo[0] + (float)i * g->step[0];
            p[1] = y;
            p[2] = z;
        }
    }
    int rc = field->sample(field->ctx, l->nx * l->ny, l->points, out);
    if (rc == NERF_OK) {
        for (size_t i = 0; i < l->nx * l->ny; i++) {
            /* Overflowed densities are solid; NaN is nothing. */
            if (isnan(out[i])) {
                out[i] = -FLT_MAX;
            } else if (isinf(out[i])) {
                out[i] = out[i] > 0.0f ? FLT_MAX : -FLT_MAX;
            }
        }
    }
    return rc;
}

/* The slot in the layer's maps of cube edge e of the cube at (i, j). */
static uint32_t *edge_slot(layer *l, int e, size_t i, size_t j)
{
    const size_t nx = l->nx;
    switch (e) {
    case 0: case 1: case 2: case 3:
        return l->xe[e >> 1] + (j + (e & 1)) * nx + i;
    case 4: case 5: case 6: case 7:
        return l->ye[(e - 4) >> 1] + j * nx + i + (e & 1);
    default:
        return l->ze + (j + ((e - 8) >> 1)) * nx + i + (e & 1);
    }
}

/* The vertex on edge e of cube (i, j) of layer k, made at first use. */
static int edge_vertex(const nerf__grid_box *g, layer *l, const float v[8],
                       int e, size_t i, size_t j, uint32_t k,
                       float threshold, nerf_mesh *mesh, uint32_t *out)
{
    uint32_t *slot = edge_slot(l, e, i, j);
    if (*slot != NONE) {
        *out = *slot;
        return NERF_OK;
    }
    int a, b;
    nerf__mc_edge_corners(e, &a, &b);
    /* v[a] and v[b] lie on either side of the threshold, so the fraction
     * is within [0, 1] but for rounding, or NaN where the samples were
     * clamped to +-FLT_MAX and their difference overflows. */
    float t = (threshold - v[a]) / (v[b] - v[a]);
    t = isnan(t) ? 0.5f : t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    const size_t corner[3] = {i + (a & 1), j + (a >> 1 & 1), k + (a >> 2 & 1)};
    const int axis = e / 4;
    float p[3];
    for (int c = 0; c < 3; c++) {
        p[c] = corner[c] == g->cells[c]
                   ? g->hi[c]
                   : g->lo[c] + (float)corner[c] * g->step[c];
        if (c == axis) {
            p[c] += t * g->step[c];
        }
    }
    int rc = nerf__mesh_add_vertex(mesh, p, slot);
    *out = *slot;
    return rc;
}

static int march_layer(const nerf__grid_box *g, layer *l, uint32_t k,
                       float threshold, const nerf__mc_case *table,
                       nerf_mesh *mesh)
{
    const size_t nx = l->nx;
    const float *p0 = l->plane[0], *p1 = l->plane[1];
    for (size_t j = 0; j + 1 < l->ny; j++) {
        for (size_t i = 0; i + 1 < nx; i++) {
            const size_t at = j * nx + i;
            const float v[8] = {p0[at], p0[at + 1], p0[at + nx],
                                p0[at + nx + 1], p1[at], p1[at + 1],
                                p1[at + nx], p1[at + nx + 1]};
            unsigned pattern = 0;
            for (int c = 0; c < 8; c++) {
                pattern |= (unsigned)(v[c] > threshold) << c;
            }
            const nerf__mc_case *cs = &table[pattern];
            for (int t = 0; t < cs->n_triangles; t++) {
                uint32_t idx[3];
                for (int c = 0; c < 3; c++) {
                    int rc = edge_vertex(g, l, v, cs->edges[t][c], i, j, k,
                                         threshold, mesh, &idx[c]);
                    if (rc != NERF_OK) {
                        return rc;
                    }
                }
                int rc = nerf__mesh_add_face(mesh, idx[0], idx[1], idx[2]);
                if (rc != NERF_OK) {
                    return rc;
                }
            }
        }
    }
    return NERF_OK;
}

int nerf__marching_cubes(const nerf__grid_box *g, const nerf__field *field,
                         float threshold,
                         const nerf__geometry_progress *progress,
                         nerf_mesh *mesh)
{
    const nerf__mc_case *table = nerf__mc_table();
    layer l;
    const size_t nx = (size_t)g->cells[0] + 1, ny = (size_t)g->cells[1] + 1;
    const size_t n = nx * ny;
    int rc = layer_alloc(&mesh->env, &l, nx, ny);
    if (rc != NERF_OK) {
        return rc;
    }
    fill_none(l.xe[1], n);
    fill_none(l.ye[1], n);
    rc = sample_plane(g, field, &l, 0, l.plane[1]);
    const uint64_t total = (uint64_t)g->cells[2] + 1;
    if (rc == NERF_OK && progress && progress->fn &&
        progress->fn(progress->ctx, 1, total)) {
        rc = nerf__error(NERF_ECANCELLED, "mesh: cancelled by the progress "
                         "callback");
    }
    for (uint32_t k = 0; k < g->cells[2] && rc == NERF_OK; k++) {
        /* The top plane of the last layer is the bottom of this one. */
        float *pf = l.plane[0];
        l.plane[0] = l.plane[1];
        l.plane[1] = pf;
        uint32_t *x = l.xe[0], *y = l.ye[0];
        l.xe[0] = l.xe[1];
        l.xe[1] = x;
        l.ye[0] = l.ye[1];
        l.ye[1] = y;
        fill_none(l.xe[1], n);
        fill_none(l.ye[1], n);
        fill_none(l.ze, n);
        rc = sample_plane(g, field, &l, k + 1, l.plane[1]);
        if (rc == NERF_OK) {
            rc = march_layer(g, &l, k, threshold, table, mesh);
        }
        if (rc == NERF_OK && progress && progress->fn &&
            progress->fn(progress->ctx, (uint64_t)k + 2, total)) {
            rc = nerf__error(NERF_ECANCELLED, "mesh: cancelled by the "
                             "progress callback");
        }
    }
    layer_free(&mesh->env, &l);
    return rc;
}
