/* nerf_bake_create() and the handle's small calls (bake.h). */
#include "bake.h"

#include <math.h>

#include "error.h"
#include "model.h"
#include "occupancy.h"
#include "options.h"
#include "space.h"

#define FN "nerf_bake_create"

static void defaults(nerf_bake_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    /* Measured on lego at 640x480, against the networks' renders: with
     * 512 steps, 6 subdivisions score 33.1 dB where 4 score 29.6, in
     * about the same time a frame; steps of one voxel (768 across) would
     * score 34.3 dB in 1.7 times the time (docs/viewer.md). */
    o->subdivisions = 6;
    o->march_steps = 512;
    o->sh_degree = 1;
    o->directions = 8;
    o->max_bytes = (uint64_t)2 << 30;
    o->appearance = NERF_APPEARANCE_NEUTRAL;
}

NERF_API int nerf_bake_options_init(nerf_bake_options *opts,
                                    size_t struct_size)
{
    nerf_bake_options d;
    defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_bake_options");
}

static int check_options(const void *opts)
{
    const nerf_bake_options *o = opts;
    if (o->subdivisions < 1 || o->subdivisions > 16) {
        return nerf__error(NERF_EINVAL, FN ": subdivisions %u is not in "
                           "1..16", (unsigned)o->subdivisions);
    }
    if (o->sh_degree > NERF__BAKE_MAX_DEGREE) {
        return nerf__error(NERF_EINVAL, FN ": sh_degree %u is not in 0..%u",
                           (unsigned)o->sh_degree, NERF__BAKE_MAX_DEGREE);
    }
    const uint32_t coefs = (o->sh_degree + 1) * (o->sh_degree + 1);
    if (o->directions < coefs || o->directions > 1024) {
        return nerf__error(NERF_EINVAL, FN ": directions %u is not in "
                           "%u..1024 for sh_degree %u",
                           (unsigned)o->directions, (unsigned)coefs,
                           (unsigned)o->sh_degree);
    }
    if (o->march_steps > 65536) {
        return nerf__error(NERF_EINVAL, FN ": march_steps %u is above 65536",
                           (unsigned)o->march_steps);
    }
    return NERF_OK;
}

/* Why model cannot be baked, or NULL. */
static const char *cannot_bake(const nerf_model *model)
{
    const nerf__occupancy *g = nerf__model_grid(model);
    if (g == NULL) {
        return "it has no occupancy grid (only models that march, as the "
               "fast preset's, can be baked)";
    }
    const nerf__space *s = nerf__model_space(model);
    if (s->kind == NERF__SPACE_CONTRACT) {
        return "its space is unbounded (contracted), whose rays bend in the "
               "grid; the bake does not follow them yet";
    }
    return NULL;
}

/* The model's render settings the bake keeps. */
static int take_settings(nerf_bake *b, const nerf_model *model,
                         const nerf_bake_options *o)
{
    nerf_sampler_options so;
    nerf_renderer_options ro;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    NERF_RENDERER_OPTIONS_INIT(&ro);
    int rc = nerf_model_render_settings(model, &so, &ro);
    if (rc != NERF_OK) {
        return rc;
    }
    const nerf__occupancy *g = nerf__model_grid(model);
    if (o->march_steps > 0) {
        b->step = nerf__march_step(g->lo, g->hi, o->march_steps);
    } else {
        /* One voxel's edge: between corners the values are linear, and
         * finer steps read the same eight corners again.  On lego, half
         * the networks' march (about this step) scored within 0.1 dB of
         * their own (docs/viewer.md). */
        b->step = INFINITY;
        for (int a = 0; a < 3; a++) {
            b->step = fminf(b->step, g->cell_size[a] / (float)o->subdivisions);
        }
    }
    b->inv_step = 1.0f / b->step;
    b->t_near = so.t_near;
    b->t_far = so.t_far;
    b->ndc = so.ndc != 0;
    b->ndc_focal = so.ndc_focal;
    b->ndc_width = (float)so.ndc_width;
    b->ndc_height = (float)so.ndc_height;
    b->background = ro.white_background ? 1.0f : 0.0f;
    if (model->appearance.n > 0) {
        rc = nerf__appearance_check(model, o->appearance, FN);
        if (rc != NERF_OK) {
            return rc;
        }
        b->appearance = true;
        nerf__appearance_pick(&model->appearance, o->appearance, b->code);
    } else if (o->appearance != NERF_APPEARANCE_NEUTRAL) {
        return nerf__error(NERF_EINVAL, FN ": appearance %u, but the model "
                           "has no appearance codes", (unsigned)o->appearance);
    }
    return NERF_OK;
}

NERF_API int nerf_bake_create(nerf_bake **out, const nerf_model *model,
                              const nerf_bake_options *opts)
{
    if (out != NULL) {
        *out = NULL;
    }
    if (out == NULL || model == NULL) {
        return nerf__error(NERF_EINVAL, FN ": NULL %s",
                           out ? "model" : "output");
    }
    nerf_bake_options o;
    defaults(&o);
    nerf__env env;
    int rc = nerf__options_open(&o, sizeof o, opts, "nerf_bake_options",
                                check_options, &o.hooks, &env);
    if (rc != NERF_OK) {
        return rc;
    }
    const char *why = cannot_bake(model);
    if (why != NULL) {
        return nerf__error(NERF_EINVAL, FN ": cannot bake this model: %s",
                           why);
    }
    rc = nerf__model_check_finite(model, FN);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf_bake *b = nerf__calloc(&env, 1, sizeof *b);
    if (b == NULL) {
        return nerf__error(NERF_ENOMEM, FN ": out of memory");
    }
    b->env = env;
    b->first_hits = true;
    const nerf__occupancy *g = nerf__model_grid(model);
    b->res = g->res;
    b->k = o.subdivisions;
    b->corners = (b->k + 1) * (b->k + 1) * (b->k + 1);
    b->degree = o.sh_degree;
    b->coefs = (b->degree + 1) * (b->degree + 1);
    b->stride = 1 + 3 * b->coefs;
    for (int a = 0; a < 3; a++) {
        b->lo[a] = g->lo[a];
        b->hi[a] = g->hi[a];
        b->cell[a] = g->cell_size[a];
        b->inv_cell[a] = g->inv_cell[a];
    }
    rc = take_settings(b, model, &o);
    if (rc == NERF_OK) {
        rc = nerf__bake_bricks(b, model, &o);
    }
    if (rc == NERF_OK) {
        rc = nerf__bake_empty_space(b);
    }
    if (rc != NERF_OK) {
        nerf_bake_destroy(b);
        return rc;
    }
    *out = b;
    return NERF_OK;
}

NERF_API void nerf_bake_destroy(nerf_bake *b)
{
    if (b == NULL) {
        return;
    }
    const nerf__env env = b->env;
    nerf__free(&env, b->brick_of);
    nerf__free(&env, b->empty);
    nerf__free(&env, b->surface);
    nerf__free(&env, b->data);
    nerf__free(&env, b);
}

NERF_API int nerf_bake_stats_get(const nerf_bake *b, nerf_bake_stats *stats)
{
    if (b == NULL || stats == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_bake_stats_get: NULL %s",
                           b ? "stats" : "bake");
    }
    nerf_bake_stats s;
    memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    s.resolution = b->res * b->k;
    s.bricks = b->bricks;
    s.points = b->points;
    s.bytes = b->bricks * b->corners * b->stride * sizeof(uint16_t) +
              (uint64_t)b->res * b->res * b->res *
                  (sizeof(int32_t) + sizeof(uint8_t)) +
              b->n_surface * sizeof(uint32_t) +
              sizeof *b;
    if (stats->struct_size < sizeof(uint32_t)) {
        return nerf__error(NERF_EINVAL, "nerf_bake_stats_get: struct_size "
                           "%u is too small", (unsigned)stats->struct_size);
    }
    nerf__options_write(stats, &s, sizeof s);
    return NERF_OK;
}
