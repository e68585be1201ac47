/*
 * Sample placement along one ray.  The stratified and hierarchical rules
 * follow the reference implementation (docs/architecture.md), including
 * its float formulas, so that fed the same uniforms it gives the same
 * depths up to rounding.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nerf.h"
#include "sampler.h"

/*
 * Value i of n evenly spaced values from 0 to 1, computed the way
 * torch.linspace does (from the nearer end), so that both ends are exact
 * and the sequence is symmetric.
 */
static float linspace01(uint32_t i, uint32_t n)
{
    if (n < 2) {
        return 0.0f;
    }
    float step = 1.0f / (float)(n - 1);
    if (i < n / 2) {
        return step * (float)i;
    }
    return 1.0f - step * (float)(n - 1 - i);
}

/* Depth at fraction s of [near, far], linear in depth or in disparity. */
static float lerp_depth(const nerf_sampler_options *o, float s)
{
    if (o->lindisp) {
        return 1.0f / (1.0f / o->t_near * (1.0f - s) + 1.0f / o->t_far * s);
    }
    return o->t_near * (1.0f - s) + o->t_far * s;
}

/* A caller's uniform, clamped so that no input can put a sample outside
 * its interval. */
static float clamp01(float u)
{
    return u > 0.0f ? (u < 1.0f ? u : 1.0f) : 0.0f; /* NaN -> 0 */
}

void nerf__sample_stratified(const nerf_sampler_options *o, bool jitter,
                             const float *u, nerf__rng *rng, float *t)
{
    const uint32_t n = o->n_coarse;
    if (o->paper_bins) {
        /* Eq. 2 of the paper: one draw in each of n equal bins; the
         * deterministic version takes the bin centres. */
        for (uint32_t i = 0; i < n; i++) {
            float r = 0.5f;
            if (jitter) {
                r = u ? clamp01(u[i]) : nerf__rng_uniform(rng);
            }
            t[i] = lerp_depth(o, ((float)i + r) / (float)n);
        }
        return;
    }
    for (uint32_t i = 0; i < n; i++) {
        t[i] = lerp_depth(o, linspace01(i, n));
    }
    if (!jitter) {
        return;
    }
    /* Each value moves uniformly between the midpoints to its neighbours;
     * the ends stay inside [near, far].  Walking forward, t[i - 1] has
     * already moved, so keep the previous original value aside. */
    float prev = t[0];
    for (uint32_t i = 0; i < n; i++) {
        float cur = t[i];
        float lower = i > 0 ? 0.5f * (cur + prev) : cur;
        float upper = i + 1 < n ? 0.5f * (t[i + 1] + cur) : cur;
        float r = u ? clamp01(u[i]) : nerf__rng_uniform(rng);
        t[i] = lower + (upper - lower) * r;
        prev = cur;
    }
}

/* Number of cdf[0..n] entries <= u, cdf being non-decreasing: the index
 * torch.searchsorted(cdf, u, right=True) returns. */
static uint32_t search_right(const float *cdf, uint32_t n, float u)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid] <= u) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return lo;
}

void nerf__sample_pdf(uint32_t n_bins, const float *edges,
                      const float *weights, uint32_t n_out, bool random,
                      const float *u, nerf__rng *rng, float *cdf,
                      float *out)
{
    float total = 0.0f;
    for (uint32_t k = 0; k < n_bins; k++) {
        /* A NaN or negative weight from a diverged model counts as 0, so
         * the search below stays well defined. */
        float w = weights[k] > 0.0f ? weights[k] : 0.0f;
        cdf[k + 1] = w + 1e-5f;
        total += cdf[k + 1];
    }
    cdf[0] = 0.0f;
    float acc = 0.0f;
    for (uint32_t k = 0; k < n_bins; k++) {
        acc += cdf[k + 1] / total;
        cdf[k + 1] = acc;
    }
    for (uint32_t i = 0; i < n_out; i++) {
        float v;
        if (!random) {
            v = linspace01(i, n_out);
        } else {
            v = u ? clamp01(u[i]) : nerf__rng_uniform(rng);
        }
        uint32_t ind = search_right(cdf, n_bins + 1, v);
        uint32_t below = ind > 0 ? ind - 1 : 0;
        uint32_t above = ind < n_bins ? ind : n_bins;
        float denom = cdf[above] - cdf[below];
        if (denom < 1e-5f) {
            denom = 1.0f;
        }
        float f = (v - cdf[below]) / denom;
        out[i] = edges[below] + f * (edges[above] - edges[below]);
    }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

void nerf__sample_fine_ray(uint32_t n_c, uint32_t n_f, const float *t_coarse,
                           const float *weights, bool random, const float *u,
                           nerf__rng *rng, float *scratch, float *t_out)
{
    float *mids = scratch;         /* n_c - 1 */
    float *cdf = scratch + n_c;    /* n_c - 1 */
    float *fine = scratch + 2 * (size_t)n_c; /* n_f */
    for (uint32_t i = 0; i + 1 < n_c; i++) {
        mids[i] = 0.5f * (t_coarse[i + 1] + t_coarse[i]);
    }
    nerf__sample_pdf(n_c - 2, mids, weights + 1, n_f, random, u, rng, cdf,
                     fine);
    if (random) {
        qsort(fine, n_f, sizeof *fine, cmp_float);
    } else {
        /* Evenly spaced u give samples in order up to rounding at bin
         * edges: insertion sort costs one pass. */
        for (uint32_t i = 1; i < n_f; i++) {
            float v = fine[i];
            uint32_t j = i;
            while (j > 0 && fine[j - 1] > v) {
                fine[j] = fine[j - 1];
                j--;
            }
            fine[j] = v;
        }
    }
    uint32_t a = 0, b = 0, k = 0;
    while (a < n_c && b < n_f) {
        t_out[k++] = fine[b] < t_coarse[a] ? fine[b++] : t_coarse[a++];
    }
    while (a < n_c) {
        t_out[k++] = t_coarse[a++];
    }
    while (b < n_f) {
        t_out[k++] = fine[b++];
    }
}
