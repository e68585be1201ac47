/*
 * The struct behind nerf_sampler, and the per-ray sampling algorithms the
 * batch renderer runs: stratified placement along a ray and hierarchical
 * placement by inverse transform of the coarse weights.
 */
#ifndef NERF_SAMPLING_SAMPLER_H
#define NERF_SAMPLING_SAMPLER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "env.h"
#include "rng.h"

struct nerf_sampler {
    nerf__env env;
    nerf_sampler_options opts; /* as created; opts.hooks is NULL */
};

/*
 * Purposes of the random streams.  A draw is keyed by (seed, purpose, ray),
 * so the stratified jitter, the hierarchical u and the density noise of one
 * ray never share numbers, and no draw depends on which batch, chunk or
 * thread handles the ray.
 */
enum {
    NERF__STREAM_STRATIFIED = 1,
    NERF__STREAM_HIERARCHICAL = 2,
    NERF__STREAM_NOISE_COARSE = 3,
    NERF__STREAM_NOISE_FINE = 4,
    NERF__STREAM_MARCH = 5,
    NERF__STREAM_BACKGROUND = 6, /* the trainer's random backgrounds */
    NERF__STREAM_MASK = 7        /* the trainer's redraws of masked pixels */
};

/* The checks nerf_sampler_create() makes of a full options struct:
 * NERF_OK, or NERF_EINVAL with the message set. */
int nerf__sampler_check_options(const nerf_sampler_options *opts);

/* Whether the sampler marches through an occupancy grid. */
static inline bool nerf__sampler_marches(const nerf_sampler *s)
{
    return s->opts.march_steps > 0;
}

/* The pass whose outputs are the render's: the fine one when there is
 * one (marching has a single pass). */
static inline int nerf__sampler_last_pass(const nerf_sampler *s)
{
    return !nerf__sampler_marches(s) && s->opts.n_fine > 0 ? 1 : 0;
}

/* The seed of one purpose's streams, one stream per ray; the marcher,
 * which draws its own offsets, is given this for NERF__STREAM_MARCH. */
static inline uint64_t nerf__stream_seed(uint64_t seed, uint32_t purpose)
{
    return seed + UINT64_C(0xd1b54a32d192ed03) * purpose;
}

/* The generator of one purpose for one ray. */
static inline nerf__rng nerf__ray_rng(uint64_t seed, uint32_t purpose,
                                      uint64_t ray)
{
    return nerf__rng_make(nerf__stream_seed(seed, purpose), ray);
}

/*
 * Stratified depths of one ray, increasing, into t[n].  With jitter, u
 * holds n uniforms in [0, 1) (NULL: draw them from rng).  Without jitter
 * neither u nor rng is used.
 */
void nerf__sample_stratified(const nerf_sampler_options *o, bool jitter,
                             const float *u, nerf__rng *rng, float *t);

/*
 * Inverse-transform samples of one ray.  edges[n_bins + 1] are increasing
 * bin boundaries and weights[n_bins] the unnormalised bin masses (1e-5 is
 * added to each here).  random: u[n_out] uniforms (NULL: draw from rng)
 * instead of evenly spaced ones, 0 and 1 included.  cdf is scratch of
 * n_bins + 1 floats.  The output is not sorted when random.
 */
void nerf__sample_pdf(uint32_t n_bins, const float *edges,
                      const float *weights, uint32_t n_out, bool random,
                      const float *u, nerf__rng *rng, float *cdf,
                      float *out);

/*
 * The fine depths of one ray: hierarchical samples from the coarse depths
 * t_coarse[n_c] and weights[n_c] (bins between neighbouring midpoints,
 * weights without first and last), merged with t_coarse into
 * t_out[n_c + n_f], sorted.  scratch holds 2 n_c + n_f floats.
 */
void nerf__sample_fine_ray(uint32_t n_c, uint32_t n_f, const float *t_coarse,
                           const float *weights, bool random, const float *u,
                           nerf__rng *rng, float *scratch, float *t_out);

/* Scratch floats nerf__sample_fine_ray() needs. */
static inline size_t nerf__sample_fine_scratch(uint32_t n_c, uint32_t n_f)
{
    return 2 * (size_t)n_c + n_f;
}

#endif
