/* Per-image appearance codes (appearance.h). */
#include "appearance.h"

#include <math.h>
#include <string.h>

#include "adam.h"
#include "error.h"
#include "model.h"

int nerf__appearance_create(nerf_model *m, uint32_t n)
{
    const size_t floats = (size_t)n * NERF__CODE_FLOATS;
    float *block = nerf__calloc(&m->env, 4 * floats, sizeof(float));
    if (block == NULL) {
        return nerf__error(NERF_ENOMEM, "out of memory for %u appearance "
                           "codes", (unsigned)n);
    }
    nerf__appearance_free(&m->env, &m->appearance);
    nerf__appearance *a = &m->appearance;
    a->n = n;
    a->block = block;
    a->code = block;
    a->grad = block + floats;
    a->adam_m = block + 2 * floats;
    a->adam_v = block + 3 * floats;
    return NERF_OK;
}

void nerf__appearance_free(const nerf__env *env, nerf__appearance *a)
{
    nerf__free(env, a->block);
    memset(a, 0, sizeof *a);
}

void nerf__appearance_pick(const nerf__appearance *a, uint32_t which,
                           float code[NERF__CODE_FLOATS])
{
    if (which != NERF_APPEARANCE_NEUTRAL) {
        memcpy(code, a->code + (size_t)(which - 1) * NERF__CODE_FLOATS,
               NERF__CODE_FLOATS * sizeof(float));
        return;
    }
    /* Summed in double, in image order: the same bits on every machine
     * and thread count. */
    double sum[NERF__CODE_FLOATS] = {0};
    for (uint32_t i = 0; i < a->n; i++) {
        const float *c = a->code + (size_t)i * NERF__CODE_FLOATS;
        for (uint32_t k = 0; k < NERF__CODE_FLOATS; k++) {
            sum[k] += c[k];
        }
    }
    for (uint32_t k = 0; k < NERF__CODE_FLOATS; k++) {
        code[k] = a->n ? (float)(sum[k] / a->n) : 0.0f;
    }
}

void nerf__appearance_adam(nerf_model *m, uint64_t t, double lr)
{
    nerf__appearance *a = &m->appearance;
    if (a->n == 0) {
        return;
    }
    const size_t n = (size_t)a->n * NERF__CODE_FLOATS;
    if (t <= NERF__CODE_WARMUP) {
        memset(a->grad, 0, n * sizeof(float));
        return;
    }
    for (size_t i = 0; i < n; i++) {
        /* Only the codes this step's rays reached, as below. */
        if (a->grad[i] != 0.0f) {
            a->grad[i] += NERF__CODE_DECAY * a->code[i];
        }
    }
    /* Sparse: a step's rays touch a few images' codes, and the others
     * keep their moments, as a hash table's untouched entries do. */
    nerf__adam_update(&m->adam, t, NERF__CODE_RATE * lr, n, a->code,
                      a->grad, a->adam_m, a->adam_v, NERF__ADAM_SPARSE);
}

void nerf__appearance_apply(const float code[NERF__CODE_FLOATS], size_t n,
                            float *rgb, const float *opacity,
                            const float *bg, float bg_all)
{
    float gain[3];
    for (int c = 0; c < 3; c++) {
        gain[c] = expf(code[c]);
    }
    for (size_t i = 0; i < n; i++) {
        float *p = rgb + 3 * i;
        const float rest = 1.0f - opacity[i];
        for (int c = 0; c < 3; c++) {
            const float g = bg ? bg[3 * i + c] : bg_all;
            p[c] = gain[c] * (p[c] - rest * g) + rest * g;
        }
    }
}

void nerf__appearance_backward(const float code[NERF__CODE_FLOATS],
                               const float d_out[3], const float rgb[3],
                               float opacity, const float bg[3],
                               float grad[NERF__CODE_FLOATS], float d_rgb[3],
                               float *d_opacity)
{
    /* out = e^l (rgb - (1 - a) g) + (1 - a) g: d out / d rgb = e^l,
     * d out / d a = (e^l - 1) g, d out / d l = e^l (rgb - (1 - a) g). */
    const float rest = 1.0f - opacity;
    float da = 0.0f;
    for (int c = 0; c < 3; c++) {
        const float gain = expf(code[c]);
        grad[c] += d_out[c] * gain * (rgb[c] - rest * bg[c]);
        d_rgb[c] = d_out[c] * gain;
        da += d_out[c] * (gain - 1.0f) * bg[c];
    }
    *d_opacity = da;
}

NERF_API int nerf_model_appearance_count(const nerf_model *model,
                                         uint32_t *count)
{
    if (model == NULL || count == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_appearance_count: NULL "
                           "argument");
    }
    *count = model->appearance.n;
    return NERF_OK;
}

int nerf__appearance_check(const nerf_model *m, uint32_t which,
                           const char *fn)
{
    if (which == NERF_APPEARANCE_NEUTRAL || which - 1 < m->appearance.n) {
        return NERF_OK;
    }
    if (m->appearance.n == 0) {
        return nerf__error(NERF_EINVAL, "%s: appearance %u asks for training "
                           "image %u's code, and the model has no appearance "
                           "codes (only NERF_APPEARANCE_NEUTRAL, 0)", fn,
                           (unsigned)which, (unsigned)(which - 1));
    }
    return nerf__error(NERF_EINVAL, "%s: appearance %u asks for training "
                       "image %u's code, and the model has codes for images "
                       "0 to %u", fn, (unsigned)which, (unsigned)(which - 1),
                       (unsigned)(m->appearance.n - 1));
}

NERF_API int nerf_model_appearance_code(const nerf_model *model,
                                        uint32_t which, float *code)
{
    if (model == NULL || code == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_appearance_code: NULL "
                           "argument");
    }
    int rc = nerf__appearance_check(model, which,
                                    "nerf_model_appearance_code");
    if (rc == NERF_OK) {
        nerf__appearance_pick(&model->appearance, which, code);
    }
    return rc;
}
