/*
 * The appearance codes in a training step (model/appearance.h): each ray's
 * composited colour mapped by its image's code before the loss, and the
 * loss gradient taken back through the map to the networks and the code.
 */
#include <string.h>

#include "trainer.h"

int nerf__trainer_appearance_setup(nerf_trainer *t)
{
    nerf_model *m = t->model;
    const uint32_t have = m->appearance.n;
    if (!t->opts.appearance_codes && have == 0) {
        return NERF_OK;
    }
    if (t->workers > 1) {
        /* The gradient hooks exchange the networks' gradients only. */
        return nerf__error(NERF_EINVAL, "nerf_trainer_create: appearance "
                           "codes are not supported with worker_count > 1 "
                           "yet");
    }
    if (have != 0 && have != t->n_images) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_create: the model "
                           "holds appearance codes for %u images and the "
                           "dataset has %u: codes belong to the images they "
                           "were trained on", (unsigned)have,
                           (unsigned)t->n_images);
    }
    const size_t B = t->opts.batch_rays;
    for (int p = 0; p < NERF__PASSES; p++) {
        t->coded[p].rgb = nerf__calloc(&t->env, 3 * B, sizeof(float));
        t->coded[p].opacity = nerf__calloc(&t->env, B, sizeof(float));
        t->coded[p].d_opacity = nerf__calloc(&t->env, B, sizeof(float));
        if (!t->coded[p].rgb || !t->coded[p].opacity ||
            !t->coded[p].d_opacity) {
            return NERF_ENOMEM;
        }
    }
    /* Last, so that a trainer that cannot be made leaves the model as it
     * was. */
    if (have == 0) {
        int rc = nerf__appearance_create(m, t->n_images);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    t->codes = true;
    return NERF_OK;
}

void nerf__trainer_appearance_free(nerf_trainer *t)
{
    for (int p = 0; p < NERF__PASSES; p++) {
        nerf__free(&t->env, t->coded[p].rgb);
        nerf__free(&t->env, t->coded[p].opacity);
        nerf__free(&t->env, t->coded[p].d_opacity);
    }
}

/* A ray of the step (numbered across the whole batch): its image's code,
 * and the background its colour was finished on. */
static const float *ray_code(const nerf_trainer *t, size_t ray)
{
    const size_t plane = (size_t)t->width * t->height;
    const size_t img = t->picked[ray] / plane;
    return t->model->appearance.code + img * NERF__CODE_FLOATS;
}

static void ray_background(const nerf_trainer *t, size_t ray, float bg[3])
{
    for (int c = 0; c < 3; c++) {
        bg[c] = t->backgrounds ? t->backgrounds[3 * ray + c]
                               : t->white ? 1.0f : 0.0f;
    }
}

void nerf__trainer_appearance_forward(nerf_trainer *t, uint32_t passes,
                                      size_t lo, size_t n)
{
    for (uint32_t p = 0; p < passes; p++) {
        float *rgb = t->rgb[p];
        memcpy(t->coded[p].rgb, rgb, 3 * n * sizeof(float));
        for (size_t r = 0; r < n; r++) {
            float bg[3];
            ray_background(t, lo + r, bg);
            nerf__appearance_apply(ray_code(t, lo + r), 1, rgb + 3 * r,
                                   t->coded[p].opacity + r, bg, 0.0f);
        }
    }
}

void nerf__trainer_appearance_backward(nerf_trainer *t, uint32_t passes,
                                       size_t lo, size_t n, size_t all)
{
    /* The loss is the mean over the batch's channels of the squared
     * error (train_step.c): its second derivative in one is 2 / (3 all). */
    const float loss_curv = 2.0f / (3.0f * (float)all);
    nerf__appearance *a = &t->model->appearance;
    const size_t plane = (size_t)t->width * t->height;
    for (uint32_t p = 0; p < passes; p++) {
        float *d = t->d_rgb[p];
        for (size_t r = 0; r < n; r++) {
            float bg[3], d_out[3];
            ray_background(t, lo + r, bg);
            memcpy(d_out, d + 3 * r, sizeof d_out);
            const size_t img = t->picked[lo + r] / plane;
            nerf__appearance_backward(a->code + img * NERF__CODE_FLOATS,
                                      d_out, t->coded[p].rgb + 3 * r,
                                      t->coded[p].opacity[r], bg,
                                      a->grad + img * NERF__CODE_FLOATS,
                                      d + 3 * r, &t->coded[p].d_opacity[r],
                                      loss_curv,
                                      a->curv + img * NERF__CODE_FLOATS);
        }
    }
}
