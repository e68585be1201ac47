/*
 * Compositing of packed samples with per-sample dt: the forward against a
 * double-precision evaluation of the formula, piecewise accumulation,
 * early termination, and the backward against forward-mode derivatives
 * of the forward, each within a bound derived from the arithmetic.
 */
#include <math.h>
#include <string.h>

#include "../float_bounds.h"
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

/* The colours and densities of n samples as exact inputs of a mirror
 * (float_bounds.h), held fixed. */
static void exact_inputs(uint32_t n, const float *rgb, const float *sigma,
                         fbd *rgb_in, fbd *sigma_in)
{
    for (uint32_t i = 0; i < n; i++) {
        sigma_in[i] = fbd_in(sigma[i]);
        for (int c = 0; c < 3; c++) {
            rgb_in[3 * i + c] = fbd_in(rgb[3 * i + c]);
        }
    }
}

/* The first m samples of a ray composited in the mirror: out = rgb[3],
 * depth, opacity; w[m] the weights, if not NULL. */
static void mirror(uint32_t m, const float *t, const float *dt,
                   const fbd *rgb, const fbd *sigma, const float *bg,
                   fbd out[5], fbd *w)
{
    fb_ray r;
    fb_ray_init(&r);
    for (uint32_t i = 0; i < m; i++) {
        fb_packed_step(&r, t[i], dt[i], rgb + 3 * i, sigma[i],
                       w ? w + i : NULL);
    }
    fb_packed_rgb(&r, bg, out);
    out[3] = r.depth;
    out[4] = r.opacity;
}

/*
 * Every output and weight within its running error bound (float_bounds.h)
 * of the formula evaluated in exact arithmetic on the same inputs: the
 * bound follows the float operations one by one, the relative error of
 * 1 - alpha included, which grows like alpha / (1 - alpha) where alpha
 * nears 1.
 */
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
        double worst = 0.0, bound = 0.0;
        size_t bad = 0;
        for (size_t k = 0; k < N_RAYS; k++) {
            const size_t at = b.offsets[k];
            const uint32_t n = (uint32_t)(b.offsets[k + 1] - at);
            fbd c[3 * MAX_PER_RAY], sg[MAX_PER_RAY], w[MAX_PER_RAY], ref[5];
            exact_inputs(n, b.rgb + 3 * at, b.sigma + at, c, sg);
            const float *bg = mode < 2 ? b.bg + (mode == 0 ? 3 * k : 0)
                                       : NULL;
            mirror(n, b.t + at, b.dt + at, c, sg, bg, ref, w);
            CHECK_EQ_INT(used[k], n);
            const float got[5] = {rgb[3 * k], rgb[3 * k + 1], rgb[3 * k + 2],
                                  depth[k], opacity[k]};
            for (int j = 0; j < 5; j++) {
                bad += !fb_holds(got[j], ref[j].x);
                worst = fmax(worst, fabs(got[j] - ref[j].x.v));
                bound = fmax(bound, ref[j].x.e + ref[j].x.ed);
            }
            for (uint32_t i = 0; i < n; i++) {
                bad += !fb_holds(weights[at + i], w[i].x);
            }
            if (n == 0) {
                CHECK(opacity[k] == 0.0f && depth[k] == 0.0f);
                CHECK(rgb[3 * k] == (mode < 2 ? b.bg[mode == 0 ? 3 * k : 0]
                                              : 0.0f));
            }
        }
        CHECK_EQ_INT(bad, 0);
        printf("  background mode %d: largest error %.2g (largest bound "
               "%.2g)\n", mode, worst, bound);
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
    /* Within the running bound of the float operations (about 2000
     * roundings of T and of 1 - alpha near 1, each at most u relative). */
    fb_ray r;
    fb_ray_init(&r);
    const fbd white[3] = {fbd_in(1.0), fbd_in(1.0), fbd_in(1.0)};
    for (int i = 0; i < 1000; i++) {
        fb_packed_step(&r, t[i], dt[i], white, fbd_in(sigma[i]), NULL);
    }
    const fb op = r.opacity.x, tr = r.trans.x;
    CHECK(fb_holds(s.opacity, op) && fb_holds(s.trans, tr));
    /* And that is float precision: 1 - expf(-x) per step would leave
     * alpha = 1e-5 with only its rounding to 2^-24 (a relative error up
     * to 3e-3), the opacity off by as much. */
    CHECK(op.e + op.ed < 2e-4 * op.v);
    printf("  opacity %.9g, bound %.2g; transmittance %.9g, bound %.2g\n",
           (double)s.opacity, op.e + op.ed, (double)s.trans, tr.e + tr.ed);
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
    size_t stopped = 0, bad = 0, all = 0, kept = 0, near_eps = 0;
    double worst = 0.0;
    for (size_t k = 0; k < N_RAYS; k++) {
        const size_t at = b.offsets[k];
        const uint32_t n = (uint32_t)(b.offsets[k + 1] - at);
        all += n;
        kept += used1[k];
        stopped += used1[k] < n;
        double d = fabs(op0[k] - op1[k]);
        for (int ch = 0; ch < 3; ch++) {
            d = fmax(d, fabs(rgb0[3 * k + ch] - rgb1[3 * k + ch]));
        }
        worst = fmax(worst, d);
        /* The ray stops at the first sample whose float T is below eps.
         * Exactly, it stops at the first whose exact T is; the two counts
         * differ only where, at the first sample at which one of them
         * stops, the exact T lies within the float T's running bound of
         * eps. */
        fb_ray r;
        fb_ray_init(&r);
        fbd c[3 * MAX_PER_RAY], sg[MAX_PER_RAY];
        exact_inputs(n, b.rgb + 3 * at, b.sigma + at, c, sg);
        uint32_t expect = 0;
        while (expect < n && r.trans.x.v >= eps) {
            fb_packed_step(&r, b.t[at + expect], b.dt[at + expect],
                           c + 3 * expect, sg[expect], NULL);
            expect++;
        }
        fb T_cut = r.trans.x;
        if (used1[k] < expect) {
            /* The float stopped first: replay to its cut. */
            fb_ray_init(&r);
            for (uint32_t i = 0; i < used1[k]; i++) {
                fb_packed_step(&r, b.t[at + i], b.dt[at + i], c + 3 * i,
                               sg[i], NULL);
            }
            T_cut = r.trans.x;
        }
        if (used1[k] != expect) {
            near_eps++;
            bad += !(fabs(T_cut.v - eps) <= (T_cut.e + T_cut.ed) *
                                                (1.0 + 0x1p-30));
        }
        /* The densities alone tell the same count. */
        float T = 1.0f;
        bad += nerf__composite_packed_ray_used(n, b.dt + at, b.sigma + at,
                                               eps, &T) != used1[k];
        /* What the samples after the cut could have added, in float
         * (float_early_stop_bound()); nothing where nothing was cut. */
        bad += d > (used1[k] < n ? float_early_stop_bound(n, used1[k], T)
                                 : 0.0);
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
    CHECK(stopped > N_RAYS / 3);
    printf("  %zu of %d rays stop early, %zu of %zu samples used; largest "
           "difference %.2g; %zu counts off the exact one by eps's "
           "rounding\n", stopped, N_RAYS, kept, all, worst, near_eps);
}

/* ---- gradients ------------------------------------------------------- */

/* L = g . (rgb, depth, opacity) over the first m samples, in the mirror
 * with its derivative along the input that moves. */
static fbd loss(uint32_t m, const float *t, const float *dt, const fbd *rgb,
                const fbd *sigma, const float *bg, const float g[5])
{
    fbd out[5];
    mirror(m, t, dt, rgb, sigma, bg, out, NULL);
    fbd l = fbd_in(0.0);
    for (int k = 0; k < 5; k++) {
        l = fbd_add(l, fbd_mul(fbd_in(g[k]), out[k]));
    }
    return l;
}

/*
 * The backward against the derivative of the forward formula taken in
 * forward mode (float_bounds.h: no step, nothing truncated), each input
 * in turn: the float backward lies within the running bound of its own
 * operations (fb_packed_backward()) of the exact derivative, and the
 * forward-mode derivative, in double, within its bound of it too.
 */
TEST(backward_matches_forward_mode)
{
    static batch b;
    const float g5[5] = {0.3f, -1.1f, 0.7f, 0.05f, -0.4f};
    const double dc[3] = {g5[0], g5[1], g5[2]};
    double worst = 0.0;
    size_t checked = 0, bad = 0;
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
            const float *t = b.t + at, *dt = b.dt + at;
            uint32_t m = nerf__composite_packed_ray_backward(
                n, t, dt, b.rgb + 3 * at, b.sigma + at, bg, eps, g5, g5[3],
                g5[4], d_rgb, d_sigma);
            nerf__composite_state s;
            nerf__composite_state_init(&s);
            CHECK_EQ_INT(m, nerf__composite_packed_ray(
                                &s, n, t, dt, b.rgb + 3 * at, b.sigma + at,
                                eps, NULL));
            fbd c[3 * MAX_PER_RAY], sg[MAX_PER_RAY];
            fb cx[3 * MAX_PER_RAY], sx[MAX_PER_RAY];
            fb want_rgb[3 * MAX_PER_RAY], want_sigma[MAX_PER_RAY];
            exact_inputs(n, b.rgb + 3 * at, b.sigma + at, c, sg);
            for (uint32_t i = 0; i < n; i++) {
                sx[i] = sg[i].x;
                for (int ch = 0; ch < 3; ch++) {
                    cx[3 * i + ch] = c[3 * i + ch].x;
                }
            }
            fb_packed_backward(m, t, dt, cx, sx, bg, dc, g5[3], g5[4],
                               want_rgb, want_sigma);
            for (uint32_t i = 0; i < 4 * n; i++) {
                const bool is_sigma = i < n;
                const uint32_t j = is_sigma ? i : i - n;
                const float analytic = is_sigma ? d_sigma[j] : d_rgb[j];
                if ((is_sigma ? j : j / 3) >= m) {
                    /* Past the cut: no gradient at all. */
                    CHECK(analytic == 0.0f);
                    continue;
                }
                fbd *x = is_sigma ? &sg[j] : &c[j];
                const fbd keep = *x;
                *x = fbd_var(keep.x.v, 1.0);
                const fb d = loss(m, t, dt, c, sg, bg, g5).dx;
                *x = keep;
                const fb want = is_sigma ? want_sigma[j] : want_rgb[j];
                const double err = fabs(analytic - d.v);
                const double tol = (want.e + want.ed + d.ed) *
                                   (1.0 + 0x1p-30);
                worst = fmax(worst, err / tol);
                checked++;
                if (!(err <= tol) && bad++ < 5) {
                    FAILF("round %d ray %zu %s %u: analytic %.9g, forward "
                          "mode %.9g (tolerance %.2g)", round, k,
                          is_sigma ? "sigma" : "rgb", j, analytic, d.v, tol);
                }
            }
        }
    }
    CHECK_EQ_INT(bad, 0);
    printf("  %zu derivatives, the largest error %.2f of its tolerance\n",
           checked, worst);
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
    RUN(backward_matches_forward_mode);
    RUN(batch_backward_matches_rays);
    HARNESS_EXIT();
}
