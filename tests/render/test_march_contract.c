/*
 * Marching through a grid over contracted space (march.h, space.h): a
 * ball at the centre and a far background (everything beyond max-norm 10,
 * five times the grid's reach in world units).  Every sample's contracted
 * point lies in an occupied cell; skipping keeps exactly the occupied
 * lattice points; pieces continue exactly; a ray to infinity takes about
 * D / step lattice points beyond the cube; and compositing the far wall's
 * samples makes it opaque at its true depth, which fails if the warped
 * spacing or the samples' world lengths are wrong.
 */
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "composite_packed.h"
#include "env.h"
#include "march.h"
#include "occupancy.h"
#include "rng.h"
#include "space.h"

#define INNER 1.0f
#define WALL_IN 10.0f
#define BALL_R 0.4f

/* The scene's density; grown, the scene the grid is built from: the
 * ball larger by a cell diagonal and the background nearer by a cell
 * (the cells at max-norm 10 are 4/128 wide in contracted space, from
 * max-norm 10 to 14.5 in the world), so that every cell the scene
 * reaches is occupied and its density is exactly 0 in every empty
 * cell. */
static float world_density(const float *p, bool grown)
{
    const float r = BALL_R + (grown ? 0.06f : 0.0f);
    const float r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    if (r2 < r * r) {
        return 30.0f;
    }
    return nerf__space_norm(p) >= WALL_IN * (grown ? 0.7f : 1.0f) ? 5.0f
                                                                   : 0.0f;
}

/* The grid's update hands over contracted points. */
static int grid_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    (void)ctx;
    nerf__space sp;
    nerf__space_contract(&sp, INNER);
    for (size_t i = 0; i < n; i++) {
        float p[3];
        nerf__space_from_domain(&sp, xyz + 3 * i, p);
        sigma[i] = world_density(p, true);
    }
    return 0;
}

static nerf__occupancy *contract_grid(uint32_t R)
{
    nerf__env env;
    nerf__env_default(&env);
    nerf__space sp;
    nerf__space_contract(&sp, INNER);
    nerf__occupancy_options o;
    nerf__occupancy_defaults(&o, sp.lo, sp.hi);
    o.resolution = R;
    o.seed = 3;
    nerf__occupancy *g = NULL;
    if (nerf__occupancy_create(&env, &o, &g) != NERF_OK) {
        FAILF("create: %s", nerf_last_error());
        return NULL;
    }
    if (nerf__occupancy_update(g, grid_density, g, g->cells) != NERF_OK) {
        FAILF("update: %s", nerf_last_error());
    }
    return g;
}

#define N_RAYS 2000

typedef struct ray_set {
    float o[3 * N_RAYS], d[3 * N_RAYS];
    nerf__march_rays rays;
} ray_set;

/* Origins inside the cube (at max-norm up to 0.9) or, for every tenth
 * ray, outside it at distance 1.5 to 3, in random directions. */
static void make_rays(ray_set *s)
{
    nerf__rng r = nerf__rng_make(21, 0);
    for (size_t k = 0; k < N_RAYS; k++) {
        float len = 0.0f;
        for (int a = 0; a < 3; a++) {
            s->d[3 * k + a] = (float)nerf__rng_normal(&r);
            len += s->d[3 * k + a] * s->d[3 * k + a];
        }
        const float scale = (0.5f + nerf__rng_uniform(&r)) / sqrtf(len);
        const float reach = k % 10 == 9 ? 1.5f + 1.5f * nerf__rng_uniform(&r)
                                        : 0.9f;
        for (int a = 0; a < 3; a++) {
            s->d[3 * k + a] *= scale;
            s->o[3 * k + a] = reach * (2.0f * nerf__rng_uniform(&r) - 1.0f);
        }
    }
    s->rays = (nerf__march_rays){.n = N_RAYS, .origins = s->o, .dirs = s->d,
                                 .near_all = 0.05f, .far_all = 1e4f};
}

#include "march_fixture.h"

static void options(const nerf__occupancy *g, nerf__march_options *o)
{
    nerf__march_defaults(o, g);
    o->contract = INNER;
    o->jitter = true;
    o->seed = 6;
}

TEST(samples_lie_in_occupied_contracted_cells)
{
    nerf__occupancy *g = contract_grid(64);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    options(g, &o);
    static marched m;
    march(g, &o, &s.rays, &m);
    size_t bad_cell = 0, bad_order = 0, bad_dt = 0, bad_point = 0;
    nerf__space sp;
    nerf__space_contract(&sp, INNER);
    for (size_t k = 0; k < N_RAYS; k++) {
        const float *ok = s.o + 3 * k, *dk = s.d + 3 * k;
        for (size_t i = m.offsets[k]; i < m.offsets[k + 1]; i++) {
            bad_cell += !nerf__occupancy_occupied(g, m.xyz + 3 * i);
            bad_order += i > m.offsets[k] && !(m.t[i] > m.t[i - 1]);
            bad_order += !(m.t[i] >= 0.05f && m.t[i] < 1e4f);
            bad_dt += !(m.dt[i] >= o.step * 0.999f);
            float p[3];
            for (int a = 0; a < 3; a++) {
                p[a] = ok[a] + m.t[i] * dk[a];
            }
            nerf__space_to_domain(&sp, p, p);
            for (int a = 0; a < 3; a++) {
                bad_point += p[a] != m.xyz[3 * i + a];
            }
        }
    }
    CHECK_EQ_INT(bad_cell, 0);
    CHECK_EQ_INT(bad_order, 0);
    CHECK_EQ_INT(bad_dt, 0);
    CHECK_EQ_INT(bad_point, 0);
    printf("  %zu samples, %.1f per ray\n", m.total, (double)m.total / N_RAYS);
    unmarch(&m);
    nerf__occupancy_destroy(g);
}

TEST(skipping_keeps_exactly_the_occupied_lattice_points)
{
    nerf__occupancy *g = contract_grid(64);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    options(g, &o);
    static marched skip, dense;
    march(g, &o, &s.rays, &skip);
    o.skip_empty = false;
    march(g, &o, &s.rays, &dense);
    size_t mismatched = 0, kept = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        size_t at = skip.offsets[k];
        for (size_t i = dense.offsets[k]; i < dense.offsets[k + 1]; i++) {
            if (!nerf__occupancy_occupied(g, dense.xyz + 3 * i)) {
                continue;
            }
            kept++;
            if (at >= skip.offsets[k + 1] || skip.t[at] != dense.t[i] ||
                skip.dt[at] != dense.dt[i]) {
                mismatched++;
            }
            at++;
        }
        mismatched += at != skip.offsets[k + 1];
    }
    CHECK_EQ_INT(mismatched, 0);
    CHECK_EQ_INT(kept, skip.total);
    printf("  %.1f samples per ray with skipping, %.1f lattice points\n",
           (double)skip.total / N_RAYS, (double)dense.total / N_RAYS);
    unmarch(&skip);
    unmarch(&dense);
    nerf__occupancy_destroy(g);
}

TEST(resumed_marches_continue_exactly)
{
    nerf__occupancy *g = contract_grid(64);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    options(g, &o);
    static marched all;
    march(g, &o, &s.rays, &all);
    size_t pieces = 0;
    CHECK_EQ_INT(march_in_pieces(g, o, s.rays, &all, 7, &pieces), 0);
    printf("  %zu pieces of at most 7 samples\n", pieces);
    unmarch(&all);
    nerf__occupancy_destroy(g);
}

TEST(one_walk_is_count_and_fill)
{
    /* Contracted marches through nerf__march_run()'s slots, continued
     * past them, are count and fill's. */
    nerf__occupancy *g = contract_grid(64);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    options(g, &o);
    const uint32_t limits[] = {0, NERF__MARCH_SLOT_ROOM + 1, 300};
    for (size_t i = 0; i < sizeof limits / sizeof limits[0]; i++) {
        o.max_samples = limits[i];
        size_t long_rays;
        CHECK_EQ_INT(one_walk_differences(g, &o, s.rays, NULL, &long_rays),
                     0);
        if (i == 0) {
            CHECK(long_rays > 0);
            printf("  %zu of %d rays longer than a slot\n", long_rays,
                   N_RAYS);
        }
    }
    nerf__occupancy_destroy(g);
}

TEST(few_lattice_points_reach_infinity)
{
    /* From the centre along x: the cube is left at u = 1, and beyond it
     * D = 1, so about 1 / step lattice points lie inside and as many
     * beyond, however far the ray goes. */
    nerf__occupancy *g = contract_grid(32);
    nerf__march_options o;
    options(g, &o);
    o.jitter = false;
    o.skip_empty = false;
    const float orig[3] = {0, 0, 0}, dir[3] = {1, 0, 0};
    nerf__march_rays r = {.n = 1, .origins = orig, .dirs = dir,
                          .near_all = 0.0f, .far_all = 1e30f};
    size_t off[2];
    size_t n = nerf__march_count(g, &o, &r, off);
    const double per_unit = 1.0 / o.step;
    CHECK(n > 1.9 * per_unit && n < 2.1 * per_unit);
    float *t = malloc(n * sizeof(float)), *dt = malloc(n * sizeof(float));
    nerf__march_fill(g, &o, &r, off, t, dt, NULL);
    /* Deep in the far field each sample stands for a long stretch, to
     * the next lattice point: the lengths sum to the distance covered. */
    double sum = 0.0;
    size_t last = 0;
    for (size_t i = 0; i + 1 < n && t[i + 1] < 100.0f; i++) {
        sum += dt[i];
        last = i;
    }
    CHECK(fabs(sum - (t[last + 1] - t[0])) < 1e-3 * t[last + 1]);
    CHECK(isfinite(dt[n - 1]));
    printf("  %zu lattice points (1 / step = %.1f); the first %zu reach "
           "t = %.1f, their lengths sum to %.1f\n", n, per_unit, last + 1,
           (double)t[last], sum);
    free(t);
    free(dt);
    nerf__occupancy_destroy(g);
}

TEST(far_wall_is_opaque_at_its_depth)
{
    nerf__occupancy *g = contract_grid(128);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    options(g, &o);
    static marched m;
    march(g, &o, &s.rays, &m);
    float *rgb = malloc((3 * m.total + 1) * sizeof(float));
    float *sigma = malloc((m.total + 1) * sizeof(float));
    nerf__space sp;
    nerf__space_contract(&sp, INNER);
    for (size_t i = 0; i < m.total; i++) {
        float p[3];
        nerf__space_from_domain(&sp, m.xyz + 3 * i, p);
        sigma[i] = world_density(p, false);
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 0.5f;
    }
    static float opacity[N_RAYS], depth[N_RAYS];
    nerf__packed_batch b = {.n_rays = N_RAYS, .offsets = m.offsets, .t = m.t,
                            .dt = m.dt, .rgb = rgb, .sigma = sigma,
                            .eps = 0.0f};
    nerf__packed_out out = {.opacity = opacity, .depth = depth};
    nerf__composite_packed(&b, &out);
    size_t transparent = 0, wrong_depth = 0, walls = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        transparent += !(opacity[k] > 0.99f);
        /* Rays that miss the ball see the wall where o + t d reaches
         * max-norm WALL_IN. */
        const float *ok = s.o + 3 * k, *dk = s.d + 3 * k;
        float t_wall = INFINITY;
        for (int a = 0; a < 3; a++) {
            if (dk[a] != 0.0f) {
                float ta = (copysignf(WALL_IN, dk[a]) - ok[a]) / dk[a];
                t_wall = ta < t_wall ? ta : t_wall;
            }
        }
        /* Rays that miss the ball (by a margin: grazing ones mix its depth
         * with the wall's) end on the wall. */
        float od = 0.0f, dd = 0.0f;
        for (int a = 0; a < 3; a++) {
            od += ok[a] * dk[a];
            dd += dk[a] * dk[a];
        }
        float tc = fmaxf(0.0f, -od / dd), miss2 = 0.0f;
        for (int a = 0; a < 3; a++) {
            miss2 += (ok[a] + tc * dk[a]) * (ok[a] + tc * dk[a]);
        }
        if (miss2 > (BALL_R + 0.01f) * (BALL_R + 0.01f)) {
            walls++;
            wrong_depth += !(fabsf(depth[k] / opacity[k] - t_wall) <
                             0.1f * t_wall);
        }
    }
    CHECK_EQ_INT(transparent, 0);
    CHECK_EQ_INT(wrong_depth, 0);
    CHECK(walls > N_RAYS / 2);
    printf("  %zu of %d rays miss the ball and end on the far wall; %.1f "
           "samples per ray\n",
           walls, N_RAYS, (double)m.total / N_RAYS);
    free(rgb);
    free(sigma);
    unmarch(&m);
    nerf__occupancy_destroy(g);
}

int main(void)
{
    RUN(samples_lie_in_occupied_contracted_cells);
    RUN(skipping_keeps_exactly_the_occupied_lattice_points);
    RUN(resumed_marches_continue_exactly);
    RUN(one_walk_is_count_and_fill);
    RUN(few_lattice_points_reach_infinity);
    RUN(far_wall_is_opaque_at_its_depth);
    HARNESS_EXIT();
}
