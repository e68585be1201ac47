/*
 * Volume rendering of marched samples (march.h): a variable number of
 * samples per ray, packed, each with its own length dt, and early ray
 * termination.  The fast model's densities are already non-negative (an
 * exponential activation), so no ReLU is applied here.
 *
 * For the samples i = 0, 1, ... of a ray, at ray parameter t_i with world
 * length dt_i, density s_i >= 0 and colour c_i:
 *   alpha_i = 1 - exp(-s_i dt_i)
 *   T_0 = 1, T_(i+1) = T_i (1 - alpha_i)
 *   w_i = T_i alpha_i
 *   rgb = sum w_i c_i + (1 - opacity) bg,  depth = sum w_i t_i,
 *   opacity = sum w_i.
 * Unlike composite.h, delta is dt_i itself (not a difference of t, and no
 * 1e10 after the last sample) and T carries no 1e-10 terms.
 *
 * Early termination: sample i is used only while T_i >= eps; the first
 * sample with T_i < eps and all after it are dropped.  What they could
 * have added is at most T_i < eps per colour channel, so with colours and
 * background in [0, 1] the result moves by less than eps.  eps = 0 uses
 * every sample.  The count used is reported, so a renderer that evaluates
 * samples in pieces can stop evaluating a ray once it is done; the forward
 * and backward make the same decision from the same arithmetic.
 */
#ifndef NERF_RENDER_COMPOSITE_PACKED_H
#define NERF_RENDER_COMPOSITE_PACKED_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* instant-ngp's transmittance threshold. */
#define NERF__COMPOSITE_EPS_DEFAULT 1e-4f

/* What one ray has accumulated so far. */
typedef struct nerf__composite_state {
    float rgb[3];    /* sum w c, without background */
    float depth;     /* sum w t */
    float opacity;   /* sum w */
    float trans;     /* T in front of the next sample */
} nerf__composite_state;

static inline void nerf__composite_state_init(nerf__composite_state *s)
{
    s->rgb[0] = s->rgb[1] = s->rgb[2] = 0.0f;
    s->depth = s->opacity = 0.0f;
    s->trans = 1.0f;
}

/* Whether further samples would be dropped. */
static inline bool nerf__composite_state_done(const nerf__composite_state *s,
                                              float eps)
{
    return s->trans < eps;
}

/*
 * Add the next n samples of a ray to s (t[n], dt[n], rgb[n, 3],
 * sigma[n]); returns how many were used (< n when the ray terminated).
 * weights[n] (may be NULL) receives w_i, 0 for samples not used.
 * Calling it piece by piece gives bit for bit the result of one call.
 */
uint32_t nerf__composite_packed_ray(nerf__composite_state *s, uint32_t n,
                                    const float *t, const float *dt,
                                    const float *rgb, const float *sigma,
                                    float eps, float *weights);

/*
 * How many of a ray's next n samples nerf__composite_packed_ray() would
 * use, from the densities alone: the transmittance in its arithmetic, so
 * that a trainer can leave the rest out of its forward and backward, where
 * their gradients are 0.  *trans: the transmittance before them (1 at the
 * ray's start), and after those used on return.
 */
uint32_t nerf__composite_packed_ray_used(uint32_t n, const float *dt,
                                         const float *sigma, float eps,
                                         float *trans);

/* The ray's colour: s->rgb + (1 - s->opacity) bg (bg NULL: black). */
void nerf__composite_state_rgb(const nerf__composite_state *s,
                               const float *bg, float rgb[3]);

/*
 * Gradients of L with respect to the colours and densities of the n
 * samples of one ray, given dL/d(rgb) (NULL: 0), dL/d(depth) and
 * dL/d(opacity) of the ray composited with the same bg and eps.  d_rgb[n,
 * 3] and d_sigma[n] are overwritten (0 for samples not used).  O(n): a
 * forward pass recomputes T, a backward pass carries the suffix sum
 *   R_i = sum_(k>i) g_k alpha_k prod_(i<j<k) (1 - alpha_j)
 * with g_k = dL/dw_k, and dL/ds_i = dt_i exp(-s_i dt_i) T_i (g_i - R_i).
 * Returns the number of samples used.
 */
uint32_t nerf__composite_packed_ray_backward(
    uint32_t n, const float *t, const float *dt, const float *rgb,
    const float *sigma, const float *bg, float eps, const float *d_out_rgb,
    float d_depth, float d_opacity, float *d_rgb, float *d_sigma);

/* Packed samples of a batch of rays, with what compositing them needs. */
typedef struct nerf__packed_batch {
    size_t n_rays;
    const size_t *offsets;  /* [n_rays + 1]: ray k has samples offsets[k] ..
                             * offsets[k + 1] - 1 */
    const float *t, *dt;    /* [total] */
    const float *rgb;       /* [total, 3] */
    const float *sigma;     /* [total], >= 0 */
    /* Background of ray k: bg + k bg_stride (3 floats); bg_stride 0 shares
     * one colour, 3 gives each ray its own (random-background training).
     * bg NULL: black. */
    const float *bg;
    size_t bg_stride;
    float eps;              /* early termination; 0: never */
} nerf__packed_batch;

/* Outputs per ray; any pointer may be NULL. */
typedef struct nerf__packed_out {
    float *rgb;             /* [n_rays, 3] */
    float *depth;           /* [n_rays] */
    float *opacity;         /* [n_rays] */
    uint32_t *used;         /* [n_rays], samples used */
    float *weights;         /* [total], w (0 past the used samples) */
} nerf__packed_out;

/* Composite every ray of b, in parallel over rays. */
void nerf__composite_packed(const nerf__packed_batch *b,
                            const nerf__packed_out *out);

/*
 * Backward of nerf__composite_packed() over b: d_out_rgb [n_rays, 3],
 * d_depth and d_opacity [n_rays] (each may be NULL for 0) into d_rgb
 * [total, 3] and d_sigma [total], overwritten.
 */
void nerf__composite_packed_backward(const nerf__packed_batch *b,
                                     const float *d_out_rgb,
                                     const float *d_depth,
                                     const float *d_opacity, float *d_rgb,
                                     float *d_sigma);

#endif
