/* A batch of rays through sampling, both networks and compositing. */
#include "render_batch.h"

#include <math.h>
#include <string.h>

#include "composite.h"
#include "ndc.h"

void nerf__batch_init(nerf__batch *b, const nerf__env *env)
{
    memset(b, 0, sizeof *b);
    b->env = *env;
}

void nerf__batch_release(nerf__batch *b)
{
    for (int p = 0; p < NERF__PASSES; p++) {
        nerf__workspace_release(&b->ws_env, &b->ws[p]);
    }
    nerf__free(&b->env, b->block);
    nerf__env env = b->env;
    nerf__batch_init(b, &env);
}

static size_t round16(size_t floats)
{
    return (floats + 15) & ~(size_t)15; /* keep each array 64-byte aligned */
}

/* Size the per-ray and per-sample arrays; workspaces are sized later. */
static int reserve(nerf__batch *b, size_t n, uint32_t n_c, uint32_t n_f,
                   bool keep)
{
    if (b->block && n <= b->cap_rays && n_c <= b->cap_c && n_f <= b->cap_f &&
        (b->cap_keep || !keep)) {
        return NERF_OK;
    }
    const size_t s0 = n_c, s1 = (size_t)n_c + n_f;
    /* Guard the products below: n is bounded by the callers, but a size
     * computation must never wrap. */
    if (n > ((size_t)1 << 30) / (s1 * 4 + 16)) {
        return nerf__error(NERF_EINVAL, "render batch of %zu rays x %zu "
                           "samples is too large", n, s1);
    }
    float **slots[] = {
        &b->ray_o, &b->ray_d, &b->viewdir, &b->dir_norm,
        &b->t[0], &b->t[1], &b->weights[0], &b->weights[1],
        &b->rgb[0], &b->rgb[1], &b->sigma[0], &b->sigma[1],
        &b->points, &b->dirs, &b->scratch, &b->d_rgb, &b->d_sigma,
    };
    const size_t sizes[] = {
        3 * n, 3 * n, 3 * n, n,
        n * s0, n * s1, n * s0, n * s1,
        3 * n * s0, 3 * n * s1, n * s0, n * s1,
        3 * n * s1, 3 * n * s1, nerf__sample_fine_scratch(n_c, n_f),
        keep ? 3 * n * s1 : 0, keep ? n * s1 : 0,
    };
    const size_t count = sizeof sizes / sizeof sizes[0];
    size_t total = 0;
    for (size_t i = 0; i < count; i++) {
        total += round16(sizes[i]);
    }
    float *block = nerf__alloc(&b->env, total * sizeof(float));
    if (block == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(&b->env, b->block);
    b->block = block;
    for (size_t i = 0; i < count; i++) {
        *slots[i] = sizes[i] ? block : NULL;
        block += round16(sizes[i]);
    }
    b->cap_rays = n;
    b->cap_c = n_c;
    b->cap_f = n_f;
    b->cap_keep = keep;
    return NERF_OK;
}

/* View directions (unit, before any warp), the rays actually sampled, and
 * their lengths. */
static void prepare_rays(nerf__batch *b, const nerf__render_setup *s,
                         size_t n, const float *o, const float *d)
{
    for (size_t k = 0; k < n; k++) {
        const float *dk = d + 3 * k;
        float len = sqrtf(dk[0] * dk[0] + dk[1] * dk[1] + dk[2] * dk[2]);
        for (int c = 0; c < 3; c++) {
            b->viewdir[3 * k + c] = dk[c] / len;
        }
    }
    if (s->sampler->opts.ndc) {
        /* The reference puts the NDC near plane at world depth 1. */
        nerf__ndc_rays(s->ndc_focal, s->ndc_width, s->ndc_height, 1.0f, n, o,
                       d, b->ray_o, b->ray_d);
    } else {
        memcpy(b->ray_o, o, 3 * n * sizeof(float));
        memcpy(b->ray_d, d, 3 * n * sizeof(float));
    }
    for (size_t k = 0; k < n; k++) {
        const float *dk = b->ray_d + 3 * k;
        b->dir_norm[k] = sqrtf(dk[0] * dk[0] + dk[1] * dk[1] + dk[2] * dk[2]);
    }
}

/* Network inputs of one pass: o + d t and the ray's view direction. */
static void fill_points(nerf__batch *b, size_t n, uint32_t m, const float *t,
                        bool with_dirs)
{
    for (size_t k = 0; k < n; k++) {
        const float *o = b->ray_o + 3 * k, *d = b->ray_d + 3 * k;
        for (uint32_t i = 0; i < m; i++) {
            size_t at = k * m + i;
            float ti = t[at];
            for (int c = 0; c < 3; c++) {
                b->points[3 * at + c] = o[c] + d[c] * ti;
            }
            if (with_dirs) {
                memcpy(b->dirs + 3 * at, b->viewdir + 3 * k, 3 * sizeof(float));
            }
        }
    }
}

static int run_network(nerf__batch *b, const nerf__render_setup *s, int pass,
                       size_t count)
{
    const nerf_model *m = s->model;
    const int net = b->net[pass];
    const float *dirs = m->nets[net].use_viewdirs ? b->dirs : NULL;
    if (s->keep) {
        /* The model sizes the workspace and keeps every activation. */
        return nerf__model_forward(m, net, &b->ws[pass], count, b->points,
                                   dirs, b->rgb[pass], b->sigma[pass]);
    }
    /* Evaluation needs no activations after the pass: one lean workspace
     * serves both passes. */
    nerf__workspace *ws = &b->ws[0];
    int rc = nerf__workspace_reserve(&b->ws_env, ws, &m->nets[net], count,
                                     false);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__network_forward(&m->nets[net], m->params, ws, count, b->points,
                          dirs, b->rgb[pass], b->sigma[pass]);
    return NERF_OK;
}

static void add_noise(nerf__batch *b, const nerf__render_setup *s, int pass,
                      size_t n)
{
    const uint32_t m = b->n_samples[pass];
    float *sigma = b->sigma[pass];
    if (s->noise[pass]) {
        for (size_t i = 0; i < n * m; i++) {
            sigma[i] += s->noise[pass][i];
        }
        return;
    }
    if (!s->training || !(s->noise_std > 0.0f)) {
        return;
    }
    const uint32_t purpose = pass == 0 ? NERF__STREAM_NOISE_COARSE
                                       : NERF__STREAM_NOISE_FINE;
    for (size_t k = 0; k < n; k++) {
        nerf__rng rng = nerf__ray_rng(s->sampler->opts.seed, purpose,
                                      s->first_ray + k);
        for (uint32_t i = 0; i < m; i++) {
            sigma[k * m + i] += (float)nerf__rng_normal(&rng) * s->noise_std;
        }
    }
}

static void composite_pass(nerf__batch *b, int pass, size_t n,
                           const nerf__pass_out *out)
{
    const uint32_t m = b->n_samples[pass];
    for (size_t k = 0; k < n; k++) {
        nerf__ray_out r;
        size_t at = k * m;
        nerf__composite_ray(m, b->t[pass] + at, b->dir_norm[k],
                            b->rgb[pass] + 3 * at, b->sigma[pass] + at,
                            b->white, b->weights[pass] + at, &r);
        if (out == NULL) {
            continue;
        }
        if (out->rgb) {
            memcpy(out->rgb + 3 * k, r.rgb, sizeof r.rgb);
        }
        if (out->depth) {
            out->depth[k] = r.depth;
        }
        if (out->disparity) {
            out->disparity[k] = r.disparity;
        }
        if (out->opacity) {
            out->opacity[k] = r.opacity;
        }
    }
}

int nerf__render_batch(nerf__batch *b, const nerf__render_setup *s,
                       size_t n_rays, const float *origins,
                       const float *directions,
                       const nerf__pass_out out[NERF__PASSES])
{
    const nerf_model *m = s->model;
    const nerf_sampler_options *so = &s->sampler->opts;
    const uint32_t n_c = so->n_coarse, n_f = so->n_fine;
    b->kept = false;
    b->n_rays = 0;
    int rc = reserve(b, n_rays, n_c, n_f, s->keep);
    if (rc != NERF_OK) {
        return rc;
    }
    if (b->model != m) {
        /* Workspaces come from the model's allocator, the one
         * nerf__model_forward() uses; start afresh for another model. */
        for (int p = 0; p < NERF__PASSES; p++) {
            nerf__workspace_release(&b->ws_env, &b->ws[p]);
        }
        b->ws_env = m->env;
        b->model = m;
    }
    b->n_rays = n_rays;
    b->white = s->white_background;
    b->n_pass = n_f > 0 ? 2 : 1;
    b->n_samples[0] = n_c;
    b->n_samples[1] = n_c + n_f;
    b->net[0] = 0;
    int fine = nerf__model_network(m, NERF_NETWORK_FINE);
    b->net[1] = fine >= 0 ? fine : 0;
    if (n_rays == 0) {
        return NERF_OK;
    }
    const bool random = s->training && so->perturb;
    const bool with_dirs = m->nets[0].use_viewdirs;

    prepare_rays(b, s, n_rays, origins, directions);
    for (size_t k = 0; k < n_rays; k++) {
        nerf__rng rng = nerf__ray_rng(so->seed, NERF__STREAM_STRATIFIED,
                                      s->first_ray + k);
        nerf__sample_stratified(so, random,
                                s->u_coarse ? s->u_coarse + k * n_c : NULL,
                                &rng, b->t[0] + k * n_c);
    }
    for (uint32_t pass = 0; pass < b->n_pass; pass++) {
        if (pass == 1) {
            for (size_t k = 0; k < n_rays; k++) {
                nerf__rng rng = nerf__ray_rng(so->seed,
                                              NERF__STREAM_HIERARCHICAL,
                                              s->first_ray + k);
                nerf__sample_fine_ray(n_c, n_f, b->t[0] + k * n_c,
                                      b->weights[0] + k * n_c, random,
                                      s->u_fine ? s->u_fine + k * n_f : NULL,
                                      &rng, b->scratch,
                                      b->t[1] + k * (n_c + n_f));
            }
        }
        fill_points(b, n_rays, b->n_samples[pass], b->t[pass], with_dirs);
        rc = run_network(b, s, (int)pass, n_rays * b->n_samples[pass]);
        if (rc != NERF_OK) {
            return rc;
        }
        add_noise(b, s, (int)pass, n_rays);
        composite_pass(b, (int)pass, n_rays, out ? &out[pass] : NULL);
    }
    b->kept = s->keep;
    return NERF_OK;
}

int nerf__render_batch_backward(nerf__batch *b, nerf_model *m,
                                const float *const d_rgb[NERF__PASSES],
                                const float *const d_depth[NERF__PASSES],
                                const float *const d_opacity[NERF__PASSES])
{
    if (!b->kept || b->model != m) {
        return nerf__error(NERF_EINVAL, "render backward: the last forward "
                           "did not keep its state for this model");
    }
    for (uint32_t pass = 0; pass < b->n_pass; pass++) {
        const float *gr = d_rgb ? d_rgb[pass] : NULL;
        const float *gd = d_depth ? d_depth[pass] : NULL;
        const float *go = d_opacity ? d_opacity[pass] : NULL;
        if (gr == NULL && gd == NULL && go == NULL) {
            continue;
        }
        const uint32_t s = b->n_samples[pass];
        for (size_t k = 0; k < b->n_rays; k++) {
            size_t at = k * s;
            nerf__composite_ray_backward(
                s, b->t[pass] + at, b->dir_norm[k], b->rgb[pass] + 3 * at,
                b->sigma[pass] + at, b->white, gr ? gr + 3 * k : NULL,
                gd ? gd[k] : 0.0f, go ? go[k] : 0.0f, b->d_rgb + 3 * at,
                b->d_sigma + at);
        }
        nerf__model_backward(m, b->net[pass], &b->ws[pass], b->d_rgb,
                             b->d_sigma);
    }
    return NERF_OK;
}
