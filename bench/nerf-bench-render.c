/*
 * Rendering speed: rays and network samples per second of
 * nerf_renderer_render_rays, evaluation settings, after a warm-up call
 * in which the workers allocate their scratch.  Without marching, the
 * top rows of the 800x800 view, render_rays() rays a call; marching, every
 * pixel of that view at FAST_RENDER_SIDE pixels a side, its samples
 * counted by replaying the call.
 */
#include <stdlib.h>
#include <string.h>

#include "nerf-bench.h"

/*
 * Network samples of rendering n rays.  Rendering is deterministic, so
 * replaying the call in the blocks its workers use (NERF__RENDER_BLOCK
 * rays from the first ray) evaluates exactly the samples the timed calls
 * did, and the batch counts them.
 */
static int count_render_samples(const nerf_renderer *r, size_t n,
                                const float *o, const float *d,
                                uint64_t *total)
{
    nerf__batch b;
    nerf__batch_init(&b, &r->env);
    nerf__render_setup s;
    nerf__renderer_eval_setup(r, &s);
    float rgb[3 * NERF__RENDER_BLOCK];
    nerf__pass_out out[NERF__PASSES];
    memset(out, 0, sizeof out);
    out[nerf__sampler_last_pass(r->sampler)].rgb = rgb;
    int rc = NERF_OK;
    *total = 0;
    for (size_t at = 0; at < n && rc == NERF_OK; at += NERF__RENDER_BLOCK) {
        size_t k = n - at < NERF__RENDER_BLOCK ? n - at : NERF__RENDER_BLOCK;
        s.first_ray = at;
        rc = nerf__render_batch(&b, &s, k, o + 3 * at, d + 3 * at, out);
        *total += b.n_evaluated;
    }
    nerf__batch_release(&b);
    return rc;
}

/* A few seconds of the reference preset on two cores, and a whole number
 * of the renderer's chunks. */
unsigned render_rays(void)
{
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    return 4 * ro.chunk_rays;
}

int measure_render(preset_setup *p, const run_info *ri,
                   const nerf_dataset *ds, figures *f)
{
    const double budget = ri->seconds;
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = ri->workers_requested;
    ro.white_background = 1;
    const int blas_before = blas_threads();
    set_blas_threads(ri->render_blas_threads);
    nerf_renderer *r = NULL;
    if (nerf_renderer_create(&r, p->model, p->eval_sampler, &ro) != NERF_OK) {
        set_blas_threads(blas_before);
        return -1;
    }
    /* Without marching, the top rows of an 800x800 view: cost does not
     * depend on where rays go, as nothing stops a ray early.  Marching:
     * a whole view (FAST_RENDER_SIDE). */
    nerf_camera cam;
    size_t n = render_rays(), warm = render_rays() / 2;
    if (render_camera(&cam, p->march ? FAST_RENDER_SIDE : 800, ds) != 0) {
        nerf_renderer_destroy(r);
        set_blas_threads(blas_before);
        return -1;
    }
    if (p->march) {
        f->render_side = FAST_RENDER_SIDE;
        n = warm = (size_t)cam.width * cam.height;
    }
    float *o = malloc(n * 3 * sizeof(float));
    float *d = malloc(n * 3 * sizeof(float));
    float *rgb = malloc(n * 3 * sizeof(float));
    int rc = o && d && rgb ? nerf_camera_rays(&cam, 0, n, o, d) : NERF_ENOMEM;
    /* Warm-up: the workers allocate their scratch on their first block. */
    if (rc == NERF_OK) {
        rc = nerf_renderer_render_rays(r, warm, o, d, rgb, NULL, NULL);
    }
    uint64_t rays = 0;
    double t0 = now(), elapsed = 0.0;
    while (rc == NERF_OK && (elapsed < budget || rays == 0)) {
        rc = nerf_renderer_render_rays(r, n, o, d, rgb, NULL, NULL);
        rays += n;
        elapsed = now() - t0;
    }
    double per_ray = 0.0;
    if (rc == NERF_OK && p->march) {
        uint64_t total = 0;
        rc = count_render_samples(r, n, o, d, &total);
        per_ray = (double)total / (double)n;
    } else {
        per_ray = p->samples[0] + (p->passes > 1 ? p->samples[1] : 0);
    }
    f->render_workers = r->threads;
    f->render_blas_threads = blas_threads();
    nerf_renderer_destroy(r);
    set_blas_threads(blas_before);
    free(o);
    free(d);
    free(rgb);
    if (rc != NERF_OK) {
        return -1;
    }
    f->render_ok = 1;
    f->render_rays = rays;
    f->render_seconds = elapsed;
    f->render_rays_per_s = rays / elapsed;
    f->render_samples_per_ray = per_ray;
    f->render_samples_per_s = per_ray * f->render_rays_per_s;
    return 0;
}
