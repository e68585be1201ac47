#include "scene_setup.h"

#include <stdio.h>
#include <string.h>

int setup_model_preset(const nerf_model *model)
{
    nerf_model_options have, want;
    NERF_MODEL_OPTIONS_INIT(&have);
    if (nerf_model_get_options(model, &have) != NERF_OK) {
        return 0;
    }
    static const int presets[] = {NERF_PRESET_REFERENCE, NERF_PRESET_TINY,
                                  NERF_PRESET_FAST};
    for (size_t i = 0; i < sizeof presets / sizeof presets[0]; i++) {
        NERF_MODEL_OPTIONS_INIT(&want);
        nerf_model_options_preset(&want, presets[i]);
        if (want.encoding == have.encoding && want.depth == have.depth &&
            want.width == have.width &&
            want.view_width == have.view_width) {
            return presets[i];
        }
    }
    return 0;
}

uint32_t setup_forward_facing(const nerf_model *model, int space)
{
    if (model == NULL) {
        return space == NERF_SPACE_NDC;
    }
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    return nerf_model_get_options(model, &mo) == NERF_OK &&
           mo.encoding == NERF_ENCODING_HASHGRID &&
           mo.space == NERF_SPACE_NDC;
}

int setup_model_space(nerf_model_options *mo, const nerf_dataset *dataset,
                      int space, const char *program)
{
    const float preset_bound = mo->bound;
    if (dataset) {
        int rc = nerf_model_options_for_dataset(mo, dataset);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    const uint32_t want = dataset ? mo->space : NERF_SPACE_BOX;
    if (space < 0 || (uint32_t)space == want) {
        return NERF_OK;
    }
    if (space == NERF_SPACE_NDC || want == NERF_SPACE_NDC) {
        /* A forward-facing dataset's bounds are NDC depths, and NDC
         * needs them. */
        fprintf(stderr, "%s: --space %s: the dataset is %sforward-facing, and "
                "NDC is for exactly those scenes\n", program,
                space == NERF_SPACE_NDC ? "ndc"
                : space == NERF_SPACE_BOX ? "box" : "unbounded",
                want == NERF_SPACE_NDC ? "" : "not ");
        return SETUP_USAGE;
    }
    /* The dataset's bound is for its own space; another one keeps the
     * preset's, except that a contraction's central cube is the scene's. */
    mo->space = (uint32_t)space;
    if (!(mo->space == NERF_SPACE_UNBOUNDED && dataset)) {
        mo->bound = preset_bound;
    }
    return NERF_OK;
}

/* A march asked of a model that does not march is set as asked, for the
 * renderer to refuse by name; steps is the programs' --march-steps,
 * 1..65536 (OPT_MARCH_STEPS()). */
static int march_with(nerf_sampler_options *so, int64_t steps)
{
    if (so->march_steps == 0) {
        so->march_steps = (uint32_t)steps;
        return NERF_OK;
    }
    return nerf_sampler_options_set_march(so, (uint32_t)steps);
}

int setup_marches(const nerf_model *model)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    /* A forged recording is setup_sampler()'s to report. */
    return nerf_model_render_settings(model, &so, NULL) == NERF_OK &&
           so.march_steps > 0;
}

int setup_sampler(nerf_sampler **out, const nerf_model *model,
                  const nerf_dataset *dataset, const sampler_choice *c)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    int rc = nerf_sampler_options_for(&so, model, dataset,
                                      c->training ? NERF_SAMPLER_FOR_TRAINING
                                                  : NERF_SAMPLER_FOR_RENDERING);
    if (rc != NERF_OK) {
        return rc;
    }
    /* Out-of-range counts are the sampler's to refuse, by name. */
    so.n_coarse = c->n_coarse >= 0 ? (uint32_t)c->n_coarse : so.n_coarse;
    so.n_fine = c->n_fine >= 0 ? (uint32_t)c->n_fine : so.n_fine;
    if (c->march_steps >= 0) {
        rc = march_with(&so, c->march_steps);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    so.seed = c->seed;
    if (c->far > c->near) {
        so.t_near = c->near;
        so.t_far = c->far;
    }
    return nerf_sampler_create(out, &so);
}

int setup_white_background(const nerf_dataset *dataset)
{
    return dataset == NULL ||
           nerf_dataset_get_format(dataset) == NERF_DATASET_BLENDER;
}

int setup_background(const nerf_model *model, const nerf_dataset *dataset)
{
    if (dataset) {
        return setup_white_background(dataset);
    }
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    return nerf_model_render_settings(model, NULL, &ro) == NERF_OK
               ? (int)ro.white_background
               : 1;
}
