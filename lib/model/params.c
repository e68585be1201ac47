/* Enum-keyed training hyperparameters of a model. */
#include <math.h>
#include <string.h>

#include "model.h"

typedef struct param_info {
    int key;
    double min, max;
    size_t offset; /* of the double in nerf__adam */
} param_info;

static const param_info params[] = {
    {NERF_PARAM_LEARNING_RATE, 1e-12, 1.0, offsetof(nerf__adam, lr)},
    {NERF_PARAM_LEARNING_RATE_FINAL, 1e-12, 1.0, offsetof(nerf__adam, lr_final)},
    {NERF_PARAM_DECAY_STEPS, 1.0, 1e15, offsetof(nerf__adam, decay_steps)},
    {NERF_PARAM_ADAM_BETA1, 0.0, 0.9999999, offsetof(nerf__adam, beta1)},
    {NERF_PARAM_ADAM_BETA2, 0.0, 0.9999999, offsetof(nerf__adam, beta2)},
    {NERF_PARAM_ADAM_EPS, 1e-30, 1.0, offsetof(nerf__adam, eps)},
    {NERF_PARAM_WEIGHT_DECAY, 0.0, 1.0, offsetof(nerf__adam, weight_decay)},
    {NERF_PARAM_DECAY_START, 0.0, 1e15, offsetof(nerf__adam, decay_start)},
    {NERF_PARAM_AVERAGE_STEPS, 0.0, 1e15,
     offsetof(nerf__adam, average_steps)},
};

static const param_info *find(int key)
{
    for (size_t i = 0; i < sizeof params / sizeof params[0]; i++) {
        if (params[i].key == key) {
            return &params[i];
        }
    }
    return NULL;
}

NERF_API int nerf_param_bounds(int param, double *min_out, double *max_out)
{
    const param_info *p = find(param);
    if (p == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_param_bounds: unknown parameter %d",
                           param);
    }
    if (min_out) {
        *min_out = p->min;
    }
    if (max_out) {
        *max_out = p->max;
    }
    return NERF_OK;
}

NERF_API int nerf_model_set_param(nerf_model *model, int param, double value)
{
    const param_info *p = find(param);
    if (model == NULL || p == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_set_param: %s",
                           model ? "unknown parameter" : "model is NULL");
    }
    if (!(value >= p->min && value <= p->max)) { /* also rejects NaN */
        return nerf__error(NERF_EINVAL, "nerf_model_set_param: parameter %d = "
                           "%g is outside [%g, %g]", param, value, p->min, p->max);
    }
    *(double *)((char *)&model->adam + p->offset) = value;
    if (param == NERF_PARAM_DECAY_STEPS || param == NERF_PARAM_DECAY_START) {
        /* A schedule set by hand replaces one fitted to a budget. */
        memset(&model->schedule, 0, sizeof model->schedule);
    }
    return NERF_OK;
}

NERF_API int nerf_model_get_param(const nerf_model *model, int param,
                                  double *value_out)
{
    const param_info *p = find(param);
    if (model == NULL || p == NULL || value_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_get_param: %s",
                           p ? "NULL argument" : "unknown parameter");
    }
    *value_out = *(const double *)((const char *)&model->adam + p->offset);
    return NERF_OK;
}

NERF_API double nerf_model_learning_rate(const nerf_model *model)
{
    return model ? nerf__adam_rate(&model->adam, model->step) : 0.0;
}
