/*
 * Ray marching through the occupancy grid: every sample lies in an
 * occupied cell, inside the bound and [near, far), in increasing t; the
 * samples with skipping are exactly the lattice points of a march without
 * skipping that fall in occupied cells; a render of a ball agrees with and
 * without skipping, and with early termination to within its epsilon.
 */
#include <math.h>
#include <string.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "composite_packed.h"
#include "env.h"
#include "march.h"
#include "occupancy.h"
#include "rng.h"

typedef struct ball {
    float c[3], r, value;
} ball;

static float dist2(const float *p, const float *c)
{
    float d2 = 0.0f;
    for (int a = 0; a < 3; a++) {
        d2 += (p[a] - c[a]) * (p[a] - c[a]);
    }
    return d2;
}

static int ball_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    const ball *b = ctx;
    for (size_t i = 0; i < n; i++) {
        sigma[i] = dist2(xyz + 3 * i, b->c) < b->r * b->r ? b->value : 0.0f;
    }
    return 0;
}

/* The scene rendered: a ball of radius 0.45.  The grid is built from the
 * ball grown by a cell diagonal, so every cell the scene's ball touches is
 * occupied and the scene's density is exactly 0 in every empty cell. */
static const ball scene = {{0.1f, -0.05f, 0.02f}, 0.45f, 30.0f};

static nerf__occupancy *scene_grid(uint32_t R)
{
    nerf__env env;
    nerf__env_default(&env);
    const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    nerf__occupancy_options o;
    nerf__occupancy_defaults(&o, lo, hi);
    o.resolution = R;
    o.seed = 2;
    nerf__occupancy *g = NULL;
    if (nerf__occupancy_create(&env, &o, &g) != NERF_OK) {
        FAILF("create: %s", nerf_last_error());
        return NULL;
    }
    ball grown = scene;
    grown.r += sqrtf(3.0f) * g->cell_size[0];
    grown.value = 50.0f;
    if (nerf__occupancy_update(g, ball_density, &grown, g->cells) != NERF_OK) {
        FAILF("update: %s", nerf_last_error());
    }
    return g;
}

/* Random rays from a sphere of radius 3 towards the middle of the bound,
 * with lengths 0.5 to 2, then a few special ones. */
#define N_RANDOM 3000
#define N_SPECIAL 8
#define N_RAYS (N_RANDOM + N_SPECIAL)

typedef struct ray_set {
    float o[3 * N_RAYS], d[3 * N_RAYS], near[N_RAYS], far[N_RAYS];
    nerf__march_rays rays;
} ray_set;

static void set_ray(ray_set *s, size_t k, float ox, float oy, float oz,
                    float dx, float dy, float dz, float near, float far)
{
    const float o[3] = {ox, oy, oz}, d[3] = {dx, dy, dz};
    memcpy(s->o + 3 * k, o, sizeof o);
    memcpy(s->d + 3 * k, d, sizeof d);
    s->near[k] = near;
    s->far[k] = far;
}

static void make_rays(ray_set *s)
{
    nerf__rng r = nerf__rng_make(5, 0);
    for (size_t k = 0; k < N_RANDOM; k++) {
        float o[3], d[3], len = 0.0f;
        for (int a = 0; a < 3; a++) {
            o[a] = (float)nerf__rng_normal(&r);
            len += o[a] * o[a];
        }
        len = sqrtf(len);
        float scale = 0.5f + 1.5f * nerf__rng_uniform(&r);
        for (int a = 0; a < 3; a++) {
            o[a] *= 3.0f / len;
            d[a] = (1.4f * nerf__rng_uniform(&r) - 0.7f - o[a]) / 3.0f * scale;
        }
        float near = 0.2f * nerf__rng_uniform(&r);
        set_ray(s, k, o[0], o[1], o[2], d[0], d[1], d[2], near, 100.0f);
    }
    size_t k = N_RANDOM;
    /* Along z through the ball: two zero components. */
    set_ray(s, k++, 0.1f, -0.05f, -3.0f, 0.0f, 0.0f, 1.0f, 0.0f, 10.0f);
    /* Starting inside the bound and inside the ball. */
    set_ray(s, k++, 0.2f, 0.1f, 0.0f, 1.0f, 0.3f, -0.2f, 0.0f, 10.0f);
    /* Missing the bound. */
    set_ray(s, k++, 3.0f, 3.0f, 3.0f, 1.0f, 0.0f, 0.0f, 0.0f, 10.0f);
    /* No direction. */
    set_ray(s, k++, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 10.0f);
    /* near beyond the exit. */
    set_ray(s, k++, 0.1f, 0.0f, -3.0f, 0.0f, 0.0f, 1.0f, 4.5f, 10.0f);
    /* far in the middle of the ball. */
    set_ray(s, k++, 0.1f, 0.0f, -3.0f, 0.0f, 0.0f, 1.0f, 0.0f, 3.0f);
    /* Grazing the ball, axis-parallel in x, along the bound's face y = lo. */
    set_ray(s, k++, -3.0f, -1.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.0f, 10.0f);
    /* Backwards: the bound is behind the origin. */
    set_ray(s, k++, 0.0f, 0.0f, -3.0f, 0.0f, 0.0f, -1.0f, 0.0f, 10.0f);
    s->rays = (nerf__march_rays){.n = N_RAYS, .origins = s->o, .dirs = s->d,
                                 .near = s->near, .far = s->far};
}

#include "march_fixture.h"

static float dir_len(const float *d)
{
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

TEST(samples_are_valid)
{
    nerf__occupancy *g = scene_grid(64);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    nerf__march_defaults(&o, g);
    o.jitter = true;
    o.seed = 4;
    o.iteration = 3;
    static marched m;
    march(g, &o, &s.rays, &m);
    size_t bad_cell = 0, bad_range = 0, bad_order = 0, bad_dt = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        for (size_t i = m.offsets[k]; i < m.offsets[k + 1]; i++) {
            const float *p = m.xyz + 3 * i;
            bad_cell += !nerf__occupancy_occupied(g, p);
            bad_range += !(m.t[i] >= s.near[k] && m.t[i] < s.far[k]);
            for (int a = 0; a < 3; a++) {
                bad_range += !(p[a] >= -1.0f && p[a] < 1.0f);
            }
            bad_order += i > m.offsets[k] && !(m.t[i] > m.t[i - 1]);
            bad_dt += m.dt[i] != o.step;
        }
    }
    CHECK_EQ_INT(bad_cell, 0);
    CHECK_EQ_INT(bad_range, 0);
    CHECK_EQ_INT(bad_order, 0);
    CHECK_EQ_INT(bad_dt, 0);
    const size_t *c = m.offsets + N_RANDOM;
    CHECK(c[1] - c[0] > 100); /* along z through the ball */
    CHECK(c[2] - c[1] > 50);  /* from inside */
    CHECK(c[3] == c[2]);      /* miss */
    CHECK(c[4] == c[3]);      /* no direction */
    CHECK(c[5] == c[4]);      /* near beyond the bound */
    CHECK(c[6] > c[5]);       /* cut by far */
    CHECK(m.t[c[6] - 1] < 3.0f);
    CHECK(c[8] == c[7]);      /* backwards */
    printf("  %zu samples, %.1f per ray\n", m.total,
           (double)m.total / N_RAYS);
    unmarch(&m);
    nerf__occupancy_destroy(g);
}

TEST(skipping_keeps_exactly_the_occupied_lattice_points)
{
    nerf__occupancy *g = scene_grid(64);
    static ray_set s;
    make_rays(&s);
    for (int jitter = 0; jitter < 2; jitter++) {
        nerf__march_options o;
        nerf__march_defaults(&o, g);
        o.jitter = jitter;
        o.seed = 8;
        static marched skip, dense;
        march(g, &o, &s.rays, &skip);
        o.skip_empty = false;
        march(g, &o, &s.rays, &dense);
        size_t mismatched = 0;
        for (size_t k = 0; k < N_RAYS; k++) {
            size_t i = skip.offsets[k];
            for (size_t j = dense.offsets[k]; j < dense.offsets[k + 1]; j++) {
                if (!nerf__occupancy_occupied(g, dense.xyz + 3 * j)) {
                    continue;
                }
                if (i >= skip.offsets[k + 1] || skip.t[i] != dense.t[j]) {
                    mismatched++;
                    break;
                }
                i++;
            }
            mismatched += i != skip.offsets[k + 1];
        }
        CHECK_EQ_INT(mismatched, 0);
        printf("  jitter %d: %.1f samples per ray without skipping, %.1f "
               "with\n", jitter, (double)dense.total / N_RAYS,
               (double)skip.total / N_RAYS);
        unmarch(&skip);
        unmarch(&dense);
    }
    nerf__occupancy_destroy(g);
}

/* Scattered single occupied cells in a third of the blocks: many short
 * runs of occupied cells between empty cells and empty blocks, the case
 * where skipping has most ways to go wrong. */
static int speckle_density(void *ctx, size_t n, const float *xyz,
                           float *sigma)
{
    const nerf__occupancy *g = ctx;
    for (size_t i = 0; i < n; i++) {
        uint32_t ijk[3];
        size_t c;
        sigma[i] = 0.0f;
        if (nerf__occupancy_cell(g, xyz + 3 * i, ijk, &c)) {
            uint64_t block = (ijk[0] / 8) + 64 * ((ijk[1] / 8) + 64 * (ijk[2] / 8));
            bool busy = nerf__mix64(block + 1000) % 3 == 0;
            bool on = nerf__mix64(c) % 16 == 0;
            sigma[i] = busy && on ? 50.0f : 0.0f;
        }
    }
    return 0;
}

TEST(skipping_through_speckles)
{
    for (uint32_t R = 40; R <= 128; R += 88) {
        nerf__env env;
        nerf__env_default(&env);
        const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
        nerf__occupancy_options go;
        nerf__occupancy_defaults(&go, lo, hi);
        go.resolution = R;
        nerf__occupancy *g = NULL;
        CHECK_OK(nerf__occupancy_create(&env, &go, &g));
        if (!g) {
            return;
        }
        CHECK_OK(nerf__occupancy_update(g, speckle_density, g, g->cells));
        static ray_set s;
        make_rays(&s);
        nerf__march_options o;
        nerf__march_defaults(&o, g);
        o.jitter = true;
        static marched skip, dense;
        march(g, &o, &s.rays, &skip);
        o.skip_empty = false;
        march(g, &o, &s.rays, &dense);
        size_t mismatched = 0, kept = 0;
        for (size_t k = 0; k < N_RAYS; k++) {
            size_t i = skip.offsets[k];
            for (size_t j = dense.offsets[k]; j < dense.offsets[k + 1]; j++) {
                if (!nerf__occupancy_occupied(g, dense.xyz + 3 * j)) {
                    continue;
                }
                kept++;
                if (i >= skip.offsets[k + 1] || skip.t[i] != dense.t[j]) {
                    mismatched++;
                    break;
                }
                i++;
            }
            mismatched += i != skip.offsets[k + 1];
        }
        CHECK_EQ_INT(mismatched, 0);
        CHECK_EQ_INT(kept, skip.total);
        printf("  %u^3, %.2f%% of cells occupied: %.1f samples per ray\n", R,
               100.0 * (double)g->occupied / (double)g->cells,
               (double)skip.total / N_RAYS);
        unmarch(&skip);
        unmarch(&dense);
        nerf__occupancy_destroy(g);
    }
}

/* The scene's density and a smooth colour at the marched points. */
static void shade(const marched *m, float value, float *rgb, float *sigma)
{
    for (size_t i = 0; i < m->total; i++) {
        const float *p = m->xyz + 3 * i;
        bool in = dist2(p, scene.c) < scene.r * scene.r;
        sigma[i] = in ? value : 0.0f;
        rgb[3 * i] = 0.5f + 0.5f * sinf(3.0f * p[0]);
        rgb[3 * i + 1] = 0.5f + 0.5f * cosf(4.0f * p[1]);
        rgb[3 * i + 2] = 0.5f + 0.4f * p[2];
    }
}

typedef struct image {
    float rgb[3 * N_RAYS], depth[N_RAYS], opacity[N_RAYS];
    uint32_t used[N_RAYS];
    float trans[N_RAYS]; /* the transmittance after the samples used */
} image;

static void render(const marched *m, float value, float eps, image *im)
{
    float *rgb = malloc((3 * m->total + 1) * sizeof(float));
    float *sigma = malloc((m->total + 1) * sizeof(float));
    shade(m, value, rgb, sigma);
    /* A background per ray, as random-background training uses. */
    static float bg[3 * N_RAYS];
    nerf__rng r = nerf__rng_make(77, 0);
    for (size_t i = 0; i < 3 * N_RAYS; i++) {
        bg[i] = nerf__rng_uniform(&r);
    }
    nerf__packed_batch b = {.n_rays = N_RAYS, .offsets = m->offsets,
                            .t = m->t, .dt = m->dt, .rgb = rgb,
                            .sigma = sigma, .bg = bg, .bg_stride = 3,
                            .eps = eps};
    nerf__packed_out out = {.rgb = im->rgb, .depth = im->depth,
                            .opacity = im->opacity, .used = im->used};
    nerf__composite_packed(&b, &out);
    for (size_t k = 0; k < N_RAYS; k++) {
        const size_t at = m->offsets[k];
        im->trans[k] = 1.0f;
        nerf__composite_packed_ray_used((uint32_t)(m->offsets[k + 1] - at),
                                        m->dt + at, sigma + at, eps,
                                        &im->trans[k]);
    }
    free(rgb);
    free(sigma);
}

static double max_diff(const float *a, const float *b, size_t n)
{
    double worst = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = fabs((double)a[i] - (double)b[i]);
        worst = d > worst ? d : worst;
    }
    return worst;
}

TEST(render_with_and_without_skipping)
{
    nerf__occupancy *g = scene_grid(128);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    nerf__march_defaults(&o, g);
    o.jitter = true;
    o.seed = 1;
    static marched skip, dense;
    march(g, &o, &s.rays, &skip);
    o.skip_empty = false;
    march(g, &o, &s.rays, &dense);
    static image a, b;
    render(&skip, scene.value, 0.0f, &a);
    render(&dense, scene.value, 0.0f, &b);
    double drgb = max_diff(a.rgb, b.rgb, 3 * N_RAYS);
    double dop = max_diff(a.opacity, b.opacity, N_RAYS);
    double ddep = max_diff(a.depth, b.depth, N_RAYS);
    CHECK(drgb <= 1e-6 && dop <= 1e-6 && ddep <= 1e-5);
    size_t hit = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        hit += a.opacity[k] > 0.5f;
    }
    CHECK(hit > N_RANDOM / 4); /* the ball is actually seen */
    printf("  128^3, %zu rays (%zu hit the ball): %.1f samples per ray with "
           "skipping, %.1f without; largest differences rgb %.2g, opacity "
           "%.2g, depth %.2g\n", (size_t)N_RAYS, hit,
           (double)skip.total / N_RAYS, (double)dense.total / N_RAYS, drgb,
           dop, ddep);
    unmarch(&skip);
    unmarch(&dense);
    nerf__occupancy_destroy(g);
}

TEST(early_termination_within_eps)
{
    nerf__occupancy *g = scene_grid(128);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    nerf__march_defaults(&o, g);
    static marched m;
    march(g, &o, &s.rays, &m);
    const float eps = NERF__COMPOSITE_EPS_DEFAULT;
    static image a, b;
    /* Dense enough that rays through the ball saturate. */
    render(&m, 300.0f, 0.0f, &a);
    render(&m, 300.0f, eps, &b);
    double drgb = max_diff(a.rgb, b.rgb, 3 * N_RAYS);
    double dop = max_diff(a.opacity, b.opacity, N_RAYS);
    size_t all = 0, used = 0, stopped = 0, bad = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        size_t n = m.offsets[k + 1] - m.offsets[k];
        CHECK_EQ_INT(a.used[k], n);
        CHECK(b.used[k] <= n);
        /* Ray by ray: what the samples after the cut could add, in float
         * (float_early_stop_bound()); nothing where nothing was cut. */
        const double most = b.used[k] < n
                                ? float_early_stop_bound((double)n,
                                                         b.used[k],
                                                         b.trans[k])
                                : 0.0;
        CHECK(b.used[k] == n || b.trans[k] < eps);
        bad += max_diff(a.rgb + 3 * k, b.rgb + 3 * k, 3) > most ||
               max_diff(a.opacity + k, b.opacity + k, 1) > most;
        stopped += b.used[k] < n;
        all += n;
        used += b.used[k];
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(stopped > N_RANDOM / 4);
    printf("  eps %g: %zu of %zu rays stop early, %.1f of %.1f samples per "
           "ray used; largest differences rgb %.2g, opacity %.2g\n",
           (double)eps, stopped, (size_t)N_RAYS, (double)used / N_RAYS,
           (double)all / N_RAYS, drgb, dop);
    unmarch(&m);
    nerf__occupancy_destroy(g);
}

TEST(jitter_offsets)
{
    nerf__occupancy *g = scene_grid(32);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    nerf__march_defaults(&o, g);
    o.skip_empty = false;
    static marched base, j1, j2, j3;
    march(g, &o, &s.rays, &base);
    o.jitter = true;
    o.seed = 3;
    o.iteration = 10;
    march(g, &o, &s.rays, &j1);
    march(g, &o, &s.rays, &j2);
    o.iteration = 11;
    march(g, &o, &s.rays, &j3);
    CHECK(j1.total == j2.total &&
          memcmp(j1.t, j2.t, j1.total * sizeof(float)) == 0);
    size_t bad = 0, same = 0, rays = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        size_t n0 = base.offsets[k + 1] - base.offsets[k];
        size_t n1 = j1.offsets[k + 1] - j1.offsets[k];
        size_t n3 = j3.offsets[k + 1] - j3.offsets[k];
        if (n0 < 2 || n1 < 2 || n3 < 1) {
            continue;
        }
        rays++;
        const float dt_t = o.step / dir_len(s.d + 3 * k);
        /* Jitter moves the lattice by [0, dt).  The entry point itself
         * may fall outside the cells (on a face at hi), so the first
         * samples can be one lattice point apart. */
        float shift = j1.t[j1.offsets[k]] - base.t[base.offsets[k]];
        if (shift < -1e-3f * dt_t) {
            shift += dt_t;
        }
        bad += !(shift >= -1e-3f * dt_t && shift < dt_t * 1.001f);
        /* Either march may lose its first or last lattice point. */
        bad += n1 > n0 + 1 || n1 + 1 < n0;
        same += j3.t[j3.offsets[k]] == j1.t[j1.offsets[k]];
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(same < rays / 100 + 1);
    unmarch(&base);
    unmarch(&j1);
    unmarch(&j2);
    unmarch(&j3);
    nerf__occupancy_destroy(g);
}

TEST(rays_are_independent_and_limited)
{
    nerf__occupancy *g = scene_grid(64);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    nerf__march_defaults(&o, g);
    o.jitter = true;
    o.seed = 6;
    static marched all, capped;
    march(g, &o, &s.rays, &all);
    size_t bad = 0;
    for (size_t k = 0; k < N_RAYS; k += 37) {
        nerf__march_rays one = {.n = 1, .origins = s.o + 3 * k,
                                .dirs = s.d + 3 * k, .near = s.near + k,
                                .far = s.far + k, .first_ray = k};
        size_t off[2];
        float t[4096], dt[4096];
        size_t n = nerf__march_count(g, &o, &one, off);
        if (n != all.offsets[k + 1] - all.offsets[k] || n > 4096) {
            bad++;
            continue;
        }
        nerf__march_fill(g, &o, &one, off, t, dt, NULL);
        bad += memcmp(t, all.t + all.offsets[k], n * sizeof(float)) != 0;
    }
    CHECK_EQ_INT(bad, 0);
    o.max_samples = 7;
    march(g, &o, &s.rays, &capped);
    bad = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        size_t n = all.offsets[k + 1] - all.offsets[k];
        size_t c = capped.offsets[k + 1] - capped.offsets[k];
        bad += c != (n < 7 ? n : 7);
        bad += memcmp(capped.t + capped.offsets[k], all.t + all.offsets[k],
                      c * sizeof(float)) != 0;
    }
    CHECK_EQ_INT(bad, 0);
    unmarch(&all);
    unmarch(&capped);
    nerf__occupancy_destroy(g);
}

TEST(resumed_marches_continue_exactly)
{
    /* Marching 5 samples at a time from where the last piece stopped
     * gives, piece after piece, exactly the samples of one march. */
    nerf__occupancy *g = scene_grid(64);
    static ray_set s;
    make_rays(&s);
    nerf__march_options o;
    nerf__march_defaults(&o, g);
    o.jitter = true;
    o.seed = 12;
    static marched all;
    march(g, &o, &s.rays, &all);
    size_t pieces = 0;
    CHECK_EQ_INT(march_in_pieces(g, o, s.rays, &all, 5, &pieces), 0);
    printf("  %zu pieces of at most 5 samples\n", pieces);
    /* Pieces of 5 for every ray fit NERF__MARCH_ONE_PASS_ROOM; pieces of
     * 40 do not, and are marched in slots of 40 all the same. */
    CHECK(N_RAYS * 5 <= NERF__MARCH_ONE_PASS_ROOM &&
          N_RAYS * 40 > NERF__MARCH_ONE_PASS_ROOM);
    CHECK_EQ_INT(march_in_pieces(g, o, s.rays, &all, 40, &pieces), 0);
    printf("  %zu pieces of at most 40 samples\n", pieces);
    unmarch(&all);
    nerf__occupancy_destroy(g);
}

TEST(one_walk_is_count_and_fill)
{
    /* nerf__march_run() marches each ray once into a slot and continues
     * the rays that fill it: the same samples as count and fill, with and
     * without skipping, limits below, at and above the slot's room, and
     * marches that resume where a caller's earlier one stopped. */
    nerf__occupancy *g = scene_grid(64);
    static ray_set s;
    make_rays(&s);
    static uint32_t from[N_RAYS];
    for (size_t k = 0; k < N_RAYS; k++) {
        from[k] = k % 5 == 0 ? NERF__MARCH_DONE : (uint32_t)(k % 7) * 13;
    }
    const uint32_t limits[] = {0, 10, NERF__MARCH_SLOT_ROOM,
                               NERF__MARCH_SLOT_ROOM + 1, 100, 100000};
    size_t longest = 0;
    for (int skip = 0; skip < 2; skip++) {
        for (size_t i = 0; i < sizeof limits / sizeof limits[0]; i++) {
            nerf__march_options o;
            nerf__march_defaults(&o, g);
            o.skip_empty = skip;
            o.jitter = true;
            o.seed = 21;
            o.max_samples = limits[i];
            s.rays.first_ray = 1000;
            size_t long_rays;
            CHECK_EQ_INT(one_walk_differences(g, &o, s.rays, NULL,
                                              &long_rays), 0);
            longest = long_rays > longest ? long_rays : longest;
            CHECK_EQ_INT(one_walk_differences(g, &o, s.rays, from,
                                              &long_rays), 0);
        }
    }
    s.rays.first_ray = 0;
    /* The continuation must have had rays to continue. */
    CHECK(longest > N_RAYS / 4);
    printf("  %zu of %d rays longer than a slot\n", longest, N_RAYS);
    nerf__occupancy_destroy(g);
}

TEST(fresh_grid_and_reusable_buffers)
{
    nerf__env env;
    nerf__env_default(&env);
    const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    nerf__occupancy_options go;
    nerf__occupancy_defaults(&go, lo, hi);
    go.resolution = 16;
    nerf__occupancy *g = NULL;
    CHECK_OK(nerf__occupancy_create(&env, &go, &g));
    if (!g) {
        return;
    }
    nerf__march_options o;
    nerf__march_defaults(&o, g);
    CHECK_NEAR(o.step, sqrt(12.0) / 1024, 1e-9);
    /* A fresh grid is all occupied: an axis ray crosses the whole bound,
     * 2 / step lattice points, from the entry on. */
    const float orig[3] = {0.3f, -0.2f, -5.0f}, dir[3] = {0.0f, 0.0f, 0.5f};
    nerf__march_rays one = {.n = 1, .origins = orig, .dirs = dir,
                            .near_all = 0.0f, .far_all = 100.0f};
    nerf__march_samples ms;
    nerf__march_samples_init(&ms, &env);
    CHECK_OK(nerf__march_run(g, &o, &one, &ms));
    size_t expect = (size_t)ceil(2.0 / o.step);
    CHECK(ms.total + 1 >= expect && ms.total <= expect + 1);
    CHECK_NEAR(ms.t[0], 8.0, 1e-5);
    CHECK_NEAR(ms.t[1] - ms.t[0], 2.0 * o.step, 1e-5);
    /* The buffers are reused and grow for a larger batch. */
    static ray_set s;
    make_rays(&s);
    CHECK_OK(nerf__march_run(g, &o, &s.rays, &ms));
    size_t offsets[N_RAYS + 1];
    CHECK_EQ_INT(nerf__march_count(g, &o, &s.rays, offsets), ms.total);
    CHECK(memcmp(offsets, ms.offsets, sizeof offsets) == 0);
    CHECK_OK(nerf__march_run(g, &o, &one, &ms));
    CHECK(ms.n_rays == 1 && ms.total + 1 >= expect);
    nerf__march_samples_release(&ms);
    nerf__occupancy_destroy(g);
}

int main(void)
{
    RUN(samples_are_valid);
    RUN(skipping_keeps_exactly_the_occupied_lattice_points);
    RUN(skipping_through_speckles);
    RUN(render_with_and_without_skipping);
    RUN(early_termination_within_eps);
    RUN(jitter_offsets);
    RUN(rays_are_independent_and_limited);
    RUN(resumed_marches_continue_exactly);
    RUN(one_walk_is_count_and_fill);
    RUN(fresh_grid_and_reusable_buffers);
    HARNESS_EXIT();
}
