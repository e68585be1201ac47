/*
 * A render batch: the part both engines share, and the choice of engine
 * (render_stratified.c, render_march.c).
 */
#include "render_batch.h"

#include <string.h>

void nerf__batch_init(nerf__batch *b, const nerf__env *env)
{
    memset(b, 0, sizeof *b);
    b->env = *env;
    nerf__march_state_init(&b->marching, env);
}

void nerf__batch_release(nerf__batch *b)
{
    for (int p = 0; p < NERF__PASSES; p++) {
        nerf__workspace_release(&b->ws_env, &b->ws[p]);
    }
    nerf__stratified_release(&b->stratified, &b->env);
    nerf__march_state_release(&b->marching, &b->env);
    nerf__free(&b->env, b->ray_block);
    nerf__env env = b->env;
    nerf__batch_init(b, &env);
}

int nerf__render_check_pair(const nerf_model *m, const nerf_sampler *s,
                            const char *fn)
{
    if (nerf__sampler_marches(s) && nerf__model_grid(m) == NULL) {
        return nerf__error(NERF_EINVAL, "%s: the sampler marches "
                           "(march_steps = %u) through an occupancy grid, "
                           "which only hash-grid models have (encoding "
                           "NERF_ENCODING_HASHGRID, as NERF_PRESET_FAST); "
                           "use march_steps = 0 with this model", fn,
                           (unsigned)s->opts.march_steps);
    }
    /* The grids of an NDC model lie over NDC space, which only an NDC
     * sampler's warped rays reach; a contracted model's, over world
     * space. */
    const uint32_t space = nerf__model_space(m)->kind;
    if (space == NERF__SPACE_NDC && !s->opts.ndc) {
        return nerf__error(NERF_EINVAL, "%s: the model's space is NDC "
                           "(NERF_SPACE_NDC), so the sampler needs ndc = 1",
                           fn);
    }
    if (s->opts.ndc && (space == NERF__SPACE_CONTRACT ||
                        (space == NERF__SPACE_BOX &&
                         nerf__sampler_marches(s)))) {
        return nerf__error(NERF_EINVAL, "%s: the sampler warps rays to NDC "
                           "(ndc = 1), which needs a model whose space is "
                           "NDC (NERF_SPACE_NDC) to march or contract", fn);
    }
    return NERF_OK;
}

/* The per-ray arrays: the rays sampled, their view directions and
 * lengths. */
static int reserve_rays(nerf__batch *b, size_t n)
{
    if (b->ray_block && n <= b->cap_rays) {
        return NERF_OK;
    }
    /* Guard the products below: n is bounded by the callers, but a size
     * computation must never wrap. */
    if (n > ((size_t)1 << 30) / 16) {
        return nerf__error(NERF_EINVAL, "render batch of %zu rays is too "
                           "large", n);
    }
    float **slots[] = {&b->ray_o, &b->ray_d, &b->viewdir, &b->dir_norm,
                       &b->opacity};
    const size_t f = sizeof(float);
    const size_t bytes[] = {3 * n * f, 3 * n * f, 3 * n * f, n * f, n * f};
    int rc = nerf__carve_floats(&b->env, &b->ray_block, slots, bytes,
                                sizeof bytes / sizeof bytes[0]);
    if (rc == NERF_OK) {
        b->cap_rays = n;
    }
    return rc;
}

int nerf__batch_begin(nerf__batch *b, const nerf__render_setup *s,
                      size_t n_rays)
{
    const nerf_model *m = s->model;
    int rc = reserve_rays(b, n_rays);
    if (rc != NERF_OK) {
        return rc;
    }
    if (b->model != m) {
        /* Workspaces come from the model's allocator, the one
         * nerf__model_forward() uses; start afresh for another model. */
        for (int p = 0; p < NERF__PASSES; p++) {
            nerf__workspace_release(&b->ws_env, &b->ws[p]);
        }
        b->ws_env = *nerf__model_env(m);
        nerf__march_state_bind(&b->marching, &b->ws_env);
        b->model = m;
    }
    b->n_rays = n_rays;
    b->white = s->white_background;
    b->ray_bg = s->background;
    return NERF_OK;
}

int nerf__render_batch(nerf__batch *b, const nerf__render_setup *s,
                       size_t n_rays, const float *origins,
                       const float *directions,
                       const nerf__pass_out out[NERF__PASSES])
{
    b->kept = false;
    b->marched = false;
    b->n_rays = 0;
    b->n_evaluated = 0;
    const int last = nerf__sampler_last_pass(s->sampler);
    const bool map = s->appearance && out[last].rgb != NULL;
    nerf__pass_out own[NERF__PASSES];
    if (map && out[last].opacity == NULL) {
        /* The map needs each ray's opacity: the batch's own array. */
        int rc = reserve_rays(b, n_rays);
        if (rc != NERF_OK) {
            return rc;
        }
        memcpy(own, out, sizeof own);
        own[last].opacity = b->opacity;
        out = own;
    }
    int rc = nerf__sampler_marches(s->sampler)
                 ? nerf__render_march(b, s, n_rays, origins, directions,
                                      out)
                 : nerf__render_stratified(b, s, n_rays, origins,
                                           directions, out);
    if (rc == NERF_OK && map) {
        nerf__appearance_apply(s->code, b->n_rays, out[last].rgb,
                               out[last].opacity, b->ray_bg, s->white_background ? 1.0f : 0.0f);
    }
    return rc;
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
    if (b->marched) {
        return nerf__render_march_backward(b, m, d_rgb ? d_rgb[0] : NULL,
                                           d_depth ? d_depth[0] : NULL,
                                           d_opacity ? d_opacity[0] : NULL);
    }
    return nerf__render_stratified_backward(b, m, d_rgb, d_depth, d_opacity);
}
