/*
 * The trainer's record of the data it trains on (model/fingerprint.h) and
 * of its batch: compared with the model's records, which a resumed
 * checkpoint carries, so that training lego's model on fern, or on another
 * downscale, or going on at another batch, is not silent; then recorded in
 * the model, for its next checkpoint.
 */
#include <string.h>

#include "dataset.h"
#include "model.h"
#include "sampler.h"
#include "trainer.h"

static void dataset_fingerprint(const nerf_trainer *t, nerf__fingerprint *f)
{
    const nerf_dataset *ds = t->dataset;
    memset(f, 0, sizeof *f);
    f->known = true;
    f->count = ds->count;
    f->width = ds->width;
    f->height = ds->height;
    f->src_width = ds->src_width;
    f->src_height = ds->src_height;
    f->kind = (uint32_t)ds->kind;
    f->flags = t->sampler->opts.ndc ? NERF__FINGERPRINT_NDC : 0;
    f->near_bound = ds->near_bound;
    f->far_bound = ds->far_bound;
    /* One pass over the pixels the loader holds: a fraction of what
     * loading them cost, and it tells scenes of one size apart. */
    const size_t pixels = (size_t)ds->count * ds->width * ds->height;
    double sum[3] = {0.0, 0.0, 0.0};
    for (size_t i = 0; i < pixels; i++) {
        for (int c = 0; c < 3; c++) {
            sum[c] += ds->pixels[3 * i + c];
        }
    }
    for (int c = 0; c < 3; c++) {
        f->mean_rgb[c] = pixels ? (float)(sum[c] / (double)pixels) : 0.0f;
    }
}

void nerf__trainer_record_data(nerf_trainer *t)
{
    nerf__fingerprint now;
    dataset_fingerprint(t, &now);
    const nerf__fingerprint *was = &t->model->data;
    char what[160];
    if (was->known && nerf__fingerprint_compare(was, &now, what,
                                                sizeof what) > 0) {
        char a[256], b[256];
        nerf__fingerprint_describe(was, 1, a, sizeof a);
        nerf__fingerprint_describe(&now, 0, b, sizeof b);
        nerf__log(&t->env, NERF_LOG_WARN, "trainer: the model was trained "
                  "on other data than this dataset (%s differ): it was "
                  "trained on %s, this dataset has %s", what, a, b);
    }
    t->model->data = now;
}

void nerf__trainer_record_batch(nerf_trainer *t)
{
    nerf_model *m = t->model;
    const uint32_t rays = t->opts.batch_rays;
    const uint32_t samples = t->opts.batch_samples;
    if (m->step > 0 && m->batch_rays > 0 &&
        (m->batch_rays != rays || m->batch_samples != samples)) {
        nerf__log(&t->env, NERF_LOG_WARN, "trainer: the model was trained "
                  "at %u rays a step (batch_samples %u) and this trainer "
                  "takes %u (batch_samples %u): its steps go on, but not as "
                  "the run it was saved from would have gone on",
                  (unsigned)m->batch_rays, (unsigned)m->batch_samples,
                  (unsigned)rays, (unsigned)samples);
    }
    m->batch_rays = rays;
    m->batch_samples = samples;
}
