/*
 * Compositing along one ray: closed-form cases (slab, step, empty space)
 * and the backward pass against the derivatives of a double-precision
 * mirror of the forward, taken in forward mode, within bounds derived
 * from the arithmetic.
 */
#include <math.h>
#include <string.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "composite.h"
#include "rng.h"
#include "sampler.h"

#define N_MAX 512

/* t[i] = a + i (b - a) / (n - 1). */
static void grid(uint32_t n, float a, float b, float *t)
{
    for (uint32_t i = 0; i < n; i++) {
        t[i] = a + (b - a) * (float)i / (float)(n - 1);
    }
}

TEST(slab_opacity)
{
    /* Density s on [z0, z0 + L): with samples on the slab's faces the
     * discrete product is exactly exp(-s L), up to the 1e-10 terms. */
    static const float s_list[] = {0.1f, 0.7f, 2.5f};
    static const float L_list[] = {0.2f, 1.0f, 1.5f};
    float t[N_MAX], rgb[3 * N_MAX], sigma[N_MAX], w[N_MAX];
    const uint32_t n = 401;
    grid(n, 2.0f, 6.0f, t); /* spacing 0.01 */
    for (int a = 0; a < 3; a++) {
        for (int b = 0; b < 3; b++) {
            float s = s_list[a], L = L_list[b], z0 = 3.0f;
            /* Direction of length 2: t spans half the world distance, so
             * the slab is L / 2 long in t. */
            for (uint32_t i = 0; i < n; i++) {
                bool inside = t[i] >= z0 - 1e-4f && t[i] < z0 + L / 2 - 1e-4f;
                sigma[i] = inside ? s : -1.0f; /* negative: ReLU to 0 */
                rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 0.5f;
            }
            nerf__ray_out out;
            nerf__composite_ray(n, t, 2.0f, rgb, sigma, false, w, &out);
            double expect = 1.0 - exp(-(double)s * L);
            CHECK_NEAR(out.opacity, expect, 2e-5);
            CHECK_NEAR(out.rgb[0], 0.5 * expect, 2e-5);
            /* White background: the rest of the ray sees white. */
            nerf__composite_ray(n, t, 2.0f, rgb, sigma, true, w, &out);
            CHECK_NEAR(out.rgb[1], 0.5 * expect + (1.0 - expect), 2e-5);
        }
    }
}

TEST(opaque_step_depth)
{
    /* An opaque wall at depth z: coarse depth lands within one sample
     * spacing after z.  The hierarchical pass fills the interval between
     * the midpoints around the first sample behind the wall, so the fine
     * depth is within half a spacing, and never worse than the coarse. */
    const uint32_t n_c = 64, n_f = 128;
    float t[N_MAX], tf[N_MAX], rgb[3 * N_MAX], sigma[N_MAX], w[N_MAX];
    float scratch[N_MAX * 3];
    static const float walls[] = {2.3f, 3.71f, 4.5f, 5.93f, 4.04f, 3.33f};
    for (int k = 0; k < 6; k++) {
        float z = walls[k];
        grid(n_c, 2.0f, 6.0f, t);
        for (uint32_t i = 0; i < n_c; i++) {
            sigma[i] = t[i] >= z ? 1e3f : 0.0f;
            rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 1.0f;
        }
        nerf__ray_out out;
        nerf__composite_ray(n_c, t, 1.0f, rgb, sigma, false, w, &out);
        float spacing = 4.0f / (n_c - 1);
        CHECK(fabsf(out.depth - z) <= spacing);
        CHECK_NEAR(out.opacity, 1.0, 1e-5);
        nerf__sample_fine_ray(n_c, n_f, t, w, false, NULL, NULL, scratch, tf);
        for (uint32_t i = 0; i < n_c + n_f; i++) {
            sigma[i] = tf[i] >= z ? 1e3f : 0.0f;
            rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 1.0f;
        }
        nerf__ray_out fine;
        nerf__composite_ray(n_c + n_f, tf, 1.0f, rgb, sigma, false, w, &fine);
        CHECK(fabsf(fine.depth - z) <= 0.5f * spacing + 1e-3f);
        CHECK(fabsf(fine.depth - z) <= fabsf(out.depth - z));
    }
}

TEST(empty_space_background)
{
    float t[64], rgb[3 * 64], sigma[64], w[64];
    grid(64, 2.0f, 6.0f, t);
    nerf__rng rng = nerf__rng_make(7, 0);
    for (int i = 0; i < 64; i++) {
        sigma[i] = -nerf__rng_uniform(&rng) * 5.0f; /* raw <= 0: empty */
        for (int c = 0; c < 3; c++) {
            rgb[3 * i + c] = nerf__rng_uniform(&rng);
        }
    }
    nerf__ray_out out;
    nerf__composite_ray(64, t, 1.3f, rgb, sigma, false, w, &out);
    for (int c = 0; c < 3; c++) {
        CHECK(out.rgb[c] == 0.0f);
    }
    CHECK(out.opacity == 0.0f && out.depth == 0.0f);
    CHECK(out.disparity == 1e10f);
    nerf__composite_ray(64, t, 1.3f, rgb, sigma, true, w, &out);
    for (int c = 0; c < 3; c++) {
        CHECK(out.rgb[c] == 1.0f);
    }
    for (int i = 0; i < 64; i++) {
        CHECK(w[i] == 0.0f);
    }
}

TEST(disparity_and_weights)
{
    float t[32], rgb[3 * 32], sigma[32], w[32];
    grid(32, 2.0f, 6.0f, t);
    for (int i = 0; i < 32; i++) {
        sigma[i] = 0.3f + 0.05f * (float)i;
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 0.2f;
    }
    nerf__ray_out out;
    nerf__composite_ray(32, t, 1.0f, rgb, sigma, false, w, &out);
    /* Sums of the weights the call returned, in double: the products of
     * floats are exact there, and each of the 32 additions rounds by at
     * most 2^-53 of the partial sum. */
    const int n = 32;
    double sum = 0.0, depth = 0.0;
    for (int i = 0; i < n; i++) {
        CHECK(w[i] >= 0.0f);
        sum += w[i];
        depth += (double)w[i] * t[i];
    }
    const double dbl = n * DOUBLE_U;
    /* The float opacity adds the n weights (n - 1 roundings after the
     * first, exact, addition to 0): within gamma(n - 1) of their exact
     * sum, all terms being >= 0.  The depth rounds each product w t too:
     * gamma(n). */
    CHECK_NEAR(out.opacity, sum, (float_gamma(n - 1) + dbl) * sum);
    CHECK_NEAR(out.depth, depth, (float_gamma(n) + dbl) * depth);
    /* disparity = 1 / (depth / opacity): the two sums' relative errors,
     * the division's and the reciprocal's, 2n + 1 factors (1 + d)^(+-1)
     * in all (Higham's lemma 3.1): gamma(2n + 1) relative. */
    const double disparity = sum / depth;
    CHECK_NEAR(out.disparity, disparity,
               (float_gamma(2 * n + 1) + 3 * dbl) * disparity);
}

/* ---- gradients ------------------------------------------------------- */

/* L = g_rgb . rgb + g_d depth + g_o opacity in the mirror of the forward
 * (float_bounds.h), with its derivative along the input that moves. */
static fbd loss_d(uint32_t n, const float *t, float dnorm, const fbd *rgb,
                  const fbd *sigma, const float *bg, const float *g)
{
    fbd c[3], depth, acc;
    fb_composite_forward(n, t, dnorm, rgb, sigma, bg, c, &depth, &acc,
                         NULL);
    fbd l = fbd_in(0.0);
    for (int k = 0; k < 3; k++) {
        l = fbd_add(l, fbd_mul(fbd_in(g[k]), c[k]));
    }
    l = fbd_add(l, fbd_mul(fbd_in(g[3]), depth));
    return fbd_add(l, fbd_mul(fbd_in(g[4]), acc));
}

/* bg: NULL (black), white (through the bool entry point) or a colour. */
static const float white_bg[3] = {1.0f, 1.0f, 1.0f};

/*
 * The backward against the derivative of the forward formula taken in
 * forward mode (float_bounds.h: no step, nothing truncated), each input
 * in turn: the float backward lies within the running bound of its own
 * operations (fb_composite_backward()) of the exact derivative, and the
 * forward-mode derivative, in double, within its bound of it too.  Raw
 * densities stay at least 0.2 from the ReLU's kink, so both sides take
 * the same branch.
 */
static void check_grad(uint32_t n, const float *bg, uint64_t seed,
                       double *worst)
{
    float t[64], rgb[3 * 64], sigma[64], d_rgb[3 * 64], d_sigma[64];
    nerf__rng rng = nerf__rng_make(seed, 1);
    float acc_t = 2.0f;
    for (uint32_t i = 0; i < n; i++) {
        acc_t += 0.02f + 0.1f * nerf__rng_uniform(&rng);
        t[i] = acc_t;
        /* Keep raw density away from the ReLU's kink at 0. */
        float s = 0.2f + 2.0f * nerf__rng_uniform(&rng);
        sigma[i] = nerf__rng_uniform(&rng) < 0.2f ? -s : s;
        for (int c = 0; c < 3; c++) {
            rgb[3 * i + c] = nerf__rng_uniform(&rng);
        }
    }
    const float dnorm = 1.7f;
    const float g[5] = {0.3f, -1.1f, 0.7f, 0.05f, -0.4f};
    if (bg == NULL || bg == white_bg) {
        nerf__composite_ray_backward(n, t, dnorm, rgb, sigma, bg != NULL, g,
                                     g[3], g[4], d_rgb, d_sigma);
    } else {
        nerf__composite_ray_backward_bg(n, t, dnorm, rgb, sigma, bg, g, g[3],
                                        g[4], d_rgb, d_sigma);
    }
    fbd c[3 * 64], sd[64];
    fb cx[3 * 64], sx[64], want_rgb[3 * 64], want_sigma[64];
    for (uint32_t i = 0; i < n; i++) {
        sd[i] = fbd_in(sigma[i]);
        sx[i] = sd[i].x;
        for (int k = 0; k < 3; k++) {
            c[3 * i + k] = fbd_in(rgb[3 * i + k]);
            cx[3 * i + k] = c[3 * i + k].x;
        }
    }
    const double dc[3] = {g[0], g[1], g[2]};
    fb_composite_backward(n, t, dnorm, cx, sx, bg, dc, g[3], g[4], want_rgb,
                          want_sigma);
    for (uint32_t i = 0; i < 4 * n; i++) {
        const bool is_sigma = i < n;
        fbd *x = is_sigma ? &sd[i] : &c[i - n];
        const float analytic = is_sigma ? d_sigma[i] : d_rgb[i - n];
        const fb want = is_sigma ? want_sigma[i] : want_rgb[i - n];
        const fbd keep = *x;
        *x = fbd_var(keep.x.v, 1.0);
        const fb d = loss_d(n, t, dnorm, c, sd, bg, g).dx;
        *x = keep;
        const double err = fabs(analytic - d.v);
        const double tol = (want.e + want.ed + d.ed) * (1.0 + 0x1p-30);
        if (err / tol > *worst) {
            *worst = err / tol;
        }
        if (!(err <= tol)) {
            FAILF("%s %u: analytic %.9g, forward mode %.9g (tolerance %.2g)",
                  i < n ? "sigma" : "rgb", i < n ? i : i - n, analytic, d.v,
                  tol);
        }
    }
}

TEST(backward_matches_forward_mode)
{
    double worst = 0.0;
    for (uint64_t seed = 0; seed < 6; seed++) {
        check_grad(seed % 2 ? 24 : 7, seed % 3 == 0 ? white_bg : NULL, seed,
                   &worst);
    }
    printf("  the largest error %.2f of its tolerance\n", worst);
}

/*
 * Random-background training finishes each ray on its own colour: the
 * colour enters the render as (1 - opacity) bg, and its gradient reaches
 * every weight as -dc . bg.  White and black through the colour entry
 * points are the bool ones bit for bit, so the default stays as it was.
 */
TEST(coloured_background)
{
    float t[24], rgb[3 * 24], sigma[24], w[24], d_rgb[2][3 * 24],
        d_sigma[2][24];
    grid(24, 2.0f, 6.0f, t);
    nerf__rng rng = nerf__rng_make(19, 0);
    for (int i = 0; i < 24; i++) {
        /* Partly transparent: the last sample, 1e10 long, is empty. */
        sigma[i] = i < 23 ? 0.4f * nerf__rng_uniform(&rng) + 0.05f : -0.1f;
        for (int c = 0; c < 3; c++) {
            rgb[3 * i + c] = nerf__rng_uniform(&rng);
        }
    }
    const float g[3] = {0.4f, -0.9f, 0.25f};
    const float bg[3] = {0.2f, 0.9f, 0.55f};
    nerf__ray_out black, a, b;
    nerf__composite_ray(24, t, 1.1f, rgb, sigma, false, w, &black);
    CHECK(black.opacity > 0.2f && black.opacity < 0.9f);
    nerf__composite_ray_bg(24, t, 1.1f, rgb, sigma, bg, w, &a);
    for (int c = 0; c < 3; c++) {
        CHECK_NEAR(a.rgb[c], black.rgb[c] + (1.0f - black.opacity) * bg[c],
                   1e-6);
    }
    for (int white = 0; white < 2; white++) {
        nerf__composite_ray(24, t, 1.1f, rgb, sigma, white, w, &a);
        nerf__composite_ray_bg(24, t, 1.1f, rgb, sigma,
                               white ? white_bg : NULL, w, &b);
        CHECK(memcmp(&a, &b, sizeof a) == 0);
        nerf__composite_ray_backward(24, t, 1.1f, rgb, sigma, white, g, 0.1f,
                                     -0.3f, d_rgb[0], d_sigma[0]);
        nerf__composite_ray_backward_bg(24, t, 1.1f, rgb, sigma,
                                        white ? white_bg : NULL, g, 0.1f,
                                        -0.3f, d_rgb[1], d_sigma[1]);
        CHECK(memcmp(d_rgb[0], d_rgb[1], sizeof d_rgb[0]) == 0);
        CHECK(memcmp(d_sigma[0], d_sigma[1], sizeof d_sigma[0]) == 0);
    }
    double worst = 0.0;
    for (uint64_t seed = 0; seed < 6; seed++) {
        const float colours[3][3] = {{0.2f, 0.9f, 0.55f},
                                     {0.0f, 0.0f, 1.0f},
                                     {0.7f, 0.05f, 0.3f}};
        check_grad(seed % 2 ? 24 : 7, colours[seed % 3], seed + 40, &worst);
    }
    printf("  the largest error %.2f of its tolerance\n", worst);
}

TEST(backward_opaque_sample)
{
    /* Behind a fully opaque sample T underflows; the gradients must stay
     * finite and those of hidden samples vanish. */
    float t[8], rgb[24], sigma[8], d_rgb[24], d_sigma[8];
    grid(8, 2.0f, 3.0f, t);
    for (int i = 0; i < 8; i++) {
        sigma[i] = i == 2 ? 1e6f : 0.5f;
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 0.5f;
    }
    const float g[3] = {1.0f, 1.0f, 1.0f};
    nerf__composite_ray_backward(8, t, 1.0f, rgb, sigma, true, g, 1.0f, 1.0f,
                                 d_rgb, d_sigma);
    for (int i = 0; i < 8; i++) {
        CHECK(isfinite(d_sigma[i]) && isfinite(d_rgb[3 * i]));
        if (i > 2) {
            CHECK(fabsf(d_rgb[3 * i]) < 1e-8f && fabsf(d_sigma[i]) < 1e-8f);
        }
    }
}

int main(void)
{
    RUN(slab_opacity);
    RUN(opaque_step_depth);
    RUN(empty_space_background);
    RUN(disparity_and_weights);
    RUN(backward_matches_forward_mode);
    RUN(coloured_background);
    RUN(backward_opaque_sample);
    HARNESS_EXIT();
}
