/*
 * Marching cubes over analytic fields (through the internal field entry):
 * the meshes of a sphere, a cube, a torus, two blobs and a field of noise
 * are closed and consistently wound, have the right Euler characteristic
 * and volume, and lie within half a cell of the true surface; the
 * component filters keep what they should.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "../harness.h"
#include "env.h"
#include "marching_cubes.h"
#include "mc_table.h"
#include "mesh.h"
#include "mesh_check.h"

/* Signed fields, positive inside: threshold 0 is the surface. */
typedef struct blob {
    float c[3], r;
} blob;

typedef struct shape {
    int kind; /* 0 spheres (union of blobs), 1 cube, 2 torus, 3 noise */
    blob b[2];
    int n_blobs;
    float half;        /* cube: half side */
    float big, small;  /* torus radii */
} shape;

static float shape_value(const shape *s, const float *p)
{
    switch (s->kind) {
    case 0: {
        float best = -INFINITY;
        for (int i = 0; i < s->n_blobs; i++) {
            const blob *b = &s->b[i];
            float d = sqrtf((p[0] - b->c[0]) * (p[0] - b->c[0]) +
                            (p[1] - b->c[1]) * (p[1] - b->c[1]) +
                            (p[2] - b->c[2]) * (p[2] - b->c[2]));
            best = fmaxf(best, b->r - d);
        }
        return best;
    }
    case 1:
        return s->half - fmaxf(fabsf(p[0]), fmaxf(fabsf(p[1]), fabsf(p[2])));
    case 2: {
        float q = sqrtf(p[0] * p[0] + p[1] * p[1]) - s->big;
        return s->small - sqrtf(q * q + p[2] * p[2]);
    }
    default: {
        /* Hash noise in [-1, 1] at the grid points, empty near the box's
         * faces so that the surface closes: every ambiguous face and
         * cube pattern shows up. */
        if (fabsf(p[0]) > 0.8f || fabsf(p[1]) > 0.8f || fabsf(p[2]) > 0.8f) {
            return -1.0f;
        }
        uint32_t h = 2166136261u;
        for (int a = 0; a < 3; a++) {
            uint32_t q = (uint32_t)(int32_t)lrintf(p[a] * 1000.0f);
            h = (h ^ q) * 16777619u;
            h ^= h >> 15;
        }
        return (float)(h % 2001u) / 1000.0f - 1.0f;
    }
    }
}

static int shape_sample(void *ctx, size_t n, const float *pts, float *out)
{
    for (size_t i = 0; i < n; i++) {
        out[i] = shape_value(ctx, pts + 3 * i);
    }
    return NERF_OK;
}

static nerf_mesh *extract(const shape *s, float half, uint32_t res,
                          nerf__grid_box *g)
{
    nerf__env env;
    nerf__env_from_hooks(&env, NULL);
    const float lo[3] = {-half, -half, -half}, hi[3] = {half, half, half};
    CHECK_OK(nerf__grid_box_init(g, lo, hi, res, "test"));
    nerf_mesh *m = NULL;
    CHECK_OK(nerf__mesh_create(&env, &m));
    nerf__field f = {shape_sample, (void *)s};
    CHECK_OK(nerf__marching_cubes(g, &f, 0.0f, NULL, m));
    return m;
}

static void destroy(nerf_mesh *m)
{
    nerf__env env = m->env;
    nerf__free(&env, m->vertices);
    nerf__free(&env, m->faces);
    nerf__free(&env, m->normals);
    nerf__free(&env, m->colours);
    nerf__free(&env, m);
}

/* The largest distance of a vertex from the zero set of a distance-like
 * field (|value| is the distance for spheres and the cube). */
static double max_surface_distance(const shape *s, const nerf_mesh *m)
{
    double worst = 0.0;
    for (size_t i = 0; i < m->n_vertices; i++) {
        double d = fabs(shape_value(s, m->vertices + 3 * i));
        worst = d > worst ? d : worst;
    }
    return worst;
}

static void check_closed(const nerf_mesh *m, long euler, size_t components,
                         mesh_stats *st)
{
    mesh_stats_compute(m->vertices, m->n_vertices, m->faces, m->n_faces, st);
    CHECK(m->n_faces > 0);
    CHECK_EQ_INT(st->bad_edges, 0);
    CHECK_EQ_INT(st->misoriented, 0);
    CHECK_EQ_INT(st->euler, euler);
    CHECK_EQ_INT(st->components, components);
    CHECK(st->volume > 0.0);
}

TEST(table_is_complete)
{
    /* Complementary patterns cross the same edges; every pattern's
     * triangles use only its crossing edges, and the empty and full
     * cubes have none. */
    const nerf__mc_case *t = nerf__mc_table();
    CHECK_EQ_INT(t[0].n_triangles, 0);
    CHECK_EQ_INT(t[255].n_triangles, 0);
    CHECK_EQ_INT(nerf__mc_table_fans(), 0);
    for (unsigned p = 1; p < 255; p++) {
        int crossing = 0, used[12] = {0};
        for (int e = 0; e < 12; e++) {
            int a, b;
            nerf__mc_edge_corners(e, &a, &b);
            crossing += ((p >> a) & 1u) != ((p >> b) & 1u);
        }
        for (int k = 0; k < t[p].n_triangles; k++) {
            for (int c = 0; c < 3; c++) {
                int e = t[p].edges[k][c], a, b;
                nerf__mc_edge_corners(e, &a, &b);
                if (((p >> a) & 1u) == ((p >> b) & 1u)) {
                    FAILF("pattern %u uses edge %d, which it does not cross", p, e);
                }
                used[e] = 1;
            }
        }
        int n_used = 0;
        for (int e = 0; e < 12; e++) {
            n_used += used[e];
        }
        if (n_used != crossing) {
            FAILF("pattern %u: %d crossing edges, %d used", p, crossing, n_used);
        }
    }
}

TEST(sphere)
{
    shape s = {.kind = 0, .n_blobs = 1, .b = {{{0.1f, -0.05f, 0.02f}, 0.7f}}};
    nerf__grid_box g;
    nerf_mesh *m = extract(&s, 1.0f, 40, &g);
    mesh_stats st;
    check_closed(m, 2, 1, &st);
    CHECK(max_surface_distance(&s, m) <= 0.5 * g.step[0]);
    const double v = 4.0 / 3.0 * M_PI * 0.7 * 0.7 * 0.7;
    CHECK_NEAR(st.volume, v, 0.02 * v);
    destroy(m);
}

TEST(cube)
{
    shape s = {.kind = 1, .half = 0.55f};
    nerf__grid_box g;
    nerf_mesh *m = extract(&s, 1.0f, 33, &g);
    mesh_stats st;
    check_closed(m, 2, 1, &st);
    CHECK(max_surface_distance(&s, m) <= 0.5 * g.step[0]);
    CHECK_NEAR(st.volume, 1.1 * 1.1 * 1.1, 0.03);
    destroy(m);
}

TEST(torus)
{
    shape s = {.kind = 2, .big = 0.55f, .small = 0.2f};
    nerf__grid_box g;
    nerf_mesh *m = extract(&s, 1.0f, 48, &g);
    mesh_stats st;
    check_closed(m, 0, 1, &st);
    const double v = 2.0 * M_PI * M_PI * 0.55 * 0.2 * 0.2;
    CHECK_NEAR(st.volume, v, 0.05 * v);
    destroy(m);
}

TEST(noise_is_closed)
{
    /* Every cube pattern, ambiguous faces and all: still no hole and no
     * edge wound the same way by both its faces. */
    shape s = {.kind = 3};
    nerf__grid_box g;
    nerf_mesh *m = extract(&s, 1.0f, 30, &g);
    mesh_stats st;
    mesh_stats_compute(m->vertices, m->n_vertices, m->faces, m->n_faces, &st);
    CHECK(m->n_faces > 1000);
    CHECK_EQ_INT(st.bad_edges, 0);
    CHECK_EQ_INT(st.misoriented, 0);
    destroy(m);
}

TEST(two_blobs_and_filters)
{
    shape s = {.kind = 0, .n_blobs = 2,
               .b = {{{-0.45f, 0.0f, 0.0f}, 0.4f}, {{0.55f, 0.1f, 0.0f}, 0.25f}}};
    nerf__grid_box g;
    nerf_mesh *m = extract(&s, 1.0f, 40, &g);
    mesh_stats st;
    check_closed(m, 4, 2, &st);
    CHECK(max_surface_distance(&s, m) <= 0.5 * g.step[0]);
    /* Faces of each blob: split by the plane x = 0.1 between them. */
    size_t big = 0;
    for (size_t f = 0; f < m->n_faces; f++) {
        big += m->vertices[3 * m->faces[3 * f]] < 0.1f;
    }
    const size_t small = m->n_faces - big, total = m->n_faces;
    CHECK(big > small && small > 0);

    nerf_mesh *largest = extract(&s, 1.0f, 40, &g);
    CHECK_OK(nerf__mesh_filter_components(largest, 1, 0));
    check_closed(largest, 2, 1, &st);
    CHECK_EQ_INT(largest->n_faces, big);
    for (size_t i = 0; i < largest->n_vertices; i++) {
        if (largest->vertices[3 * i] > 0.1f) {
            FAILF("vertex %zu of the smaller blob kept", i);
            break;
        }
    }
    destroy(largest);

    nerf_mesh *dropped = extract(&s, 1.0f, 40, &g);
    CHECK_OK(nerf__mesh_filter_components(dropped, 0, small + 1));
    CHECK_EQ_INT(dropped->n_faces, big);
    destroy(dropped);

    nerf_mesh *both = extract(&s, 1.0f, 40, &g);
    CHECK_OK(nerf__mesh_filter_components(both, 0, small));
    CHECK_EQ_INT(both->n_faces, total);
    destroy(both);
    destroy(m);
}

TEST(normals_point_out)
{
    shape s = {.kind = 0, .n_blobs = 1, .b = {{{0.0f, 0.0f, 0.0f}, 0.6f}}};
    nerf__grid_box g;
    nerf_mesh *m = extract(&s, 1.0f, 24, &g);
    CHECK_OK(nerf__mesh_compute_normals(m));
    size_t bad = 0;
    for (size_t i = 0; i < m->n_vertices; i++) {
        const float *p = m->vertices + 3 * i, *n = m->normals + 3 * i;
        float r = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        float c = (p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / r;
        bad += !(c > 0.9f);
    }
    CHECK_EQ_INT(bad, 0);
    destroy(m);
}

TEST(open_where_the_box_cuts)
{
    /* A sphere larger than the box: the mesh is open along the box's
     * faces (marching cubes sees no surface beyond its samples), and
     * nothing else is wrong. */
    shape s = {.kind = 0, .n_blobs = 1, .b = {{{0.0f, 0.0f, 0.0f}, 0.9f}}};
    nerf__grid_box g;
    nerf_mesh *m = extract(&s, 0.8f, 20, &g);
    mesh_stats st;
    mesh_stats_compute(m->vertices, m->n_vertices, m->faces, m->n_faces, &st);
    CHECK(st.bad_edges > 0);
    CHECK_EQ_INT(st.misoriented, 0);
    destroy(m);
}

TEST(bad_grids)
{
    nerf__grid_box g;
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1}, flat[3] = {1, 0, 1};
    const float nan3[3] = {NAN, 1, 1};
    CHECK_EQ_INT(nerf__grid_box_init(&g, lo, hi, 0, "t"), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "resolution") != NULL);
    CHECK_EQ_INT(nerf__grid_box_init(&g, lo, flat, 8, "t"), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "volume") != NULL);
    CHECK_EQ_INT(nerf__grid_box_init(&g, lo, nan3, 8, "t"), NERF_EINVAL);
    /* A flat box gets one cell on its short side, cells near cubes. */
    const float wide[3] = {4, 1, 0.01f};
    CHECK_OK(nerf__grid_box_init(&g, lo, wide, 64, "t"));
    CHECK_EQ_INT(g.cells[0], 64);
    CHECK_EQ_INT(g.cells[1], 16);
    CHECK_EQ_INT(g.cells[2], 1);
}

int main(void)
{
    RUN(table_is_complete);
    RUN(sphere);
    RUN(cube);
    RUN(torus);
    RUN(noise_is_closed);
    RUN(two_blobs_and_filters);
    RUN(normals_point_out);
    RUN(open_where_the_box_cuts);
    RUN(bad_grids);
    HARNESS_EXIT();
}
