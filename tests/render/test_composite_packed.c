/*
 * Compositing of packed samples with per-sample dt: the forward against a
 * double-precision evaluation of the formula, piecewise accumulation,
 * early termination, and the backward against central differences.
 */
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "composite_packed.h"
#include "rng.h"

#define N_RAYS 300
#define MAX_PER_RAY 60

typedef struct batch {
    size_t offsets[N_RAYS + 1];
    float t[N_RAYS * MAX_PER_RAY], dt[N_RAYS * MAX_PER_RAY];
    float rgb[3 * N_RAYS * MAX_PER_RAY], sigma[N_RAYS * MAX_PER_RAY];
    float bg[3 * N_RAYS];
} batch;

/* Random rays: 0 .. MAX_PER_RAY samples, some empty space, densities up
 * to `dense`. */
static void make_batch(batch *b, uint64_t seed, float dense)
{
    nerf__rng r = nerf__rng_make(seed, 0);
    size_t at = 0;
    b->offsets[0] = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        uint32_t n = (uint32_t)(nerf__rng_uniform(&r) * (MAX_PER_RAY + 1));
        float t = 2.0f + nerf__rng_uniform(&r);
        for (uint32_t i = 0; i < n; i++, at++) {
            b->dt[at] = 0.001f + 0.05f * nerf__rng_uniform(&r);
            t += b->dt[at] * (1.0f + 3.0f * nerf__rng_uniform(&r));
            b->t[at] = t;
            b->sigma[at] = nerf__rng_uniform(&r) < 0.3f
                               ? 0.0f
                               : dense * nerf__rng_uniform(&r);
            for (int c = 0; c < 3; c++) {
                b->rgb[3 * at + c] = nerf__rng_uniform(&r);
            }
        }
        b->offsets[k + 1] = at;
        for (int c = 0; c < 3; c++) {
            b->bg[3 * k + c] = nerf__rng_uniform(&r);
        }
    }
}

/* rgb[3], depth, opacity of the first m samples in double. */
static void reference(uint32_t m, const double *t, const double *dt,
                      const double *rgb, const double *sigma,
                      const double *bg, double out[5], double *w_out)
{
    double trans = 1.0, acc = 0.0;
    memset(out, 0, 5 * sizeof(double));
    for (uint32_t i = 0; i < m; i++) {
        double alpha = 1.0 - exp(-sigma[i] * dt[i]);
        double w = trans * alpha;
        for (int c = 0; c < 3; c++) {
            out[c] += w * rgb[3 * i + c];
        }
        out[3] += w * t[i];
        acc += w;
        trans *= 1.0 - alpha;
        if (w_out) {
            w_out[i] = w;
        }
    }
    for (int c = 0; c < 3 && bg; c++) {
        out[c] += (1.0 - acc) * bg[c];
    }
    out[4] = acc;
}

static void to_double(const float *x, double *y, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        y[i] = x[i];
    }
}

TEST(forward_matches_formula)
{
    static batch b;
    make_batch(&b, 1, 40.0f);
    static float rgb[3 * N_RAYS], depth[N_RAYS], opacity[N_RAYS];
    static float weights[N_RAYS * MAX_PER_RAY];
    static uint32_t used[N_RAYS];
    for (int mode = 0; mode < 3; mode++) {
        /* Per-ray background, one shared, none. */
        nerf__packed_batch pb = {.n_rays = N_RAYS, .offsets = b.offsets,
                                 .t = b.t, .dt = b.dt, .rgb = b.rgb,
                                 .sigma = b.sigma,
                                 .bg = mode < 2 ? b.bg : NULL,
                                 .bg_stride = mode == 0 ? 3 : 0, .eps = 0.0f};
        nerf__packed_out out = {rgb, depth, opacity, used, weights};
        nerf__composite_packed(&pb, &out);
        double worst = 0.0, worst_w = 0.0;
        for (size_t k = 0; k < N_RAYS; k++) {
            const size_t at = b.offsets[k];
            const uint32_t n = (uint32_t)(b.offsets[k + 1] - at);
            double t[MAX_PER_RAY], dt[MAX_PER_RAY], c[3 * MAX_PER_RAY];
            double s[MAX_PER_RAY], w[MAX_PER_RAY], bg[3], ref[5];
            to_double(b.t + at, t, n);
            to_double(b.dt + at, dt, n);
            to_double(b.rgb + 3 * at, c, 3 * n);
            to_double(b.sigma + at, s, n);
            to_double(b.bg + (mode == 0 ? 3 * k : 0), bg, 3);
            reference(n, t, dt, c, s, mode < 2 ? bg : NULL, ref, w);
            CHECK_EQ_INT(used[k], n);
            for (int ch = 0; ch < 3; ch++) {
                worst = fmax(worst, fabs(rgb[3 * k + ch] - ref[ch]));
            }
            worst = fmax(worst, fabs(depth[k] - ref[3]) / (1.0 + ref[3]));
            worst = fmax(worst, fabs(opacity[k] - ref[4]));
            /* Not fmax: GCC 12 for aarch64 crashes (internal compiler
             * error) vectorising an fmax reduction over widened floats.
             * A NaN error is skipped here just as fmax skips it. */
            for (uint32_t i = 0; i < n; i++) {
                const double e = fabs(weights[at + i] - w[i]);
                if (e > worst_w) {
                    worst_w = e;
                }
            }
            if (n == 0) {
                CHECK(opacity[k] == 0.0f && depth[k] == 0.0f);
                CHECK(rgb[3 * k] == (mode < 2 ? b.bg[mode == 0 ? 3 * k : 0]
                                              : 0.0f));
            }
        }
        CHECK(worst < 2e-6 && worst_w < 1e-6);
        printf("  background mode %d: largest error %.2g (weights %.2g)\n",
               mode, worst, worst_w);
    }
}

TEST(thin_media_keep_precision)
{
    /* 1000 steps of s dt = 1e-5: opacity 1 - exp(-0.01) to float
     * precision, where 1 - expf(-x) per step would be off by ~1%. */
    static float t[1000], dt[1000], rgb[3000], sigma[1000];
    for (int i = 0; i < 1000; i++) {
        t[i] = 1.0f + 0.001f * (float)i;
        dt[i] = 0.001f;
        sigma[i] = 0.01f;
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 1.0f;
    }
    nerf__composite_state s;
    nerf__composite_state_init(&s);
    CHECK_EQ_INT(nerf__composite_packed_ray(&s, 1000, t, dt, rgb, sigma,
                                            0.0f, NULL), 1000);
    double expect = -expm1(-0.01);
    CHECK(fabs(s.opacity - expect) < 1e-4 * expect);
    CHECK(fabs(s.trans - (1.0 - expect)) < 3e-5);
}

TEST(pieces_equal_one_call)
{
    static batch b;
    make_batch(&b, 2, 80.0f);
    nerf__rng r = nerf__rng_make(3, 0);
    const float eps = 1e-3f;
    size_t bad = 0;
    for (size_t k = 0; k < N_RAYS; k++) {
        const size_t at = b.offsets[k];
        const uint32_t n = (uint32_t)(b.offsets[k + 1] - at);
        nerf__composite_state one, parts;
        nerf__composite_state_init(&one);
        nerf__composite_state_init(&parts);
        uint32_t u1 = nerf__composite_packed_ray(&one, n, b.t + at, b.dt + at,
                                                 b.rgb + 3 * at,
                                                 b.sigma + at, eps, NULL);
        uint32_t u2 = 0, i = 0;
        while (i < n && !nerf__composite_state_done(&parts, eps)) {
            uint32_t piece = 1 + (uint32_t)(nerf__rng_uniform(&r) * 8);
            piece = piece < n - i ? piece : n - i;
            uint32_t got = nerf__composite_packed_ray(
                &parts, piece, b.t + at + i, b.dt + at + i,
                b.rgb + 3 * (at + i), b.sigma + at + i, eps, NULL);
            u2 += got;
            i += piece;
            if (got < piece) {
                break;
            }
        }
        bad += u1 != u2 || memcmp(&one, &parts, sizeof one) != 0;
    }
    CHECK_EQ_INT(bad, 0);
}

TEST(early_termination)
{
    static batch b;
    make_batch(&b, 4, 200.0f);
    static float rgb0[3 * N_RAYS], op0[N_RAYS], rgb1[3 * N_RAYS], op1[N_RAYS];
    static float w1[N_RAYS * MAX_PER_RAY];
    static uint32_t used0[N_RAYS], used1[N_RAYS];
    const float eps = NERF__COMPOSITE_EPS_DEFAULT;
    nerf__packed_batch pb = {.n_rays = N_RAYS, .offsets = b.offsets,
                             .t = b.t, .dt = b.dt, .rgb = b.rgb,
                             .sigma = b.sigma, .bg = b.bg, .bg_stride = 3};
    nerf__packed_out out0 = {.rgb = rgb0, .opacity = op0, .used = used0};
    nerf__composite_packed(&pb, &out0);
    pb.eps = eps;
    nerf__packed_out out1 = {.rgb = rgb1, .opacity = op1, .used = used1,
                             .weights = w1};
    nerf__composite_packed(&pb, &out1);
    size_t stopped = 0, bad = 0, all = 0, kept = 0;
    double worst = 0.0;
    for (size_t k = 0; k < N_RAYS; k++) {
        const size_t at = b.offsets[k];
        const uint32_t n = (uint32_t)(b.offsets[k + 1] - at);
        all += n;
        kept += used1[k];
        stopped += used1[k] < n;
        for (int c = 0; c < 3; c++) {
            worst = fmax(worst, fabs(rgb0[3 * k + c] - rgb1[3 * k + c]));
        }
        worst = fmax(worst, fabs(op0[k] - op1[k]));
        /* The ray stops at the first sample with T below eps. */
        double trans = 1.0;
        uint32_t expect = 0;
        while (expect < n && trans >= eps) {
            trans *= exp(-(double)b.sigma[at + expect] * b.dt[at + expect]);
            expect++;
        }
        bad += used1[k] != expect && fabs(trans - eps) > 1e-4 * eps;
        /* The densities alone tell the same count. */
        float T = 1.0f;
        bad += nerf__composite_packed_ray_used(n, b.dt + at, b.sigma + at,
                                               eps, &T) != used1[k];
        /* And so do they counted in two pieces, the transmittance carried
         * from the first to the second. */
        const uint32_t first = n / 3;
        float T2 = 1.0f;
        uint32_t u2 = nerf__composite_packed_ray_used(first, b.dt + at,
                                                      b.sigma + at, eps, &T2);
        if (u2 == first) {
            u2 += nerf__composite_packed_ray_used(n - first,
                                                  b.dt + at + first,
                                                  b.sigma + at + first, eps,
                                                  &T2);
        }
        bad += u2 != used1[k] || T2 != T;
        for (uint32_t i = used1[k]; i < n; i++) {
            bad += w1[at + i] != 0.0f;
        }
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(worst < eps);
    CHECK(stopped > N_RAYS / 3);
    printf("  %zu of %d rays stop early, %zu of %zu samples used; largest "
           "difference %.2g\n", stopped, N_RAYS, kept, all, worst);
}

/* ---- gradients ------------------------------------------------------- */

/* L = g . (rgb, depth, opacity) over the first m samples. */
static double loss(uint32_t m, const double *t, const double *dt,
                   const double *rgb, const double *sigma, const double *bg,
                   const double g[5])
{
    double out[5];
    reference(m, t, dt, rgb, sigma, bg, out, NULL);
    double l = 0.0;
    for (int k = 0; k < 5; k++) {
        l += g[k] * out[k];
    }
    return l;
}

TEST(backward_matches_finite_differences)
{
    static batch b;
    const float g5[5] = {0.3f, -1.1f, 0.7f, 0.05f, -0.4f};
    double worst = 0.0;
    size_t checked = 0;
    for (int round = 0; round < 4; round++) {
        /* Densities up to 60 with eps > 0 make some rays terminate; the
         * samples used are then held fixed (the cut is piecewise
         * constant). */
        const float eps = round % 2 ? 1e-3f : 0.0f;
        const bool with_bg = round < 2;
        make_batch(&b, 10 + (uint64_t)round, round < 2 ? 20.0f : 60.0f);
        for (size_t k = 0; k < N_RAYS; k += 7) {
            const size_t at = b.offsets[k];
            const uint32_t n = (uint32_t)(b.offsets[k + 1] - at);
            float d_rgb[3 * MAX_PER_RAY], d_sigma[MAX_PER_RAY];
            const float *bg = with_bg ? b.bg + 3 * k : NULL;
            uint32_t m = nerf__composite_packed_ray_backward(
                n, b.t + at, b.dt + at, b.rgb + 3 * at, b.sigma + at, bg, eps,
                g5, g5[3], g5[4], d_rgb, d_sigma);
            nerf__composite_state s;
            nerf__composite_state_init(&s);
            CHECK_EQ_INT(m, nerf__composite_packed_ray(
                                &s, n, b.t + at, b.dt + at, b.rgb + 3 * at,
                                b.sigma + at, eps, NULL));
            double t[MAX_PER_RAY], dt[MAX_PER_RAY], c[3 * MAX_PER_RAY];
            double sg[MAX_PER_RAY], bgd[3], g[5];
            to_double(b.t + at, t, n);
            to_double(b.dt + at, dt, n);
            to_double(b.rgb + 3 * at, c, 3 * n);
            to_double(b.sigma + at, sg, n);
            to_double(b.bg + 3 * k, bgd, 3);
            to_double(g5, g, 5);
            const double h = 1e-6;
            for (uint32_t i = 0; i < 4 * n; i++) {
                const bool is_sigma = i < n;
                const uint32_t j = is_sigma ? i : i - n;
                const float analytic = is_sigma ? d_sigma[j] : d_rgb[j];
                if ((is_sigma ? j : j / 3) >= m) {
                    /* Past the cut: no gradient at all. */
                    CHECK(analytic == 0.0f);
                    continue;
                }
                double *x = is_sigma ? &sg[j] : &c[j];
                const double x0 = *x;
                *x = x0 + h;
                double lp = loss(m, t, dt, c, sg, with_bg ? bgd : NULL, g);
                *x = x0 - h;
                double lm = loss(m, t, dt, c, sg, with_bg ? bgd : NULL, g);
                *x = x0;
                const double fd = (lp - lm) / (2 * h);
                const double err = fabs(analytic - fd) / (fabs(fd) + 1e-3);
                worst = fmax(worst, err);
                checked++;
                if (err > 1e-3) {
                    FAILF("round %d ray %zu %s %u: analytic %.8g, finite "
                          "difference %.8g", round, k,
                          is_sigma ? "sigma" : "rgb", j, analytic, fd);
                }
            }
        }
    }
    printf("  %zu derivatives, worst relative error %.2e\n", checked, worst);
}

TEST(batch_backward_matches_rays)
{
    static batch b;
    make_batch(&b, 21, 50.0f);
    static float d_out[3 * N_RAYS], d_depth[N_RAYS], d_op[N_RAYS];
    static float d_rgb[3 * N_RAYS * MAX_PER_RAY], d_sigma[N_RAYS * MAX_PER_RAY];
    nerf__rng r = nerf__rng_make(22, 0);
    for (size_t i = 0; i < N_RAYS; i++) {
        for (int c = 0; c < 3; c++) {
            d_out[3 * i + c] = nerf__rng_uniform(&r) - 0.5f;
        }
        d_depth[i] = 0.1f * (nerf__rng_uniform(&r) - 0.5f);
        d_op[i] = nerf__rng_uniform(&r) - 0.5f;
    }
    const float shared_bg[3] = {1.0f, 1.0f, 1.0f};
    nerf__packed_batch pb = {.n_rays = N_RAYS, .offsets = b.offsets,
                             .t = b.t, .dt = b.dt, .rgb = b.rgb,
                             .sigma = b.sigma, .bg = shared_bg,
                             .bg_stride = 0, .eps = 1e-3f};
    for (int variant = 0; variant < 2; variant++) {
        const float *dd = variant ? NULL : d_depth;
        const float *dop = variant ? NULL : d_op;
        memset(d_sigma, 0xff, sizeof d_sigma); /* NaN: all overwritten */
        nerf__composite_packed_backward(&pb, d_out, dd, dop, d_rgb, d_sigma);
        size_t bad = 0;
        for (size_t k = 0; k < N_RAYS; k++) {
            const size_t at = b.offsets[k];
            const uint32_t n = (uint32_t)(b.offsets[k + 1] - at);
            float gr[3 * MAX_PER_RAY], gs[MAX_PER_RAY];
            nerf__composite_packed_ray_backward(
                n, b.t + at, b.dt + at, b.rgb + 3 * at, b.sigma + at,
                shared_bg, pb.eps, d_out + 3 * k, dd ? dd[k] : 0.0f,
                dop ? dop[k] : 0.0f, gr, gs);
            bad += memcmp(gr, d_rgb + 3 * at, 3 * n * sizeof(float)) != 0;
            bad += memcmp(gs, d_sigma + at, n * sizeof(float)) != 0;
        }
        CHECK_EQ_INT(bad, 0);
    }
}

int main(void)
{
    RUN(forward_matches_formula);
    RUN(thin_media_keep_precision);
    RUN(pieces_equal_one_call);
    RUN(early_termination);
    RUN(backward_matches_finite_differences);
    RUN(batch_backward_matches_rays);
    HARNESS_EXIT();
}
