/* The nerf_sampler handle: options, validation and the public calls. */
#include <math.h>
#include <string.h>

#include "occupancy.h"
#include "options.h"
#include "sampler.h"

#define MAX_SAMPLES 4096u
/* Marching: steps across the bound's diagonal, and samples per ray.  The
 * marcher handles up to 2^24 steps along a ray; these keep far below. */
#define MAX_MARCH_STEPS 65536u
#define MAX_MARCH_SAMPLES 65536u
#define DEFAULT_MARCH_SAMPLES 1024u

static void sampler_defaults(nerf_sampler_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->n_coarse = 64;
    o->n_fine = 128;
    o->perturb = 1;
    o->t_near = 2.0f;
    o->t_far = 6.0f;
    o->max_samples = DEFAULT_MARCH_SAMPLES;
}

NERF_API int nerf_sampler_options_init(nerf_sampler_options *opts,
                                       size_t struct_size)
{
    nerf_sampler_options d;
    sampler_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_sampler_options");
}

NERF_API int nerf_sampler_options_preset(nerf_sampler_options *opts,
                                         int preset)
{
    nerf_sampler_options o;
    sampler_defaults(&o);
    int rc = nerf__options_read(&o, sizeof o, opts, "nerf_sampler_options");
    if (rc != NERF_OK) {
        return rc;
    }
    switch (preset) {
    case NERF_PRESET_REFERENCE:
        o.n_coarse = 64;
        o.n_fine = 128;
        o.march_steps = 0;
        break;
    case NERF_PRESET_TINY:
        o.n_coarse = 32;
        o.n_fine = 64;
        o.march_steps = 0;
        break;
    case NERF_PRESET_FAST:
        /* Mueller et al.'s sampler.  The stratified counts stay valid,
         * one pass for the one network, for a caller who sets
         * march_steps back to 0. */
        o.n_coarse = 128;
        o.n_fine = 0;
        o.march_steps = NERF__MARCH_STEPS_DEFAULT;
        o.max_samples = DEFAULT_MARCH_SAMPLES;
        break;
    default:
        return nerf__error(NERF_EINVAL, "nerf_sampler_options_preset: "
                           "unknown preset %d", preset);
    }
    nerf__options_write(opts, &o, sizeof o);
    return NERF_OK;
}

NERF_API int nerf_sampler_options_set_march(nerf_sampler_options *opts,
                                            uint32_t steps)
{
    nerf_sampler_options o;
    sampler_defaults(&o);
    int rc = nerf__options_read(&o, sizeof o, opts, "nerf_sampler_options");
    if (rc != NERF_OK) {
        return rc;
    }
    if (steps < 1 || steps > MAX_MARCH_STEPS) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_options_set_march: "
                           "steps must be 1..65536, not %u", (unsigned)steps);
    }
    if (o.march_steps == 0) {
        return NERF_OK;
    }
    /* The cap on a ray's samples is a distance in steps: a finer march
     * must take more of them to reach as far. */
    const double cap = (double)o.max_samples * steps / o.march_steps;
    o.max_samples = cap < 1.0                 ? 1u
                    : cap > MAX_MARCH_SAMPLES ? MAX_MARCH_SAMPLES
                                              : (uint32_t)cap;
    o.march_steps = steps;
    nerf__options_write(opts, &o, sizeof o);
    return NERF_OK;
}

static bool finite_nonneg(float v)
{
    return isfinite(v) && v >= 0.0f;
}

static int check_options(const void *opts)
{
    const nerf_sampler_options *o = opts;
    const char *what = NULL;
    bool frustum_zero = o->ndc_focal == 0.0f && o->ndc_width == 0 &&
                        o->ndc_height == 0;
    bool frustum_set = isfinite(o->ndc_focal) && o->ndc_focal > 0.0f &&
                       o->ndc_width > 0 && o->ndc_height > 0;
    if (o->n_coarse < 2 || o->n_coarse > MAX_SAMPLES) {
        what = "n_coarse must be 2..4096";
    } else if (o->n_fine > MAX_SAMPLES) {
        what = "n_fine must be 0..4096";
    } else if (o->n_fine > 0 && o->n_coarse < 3) {
        what = "hierarchical sampling needs n_coarse >= 3";
    } else if (o->perturb > 1 || o->lindisp > 1 || o->paper_bins > 1 ||
               o->ndc > 1) {
        what = "perturb, lindisp, paper_bins and ndc must be 0 or 1";
    } else if (o->reserved0 != 0 || o->reserved1 != 0) {
        what = "reserved fields must be 0";
    } else if (!finite_nonneg(o->t_near) || !finite_nonneg(o->t_far) ||
               !(o->t_near < o->t_far)) {
        what = "t_near and t_far must be finite with 0 <= t_near < t_far";
    } else if (o->lindisp && !(o->t_near > 0.0f)) {
        what = "lindisp needs t_near > 0";
    } else if (o->ndc && o->t_far > 1.0f) {
        what = "with ndc, t_near and t_far are NDC depths within [0, 1]";
    } else if (!frustum_zero && !frustum_set) {
        what = "ndc_focal, ndc_width and ndc_height must all be 0 or all "
               "positive and finite";
    } else if (o->march_steps > MAX_MARCH_STEPS) {
        what = "march_steps must be 0..65536";
    } else if (o->march_steps > 0 &&
               (o->max_samples < 1 || o->max_samples > MAX_MARCH_SAMPLES)) {
        what = "max_samples must be 1..65536";
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_options: %s", what);
    }
    return NERF_OK;
}

int nerf__sampler_check_options(const nerf_sampler_options *opts)
{
    return check_options(opts);
}

NERF_API int nerf_sampler_create(nerf_sampler **out,
                                 const nerf_sampler_options *opts)
{
    if (out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_create: out is NULL");
    }
    *out = NULL;
    nerf_sampler_options o;
    sampler_defaults(&o);
    nerf__env env;
    int rc = nerf__options_open(&o, sizeof o, opts, "nerf_sampler_options",
                                check_options, &o.hooks, &env);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf_sampler *s = nerf__calloc(&env, 1, sizeof *s);
    if (s == NULL) {
        return NERF_ENOMEM;
    }
    s->env = env;
    s->opts = o;
    s->opts.hooks = NULL;
    *out = s;
    return NERF_OK;
}

NERF_API void nerf_sampler_destroy(nerf_sampler *sampler)
{
    if (sampler == NULL) {
        return; /* support free on NULL */
    }
    nerf__env env = sampler->env;
    nerf__free(&env, sampler);
}

static int check_call(const nerf_sampler *s, uint32_t flags, const char *fn)
{
    if (s == NULL) {
        return nerf__error(NERF_EINVAL, "%s: sampler is NULL", fn);
    }
    if (flags & ~NERF_SAMPLE_TRAINING) {
        return nerf__error(NERF_EINVAL, "%s: unknown flags 0x%x", fn,
                           (unsigned)flags);
    }
    return NERF_OK;
}

NERF_API int nerf_sampler_sample_coarse(const nerf_sampler *sampler,
                                        size_t n_rays, uint32_t flags,
                                        uint64_t first_ray, const float *u,
                                        float *t_out)
{
    int rc = check_call(sampler, flags, "nerf_sampler_sample_coarse");
    if (rc != NERF_OK) {
        return rc;
    }
    if (t_out == NULL && n_rays > 0) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_sample_coarse: t_out "
                           "is NULL");
    }
    const nerf_sampler_options *o = &sampler->opts;
    bool jitter = (flags & NERF_SAMPLE_TRAINING) && o->perturb;
    const size_t n_c = o->n_coarse;
    for (size_t k = 0; k < n_rays; k++) {
        nerf__rng rng = nerf__ray_rng(o->seed, NERF__STREAM_STRATIFIED,
                                      first_ray + k);
        nerf__sample_stratified(o, jitter, u ? u + k * n_c : NULL, &rng,
                                t_out + k * n_c);
    }
    return NERF_OK;
}

NERF_API int nerf_sampler_sample_fine(const nerf_sampler *sampler,
                                      size_t n_rays, uint32_t flags,
                                      uint64_t first_ray,
                                      const float *t_coarse,
                                      const float *weights, const float *u,
                                      float *t_out)
{
    int rc = check_call(sampler, flags, "nerf_sampler_sample_fine");
    if (rc != NERF_OK) {
        return rc;
    }
    const nerf_sampler_options *o = &sampler->opts;
    if (o->n_fine == 0) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_sample_fine: the "
                           "sampler has n_fine = 0");
    }
    if (n_rays > 0 && (t_coarse == NULL || weights == NULL || t_out == NULL)) {
        return nerf__error(NERF_EINVAL, "nerf_sampler_sample_fine: NULL "
                           "t_coarse, weights or t_out");
    }
    const uint32_t n_c = o->n_coarse, n_f = o->n_fine;
    float *scratch = nerf__alloc(&sampler->env, sizeof(float) *
                                 nerf__sample_fine_scratch(n_c, n_f));
    if (scratch == NULL) {
        return NERF_ENOMEM;
    }
    bool random = (flags & NERF_SAMPLE_TRAINING) && o->perturb;
    for (size_t k = 0; k < n_rays; k++) {
        nerf__rng rng = nerf__ray_rng(o->seed, NERF__STREAM_HIERARCHICAL,
                                      first_ray + k);
        nerf__sample_fine_ray(n_c, n_f, t_coarse + k * n_c, weights + k * n_c,
                              random, u ? u + k * n_f : NULL, &rng, scratch,
                              t_out + k * (n_c + n_f));
    }
    nerf__free(&sampler->env, scratch);
    return NERF_OK;
}
