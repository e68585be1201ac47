/* One optimisation step, and the loop that runs many with progress,
 * cancellation and periodic checkpoints. */
#include <math.h>
#include <string.h>

#include "occupancy.h"
#include "progress.h"
#include "trainer.h"

/*
 * Squared error of one pass over n colour values, and its gradient with
 * respect to them, of the mean over `all` values: the whole batch's, of
 * which a worker may hold a share.  The loss is the sum of the passes'
 * MSEs, as the reference (img_loss + img_loss0).  Returns the mean over
 * the n values.
 */
static double pass_loss(size_t n, size_t all, const float *rgb,
                        const float *target, float *grad)
{
    double sum = 0.0;
    const float scale = 2.0f / (float)all;
    for (size_t i = 0; i < n; i++) {
        float e = rgb[i] - target[i];
        sum += (double)e * e;
        grad[i] = scale * e;
    }
    return n > 0 ? sum / (double)n : 0.0;
}

/*
 * A run that diverged, found at step k: by its loss (then the weights
 * are left as they were before the step), or by a save or the run's end
 * finding the weights not finite.  The message says which, and where the
 * first weight that is not finite lies; file, when given, is the
 * checkpoint that was therefore not written.
 */
static int diverged(const nerf_trainer *t, uint64_t k, double loss,
                    const char *file)
{
    const nerf_model *m = t->model;
    if (nerf__model_finite(m)) {
        return nerf__error(NERF_ERROR, "training diverged: the loss is %g at "
                           "step %llu, the weights still finite (try a "
                           "lower learning rate)", loss,
                           (unsigned long long)k);
    }
    char text[320];
    nerf__model_nonfinite_text(m, text, sizeof text);
    return nerf__error(NERF_ERROR, "training diverged by step %llu: the "
                       "weights are not finite (%s)%s%s%s (try a lower "
                       "learning rate)", (unsigned long long)k, text,
                       file ? "; " : "", file ? file : "",
                       file ? " was not written and keeps what it held" : "");
}

static double psnr_of(double mse)
{
    return mse > 0.0 ? -10.0 * log10(mse) : INFINITY;
}

static void fill_stats(nerf_train_stats *out, const nerf_train_stats *s)
{
    if (out == NULL) {
        return;
    }
    uint32_t size = out->struct_size;
    size_t n = size < sizeof *s ? size : sizeof *s;
    if (n > sizeof(uint32_t)) {
        memcpy((char *)out + sizeof(uint32_t), (const char *)s + sizeof(uint32_t),
               n - sizeof(uint32_t));
    }
}

int nerf__trainer_grid_density(void *ctx, size_t n, const float *xyz,
                               float *sigma)
{
    nerf_trainer *t = ctx;
    return nerf__model_density(t->model, 0, &t->density_ws, n, xyz, sigma);
}

int nerf__trainer_update_grid(nerf_trainer *t)
{
    nerf_model *m = t->model;
    nerf__occupancy *g = m->grid;
    if (g == NULL || !nerf__grid_due(m->step)) {
        return NERF_OK;
    }
    /* The update's random draws are keyed by the model's seed (the grid's)
     * and the grid's update count, both in checkpoints, so a resumed run
     * refreshes the grid as the unbroken one did. */
    size_t n_random = nerf__grid_random_cells(m->step, g->cells);
    int rc = nerf__occupancy_update(g, nerf__trainer_grid_density, t,
                                    n_random);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__log(&t->env, NERF_LOG_DEBUG, "trainer: step %llu, occupancy grid "
              "update %llu: %zu cells sampled, %zu of %zu occupied (%.1f%%), "
              "threshold %g", (unsigned long long)m->step,
              (unsigned long long)g->updates, g->evaluated, g->occupied,
              g->cells, 100.0 * (double)g->occupied / (double)g->cells,
              (double)g->threshold);
    return NERF_OK;
}

/* This worker's rays of step k, rendered into t->rgb (the setup's ray
 * numbering and background moved to the share's first ray). */
static int render_share(nerf_trainer *t, uint64_t k, nerf__share *sh)
{
    const size_t B = t->opts.batch_rays;
    if (t->workers > 1) {
        nerf__trainer_share(t, k, sh);
    } else {
        *sh = (nerf__share){.all = B, .lo = 0, .hi = B};
    }
    const size_t lo = sh->lo;
    t->setup.first_ray = k * B + lo;
    t->setup.background = t->backgrounds ? t->backgrounds + 3 * lo : NULL;
    t->batch.n_rays = 0;
    t->batch.n_evaluated = 0;
    if (sh->hi == lo) {
        return NERF_OK;
    }
    nerf__pass_out out[NERF__PASSES];
    memset(out, 0, sizeof out);
    for (int p = 0; p < NERF__PASSES; p++) {
        out[p].rgb = t->rgb[p];
        out[p].opacity = t->codes ? t->coded[p].opacity : NULL;
    }
    int rc = nerf__render_batch(&t->batch, &t->setup, sh->hi - lo,
                                t->origins + 3 * lo, t->directions + 3 * lo,
                                out);
    if (rc == NERF_OK && t->workers <= 1) {
        /* With batch_samples the batch took the first n of the B rays. */
        sh->all = sh->hi = t->batch.n_rays;
    }
    return rc;
}

static int step(nerf_trainer *t, nerf_train_stats *stats)
{
    nerf_model *m = t->model;
    const uint64_t k = m->step;
    if (!t->checked) {
        /* Workers that start from different weights would train apart
         * from the first step on. */
        int rc = nerf__trainer_check_workers(t, true);
        if (rc != NERF_OK) {
            return rc;
        }
        t->checked = true;
    }
    if (t->march) {
        int rc = nerf__trainer_update_grid(t);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    nerf__trainer_pick_rays(t, k);
    nerf__share sh;
    int rc = render_share(t, k, &sh);
    if (rc != NERF_OK) {
        return rc;
    }
    const nerf_sampler_options *so = &t->sampler->opts;
    const uint32_t passes = t->march || so->n_fine == 0 ? 1 : 2;
    const size_t n = sh.hi - sh.lo;
    const float *targets = t->targets + 3 * sh.lo;
    double mse[NERF__PASSES] = {0.0, 0.0};
    if (t->codes) {
        nerf__trainer_appearance_forward(t, passes, sh.lo, n);
    }
    for (uint32_t p = 0; p < passes; p++) {
        mse[p] = pass_loss(3 * n, 3 * sh.all, t->rgb[p], targets, t->d_rgb[p]);
    }
    double loss = mse[0] + mse[1];
    if (!isfinite(loss)) {
        return diverged(t, k, loss, NULL);
    }
    nerf__model_clear_grad(m);
    if (n > 0) {
        const float *d_rgb[NERF__PASSES] = {t->d_rgb[0],
                                            passes > 1 ? t->d_rgb[1] : NULL};
        const float *none[NERF__PASSES] = {NULL, NULL};
        const float *d_opacity[NERF__PASSES] = {NULL, NULL};
        if (t->codes) {
            nerf__trainer_appearance_backward(t, passes, sh.lo, n, sh.all);
            for (uint32_t p = 0; p < passes; p++) {
                d_opacity[p] = t->coded[p].d_opacity;
            }
        }
        rc = nerf__render_batch_backward(&t->batch, m, d_rgb, none,
                                         d_opacity);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    rc = nerf__trainer_exchange(t, k, n, sh.all);
    if (rc != NERF_OK) {
        return rc;
    }
    double lr = nerf__adam_rate(&m->adam, m->step);
    rc = nerf__model_adam_step(m);
    if (rc != NERF_OK) {
        return rc;
    }
    stats->struct_size = sizeof *stats;
    stats->step = m->step;
    stats->loss = loss;
    stats->psnr = psnr_of(mse[passes - 1]);
    stats->psnr_coarse = psnr_of(mse[0]);
    stats->learning_rate = lr;
    stats->samples_per_ray =
        n > 0 ? (double)t->batch.n_evaluated / (double)n : 0.0;
    stats->rays = n;
    return nerf__trainer_check_workers(t, false);
}

NERF_API int nerf_trainer_step(nerf_trainer *t, nerf_train_stats *stats_out)
{
    if (t == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_step: trainer is NULL");
    }
    if (stats_out && (stats_out->struct_size < sizeof(uint32_t) ||
                      stats_out->struct_size > 65536)) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_step: stats struct_size "
                           "%u is invalid", (unsigned)stats_out->struct_size);
    }
    nerf_train_stats s;
    memset(&s, 0, sizeof s);
    int rc = step(t, &s);
    if (rc == NERF_OK) {
        fill_stats(stats_out, &s);
    }
    return rc;
}

static int save_checkpoint(nerf_trainer *t, nerf__run *r)
{
    if (!nerf__model_finite(t->model)) {
        /* The last good checkpoint stays: a step since made the weights
         * NaN without the loss showing it yet. */
        return diverged(t, t->model->step, NAN, t->checkpoint_path);
    }
    const double begin = nerf__run_elapsed(r);
    int rc = nerf_model_save(t->model, t->checkpoint_path);
    if (rc == NERF_OK) {
        nerf__log(&t->env, NERF_LOG_INFO, "trainer: saved %s at step %llu",
                  t->checkpoint_path, (unsigned long long)t->model->step);
    }
    /* Timed saves count from the end of this one, failed or not: a save
     * of a large model takes seconds, which are not training. */
    r->last_save = nerf__run_elapsed(r);
    r->save_seconds = r->last_save - begin;
    r->saving += r->save_seconds;
    r->saved_step = t->model->step;
    r->saved = true;
    return rc;
}

/* Whether the step just taken is one to save after. */
static bool save_due(const nerf_trainer *t, const nerf__run *r)
{
    const uint32_t every = t->opts.checkpoint_every;
    if (every > 0 && r->last.step % every == 0) {
        return true;
    }
    const double s = t->opts.checkpoint_seconds;
    return s > 0.0 && nerf__run_elapsed(r) - r->last_save >= s;
}

void nerf__run_begin(nerf_trainer *t, nerf__run *r, uint64_t total)
{
    atomic_store(&t->cancel, 0);
    memset(r, 0, sizeof *r);
    r->start = nerf__seconds();
    r->total = total;
}

double nerf__run_elapsed(const nerf__run *r)
{
    return nerf__seconds() - r->start;
}

int nerf__run_step(nerf_trainer *t, nerf__run *r, nerf_train_stats *stats_out)
{
    int rc = step(t, &r->last);
    if (rc != NERF_OK) {
        return rc;
    }
    r->done++;
    fill_stats(stats_out, &r->last);
    if (t->checkpoint_path && save_due(t, r)) {
        rc = save_checkpoint(t, r);
    }
    if (rc == NERF_OK && t->progress) {
        nerf_progress p;
        memset(&p, 0, sizeof p);
        p.struct_size = sizeof p;
        p.kind = NERF_PROGRESS_TRAIN;
        p.done = r->done;
        p.total = r->total;
        p.elapsed = nerf__run_elapsed(r);
        p.loss = r->last.loss;
        p.psnr = r->last.psnr;
        if (t->progress(&p, t->progress_user) != 0) {
            atomic_store(&t->cancel, 1);
        }
    }
    if (rc == NERF_OK && atomic_load(&t->cancel)) {
        rc = nerf__error(NERF_ECANCELLED, "nerf_trainer_run: cancelled "
                         "at step %llu", (unsigned long long)r->last.step);
    }
    return rc;
}

int nerf__run_end(nerf_trainer *t, nerf__run *r, int rc)
{
    /* A checkpoint at the end too, cancelled or not, so that no finished
     * step is lost. */
    if (t->checkpoint_path && r->done > 0 &&
        !(r->saved && r->saved_step == t->model->step)) {
        int save_rc = save_checkpoint(t, r);
        /* A failed save outranks a cancellation: the caller asked for the
         * stop, but must learn that the steps since the last checkpoint
         * are not on disk. */
        if (save_rc != NERF_OK &&
            (rc == NERF_OK || rc == NERF_ECANCELLED)) {
            rc = save_rc;
        }
    }
    /* Without a checkpoint to save, a run whose steps made the weights NaN
     * with finite losses says so here rather than at the next use. */
    if ((rc == NERF_OK || rc == NERF_ECANCELLED) && r->done > 0 &&
        !nerf__model_finite(t->model)) {
        rc = diverged(t, t->model->step, NAN, NULL);
    }
    return rc;
}

NERF_API int nerf_trainer_run(nerf_trainer *t, uint64_t n_steps,
                              nerf_train_stats *stats_out)
{
    if (t == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_run: trainer is NULL");
    }
    nerf__run r;
    nerf__run_begin(t, &r, n_steps);
    int rc = NERF_OK;
    while (r.done < n_steps && rc == NERF_OK) {
        rc = nerf__run_step(t, &r, stats_out);
    }
    return nerf__run_end(t, &r, rc);
}
