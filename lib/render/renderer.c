/* The nerf_renderer handle, its options, and rendering of caller's rays. */
#include "renderer.h"

#include <math.h>
#include <string.h>

#include "cpu.h"
#include "gemm.h"
#include "options.h"

#define MAX_CHUNK (1u << 20)

/*
 * Workers when the caller leaves the choice to us.  Each worker's sgemm
 * already runs on the BLAS's threads, so one worker per core on top of an
 * OpenBLAS threaded over every core oversubscribes them.  In bench_render
 * a second worker over a two-thread OpenBLAS gained nothing, while two
 * workers over a one-thread OpenBLAS were the fastest set-up
 * (docs/perf-log/early-first-measurements.md, "Rendering").  So: cores
 * divided by the BLAS's threads, at least 1.  A model on the fused path
 * calls no BLAS: one worker per core, or a lone worker would hand every
 * small loop of its blocks to the thread pool, which made frames several
 * times slower (docs/perf-log/2026-11-26-rendering-a-trained-fast-model.md).
 */
static uint32_t auto_threads(const nerf_model *m)
{
    uint32_t cores = nerf__cpu_count();
    int blas = nerf__model_uses_blas(m) ? nerf__blas_threads() : 1;
    uint32_t t = blas > 1 ? cores / (uint32_t)blas : cores;
    return t ? t : 1;
}

static void renderer_defaults(nerf_renderer_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->raw_noise_std = NERF_NOISE_AUTO;
    o->chunk_rays = 512;
}

NERF_API int nerf_renderer_options_init(nerf_renderer_options *opts,
                                        size_t struct_size)
{
    nerf_renderer_options d;
    renderer_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_renderer_options");
}

static int check_options(const void *opts)
{
    const nerf_renderer_options *o = opts;
    const char *what = NULL;
    if (o->white_background > 1) {
        what = "white_background must be 0 or 1";
    } else if (!(o->raw_noise_std == NERF_NOISE_AUTO ||
                 (isfinite(o->raw_noise_std) && o->raw_noise_std >= 0.0f))) {
        what = "raw_noise_std must be finite and >= 0, or NERF_NOISE_AUTO";
    } else if (o->chunk_rays < 1 || o->chunk_rays > MAX_CHUNK) {
        what = "chunk_rays must be 1..2^20";
    } else if (o->threads > NERF__MAX_THREADS) {
        what = "threads must be 0..1024";
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "nerf_renderer_options: %s", what);
    }
    return NERF_OK;
}

/*
 * The sampler of a caller who gave none: the model's render settings, and
 * with no options either, its background too, so that a model renders as
 * it was trained without the caller knowing how.
 */
static int own_sampler(const nerf_model *model, nerf_renderer_options *o,
                       bool background, nerf_sampler **out)
{
    nerf_sampler_options so;
    nerf_sampler_options_init(&so, sizeof so);
    so.hooks = o->hooks;
    int rc = nerf_model_render_settings(model, &so, background ? o : NULL);
    return rc == NERF_OK ? nerf_sampler_create(out, &so) : rc;
}

NERF_API int nerf_renderer_create(nerf_renderer **out,
                                  const nerf_model *model,
                                  const nerf_sampler *sampler,
                                  const nerf_renderer_options *opts)
{
    if (out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_renderer_create: out is NULL");
    }
    *out = NULL;
    if (model == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_renderer_create: model must "
                           "not be NULL");
    }
    nerf_renderer_options o;
    renderer_defaults(&o);
    nerf__env env;
    int rc = nerf__options_open(&o, sizeof o, opts, "nerf_renderer_options",
                                check_options, &o.hooks, &env);
    if (rc == NERF_OK) {
        /* NaN weights would render black (or NaN) with no word of why. */
        rc = nerf__model_check_finite(model, "nerf_renderer_create");
    }
    if (rc == NERF_OK) {
        rc = nerf__appearance_check(model, o.appearance,
                                    "nerf_renderer_create");
    }
    nerf_sampler *owned = NULL;
    if (rc == NERF_OK && sampler == NULL) {
        rc = own_sampler(model, &o, opts == NULL, &owned);
        sampler = owned;
    }
    if (rc == NERF_OK) {
        rc = nerf__render_check_pair(model, sampler, "nerf_renderer_create");
    }
    nerf_renderer *r = rc == NERF_OK ? nerf__calloc(&env, 1, sizeof *r)
                                     : NULL;
    if (r == NULL) {
        nerf_sampler_destroy(owned);
        return rc == NERF_OK ? NERF_ENOMEM : rc;
    }
    r->env = env;
    r->opts = o;
    r->opts.hooks = NULL;
    r->model = model;
    r->sampler = sampler;
    r->own_sampler = owned;
    if (o.raw_noise_std == NERF_NOISE_AUTO) {
        /* The reference trains forward-facing scenes with noise std 1 and
         * Blender scenes without. */
        r->noise_std = sampler->opts.ndc ? 1.0f : 0.0f;
    } else {
        r->noise_std = o.raw_noise_std;
    }
    r->threads = o.threads ? o.threads : auto_threads(model);
    r->chunk = ((size_t)o.chunk_rays + NERF__RENDER_BLOCK - 1) /
               NERF__RENDER_BLOCK * NERF__RENDER_BLOCK;
    atomic_init(&r->cancel, 0);
    if (nerf__sampler_marches(sampler)) {
        nerf__log(&r->env, NERF_LOG_DEBUG, "renderer: %u thread(s), chunks "
                  "of %zu rays, marching %u steps, at most %u samples",
                  r->threads, r->chunk, sampler->opts.march_steps,
                  sampler->opts.max_samples);
    } else {
        nerf__log(&r->env, NERF_LOG_DEBUG, "renderer: %u thread(s), chunks "
                  "of %zu rays, %u + %u samples", r->threads, r->chunk,
                  sampler->opts.n_coarse, sampler->opts.n_fine);
    }
    *out = r;
    return NERF_OK;
}

NERF_API void nerf_renderer_destroy(nerf_renderer *renderer)
{
    if (renderer == NULL) {
        return; /* support free on NULL */
    }
    nerf__env env = renderer->env;
    for (uint32_t i = 0; i < renderer->n_workers; i++) {
        nerf__batch_release(&renderer->workers[i]->batch);
        nerf__free(&env, renderer->workers[i]);
    }
    nerf__free(&env, renderer->workers);
    nerf_sampler_destroy(renderer->own_sampler);
    nerf__free(&env, renderer);
}

NERF_API int nerf_renderer_set_progress(nerf_renderer *renderer,
                                        nerf_progress_cb cb, void *user)
{
    if (renderer == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_renderer_set_progress: "
                           "renderer is NULL");
    }
    renderer->progress = cb;
    renderer->progress_user = cb ? user : NULL;
    return NERF_OK;
}

NERF_API void nerf_renderer_cancel(nerf_renderer *renderer)
{
    if (renderer) {
        atomic_store(&renderer->cancel, 1);
    }
}

void nerf__renderer_eval_setup(const nerf_renderer *r, nerf__render_setup *s)
{
    memset(s, 0, sizeof *s);
    s->model = r->model;
    s->sampler = r->sampler;
    s->noise_std = r->noise_std;
    s->white_background = r->opts.white_background != 0;
    s->ndc_focal = r->sampler->opts.ndc_focal;
    s->ndc_width = (float)r->sampler->opts.ndc_width;
    s->ndc_height = (float)r->sampler->opts.ndc_height;
    /* Checked against the model's codes at creation; a model gains codes
     * (a trainer adds them) but never loses them. */
    if (r->model->appearance.n > 0) {
        s->appearance = true;
        nerf__appearance_pick(&r->model->appearance, r->opts.appearance,
                              s->code);
    }
}

int nerf__renderer_set_march_test(nerf_renderer *r,
                                  const nerf__march_test *t)
{
    /* Every worker a render will use: nerf__renderer_run() takes at most
     * this many. */
    uint32_t n = r->threads < NERF__MAX_THREADS ? r->threads
                                                : NERF__MAX_THREADS;
    int rc = nerf__renderer_ensure_workers(r, n);
    for (uint32_t i = 0; rc == NERF_OK && i < r->n_workers; i++) {
        nerf__batch_set_march_test(&r->workers[i]->batch, t);
    }
    return rc;
}

typedef struct rays_job {
    const nerf_renderer *r;
    nerf__render_setup setup;
    const float *origins, *directions;
    float *rgb, *depth, *opacity;
} rays_job;

static int rays_chunk(void *p, nerf__worker *w, size_t first, size_t count)
{
    rays_job *job = p;
    for (size_t at = first; at < first + count; at += NERF__RENDER_BLOCK) {
        if (nerf__renderer_cancelled(job->r)) {
            return nerf__error(NERF_ECANCELLED, "render cancelled");
        }
        size_t k = first + count - at;
        k = k < NERF__RENDER_BLOCK ? k : NERF__RENDER_BLOCK;
        const float *o = job->origins + 3 * at, *d = job->directions + 3 * at;
        for (size_t i = 0; i < 3 * k; i++) {
            if (!isfinite(o[i]) || !isfinite(d[i])) {
                return nerf__error(NERF_EINVAL, "nerf_renderer_render_rays: "
                                   "ray %zu is not finite", at + i / 3);
            }
        }
        for (size_t i = 0; i < k; i++) {
            const float *di = d + 3 * i;
            if (di[0] == 0.0f && di[1] == 0.0f && di[2] == 0.0f) {
                return nerf__error(NERF_EINVAL, "nerf_renderer_render_rays: "
                                   "ray %zu has a zero direction", at + i);
            }
        }
        nerf__render_setup s = job->setup;
        s.first_ray = at;
        nerf__pass_out out[NERF__PASSES];
        memset(out, 0, sizeof out);
        nerf__pass_out *last = &out[nerf__sampler_last_pass(s.sampler)];
        last->rgb = job->rgb ? job->rgb + 3 * at : NULL;
        last->depth = job->depth ? job->depth + at : NULL;
        last->opacity = job->opacity ? job->opacity + at : NULL;
        int rc = nerf__render_batch(&w->batch, &s, k, o, d, out);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    return NERF_OK;
}

NERF_API int nerf_renderer_render_rays(nerf_renderer *renderer,
                                       size_t n_rays, const float *origins,
                                       const float *directions,
                                       float *rgb_out, float *depth_out,
                                       float *opacity_out)
{
    static const char fn[] = "nerf_renderer_render_rays";
    if (renderer == NULL) {
        return nerf__error(NERF_EINVAL, "%s: renderer is NULL", fn);
    }
    if (n_rays > 0 && (origins == NULL || directions == NULL)) {
        return nerf__error(NERF_EINVAL, "%s: NULL origins or directions", fn);
    }
    if (rgb_out == NULL && depth_out == NULL && opacity_out == NULL) {
        return nerf__error(NERF_EINVAL, "%s: every output is NULL", fn);
    }
    if (n_rays > SIZE_MAX / (3 * sizeof(float))) {
        return nerf__error(NERF_EINVAL, "%s: %zu rays is too many", fn, n_rays);
    }
    /* Weights that became NaN in training since the renderer was made. */
    int rc = nerf__model_check_finite(renderer->model, fn);
    if (rc != NERF_OK) {
        return rc;
    }
    rays_job job;
    nerf__renderer_eval_setup(renderer, &job.setup);
    if (renderer->sampler->opts.ndc && job.setup.ndc_focal == 0.0f) {
        return nerf__error(NERF_EINVAL, "%s: the sampler uses NDC but its "
                           "ndc_focal, ndc_width and ndc_height are not set",
                           fn);
    }
    job.r = renderer;
    job.origins = origins;
    job.directions = directions;
    job.rgb = rgb_out;
    job.depth = depth_out;
    job.opacity = opacity_out;
    return nerf__renderer_run(renderer, n_rays, rays_chunk, &job);
}
