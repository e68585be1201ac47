/* Compositing of packed, marched samples (see composite_packed.h). */
#include "composite_packed.h"

#include <math.h>
#include <string.h>

#include "parallel.h"

/* expm1f keeps alpha accurate for the small s dt of fine steps through
 * thin media, where 1 - expf(-x) would keep only a few digits. */
static inline float alpha_of(float sigma, float dt)
{
    return -expm1f(-sigma * dt);
}

uint32_t nerf__composite_packed_ray(nerf__composite_state *s, uint32_t n,
                                    const float *t, const float *dt,
                                    const float *rgb, const float *sigma,
                                    float eps, float *weights)
{
    float trans = s->trans;
    float r = s->rgb[0], g = s->rgb[1], b = s->rgb[2];
    float depth = s->depth, acc = s->opacity;
    uint32_t i = 0;
    for (; i < n && !(trans < eps); i++) {
        float alpha = alpha_of(sigma[i], dt[i]);
        float w = trans * alpha;
        r += w * rgb[3 * i];
        g += w * rgb[3 * i + 1];
        b += w * rgb[3 * i + 2];
        depth += w * t[i];
        acc += w;
        trans *= 1.0f - alpha;
        if (weights) {
            weights[i] = w;
        }
    }
    if (weights) {
        for (uint32_t k = i; k < n; k++) {
            weights[k] = 0.0f;
        }
    }
    s->rgb[0] = r;
    s->rgb[1] = g;
    s->rgb[2] = b;
    s->depth = depth;
    s->opacity = acc;
    s->trans = trans;
    return i;
}

uint32_t nerf__composite_packed_ray_used(uint32_t n, const float *dt,
                                         const float *sigma, float eps,
                                         float *trans)
{
    float T = *trans;
    uint32_t i = 0;
    for (; i < n && !(T < eps); i++) {
        T *= 1.0f - alpha_of(sigma[i], dt[i]);
    }
    *trans = T;
    return i;
}

void nerf__composite_state_rgb(const nerf__composite_state *s,
                               const float *bg, float rgb[3])
{
    /* 1 - opacity rather than T: the two agree up to rounding, and this
     * one has the simple gradient -bg per weight. */
    float rest = 1.0f - s->opacity;
    for (int c = 0; c < 3; c++) {
        rgb[c] = s->rgb[c] + (bg ? rest * bg[c] : 0.0f);
    }
}

uint32_t nerf__composite_packed_ray_backward(
    uint32_t n, const float *t, const float *dt, const float *rgb,
    const float *sigma, const float *bg, float eps, const float *d_out_rgb,
    float d_depth, float d_opacity, float *d_rgb, float *d_sigma)
{
    const float dc[3] = {d_out_rgb ? d_out_rgb[0] : 0.0f,
                         d_out_rgb ? d_out_rgb[1] : 0.0f,
                         d_out_rgb ? d_out_rgb[2] : 0.0f};
    const float dbg = bg ? dc[0] * bg[0] + dc[1] * bg[1] + dc[2] * bg[2]
                         : 0.0f;
    /* Forward again, in the forward's arithmetic so that the same samples
     * are used; d_sigma holds T_i meanwhile. */
    float trans = 1.0f;
    uint32_t m = 0;
    for (; m < n && !(trans < eps); m++) {
        d_sigma[m] = trans;
        trans *= 1.0f - alpha_of(sigma[m], dt[m]);
    }
    for (uint32_t i = m; i < n; i++) {
        d_sigma[i] = 0.0f;
        d_rgb[3 * i] = d_rgb[3 * i + 1] = d_rgb[3 * i + 2] = 0.0f;
    }
    float rest = 0.0f; /* R_i */
    for (uint32_t i = m; i-- > 0;) {
        const float alpha = alpha_of(sigma[i], dt[i]);
        const float ti = d_sigma[i];
        const float w = ti * alpha;
        const float g = dc[0] * rgb[3 * i] + dc[1] * rgb[3 * i + 1] +
                        dc[2] * rgb[3 * i + 2] - dbg + d_depth * t[i] +
                        d_opacity;
        for (int c = 0; c < 3; c++) {
            d_rgb[3 * i + c] = w * dc[c];
        }
        /* d alpha / d s = dt exp(-s dt) = dt (1 - alpha). */
        d_sigma[i] = ti * (g - rest) * dt[i] * (1.0f - alpha);
        rest = g * alpha + (1.0f - alpha) * rest;
    }
    return m;
}

typedef struct packed_job {
    const nerf__packed_batch *b;
    const nerf__packed_out *out;
    const float *d_out_rgb, *d_depth, *d_opacity;
    float *d_rgb, *d_sigma;
} packed_job;

static const float *ray_bg(const nerf__packed_batch *b, size_t k)
{
    return b->bg ? b->bg + k * b->bg_stride : NULL;
}

static void forward_range(void *ctx, size_t begin, size_t end)
{
    const packed_job *j = ctx;
    const nerf__packed_batch *b = j->b;
    const nerf__packed_out *out = j->out;
    for (size_t k = begin; k < end; k++) {
        const size_t at = b->offsets[k];
        const uint32_t n = (uint32_t)(b->offsets[k + 1] - at);
        nerf__composite_state s;
        nerf__composite_state_init(&s);
        uint32_t used = nerf__composite_packed_ray(
            &s, n, b->t + at, b->dt + at, b->rgb + 3 * at, b->sigma + at,
            b->eps, out->weights ? out->weights + at : NULL);
        if (out->rgb) {
            nerf__composite_state_rgb(&s, ray_bg(b, k), out->rgb + 3 * k);
        }
        if (out->depth) {
            out->depth[k] = s.depth;
        }
        if (out->opacity) {
            out->opacity[k] = s.opacity;
        }
        if (out->used) {
            out->used[k] = used;
        }
    }
}

/* Rough operations per ray, from the mean samples per ray. */
static size_t ray_cost(const nerf__packed_batch *b, size_t per_sample)
{
    size_t per_ray = b->n_rays ? b->offsets[b->n_rays] / b->n_rays : 0;
    return per_sample * (per_ray + 1);
}

void nerf__composite_packed(const nerf__packed_batch *b,
                            const nerf__packed_out *out)
{
    packed_job j = {.b = b, .out = out};
    nerf__parallel_for(b->n_rays, ray_cost(b, 30), forward_range, &j);
}

static void backward_range(void *ctx, size_t begin, size_t end)
{
    const packed_job *j = ctx;
    const nerf__packed_batch *b = j->b;
    for (size_t k = begin; k < end; k++) {
        const size_t at = b->offsets[k];
        const uint32_t n = (uint32_t)(b->offsets[k + 1] - at);
        nerf__composite_packed_ray_backward(
            n, b->t + at, b->dt + at, b->rgb + 3 * at, b->sigma + at,
            ray_bg(b, k), b->eps, j->d_out_rgb ? j->d_out_rgb + 3 * k : NULL,
            j->d_depth ? j->d_depth[k] : 0.0f,
            j->d_opacity ? j->d_opacity[k] : 0.0f, j->d_rgb + 3 * at,
            j->d_sigma + at);
    }
}

void nerf__composite_packed_backward(const nerf__packed_batch *b,
                                     const float *d_out_rgb,
                                     const float *d_depth,
                                     const float *d_opacity, float *d_rgb,
                                     float *d_sigma)
{
    packed_job j = {.b = b, .d_out_rgb = d_out_rgb, .d_depth = d_depth,
                    .d_opacity = d_opacity, .d_rgb = d_rgb,
                    .d_sigma = d_sigma};
    nerf__parallel_for(b->n_rays, ray_cost(b, 60), backward_range, &j);
}
