/*
 * Stratified and hierarchical sampling: placement rules, a statistical
 * test of inverse-transform sampling against a known density, caller
 * supplied uniforms, and independence from how a batch is split.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../harness.h"
#include "nerf.h"
#include "rng.h"
#include "sampler.h"

static nerf_sampler *make(uint32_t n_c, uint32_t n_f, float near, float far,
                          uint32_t lindisp, uint32_t paper, uint64_t seed)
{
    nerf_sampler_options o;
    NERF_SAMPLER_OPTIONS_INIT(&o);
    o.n_coarse = n_c;
    o.n_fine = n_f;
    o.t_near = near;
    o.t_far = far;
    o.lindisp = lindisp;
    o.paper_bins = paper;
    o.seed = seed;
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &o));
    return s;
}

TEST(options_and_presets)
{
    nerf_sampler_options o;
    CHECK_OK(NERF_SAMPLER_OPTIONS_INIT(&o));
    CHECK(o.n_coarse == 64 && o.n_fine == 128 && o.perturb == 1);
    CHECK(o.t_near == 2.0f && o.t_far == 6.0f && o.ndc == 0);
    CHECK_OK(nerf_sampler_options_preset(&o, NERF_PRESET_TINY));
    CHECK(o.n_coarse == 32 && o.n_fine == 64 && o.t_near == 2.0f);
    CHECK_EQ_INT(nerf_sampler_options_preset(&o, 99), NERF_EINVAL);

    nerf_sampler *s = NULL;
    o.t_near = 6.0f;
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
    CHECK(s == NULL);
    /* Bounds that are backwards, negative or not finite. */
    const float bad[][2] = {{6.0f, 2.0f}, {-1.0f, 2.0f}, {2.0f, INFINITY},
                            {NAN, 6.0f}, {2.0f, NAN}, {-INFINITY, 6.0f}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        o.t_near = bad[i][0];
        o.t_far = bad[i][1];
        CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
        CHECK(s == NULL);
        CHECK(strstr(nerf_last_error(), "0 <= t_near < t_far") != NULL);
    }
    o.t_far = 6.0f;
    o.t_near = 0.0f;
    o.lindisp = 1;
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
    o.lindisp = 0;
    o.ndc = 1;
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL); /* far 6 */
    o.t_far = 1.0f;
    CHECK_OK(nerf_sampler_create(&s, &o));
    nerf_sampler_destroy(s);
    o.ndc_focal = 400.0f; /* frustum partly set */
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
    o.ndc_focal = NAN;
    o.ndc_width = 10;
    o.ndc_height = 10;
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
    NERF_SAMPLER_OPTIONS_INIT(&o);
    o.n_coarse = 2; /* hierarchical sampling needs interior weights */
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
    o.n_fine = 0;
    CHECK_OK(nerf_sampler_create(&s, &o));
    float t[2];
    CHECK_OK(nerf_sampler_sample_coarse(s, 1, 0, 0, NULL, t));
    CHECK(t[0] == 2.0f && t[1] == 6.0f);
    CHECK_EQ_INT(nerf_sampler_sample_fine(s, 1, 0, 0, t, t, NULL, t),
                 NERF_EINVAL);
    CHECK_EQ_INT(nerf_sampler_sample_coarse(s, 1, 0x80, 0, NULL, t),
                 NERF_EINVAL);
    nerf_sampler_destroy(s);
    CHECK_OK(nerf_sampler_create(&s, NULL)); /* NULL: defaults */
    nerf_sampler_destroy(s);
    nerf_sampler_destroy(NULL);
}

TEST(marching_options)
{
    nerf_sampler_options o;
    CHECK_OK(NERF_SAMPLER_OPTIONS_INIT(&o));
    CHECK(o.march_steps == 0 && o.max_samples == 1024);
    CHECK_OK(nerf_sampler_options_preset(&o, NERF_PRESET_FAST));
    CHECK(o.march_steps == 1024 && o.max_samples == 1024);
    CHECK(o.n_coarse == 128 && o.n_fine == 0);
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &o));
    nerf_sampler_destroy(s);
    /* The other presets sample as before. */
    CHECK_OK(nerf_sampler_options_preset(&o, NERF_PRESET_TINY));
    CHECK(o.march_steps == 0 && o.n_coarse == 32);
    o.march_steps = 65537;
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "march_steps") != NULL);
    o.march_steps = 65536;
    o.max_samples = 0;
    CHECK_EQ_INT(nerf_sampler_create(&s, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "max_samples") != NULL);
    o.max_samples = 1;
    CHECK_OK(nerf_sampler_create(&s, &o));
    nerf_sampler_destroy(s);
    /* Marching NDC rays is for models whose space is NDC, which the
     * renderer and trainer check: the sampler alone accepts it. */
    o.ndc = 1;
    o.t_near = 0.0f;
    o.t_far = 1.0f;
    CHECK_OK(nerf_sampler_create(&s, &o));
    nerf_sampler_destroy(s);
    /* Without marching max_samples is not looked at. */
    o.march_steps = 0;
    o.max_samples = 0;
    CHECK_OK(nerf_sampler_create(&s, &o));
    nerf_sampler_destroy(s);
    /* A caller built against the header before 0.2 gets the defaults for
     * the fields its struct lacks: no marching. */
    NERF_SAMPLER_OPTIONS_INIT(&o);
    o.march_steps = 77;
    o.struct_size = offsetof(nerf_sampler_options, march_steps);
    CHECK_OK(nerf_sampler_create(&s, &o));
    CHECK(s != NULL && s->opts.march_steps == 0);
    CHECK(s != NULL && s->opts.max_samples == 1024);
    nerf_sampler_destroy(s);
}

TEST(stratified_evaluation)
{
    nerf_sampler *s = make(64, 0, 2.0f, 6.0f, 0, 0, 0);
    float t[64];
    CHECK_OK(nerf_sampler_sample_coarse(s, 1, 0, 0, NULL, t));
    CHECK(t[0] == 2.0f && t[63] == 6.0f); /* both ends included */
    for (int i = 0; i < 64; i++) {
        CHECK_NEAR(t[i], 2.0 + 4.0 * i / 63.0, 1e-6);
    }
    nerf_sampler_destroy(s);

    s = make(16, 0, 2.0f, 6.0f, 1, 0, 0); /* linear in disparity */
    float d[16];
    CHECK_OK(nerf_sampler_sample_coarse(s, 1, 0, 0,
                                        NULL, d));
    for (int i = 0; i < 16; i++) {
        double f = i / 15.0;
        CHECK_NEAR(d[i], 1.0 / (0.5 * (1 - f) + f / 6.0), 1e-5);
    }
    nerf_sampler_destroy(s);

    s = make(8, 0, 2.0f, 6.0f, 0, 1, 0); /* paper bins: centres */
    CHECK_OK(nerf_sampler_sample_coarse(s, 1, 0, 0, NULL, t));
    for (int i = 0; i < 8; i++) {
        CHECK_NEAR(t[i], 2.0 + 4.0 * (i + 0.5) / 8.0, 1e-6);
    }
    nerf_sampler_destroy(s);
}

TEST(stratified_training)
{
    /* Each jittered value is uniform between the midpoints to its
     * neighbours; the first starts at near, the last ends at far. */
    const int n = 16, rays = 4000;
    nerf_sampler *s = make(n, 0, 2.0f, 6.0f, 0, 0, 42);
    float *t = malloc(sizeof(float) * n * rays);
    CHECK_OK(nerf_sampler_sample_coarse(s, rays, NERF_SAMPLE_TRAINING, 0,
                                        NULL, t));
    double h = 4.0 / (n - 1), mean_frac[16] = {0};
    for (int r = 0; r < rays; r++) {
        for (int i = 0; i < n; i++) {
            double c = 2.0 + h * i;
            double lo = i == 0 ? c : c - h / 2, hi = i == n - 1 ? c : c + h / 2;
            float v = t[r * n + i];
            if (!(v >= lo - 1e-5 && v <= hi + 1e-5)) {
                FAILF("ray %d sample %d = %g outside [%g, %g]", r, i, v, lo,
                      hi);
                r = rays;
                break;
            }
            mean_frac[i] += (v - lo) / (hi - lo) / rays;
        }
    }
    for (int i = 0; i < n; i++) {
        /* The mean of 4000 uniforms has std 0.0046. */
        CHECK_NEAR(mean_frac[i], 0.5, 0.025);
    }
    /* Same seed, same first ray: same draws; split batches agree. */
    float *t2 = malloc(sizeof(float) * n * rays);
    CHECK_OK(nerf_sampler_sample_coarse(s, 1000, NERF_SAMPLE_TRAINING, 0,
                                        NULL, t2));
    CHECK_OK(nerf_sampler_sample_coarse(s, rays - 1000, NERF_SAMPLE_TRAINING,
                                        1000, NULL, t2 + 1000 * n));
    CHECK(memcmp(t, t2, sizeof(float) * n * rays) == 0);
    nerf_sampler_destroy(s);
    /* Another seed, other draws. */
    s = make(n, 0, 2.0f, 6.0f, 0, 0, 43);
    CHECK_OK(nerf_sampler_sample_coarse(s, rays, NERF_SAMPLE_TRAINING, 0,
                                        NULL, t2));
    CHECK(memcmp(t, t2, sizeof(float) * n * rays) != 0);
    nerf_sampler_destroy(s);

    /* Paper bins: one value in each equal bin. */
    s = make(n, 0, 2.0f, 6.0f, 0, 1, 1);
    CHECK_OK(nerf_sampler_sample_coarse(s, 100, NERF_SAMPLE_TRAINING, 0,
                                        NULL, t));
    for (int r = 0; r < 100; r++) {
        for (int i = 0; i < n; i++) {
            float v = t[r * n + i];
            CHECK(v >= 2.0f + 4.0f * i / n - 1e-5f &&
                  v <= 2.0f + 4.0f * (i + 1) / n + 1e-5f);
        }
    }
    nerf_sampler_destroy(s);
    free(t);
    free(t2);
}

TEST(caller_uniforms)
{
    const int n = 8;
    nerf_sampler *s = make(n, 4, 2.0f, 6.0f, 0, 0, 5);
    float u[8] = {0.0f, 0.999f, 0.5f, 0.25f, 0.75f, 0.1f, 0.9f, 0.3f};
    float t[8], even[8];
    CHECK_OK(nerf_sampler_sample_coarse(s, 1, 0, 0, NULL, even));
    CHECK_OK(nerf_sampler_sample_coarse(s, 1, NERF_SAMPLE_TRAINING, 0, u, t));
    for (int i = 0; i < n; i++) {
        float lo = i ? 0.5f * (even[i] + even[i - 1]) : even[0];
        float hi = i + 1 < n ? 0.5f * (even[i + 1] + even[i]) : even[n - 1];
        CHECK(t[i] == lo + (hi - lo) * u[i]);
    }
    /* Fine: u supplied gives the inverse CDF of those u. */
    float w[8] = {0, 0, 1, 0, 0, 0, 0, 0}; /* all mass on sample 2 */
    float uf[4] = {0.1f, 0.4f, 0.6f, 0.9f}, tf[12];
    CHECK_OK(nerf_sampler_sample_fine(s, 1, NERF_SAMPLE_TRAINING, 0, even, w,
                                      uf, tf));
    /* Sample 2 owns [mid(1,2), mid(2,3)]; nearly all mass is there. */
    float lo = 0.5f * (even[1] + even[2]), hi = 0.5f * (even[2] + even[3]);
    int inside = 0;
    for (int i = 0; i < 12; i++) {
        inside += tf[i] > lo && tf[i] < hi && tf[i] != even[2];
        if (i) {
            CHECK(tf[i] >= tf[i - 1]);
        }
    }
    CHECK_EQ_INT(inside, 4);
    nerf_sampler_destroy(s);
}

/* ---- inverse transform against a known density ---------------------- */

/* The CDF of the piecewise-constant density over edges with masses p. */
static double model_cdf(int nb, const double *edges, const double *p, double x)
{
    double c = 0.0;
    for (int k = 0; k < nb; k++) {
        if (x >= edges[k + 1]) {
            c += p[k];
        } else if (x > edges[k]) {
            c += p[k] * (x - edges[k]) / (edges[k + 1] - edges[k]);
        }
    }
    return c;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Kolmogorov-Smirnov distance between samples and the model CDF. */
static double ks_distance(int n, double *x, int nb, const double *edges,
                          const double *p)
{
    qsort(x, n, sizeof *x, cmp_double);
    double d = 0.0;
    for (int i = 0; i < n; i++) {
        double f = model_cdf(nb, edges, p, x[i]);
        double a = fabs(f - (double)i / n), b = fabs(f - (double)(i + 1) / n);
        d = fmax(d, fmax(a, b));
    }
    return d;
}

TEST(hierarchical_matches_pdf)
{
    /* Unevenly spaced bins with uneven masses.  The 1e-5 added to each
     * weight is part of the density. */
    enum { NB = 12, DRAWS = 64, RAYS = 2000 };
    float edges_f[NB + 1], w[NB], cdf[NB + 1], out[DRAWS];
    double edges[NB + 1], p[NB], total = 0.0;
    nerf__rng g = nerf__rng_make(99, 0);
    edges_f[0] = 2.0f;
    for (int k = 0; k < NB; k++) {
        edges_f[k + 1] = edges_f[k] + 0.05f + 0.5f * nerf__rng_uniform(&g);
        w[k] = k % 4 == 1 ? 0.0f : nerf__rng_uniform(&g);
    }
    for (int k = 0; k <= NB; k++) {
        edges[k] = edges_f[k];
    }
    for (int k = 0; k < NB; k++) {
        p[k] = (double)w[k] + 1e-5;
        total += p[k];
    }
    for (int k = 0; k < NB; k++) {
        p[k] /= total;
    }
    double *x = malloc(sizeof(double) * DRAWS * RAYS);
    for (int r = 0; r < RAYS; r++) {
        nerf__rng rng = nerf__ray_rng(3, NERF__STREAM_HIERARCHICAL, r);
        nerf__sample_pdf(NB, edges_f, w, DRAWS, true, NULL, &rng, cdf, out);
        for (int i = 0; i < DRAWS; i++) {
            x[r * DRAWS + i] = out[i];
        }
    }
    /* Critical value at level 1e-3 is 1.95 / sqrt(n) = 0.0054 here. */
    const int n = DRAWS * RAYS;
    double d = ks_distance(n, x, NB, edges, p);
    printf("  KS distance %.5f over %d draws (critical %.5f)\n", d, n,
           1.95 / sqrt(n));
    CHECK(d < 1.95 / sqrt(n));
    /* The test has power: the same draws against a density with two bins'
     * masses swapped are rejected. */
    double q[NB];
    memcpy(q, p, sizeof q);
    q[2] = p[3];
    q[3] = p[2];
    CHECK(ks_distance(n, x, NB, edges, q) > 1.95 / sqrt(n));
    /* Evenly spaced u: the empirical CDF is within one step of the model. */
    nerf__sample_pdf(NB, edges_f, w, DRAWS, false, NULL, NULL, cdf, out);
    double xe[DRAWS];
    for (int i = 0; i < DRAWS; i++) {
        xe[i] = out[i];
        CHECK(i == 0 || out[i] >= out[i - 1]);
    }
    CHECK(xe[0] == edges[0] && fabs(xe[DRAWS - 1] - edges[NB]) < 1e-5);
    CHECK(ks_distance(DRAWS, xe, NB, edges, p) <= 1.0 / (DRAWS - 1) + 1e-4);
    free(x);
}

TEST(fine_union_sorted)
{
    const uint32_t n_c = 32, n_f = 64, rays = 50;
    nerf_sampler *s = make(n_c, n_f, 2.0f, 6.0f, 0, 0, 11);
    float *tc = malloc(sizeof(float) * n_c * rays);
    float *w = malloc(sizeof(float) * n_c * rays);
    float *tf = malloc(sizeof(float) * (n_c + n_f) * rays);
    float *tf2 = malloc(sizeof(float) * (n_c + n_f) * rays);
    CHECK_OK(nerf_sampler_sample_coarse(s, rays, NERF_SAMPLE_TRAINING, 0, NULL,
                                        tc));
    nerf__rng g = nerf__rng_make(1, 2);
    for (uint32_t i = 0; i < n_c * rays; i++) {
        w[i] = nerf__rng_uniform(&g) < 0.5f ? 0.0f : nerf__rng_uniform(&g);
    }
    CHECK_OK(nerf_sampler_sample_fine(s, rays, NERF_SAMPLE_TRAINING, 0, tc, w,
                                      NULL, tf));
    for (uint32_t r = 0; r < rays; r++) {
        const float *a = tf + r * (n_c + n_f);
        uint32_t found = 0;
        for (uint32_t i = 0; i < n_c + n_f; i++) {
            CHECK(i == 0 || a[i] >= a[i - 1]);
            CHECK(a[i] >= 2.0f && a[i] <= 6.0f);
        }
        for (uint32_t j = 0; j < n_c; j++) {
            for (uint32_t i = 0; i < n_c + n_f; i++) {
                if (a[i] == tc[r * n_c + j]) {
                    found++;
                    break;
                }
            }
        }
        CHECK_EQ_INT(found, n_c);
    }
    /* Split in two calls: identical. */
    CHECK_OK(nerf_sampler_sample_fine(s, 20, NERF_SAMPLE_TRAINING, 0, tc, w,
                                      NULL, tf2));
    CHECK_OK(nerf_sampler_sample_fine(s, rays - 20, NERF_SAMPLE_TRAINING, 20,
                                      tc + 20 * n_c, w + 20 * n_c, NULL,
                                      tf2 + 20 * (n_c + n_f)));
    CHECK(memcmp(tf, tf2, sizeof(float) * (n_c + n_f) * rays) == 0);
    nerf_sampler_destroy(s);
    free(tc);
    free(w);
    free(tf);
    free(tf2);
}

int main(void)
{
    RUN(options_and_presets);
    RUN(marching_options);
    RUN(stratified_evaluation);
    RUN(stratified_training);
    RUN(caller_uniforms);
    RUN(hierarchical_matches_pdf);
    RUN(fine_union_sorted);
    HARNESS_EXIT();
}
