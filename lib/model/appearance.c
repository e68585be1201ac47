/* Per-image appearance codes (appearance.h). */
#include "appearance.h"

#include <math.h>
#include <string.h>

#include "error.h"
#include "model.h"

int nerf__appearance_create(nerf_model *m, uint32_t n)
{
    const size_t floats = (size_t)n * NERF__CODE_FLOATS;
    float *block = nerf__calloc(&m->env, 5 * floats, sizeof(float));
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
    a->curv = block + 2 * floats;
    a->mean_grad = block + 3 * floats;
    a->mean_curv = block + 4 * floats;
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

void nerf__appearance_step(nerf_model *m, uint64_t t)
{
    nerf__appearance *a = &m->appearance;
    const size_t n = (size_t)a->n * NERF__CODE_FLOATS;
    if (n == 0) {
        return;
    }
    const float keep = NERF__CODE_MEMORY, take = 1.0f - NERF__CODE_MEMORY;
    const float p = NERF__CODE_PRIOR / (float)a->n;
    for (size_t i = 0; t > NERF__CODE_WARMUP && i < n; i++) {
        /* Only the codes this step's rays reached: a photo drawn in no
         * step keeps its means, as a hash table's untouched entries keep
         * their moments.  A ray with no curvature (all background) gives
         * no slope either. */
        if (a->curv[i] > 0.0f) {
            a->mean_grad[i] = keep * a->mean_grad[i] +
                              take * (a->grad[i] + p * a->code[i]);
            a->mean_curv[i] = keep * a->mean_curv[i] +
                              take * (a->curv[i] + p);
            /* Both means start at 0 and share their weights, so that
             * their ratio needs no correction of that start. */
            a->code[i] -= NERF__CODE_STEP * a->mean_grad[i] /
                          a->mean_curv[i];
        }
    }
    memset(a->grad, 0, n * sizeof(float));
    memset(a->curv, 0, n * sizeof(float));
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
                               float *d_opacity, float loss_curv,
                               float curv[NERF__CODE_FLOATS])
{
    /* out = e^l (rgb - (1 - a) g) + (1 - a) g: d out / d rgb = e^l,
     * d out / d a = (e^l - 1) g, d out / d l = e^l (rgb - (1 - a) g) = x,
     * whose Gauss-Newton curvature is x^2 times the loss's. */
    const float rest = 1.0f - opacity;
    float da = 0.0f;
    for (int c = 0; c < 3; c++) {
        const float gain = expf(code[c]);
        const float x = gain * (rgb[c] - rest * bg[c]);
        grad[c] += d_out[c] * x;
        curv[c] += loss_curv * x * x;
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
