/* The stratified engine of a render batch: sampling, both networks and
 * compositing (render_stratified.h). */
#include "render_stratified.h"

#include <math.h>
#include <string.h>

#include "composite.h"
#include "parallel.h"
#include "render_batch.h"

void nerf__stratified_release(nerf__stratified_state *st,
                              const nerf__env *env)
{
    nerf__free(env, st->block);
    memset(st, 0, sizeof *st);
}

/* Size the per-sample arrays; workspaces are sized later. */
static int reserve(nerf__stratified_state *st, const nerf__env *env,
                   size_t n, uint32_t n_c, uint32_t n_f, bool keep)
{
    if (st->block && n <= st->cap_rays && n_c <= st->cap_c &&
        n_f <= st->cap_f && (st->cap_keep || !keep)) {
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
        &st->t[0], &st->t[1], &st->weights[0], &st->weights[1],
        &st->rgb[0], &st->rgb[1], &st->sigma[0], &st->sigma[1],
        &st->points, &st->dirs, &st->scratch, &st->d_rgb, &st->d_sigma,
    };
    size_t bytes[] = {
        n * s0, n * s1, n * s0, n * s1,
        3 * n * s0, 3 * n * s1, n * s0, n * s1,
        3 * n * s1, 3 * n * s1, n * nerf__sample_fine_scratch(n_c, n_f),
        keep ? 3 * n * s1 : 0, keep ? n * s1 : 0,
    };
    const size_t count = sizeof bytes / sizeof bytes[0];
    for (size_t i = 0; i < count; i++) {
        bytes[i] *= sizeof(float);
    }
    int rc = nerf__carve_floats(env, &st->block, slots, bytes, count);
    if (rc != NERF_OK) {
        return rc;
    }
    st->cap_rays = n;
    st->cap_c = n_c;
    st->cap_f = n_f;
    st->cap_keep = keep;
    return NERF_OK;
}

/*
 * Every loop below works ray by ray, each ray writing only its own rows, so
 * they run over the thread pool in ranges of rays; a job carries the batch,
 * the setup and the pass.
 */
typedef struct batch_job {
    nerf__batch *b;
    const nerf__render_setup *s;
    const float *o, *d; /* the caller's rays */
    int pass;
    bool random, with_dirs;
    const nerf__space *space; /* the model's */
    const nerf__pass_out *out;
    const float *d_rgb, *d_depth, *d_opacity;
} batch_job;

/* View directions (unit, before any warp), the rays actually sampled, and
 * their lengths. */
static void prepare_rays(void *ctx, size_t begin, size_t end)
{
    const batch_job *j = ctx;
    nerf__batch *b = j->b;
    const nerf__render_setup *s = j->s;
    for (size_t k = begin; k < end; k++) {
        const float *dk = j->d + 3 * k;
        float len = sqrtf(dk[0] * dk[0] + dk[1] * dk[1] + dk[2] * dk[2]);
        for (int c = 0; c < 3; c++) {
            b->viewdir[3 * k + c] = dk[c] / len;
        }
    }
    const size_t n = end - begin;
    if (s->sampler->opts.ndc) {
        nerf__render_ndc_rays(s, n, j->o + 3 * begin, j->d + 3 * begin,
                              b->ray_o + 3 * begin, b->ray_d + 3 * begin);
    } else {
        memcpy(b->ray_o + 3 * begin, j->o + 3 * begin, 3 * n * sizeof(float));
        memcpy(b->ray_d + 3 * begin, j->d + 3 * begin, 3 * n * sizeof(float));
    }
    for (size_t k = begin; k < end; k++) {
        const float *dk = b->ray_d + 3 * k;
        b->dir_norm[k] = sqrtf(dk[0] * dk[0] + dk[1] * dk[1] + dk[2] * dk[2]);
    }
}

static void sample_coarse(void *ctx, size_t begin, size_t end)
{
    const batch_job *j = ctx;
    const nerf__render_setup *s = j->s;
    const nerf_sampler_options *so = &s->sampler->opts;
    const uint32_t n_c = so->n_coarse;
    for (size_t k = begin; k < end; k++) {
        nerf__rng rng = nerf__ray_rng(so->seed, NERF__STREAM_STRATIFIED,
                                      s->first_ray + k);
        nerf__sample_stratified(so, j->random,
                                s->u_coarse ? s->u_coarse + k * n_c : NULL,
                                &rng, j->b->stratified.t[0] + k * n_c);
    }
}

static void sample_fine(void *ctx, size_t begin, size_t end)
{
    const batch_job *j = ctx;
    nerf__stratified_state *st = &j->b->stratified;
    const nerf__render_setup *s = j->s;
    const nerf_sampler_options *so = &s->sampler->opts;
    const uint32_t n_c = so->n_coarse, n_f = so->n_fine;
    const size_t scratch = nerf__sample_fine_scratch(n_c, n_f);
    for (size_t k = begin; k < end; k++) {
        nerf__rng rng = nerf__ray_rng(so->seed, NERF__STREAM_HIERARCHICAL,
                                      s->first_ray + k);
        nerf__sample_fine_ray(n_c, n_f, st->t[0] + k * n_c,
                              st->weights[0] + k * n_c, j->random,
                              s->u_fine ? s->u_fine + k * n_f : NULL, &rng,
                              st->scratch + k * scratch,
                              st->t[1] + k * (n_c + n_f));
    }
}

/* Network inputs of one pass: o + d t and the ray's view direction. */
static void fill_points(void *ctx, size_t begin, size_t end)
{
    const batch_job *j = ctx;
    nerf__batch *b = j->b;
    nerf__stratified_state *st = &b->stratified;
    const uint32_t m = b->n_samples[j->pass];
    const float *t = st->t[j->pass];
    const bool with_dirs = j->with_dirs;
    /* An unbounded model works on contracted points; the others take the
     * points as they are. */
    const bool contract = j->space->kind == NERF__SPACE_CONTRACT;
    for (size_t k = begin; k < end; k++) {
        const float *o = b->ray_o + 3 * k, *d = b->ray_d + 3 * k;
        for (uint32_t i = 0; i < m; i++) {
            size_t at = k * m + i;
            float ti = t[at];
            for (int c = 0; c < 3; c++) {
                st->points[3 * at + c] = o[c] + d[c] * ti;
            }
            if (contract) {
                nerf__space_to_domain(j->space, st->points + 3 * at,
                                      st->points + 3 * at);
            }
            if (with_dirs) {
                memcpy(st->dirs + 3 * at, b->viewdir + 3 * k,
                       3 * sizeof(float));
            }
        }
    }
}

static int run_network(nerf__batch *b, const nerf__render_setup *s, int pass,
                       size_t count)
{
    const nerf_model *m = s->model;
    nerf__stratified_state *st = &b->stratified;
    const int net = b->net[pass];
    const float *dirs = nerf__model_uses_viewdirs(m) ? st->dirs : NULL;
    if (s->keep) {
        /* The model sizes the workspace and keeps every activation. */
        return nerf__model_forward(m, net, &b->ws[pass], count, st->points,
                                   dirs, st->rgb[pass], st->sigma[pass]);
    }
    /* Evaluation needs no activations after the pass: one lean workspace
     * serves both passes. */
    return nerf__model_evaluate(m, net, &b->ws[0], count, st->points, dirs,
                                st->rgb[pass], st->sigma[pass]);
}

static bool has_noise(const nerf__render_setup *s, int pass)
{
    return s->noise[pass] || (s->training && s->noise_std > 0.0f);
}

static void add_noise(void *ctx, size_t begin, size_t end)
{
    const batch_job *j = ctx;
    nerf__batch *b = j->b;
    const nerf__render_setup *s = j->s;
    const int pass = j->pass;
    const uint32_t m = b->n_samples[pass];
    float *sigma = b->stratified.sigma[pass];
    if (s->noise[pass]) {
        for (size_t i = begin * m; i < end * m; i++) {
            sigma[i] += s->noise[pass][i];
        }
        return;
    }
    const uint32_t purpose = pass == 0 ? NERF__STREAM_NOISE_COARSE
                                       : NERF__STREAM_NOISE_FINE;
    for (size_t k = begin; k < end; k++) {
        nerf__rng rng = nerf__ray_rng(s->sampler->opts.seed, purpose,
                                      s->first_ray + k);
        for (uint32_t i = 0; i < m; i++) {
            sigma[k * m + i] += (float)nerf__rng_normal(&rng) * s->noise_std;
        }
    }
}

/* The background ray k is finished on (NULL: black). */
static const float *ray_background(const nerf__batch *b, size_t k)
{
    static const float white[3] = {1.0f, 1.0f, 1.0f};
    return b->ray_bg ? b->ray_bg + 3 * k : b->white ? white : NULL;
}

static void composite_pass(void *ctx, size_t begin, size_t end)
{
    const batch_job *j = ctx;
    nerf__batch *b = j->b;
    nerf__stratified_state *st = &b->stratified;
    const int pass = j->pass;
    const nerf__pass_out *out = j->out;
    const uint32_t m = b->n_samples[pass];
    for (size_t k = begin; k < end; k++) {
        nerf__ray_out r;
        size_t at = k * m;
        nerf__composite_ray_bg(m, st->t[pass] + at, b->dir_norm[k],
                               st->rgb[pass] + 3 * at, st->sigma[pass] + at,
                               ray_background(b, k), st->weights[pass] + at,
                               &r);
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

int nerf__render_stratified(nerf__batch *b, const nerf__render_setup *s,
                            size_t n_rays, const float *origins,
                            const float *directions,
                            const nerf__pass_out out[NERF__PASSES])
{
    const nerf_model *m = s->model;
    const nerf_sampler_options *so = &s->sampler->opts;
    const uint32_t n_c = so->n_coarse, n_f = so->n_fine;
    if (s->sample_budget > 0) {
        /* Every ray has the same count: the budget is a number of rays. */
        const size_t per_ray = n_c + (n_f > 0 ? (size_t)n_c + n_f : 0);
        const size_t fit = (s->sample_budget + per_ray - 1) / per_ray;
        n_rays = fit < n_rays ? fit : n_rays;
    }
    int rc = reserve(&b->stratified, &b->env, n_rays, n_c, n_f, s->keep);
    if (rc == NERF_OK) {
        rc = nerf__batch_begin(b, s, n_rays);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    b->n_pass = n_f > 0 ? 2 : 1;
    b->n_samples[0] = n_c;
    b->n_samples[1] = n_c + n_f;
    b->net[0] = 0;
    int fine = nerf__model_network(m, NERF_NETWORK_FINE);
    b->net[1] = fine >= 0 ? fine : 0;
    if (n_rays == 0) {
        return NERF_OK;
    }
    batch_job j = {.b = b, .s = s, .o = origins, .d = directions,
                   .random = s->training && so->perturb,
                   .with_dirs = nerf__model_uses_viewdirs(m),
                   .space = nerf__model_space(m)};
    /* Rough operations per ray of each loop, to decide whether it is worth
     * waking the pool. */
    nerf__parallel_for(n_rays, 32, prepare_rays, &j);
    nerf__parallel_for(n_rays, 8 * n_c, sample_coarse, &j);
    for (uint32_t pass = 0; pass < b->n_pass; pass++) {
        const uint32_t samples = b->n_samples[pass];
        j.pass = (int)pass;
        j.out = out ? &out[pass] : NULL;
        if (pass == 1) {
            nerf__parallel_for(n_rays, 128 * (n_c + n_f), sample_fine, &j);
        }
        nerf__parallel_for(n_rays, 6 * samples, fill_points, &j);
        rc = run_network(b, s, (int)pass, n_rays * samples);
        if (rc != NERF_OK) {
            return rc;
        }
        if (has_noise(s, (int)pass)) {
            nerf__parallel_for(n_rays, 40 * samples, add_noise, &j);
        }
        nerf__parallel_for(n_rays, 40 * samples, composite_pass, &j);
        b->n_evaluated += n_rays * samples;
    }
    b->kept = s->keep;
    return NERF_OK;
}

static void composite_backward(void *ctx, size_t begin, size_t end)
{
    const batch_job *j = ctx;
    nerf__batch *b = j->b;
    nerf__stratified_state *st = &b->stratified;
    const int pass = j->pass;
    const uint32_t s = b->n_samples[pass];
    for (size_t k = begin; k < end; k++) {
        size_t at = k * s;
        nerf__composite_ray_backward_bg(
            s, st->t[pass] + at, b->dir_norm[k], st->rgb[pass] + 3 * at,
            st->sigma[pass] + at, ray_background(b, k),
            j->d_rgb ? j->d_rgb + 3 * k : NULL,
            j->d_depth ? j->d_depth[k] : 0.0f,
            j->d_opacity ? j->d_opacity[k] : 0.0f, st->d_rgb + 3 * at,
            st->d_sigma + at);
    }
}

int nerf__render_stratified_backward(
    nerf__batch *b, nerf_model *m, const float *const d_rgb[NERF__PASSES],
    const float *const d_depth[NERF__PASSES],
    const float *const d_opacity[NERF__PASSES])
{
    for (uint32_t pass = 0; pass < b->n_pass; pass++) {
        const float *gr = d_rgb ? d_rgb[pass] : NULL;
        const float *gd = d_depth ? d_depth[pass] : NULL;
        const float *go = d_opacity ? d_opacity[pass] : NULL;
        if (gr == NULL && gd == NULL && go == NULL) {
            continue;
        }
        batch_job j = {.b = b, .pass = (int)pass, .d_rgb = gr, .d_depth = gd,
                       .d_opacity = go};
        nerf__parallel_for(b->n_rays, 60 * b->n_samples[pass],
                           composite_backward, &j);
        int rc = nerf__model_backward(m, b->net[pass], &b->ws[pass],
                                      b->stratified.d_rgb,
                                      b->stratified.d_sigma);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    return NERF_OK;
}
