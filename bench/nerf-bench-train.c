/*
 * Training speed in steady state: rays and network samples per second of
 * BATCH_RAYS-ray steps on the training images, after warm-up steps that
 * allocate the buffers and, for a marching preset, let the occupancy grid
 * carve the empty space; also the loss and PSNR the steps reached.
 */
#include <math.h>
#include <string.h>

#include "nerf-bench.h"

int measure_training(preset_setup *p, const nerf_dataset *ds,
                     const run_info *ri, figures *f, nerf_trainer **keep)
{
    const double budget = ri->seconds;
    nerf_trainer_options to;
    NERF_TRAINER_OPTIONS_INIT(&to);
    to.batch_rays = BATCH_RAYS;
    /* The central crop only changes which pixels are drawn; the steady
     * state of a run is past it. */
    to.precrop_steps = 0;
    /* As nerf-train trains a hash-grid model (images without alpha
     * ignore it). */
    to.random_background = p->march ? 1 : 0;
    nerf_trainer *t = NULL;
    if (nerf_trainer_create(&t, p->model, ds, p->train_sampler, &to) !=
        NERF_OK) {
        return -1;
    }
    nerf_train_stats s;
    memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    /* The first step allocates every buffer; the tiny preset's steps are
     * short enough that a few more cost nothing and settle the caches.
     * A marching preset's cost depends on what the model has learnt (the
     * grid it has carved, where rays become opaque), so it trains first. */
    f->warmup_steps = p->march                  ? (int)ri->fast_warmup
                      : p->id == NERF_PRESET_TINY ? 3
                                                  : 1;
    int rc = NERF_OK;
    double w0 = now();
    for (int i = 0; i < f->warmup_steps && rc == NERF_OK; i++) {
        rc = nerf_trainer_step(t, &s);
    }
    f->warmup_seconds = now() - w0;
    f->warmup_psnr = s.psnr;
    /* Marching: whole cycles of NERF__GRID_EVERY steps, so that the grid
     * refreshes weigh in the mean as often as in a long run. */
    const int cycle = p->march ? (int)NERF__GRID_EVERY : 1;
    const int min_steps = p->march ? cycle : MIN_TRAIN_STEPS;
    int steps = 0;
    double samples = 0.0;
    double t0 = now(), elapsed = 0.0, fastest = INFINITY;
    while (rc == NERF_OK &&
           (elapsed < budget || steps < min_steps || steps % cycle != 0)) {
        double before = elapsed;
        rc = nerf_trainer_step(t, &s);
        steps++;
        elapsed = now() - t0;
        fastest = fmin(fastest, elapsed - before);
        samples += s.samples_per_ray * BATCH_RAYS;
    }
    if (rc == NERF_OK && p->model->grid) {
        const nerf__occupancy *g = p->model->grid;
        f->grid_occupied = (double)g->occupied / (double)g->cells;
    }
    if (rc == NERF_OK && keep) {
        *keep = t;
    } else {
        nerf_trainer_destroy(t);
    }
    if (rc != NERF_OK) {
        return -1;
    }
    f->train_ok = 1;
    f->train_steps = steps;
    f->train_seconds = elapsed;
    f->train_rays_per_s = steps * (double)BATCH_RAYS / elapsed;
    f->train_samples_per_ray = samples / (steps * (double)BATCH_RAYS);
    f->train_samples_per_s = samples / elapsed;
    f->train_loss = s.loss;
    f->train_psnr = s.psnr;
    f->train_last_step = s.step;
    f->train_fastest_step = fastest;
    return 0;
}
