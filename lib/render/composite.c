/* Compositing along one ray, forward and backward (see composite.h). */
#include "composite.h"

#include <math.h>
#include <stddef.h>

/* Distance to the next sample, scaled to world units. */
static float delta(uint32_t n, const float *t, uint32_t i, float dir_norm)
{
    float dt = i + 1 < n ? t[i + 1] - t[i] : 1e10f;
    return dt * dir_norm;
}

/* x * 1.0f is x exactly, so white through the general path is the
 * white of before. */
static const float white_bg[3] = {1.0f, 1.0f, 1.0f};

void nerf__composite_ray(uint32_t n, const float *t, float dir_norm,
                         const float *rgb, const float *sigma, bool white,
                         float *weights, nerf__ray_out *out)
{
    nerf__composite_ray_bg(n, t, dir_norm, rgb, sigma,
                           white ? white_bg : NULL, weights, out);
}

void nerf__composite_ray_bg(uint32_t n, const float *t, float dir_norm,
                            const float *rgb, const float *sigma,
                            const float *bg, float *weights,
                            nerf__ray_out *out)
{
    float trans = 1.0f;
    float r = 0.0f, g = 0.0f, b = 0.0f, depth = 0.0f, acc = 0.0f;
    for (uint32_t i = 0; i < n; i++) {
        float density = sigma[i] > 0.0f ? sigma[i] : 0.0f;
        float alpha = 1.0f - expf(-density * delta(n, t, i, dir_norm));
        float w = alpha * trans;
        trans = trans * (1.0f - alpha + 1e-10f);
        if (weights) {
            weights[i] = w;
        }
        r += w * rgb[3 * i];
        g += w * rgb[3 * i + 1];
        b += w * rgb[3 * i + 2];
        depth += w * t[i];
        acc += w;
    }
    if (bg) {
        r += (1.0f - acc) * bg[0];
        g += (1.0f - acc) * bg[1];
        b += (1.0f - acc) * bg[2];
    }
    out->rgb[0] = r;
    out->rgb[1] = g;
    out->rgb[2] = b;
    out->depth = depth;
    out->opacity = acc;
    /* The reference divides 0 by 0 on empty rays and gets NaN; fmaxf
     * drops the NaN, giving disparity 1e10 there. */
    out->disparity = 1.0f / fmaxf(1e-10f, depth / acc);
}

/*
 * With q_j = 1 - alpha_j + 1e-10, dw_k/dalpha_i is T_i for k = i and
 * -T_i alpha_k prod_(i<j<k) q_j for k > i.  So, with g_k = dL/dw_k,
 *   dL/dalpha_i = T_i (g_i - R_i),  R_i = sum_(k>i) g_k alpha_k
 *                                          prod_(i<j<k) q_j,
 * and R runs backwards as R_(i-1) = g_i alpha_i + q_i R_i.  Nothing is
 * divided by q, which stays exact when T underflows behind an opaque
 * sample.  T_i is recomputed forward first.
 */
void nerf__composite_ray_backward(uint32_t n, const float *t, float dir_norm,
                                  const float *rgb, const float *sigma,
                                  bool white, const float *d_out_rgb,
                                  float d_depth, float d_opacity,
                                  float *d_rgb, float *d_sigma)
{
    nerf__composite_ray_backward_bg(n, t, dir_norm, rgb, sigma,
                                    white ? white_bg : NULL, d_out_rgb,
                                    d_depth, d_opacity, d_rgb, d_sigma);
}

void nerf__composite_ray_backward_bg(uint32_t n, const float *t,
                                     float dir_norm, const float *rgb,
                                     const float *sigma, const float *bg,
                                     const float *d_out_rgb, float d_depth,
                                     float d_opacity, float *d_rgb,
                                     float *d_sigma)
{
    const float dc[3] = {d_out_rgb ? d_out_rgb[0] : 0.0f,
                         d_out_rgb ? d_out_rgb[1] : 0.0f,
                         d_out_rgb ? d_out_rgb[2] : 0.0f};
    /* rgb carries + (1 - sum w) bg: each weight also gains -dc . bg. */
    const float dbg = bg ? dc[0] * bg[0] + dc[1] * bg[1] + dc[2] * bg[2]
                         : 0.0f;
    /* d_sigma doubles as storage for T while going forward. */
    float trans = 1.0f;
    for (uint32_t i = 0; i < n; i++) {
        float density = sigma[i] > 0.0f ? sigma[i] : 0.0f;
        float alpha = 1.0f - expf(-density * delta(n, t, i, dir_norm));
        d_sigma[i] = trans;
        trans = trans * (1.0f - alpha + 1e-10f);
    }
    float rest = 0.0f; /* R_i */
    for (uint32_t i = n; i-- > 0;) {
        float dist = delta(n, t, i, dir_norm);
        float density = sigma[i] > 0.0f ? sigma[i] : 0.0f;
        float e = expf(-density * dist);
        float alpha = 1.0f - e;
        float ti = d_sigma[i];
        float w = alpha * ti;
        float g = dc[0] * rgb[3 * i] + dc[1] * rgb[3 * i + 1] +
                  dc[2] * rgb[3 * i + 2] - dbg + d_depth * t[i] + d_opacity;
        for (int c = 0; c < 3; c++) {
            d_rgb[3 * i + c] = w * dc[c];
        }
        float d_alpha = ti * (g - rest);
        d_sigma[i] = sigma[i] > 0.0f ? d_alpha * dist * e : 0.0f;
        rest = g * alpha + (1.0f - alpha + 1e-10f) * rest;
    }
}
