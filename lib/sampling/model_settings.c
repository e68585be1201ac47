/*
 * nerf_model_set_render_settings() and nerf_model_render_settings(): the
 * sampler settings and background a model is rendered with, recorded by
 * its trainer, or guessed from its shape for a model that has none.  Here
 * rather than in model/ because a sampler's checks and presets decide what
 * is valid.
 */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "error.h"
#include "model.h"
#include "options.h"
#include "sampler.h"

/* How far an unbounded scene is marched when no trainer said, in units of
 * the central cube's half side: the contracted march takes about as many
 * samples to any distance, and this is as far as float t stays precise
 * enough.  The programs train with it too (examples/common). */
#define UNBOUNDED_NEAR 0.05f
#define UNBOUNDED_FAR 1e4f

/* The fields a recording keeps: what places samples, not how randomly. */
static void copy_render_fields(nerf_sampler_options *dst,
                               const nerf_sampler_options *src)
{
    dst->n_coarse = src->n_coarse;
    dst->n_fine = src->n_fine;
    dst->lindisp = src->lindisp;
    dst->paper_bins = src->paper_bins;
    dst->ndc = src->ndc;
    dst->t_near = src->t_near;
    dst->t_far = src->t_far;
    dst->ndc_focal = src->ndc_focal;
    dst->ndc_width = src->ndc_width;
    dst->ndc_height = src->ndc_height;
    dst->march_steps = src->march_steps;
    dst->max_samples = src->max_samples;
}

NERF_API int nerf_model_set_render_settings(nerf_model *model,
                                            const nerf_sampler_options *sampler,
                                            uint32_t white_background)
{
    if (model == NULL || sampler == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_set_render_settings: "
                           "NULL %s", model ? "sampler" : "model");
    }
    if (white_background > 1) {
        return nerf__error(NERF_EINVAL, "nerf_model_set_render_settings: "
                           "white_background must be 0 or 1");
    }
    nerf_sampler_options o;
    nerf_sampler_options_init(&o, sizeof o);
    int rc = nerf__options_read(&o, sizeof o, sampler, "nerf_sampler_options");
    if (rc == NERF_OK) {
        rc = nerf__sampler_check_options(&o);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    nerf_sampler_options kept;
    memset(&kept, 0, sizeof kept);
    kept.struct_size = sizeof kept;
    copy_render_fields(&kept, &o);
    model->render_sampler = kept;
    model->render_white = white_background;
    model->has_render = true;
    return NERF_OK;
}

/* The preset whose networks the model has (0: none). */
static int shape_preset(const nerf_model_options *have)
{
    static const int presets[3] = {NERF_PRESET_REFERENCE, NERF_PRESET_TINY,
                                   NERF_PRESET_FAST};
    for (int i = 0; i < 3; i++) {
        nerf_model_options want;
        nerf_model_options_init(&want, sizeof want);
        nerf_model_options_preset(&want, presets[i]);
        if (want.encoding == have->encoding && want.depth == have->depth &&
            want.width == have->width && want.view_width == have->view_width) {
            return presets[i];
        }
    }
    return 0;
}

/* What a model without recorded settings is rendered with: the choices
 * the example programs make for it without a dataset. */
static void guess(const nerf_model *m, nerf_sampler_options *o,
                  uint32_t *white)
{
    const nerf_model_options *mo = &m->opts;
    nerf_sampler_options_init(o, sizeof *o);
    const int preset = mo->encoding == NERF_ENCODING_HASHGRID
                           ? NERF_PRESET_FAST
                           : shape_preset(mo);
    if (preset != 0) {
        nerf_sampler_options_preset(o, preset);
    }
    if (!mo->use_fine && o->march_steps == 0) {
        /* The paper's "no hierarchical sampling" ablation: all in one. */
        o->n_coarse += o->n_fine;
        o->n_fine = 0;
    }
    *white = 0;
    if (mo->encoding != NERF_ENCODING_HASHGRID || mo->space == NERF_SPACE_BOX) {
        *white = 1; /* Blender scenes */
    } else if (mo->space == NERF_SPACE_NDC) {
        o->ndc = 1;
        o->t_near = 0.0f;
        o->t_far = 1.0f;
    } else {
        o->t_near = UNBOUNDED_NEAR * mo->bound;
        o->t_far = UNBOUNDED_FAR * mo->bound;
    }
}

static int set_renderer(nerf_renderer_options *r, uint32_t white)
{
    const size_t need = offsetof(nerf_renderer_options, white_background) +
                        sizeof r->white_background;
    if (r->struct_size < need || r->struct_size > 65536) {
        return nerf__error(NERF_EINVAL, "nerf_model_render_settings: "
                           "nerf_renderer_options struct_size %u is invalid",
                           (unsigned)r->struct_size);
    }
    r->white_background = white;
    return NERF_OK;
}

NERF_API int nerf_model_render_settings(const nerf_model *model,
                                        nerf_sampler_options *sampler,
                                        nerf_renderer_options *renderer)
{
    if (model == NULL || (sampler == NULL && renderer == NULL)) {
        return nerf__error(NERF_EINVAL, "nerf_model_render_settings: NULL "
                           "%s", model ? "outputs" : "model");
    }
    nerf_sampler_options want;
    uint32_t white = model->render_white;
    if (model->has_render) {
        nerf_sampler_options_init(&want, sizeof want);
        copy_render_fields(&want, &model->render_sampler);
        if (nerf__sampler_check_options(&want) != NERF_OK) {
            char why[512];
            snprintf(why, sizeof why, "%s", nerf_last_error());
            return nerf__error(NERF_EFORMAT, "nerf_model_render_settings: "
                               "the model's recorded render settings are "
                               "invalid (%s)", why);
        }
    } else {
        guess(model, &want, &white);
    }
    if (sampler != NULL) {
        nerf_sampler_options o;
        nerf_sampler_options_init(&o, sizeof o);
        int rc = nerf__options_read(&o, sizeof o, sampler,
                                    "nerf_sampler_options");
        if (rc != NERF_OK) {
            return rc;
        }
        copy_render_fields(&o, &want);
        nerf__options_write(sampler, &o, sizeof o);
    }
    return renderer != NULL ? set_renderer(renderer, white) : NERF_OK;
}
