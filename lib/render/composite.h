/*
 * Volume rendering of one ray from its samples, exactly as the paper and
 * its reference implementation define it, and the backward pass of the
 * same function with respect to the sample colours and raw densities.
 *
 * For samples i = 0 .. n-1 at increasing t_i with colour c_i and raw
 * density s_i (noise already added):
 *   delta_i = (t_(i+1) - t_i) |d|, the last one 1e10 |d|
 *   alpha_i = 1 - exp(-relu(s_i) delta_i)
 *   T_i     = prod_(j<i) (1 - alpha_j + 1e-10)
 *   w_i     = T_i alpha_i
 *   rgb = sum w_i c_i (+ 1 - opacity on white), depth = sum w_i t_i,
 *   opacity = sum w_i, disparity = 1 / max(1e-10, depth / opacity).
 */
#ifndef NERF_RENDER_COMPOSITE_H
#define NERF_RENDER_COMPOSITE_H

#include <stdbool.h>
#include <stdint.h>

typedef struct nerf__ray_out {
    float rgb[3];
    float depth;
    float disparity;
    float opacity;
} nerf__ray_out;

/*
 * Composite n samples of one ray.  t[n], rgb[n * 3], sigma[n];
 * dir_norm = |d|.  weights[n] receives w (may be NULL).
 */
void nerf__composite_ray(uint32_t n, const float *t, float dir_norm,
                         const float *rgb, const float *sigma, bool white,
                         float *weights, nerf__ray_out *out);

/*
 * Gradients of a loss L with respect to the sample colours and raw
 * densities, given dL/d(rgb) (3 floats, NULL = 0), dL/d(depth) and
 * dL/d(opacity) of the ray (disparity takes no gradient).  d_rgb[n * 3] and
 * d_sigma[n] are overwritten.  ReLU'(0) is taken as 0, as autograd does.
 */
void nerf__composite_ray_backward(uint32_t n, const float *t, float dir_norm,
                                  const float *rgb, const float *sigma,
                                  bool white, const float *d_out_rgb,
                                  float d_depth, float d_opacity,
                                  float *d_rgb, float *d_sigma);

/*
 * The same two functions finishing the ray on background colour bg[3]
 * (rgb += (1 - opacity) bg; NULL: black), so that training can give each
 * ray its own.  The functions above are these with bg white or NULL, bit
 * for bit.
 */
void nerf__composite_ray_bg(uint32_t n, const float *t, float dir_norm,
                            const float *rgb, const float *sigma,
                            const float *bg, float *weights,
                            nerf__ray_out *out);
void nerf__composite_ray_backward_bg(uint32_t n, const float *t,
                                     float dir_norm, const float *rgb,
                                     const float *sigma, const float *bg,
                                     const float *d_out_rgb, float d_depth,
                                     float d_opacity, float *d_rgb,
                                     float *d_sigma);

#endif
