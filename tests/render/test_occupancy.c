/*
 * The occupancy grid: cells of an analytic sphere, the update schedule
 * (decay, sampled cells, threshold), determinism, errors and the
 * serialisation helpers.
 */
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "env.h"
#include "occupancy.h"
#include "rng.h"

/* Density `value` inside a ball, 0 outside. */
typedef struct ball {
    float c[3], r, value;
} ball;

static int ball_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    const ball *b = ctx;
    for (size_t i = 0; i < n; i++) {
        float d2 = 0.0f;
        for (int a = 0; a < 3; a++) {
            float e = xyz[3 * i + a] - b->c[a];
            d2 += e * e;
        }
        sigma[i] = d2 < b->r * b->r ? b->value : 0.0f;
    }
    return 0;
}

/* A smooth density, so that every jittered point sees a different value. */
static int smooth_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    (void)ctx;
    for (size_t i = 0; i < n; i++) {
        const float *p = xyz + 3 * i;
        sigma[i] = 30.0f * expf(-4.0f * (p[0] * p[0] + p[1] * p[1] +
                                         p[2] * p[2])) +
                   0.5f * sinf(7.0f * p[0]) * sinf(5.0f * p[1]);
    }
    return 0;
}

static int zero_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    (void)ctx;
    (void)xyz;
    memset(sigma, 0, n * sizeof(float));
    return 0;
}

static nerf__occupancy *make_grid(uint32_t R, float lo, float hi,
                                  uint64_t seed, size_t chunk)
{
    nerf__env env;
    nerf__env_default(&env);
    const float l[3] = {lo, lo, lo}, h[3] = {hi, hi, hi};
    nerf__occupancy_options o;
    nerf__occupancy_defaults(&o, l, h);
    o.resolution = R;
    o.seed = seed;
    if (chunk) {
        o.chunk = chunk;
    }
    nerf__occupancy *g = NULL;
    if (nerf__occupancy_create(&env, &o, &g) != NERF_OK) {
        FAILF("create: %s", nerf_last_error());
    }
    return g;
}

static void cell_center(const nerf__occupancy *g, size_t c, float p[3])
{
    const size_t R = g->res;
    const size_t ijk[3] = {c % R, (c / R) % R, c / (R * R)};
    for (int a = 0; a < 3; a++) {
        p[a] = g->lo[a] + ((float)ijk[a] + 0.5f) * g->cell_size[a];
    }
}

TEST(defaults_and_threshold_rule)
{
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    /* instant-ngp's unit cube: 1024 steps of sqrt(3)/1024, and its
     * threshold 0.01 * 1024 / sqrt(3) = 5.91 (alpha ~ sigma dt). */
    CHECK_NEAR(nerf__march_step(lo, hi, 1024), sqrt(3.0) / 1024, 1e-9);
    nerf__occupancy_options o;
    nerf__occupancy_defaults(&o, lo, hi);
    CHECK_EQ_INT(o.resolution, 128);
    CHECK_NEAR(o.decay, 0.95, 1e-7);
    CHECK_NEAR(o.density_threshold, 0.01 * 1024 / sqrt(3.0), 0.06);
    /* One step at the threshold has alpha 0.01 exactly. */
    float dt = nerf__march_step(lo, hi, 1024);
    CHECK_NEAR(1.0 - exp(-(double)o.density_threshold * dt), 0.01, 1e-6);
    /* The Blender bound is 3 units wide: a third of the density. */
    const float blo[3] = {-1.5f, -1.5f, -1.5f}, bhi[3] = {1.5f, 1.5f, 1.5f};
    nerf__occupancy_options b;
    nerf__occupancy_defaults(&b, blo, bhi);
    CHECK_NEAR(b.density_threshold, o.density_threshold / 3.0, 1e-4);
}

TEST(fresh_grid_is_all_occupied)
{
    nerf__occupancy *g = make_grid(5, -1.0f, 1.0f, 1, 0); /* 125 cells */
    if (!g) {
        return;
    }
    CHECK_EQ_INT(g->cells, 125);
    CHECK_EQ_INT(g->words, 2);
    CHECK_EQ_INT(g->occupied, 125);
    CHECK(g->bits[1] == (UINT64_C(1) << 61) - 1); /* no bits past the end */
    const float in[3] = {0.3f, -0.99f, 0.999f};
    const float out1[3] = {1.0f, 0.0f, 0.0f}; /* hi is outside */
    const float out2[3] = {0.0f, -1.0001f, 0.0f};
    const float nan[3] = {NAN, 0.0f, 0.0f};
    CHECK(nerf__occupancy_occupied(g, in));
    CHECK(!nerf__occupancy_occupied(g, out1));
    CHECK(!nerf__occupancy_occupied(g, out2));
    CHECK(!nerf__occupancy_occupied(g, nan));
    nerf__occupancy_destroy(g);
}

TEST(sphere_cells)
{
    /* The default resolution, a ball of radius 0.5 in [-1, 1]^3. */
    nerf__occupancy *g = make_grid(128, -1.0f, 1.0f, 3, 0);
    if (!g) {
        return;
    }
    ball b = {{0.1f, -0.05f, 0.02f}, 0.5f, 50.0f};
    CHECK_OK(nerf__occupancy_update(g, ball_density, &b, g->cells));
    CHECK_EQ_INT(g->evaluated, g->cells);
    CHECK_EQ_INT(g->updates, 1);
    const float half_diag = 0.5f * sqrtf(3.0f) * g->cell_size[0];
    size_t inside = 0, outside = 0, wrong = 0, occupied = 0;
    for (size_t c = 0; c < g->cells; c++) {
        float p[3];
        cell_center(g, c, p);
        float d = sqrtf((p[0] - b.c[0]) * (p[0] - b.c[0]) +
                        (p[1] - b.c[1]) * (p[1] - b.c[1]) +
                        (p[2] - b.c[2]) * (p[2] - b.c[2]));
        bool bit = nerf__occupancy_bit(g, c);
        occupied += bit;
        if (d + half_diag < b.r) {
            inside++;
            wrong += !bit || !nerf__occupancy_occupied(g, p);
        } else if (d - half_diag > b.r) {
            outside++;
            wrong += bit || nerf__occupancy_occupied(g, p);
        }
    }
    CHECK_EQ_INT(wrong, 0);
    CHECK_EQ_INT(occupied, g->occupied);
    /* The ball is 6.5% of the bound. */
    double frac = (double)occupied / (double)g->cells;
    CHECK(frac > 0.06 && frac < 0.07);
    CHECK(inside > 100000 && outside > 1800000);
    /* Every occupied cell holds 50, every other 0. */
    CHECK_NEAR(g->mean, 50.0 * frac, 1e-4);
    CHECK(g->threshold == fminf(g->opts.density_threshold, g->mean));
    printf("  128^3: %zu occupied cells (%.2f%%), mean EMA %.3f\n", occupied,
           100.0 * frac, (double)g->mean);
    nerf__occupancy_destroy(g);
}

TEST(threshold_is_min_of_rule_and_mean)
{
    nerf__occupancy *g = make_grid(32, -1.0f, 1.0f, 3, 0);
    if (!g) {
        return;
    }
    /* A low rule threshold applies when the mean is higher. */
    g->opts.density_threshold = 0.2f;
    CHECK_OK(nerf__occupancy_update(g, smooth_density, NULL, g->cells));
    CHECK(g->threshold == 0.2f && g->mean > 0.2f);
    size_t n = 0;
    for (size_t c = 0; c < g->cells; c++) {
        CHECK(nerf__occupancy_bit(g, c) == (g->ema[c] > 0.2f));
        n += g->ema[c] > 0.2f;
    }
    CHECK_EQ_INT(n, g->occupied);
    nerf__occupancy_destroy(g);
}

TEST(decay_and_schedule)
{
    nerf__occupancy *g = make_grid(32, -1.0f, 1.0f, 9, 0);
    if (!g) {
        return;
    }
    ball b = {{0.0f, 0.0f, 0.0f}, 0.6f, 40.0f};
    CHECK_OK(nerf__occupancy_update(g, ball_density, &b, g->cells));
    const size_t occ = g->occupied;
    float *old = malloc(g->cells * sizeof(float));
    uint64_t *old_bits = malloc(g->words * sizeof(uint64_t));
    memcpy(old, g->ema, g->cells * sizeof(float));
    memcpy(old_bits, g->bits, g->words * sizeof(uint64_t));
    /* Sample every occupied cell plus a quarter of the others. */
    const size_t quarter = g->cells / 4;
    CHECK_OK(nerf__occupancy_update(g, zero_density, NULL, quarter));
    double expect = (double)(g->cells - occ) / 4.0;
    double sd = sqrt(expect * 0.75);
    double got = (double)(g->evaluated - occ);
    CHECK(fabs(got - expect) < 5.0 * sd);
    printf("  partial update: %zu occupied + %.0f others sampled "
           "(expected %.0f +- %.0f)\n", occ, got, expect, sd);
    /* The scene vanished: every cell, sampled or not, decays. */
    for (size_t c = 0; c < g->cells; c++) {
        if (g->ema[c] != old[c] * 0.95f) {
            FAILF("cell %zu: %g, expected %g", c, (double)g->ema[c],
                  (double)(old[c] * 0.95f));
            break;
        }
    }
    /* 40 * 0.95 stays above the mean-limited threshold. */
    CHECK(memcmp(old_bits, g->bits, g->words * sizeof(uint64_t)) == 0);
    free(old);
    free(old_bits);
    nerf__occupancy_destroy(g);
}

/* Records every cell an update samples, and checks the point lies in it. */
typedef struct recorder {
    const nerf__occupancy *g;
    unsigned char *seen;
    size_t calls, max_n, twice, outside;
} recorder;

static int record_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    recorder *r = ctx;
    r->calls++;
    r->max_n = n > r->max_n ? n : r->max_n;
    for (size_t i = 0; i < n; i++) {
        uint32_t ijk[3];
        size_t c;
        if (!nerf__occupancy_cell(r->g, xyz + 3 * i, ijk, &c)) {
            r->outside++;
        } else {
            r->twice += r->seen[c];
            r->seen[c] = 1;
        }
        sigma[i] = 0.0f;
    }
    return 0;
}

TEST(occupied_cells_always_sampled)
{
    nerf__occupancy *g = make_grid(24, -2.0f, 1.0f, 4, 1000);
    if (!g) {
        return;
    }
    ball b = {{-0.5f, -0.5f, -0.5f}, 0.7f, 40.0f};
    CHECK_OK(nerf__occupancy_update(g, ball_density, &b, g->cells));
    recorder r = {g, calloc(g->cells, 1), 0, 0, 0, 0};
    uint64_t *before = malloc(g->words * sizeof(uint64_t));
    memcpy(before, g->bits, g->words * sizeof(uint64_t));
    CHECK_OK(nerf__occupancy_update(g, record_density, &r, 500));
    CHECK(r.max_n <= 1000);
    CHECK_EQ_INT(r.calls, (g->evaluated + 999) / 1000);
    CHECK_EQ_INT(r.twice, 0);
    CHECK_EQ_INT(r.outside, 0);
    size_t missed = 0, seen = 0;
    for (size_t c = 0; c < g->cells; c++) {
        missed += ((before[c / 64] >> (c % 64)) & 1) && !r.seen[c];
        seen += r.seen[c];
    }
    CHECK_EQ_INT(missed, 0);
    CHECK_EQ_INT(seen, g->evaluated);
    free(before);
    free(r.seen);
    nerf__occupancy_destroy(g);
}

TEST(updates_are_deterministic)
{
    nerf__occupancy *a = make_grid(40, -1.0f, 1.0f, 11, 0);
    nerf__occupancy *b = make_grid(40, -1.0f, 1.0f, 11, 777); /* chunks */
    nerf__occupancy *c = make_grid(40, -1.0f, 1.0f, 12, 0);   /* seed */
    if (!a || !b || !c) {
        return;
    }
    nerf__occupancy *gs[3] = {a, b, c};
    for (int k = 0; k < 3; k++) {
        CHECK_OK(nerf__occupancy_update(gs[k], smooth_density, NULL,
                                        gs[k]->cells));
        for (int u = 0; u < 3; u++) {
            CHECK_OK(nerf__occupancy_update(gs[k], smooth_density, NULL,
                                            gs[k]->cells / 8));
        }
    }
    CHECK(memcmp(a->ema, b->ema, a->cells * sizeof(float)) == 0);
    CHECK(memcmp(a->bits, b->bits, a->words * sizeof(uint64_t)) == 0);
    CHECK_EQ_INT(a->evaluated, b->evaluated);
    CHECK(memcmp(a->ema, c->ema, a->cells * sizeof(float)) != 0);
    /* The update index keys the draws: the same grid updated again draws
     * new points. */
    nerf__occupancy_reset(b);
    CHECK_OK(nerf__occupancy_update(b, smooth_density, NULL, b->cells));
    nerf__occupancy_reset(c);
    c->opts.seed = 11;
    c->updates = 1;
    CHECK_OK(nerf__occupancy_update(c, smooth_density, NULL, c->cells));
    CHECK(memcmp(b->ema, c->ema, b->cells * sizeof(float)) != 0);
    for (int k = 0; k < 3; k++) {
        nerf__occupancy_destroy(gs[k]);
    }
}

static int failing_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    int *calls = ctx;
    if (++*calls == 2) {
        return NERF_EIO;
    }
    for (size_t i = 0; i < n; i++) {
        sigma[i] = 1.0f;
    }
    return 0;
}

/* Each block bit is the OR of its cells' bits. */
static size_t coarse_errors(const nerf__occupancy *g)
{
    size_t errors = 0;
    const uint32_t R = g->res;
    bool *any = calloc((size_t)g->coarse_res * g->coarse_res * g->coarse_res,
                       sizeof(bool));
    for (uint32_t k = 0; k < R; k++) {
        for (uint32_t j = 0; j < R; j++) {
            for (uint32_t i = 0; i < R; i++) {
                size_t c = i + (size_t)R * (j + (size_t)R * k);
                size_t b = i / 8 + g->coarse_res * (j / 8 + g->coarse_res *
                                                    (k / 8));
                any[b] |= nerf__occupancy_bit(g, c);
            }
        }
    }
    for (uint32_t k = 0; k < R; k++) {
        for (uint32_t j = 0; j < R; j++) {
            for (uint32_t i = 0; i < R; i++) {
                const uint32_t ijk[3] = {i, j, k};
                size_t b = i / 8 + g->coarse_res * (j / 8 + g->coarse_res *
                                                    (k / 8));
                errors += nerf__occupancy_block_bit(g, ijk) != any[b];
            }
        }
    }
    free(any);
    return errors;
}

TEST(coarse_level)
{
    /* 8 does not divide 21: the last blocks are partial. */
    nerf__occupancy *g = make_grid(21, -1.0f, 1.0f, 3, 0);
    if (!g) {
        return;
    }
    CHECK_EQ_INT(g->coarse_res, 3);
    CHECK_EQ_INT(coarse_errors(g), 0);
    ball b = {{0.6f, -0.7f, 0.1f}, 0.25f, 40.0f};
    CHECK_OK(nerf__occupancy_update(g, ball_density, &b, g->cells));
    CHECK_EQ_INT(coarse_errors(g), 0);
    size_t blocks = 0;
    for (int i = 0; i < 27; i++) {
        blocks += (g->coarse[0] >> i) & 1;
    }
    CHECK(blocks > 0 && blocks < 27);
    /* The ball moves to the opposite corner: its old cells decay below
     * the threshold (the mean of the new ball's, 40 x 0.8%) within 130
     * updates, and the blocks follow. */
    ball moved = {{-0.6f, 0.7f, -0.1f}, 0.25f, 40.0f};
    for (int u = 0; u < 130; u++) {
        CHECK_OK(nerf__occupancy_update(g, ball_density, &moved,
                                        g->cells / 4));
    }
    CHECK_EQ_INT(coarse_errors(g), 0);
    const float old_c[3] = {0.6f, -0.7f, 0.1f};
    CHECK(!nerf__occupancy_occupied(g, old_c));
    CHECK(nerf__occupancy_occupied(g, moved.c));
    uint32_t ijk[3];
    size_t cell;
    CHECK(nerf__occupancy_cell(g, old_c, ijk, &cell));
    CHECK(!nerf__occupancy_block_bit(g, ijk));
    nerf__occupancy_destroy(g);
    g = make_grid(128, -1.0f, 1.0f, 3, 0);
    if (g) {
        ball c = {{0.1f, 0.2f, -0.3f}, 0.4f, 40.0f};
        CHECK_OK(nerf__occupancy_update(g, ball_density, &c, g->cells));
        CHECK_EQ_INT(coarse_errors(g), 0);
        nerf__occupancy_destroy(g);
    }
}

TEST(callback_failure)
{
    nerf__occupancy *g = make_grid(16, -1.0f, 1.0f, 1, 1000);
    if (!g) {
        return;
    }
    int calls = 0;
    CHECK_EQ_INT(nerf__occupancy_update(g, failing_density, &calls, g->cells),
                 NERF_EIO);
    CHECK_EQ_INT(g->updates, 0);
    CHECK_EQ_INT(g->occupied, g->cells);
    /* The first chunk's cells were refreshed, no other. */
    size_t touched = 0;
    for (size_t c = 0; c < g->cells; c++) {
        touched += g->ema[c] != 0.0f;
    }
    CHECK_EQ_INT(touched, 1000);
    nerf__occupancy_destroy(g);
}

TEST(serialisation_round_trip)
{
    nerf__occupancy *a = make_grid(20, -1.0f, 1.0f, 5, 0);
    nerf__occupancy *b = make_grid(20, -1.0f, 1.0f, 5, 0);
    if (!a || !b) {
        return;
    }
    /* A fresh grid rebuilds to all occupied. */
    nerf__occupancy_rebuild_bits(b);
    CHECK_EQ_INT(b->occupied, b->cells);
    CHECK_OK(nerf__occupancy_update(a, smooth_density, NULL, a->cells));
    CHECK_OK(nerf__occupancy_update(a, smooth_density, NULL, 100));
    size_t ema_bytes, bits_bytes, eb, bb;
    const float *ema = nerf__occupancy_ema(a, &ema_bytes);
    const uint64_t *bits = nerf__occupancy_bits(a, &bits_bytes);
    CHECK_EQ_INT(ema_bytes, 8000 * sizeof(float));
    CHECK_EQ_INT(bits_bytes, 125 * sizeof(uint64_t));
    /* Sizes of another grid are refused. */
    CHECK_EQ_INT(nerf__occupancy_restore(b, ema, ema_bytes - 4, bits,
                                         bits_bytes, a->updates),
                 NERF_EFORMAT);
    CHECK_EQ_INT(nerf__occupancy_restore(b, ema, ema_bytes, bits,
                                         bits_bytes + 8, a->updates),
                 NERF_EFORMAT);
    CHECK_EQ_INT(b->updates, 0);
    /* Restore only the EMA and the counter; the bits follow. */
    CHECK_OK(nerf__occupancy_restore(b, ema, ema_bytes, NULL, 0, a->updates));
    CHECK(memcmp(nerf__occupancy_bits(b, &bb), bits, bits_bytes) == 0);
    CHECK(memcmp(nerf__occupancy_ema(b, &eb), ema, ema_bytes) == 0);
    CHECK(memcmp(a->coarse, b->coarse, 8) == 0);
    CHECK_EQ_INT(b->occupied, a->occupied);
    CHECK_EQ_INT(b->updates, a->updates);
    CHECK(b->threshold == a->threshold);
    /* Or both. */
    nerf__occupancy_reset(b);
    CHECK_OK(nerf__occupancy_restore(b, ema, ema_bytes, bits, bits_bytes,
                                     a->updates));
    CHECK(memcmp(b->bits, bits, bits_bytes) == 0);
    CHECK(memcmp(a->coarse, b->coarse, 8) == 0);
    CHECK_EQ_INT(b->occupied, a->occupied);
    CHECK(b->mean == a->mean && b->threshold == a->threshold);
    /* And both continue identically. */
    CHECK_OK(nerf__occupancy_update(a, smooth_density, NULL, 300));
    CHECK_OK(nerf__occupancy_update(b, smooth_density, NULL, 300));
    CHECK(memcmp(a->ema, b->ema, ema_bytes) == 0);
    CHECK(memcmp(a->bits, b->bits, bits_bytes) == 0);
    nerf__occupancy_destroy(a);
    nerf__occupancy_destroy(b);
}

TEST(bad_options)
{
    nerf__env env;
    nerf__env_default(&env);
    const float lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    nerf__occupancy_options o;
    nerf__occupancy *g = NULL;
    nerf__occupancy_defaults(&o, lo, hi);
    o.resolution = 0;
    CHECK_EQ_INT(nerf__occupancy_create(&env, &o, &g), NERF_EINVAL);
    o.resolution = 1025;
    CHECK_EQ_INT(nerf__occupancy_create(&env, &o, &g), NERF_EINVAL);
    nerf__occupancy_defaults(&o, lo, hi);
    o.hi[1] = -1.0f;
    CHECK_EQ_INT(nerf__occupancy_create(&env, &o, &g), NERF_EINVAL);
    nerf__occupancy_defaults(&o, lo, hi);
    o.decay = 0.0f;
    CHECK_EQ_INT(nerf__occupancy_create(&env, &o, &g), NERF_EINVAL);
    nerf__occupancy_defaults(&o, lo, hi);
    o.density_threshold = NAN;
    CHECK_EQ_INT(nerf__occupancy_create(&env, &o, &g), NERF_EINVAL);
    CHECK(g == NULL);
    /* A single cell works. */
    nerf__occupancy_defaults(&o, lo, hi);
    o.resolution = 1;
    CHECK_OK(nerf__occupancy_create(&env, &o, &g));
    if (g) {
        CHECK_OK(nerf__occupancy_update(g, smooth_density, NULL, 0));
        CHECK_EQ_INT(g->evaluated, 1);
        nerf__occupancy_destroy(g);
    }
}

int main(void)
{
    RUN(defaults_and_threshold_rule);
    RUN(fresh_grid_is_all_occupied);
    RUN(sphere_cells);
    RUN(threshold_is_min_of_rule_and_mean);
    RUN(decay_and_schedule);
    RUN(occupied_cells_always_sampled);
    RUN(updates_are_deterministic);
    RUN(coarse_level);
    RUN(callback_failure);
    RUN(serialisation_round_trip);
    RUN(bad_options);
    HARNESS_EXIT();
}
