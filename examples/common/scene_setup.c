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
    uint32_t want = NERF_SPACE_BOX;
    float bound = mo->bound;
    if (dataset) {
        int rc = nerf_dataset_space(dataset, &want, &bound);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    if (space >= 0 && (uint32_t)space != want &&
        (space == NERF_SPACE_NDC || want == NERF_SPACE_NDC)) {
        /* A forward-facing dataset's bounds are NDC depths, and NDC
         * needs them. */
        fprintf(stderr, "%s: --space %s: the dataset is %sforward-facing, and "
                "NDC is for exactly those scenes\n", program,
                space == NERF_SPACE_NDC ? "ndc"
                : space == NERF_SPACE_BOX ? "box" : "unbounded",
                want == NERF_SPACE_NDC ? "" : "not ");
        return SETUP_USAGE;
    }
    if (space >= 0 && (uint32_t)space != want) {
        /* The dataset's bound is for its own space; another one keeps
         * the preset's, except that a contraction's central cube is the
         * scene's. */
        want = (uint32_t)space;
        bound = want == NERF_SPACE_UNBOUNDED && dataset ? bound : mo->bound;
    }
    mo->space = want;
    mo->bound = bound;
    return NERF_OK;
}

/* A finer march than the recorded one must reach as far along a ray, so
 * the cap on a ray's samples grows with it.  steps is the programs'
 * --march-steps or --render-march-steps, 1..65536 (OPT_MARCH_STEPS()),
 * or the fast preset's. */
static void march_with(nerf_sampler_options *so, int64_t steps)
{
    if (so->march_steps > 0 && steps > 0) {
        const double cap = (double)so->max_samples * (double)steps /
                           (double)so->march_steps;
        so->max_samples = cap < 1.0       ? 1u
                          : cap > 65536.0 ? 65536u
                                          : (uint32_t)cap;
    }
    so->march_steps = (uint32_t)steps;
}

int64_t setup_train_march(const nerf_model *model)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    if (nerf_model_render_settings(model, &so, NULL) != NERF_OK ||
        so.march_steps == 0) {
        /* A forged recording is setup_sampler()'s to report. */
        return -1;
    }
    nerf_sampler_options_preset(&so, NERF_PRESET_FAST);
    return so.march_steps;
}

int setup_render_march(nerf_model *model, int64_t steps)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    int rc = nerf_model_render_settings(model, &so, &ro);
    if (rc != NERF_OK || so.march_steps == 0) {
        return rc;
    }
    march_with(&so, steps);
    return nerf_model_set_render_settings(model, &so, ro.white_background);
}

/*
 * The model says how it is sampled: the settings it was trained with
 * (guessed from its shape for files from before libnerf 0.4).  A scene,
 * when there is one, says where: its bounds and NDC frustum, except that
 * a contracted scene is marched as far as the model's settings reach.
 */
int setup_sampler(nerf_sampler **out, const nerf_model *model,
                  const nerf_dataset *dataset, const sampler_choice *c)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    int rc = nerf_model_render_settings(model, &so, NULL);
    if (rc != NERF_OK) {
        return rc;
    }
    /* Out-of-range counts are the sampler's to refuse, by name. */
    so.n_coarse = c->n_coarse >= 0 ? (uint32_t)c->n_coarse : so.n_coarse;
    so.n_fine = c->n_fine >= 0 ? (uint32_t)c->n_fine : so.n_fine;
    if (c->march_steps >= 0) {
        march_with(&so, c->march_steps);
    }
    so.seed = c->seed;
    if (dataset) {
        float t_far = so.t_far;
        rc = nerf_dataset_bounds(dataset, &so.t_near, &so.t_far);
        if (rc != NERF_OK) {
            return rc;
        }
        nerf_model_options mo;
        NERF_MODEL_OPTIONS_INIT(&mo);
        nerf_model_get_options(model, &mo);
        if (mo.space == NERF_SPACE_UNBOUNDED) {
            so.t_far = t_far;
        }
        so.ndc = (uint32_t)nerf_dataset_is_ndc(dataset);
        so.ndc_focal = 0.0f;
        so.ndc_width = so.ndc_height = 0;
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        if (so.ndc && nerf_dataset_camera(dataset, 0, &cam) == NERF_OK) {
            /* One NDC frustum for every view, that of the training images,
             * so renders at other sizes see the same warped scene. */
            so.ndc_focal = cam.fx;
            so.ndc_width = cam.width;
            so.ndc_height = cam.height;
        }
    }
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
