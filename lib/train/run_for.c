/*
 * Training to a time budget (nerf_trainer_run_for()): measure the step
 * rate with the learning rate held, then fix the run's length and decay
 * over it; at a half, three quarters and nine tenths of the budget, fit
 * the length again to the rate then, or earlier if the run reaches its
 * length before.
 * Only the moments of the fits depend on the clock; what they fix is
 * recorded in the model, so everything after them is as deterministic as
 * a run of a given step count.
 */
#include <math.h>
#include <string.h>

#include "error.h"
#include "model.h"
#include "trainer.h"

/* Share of the budget spent measuring before the fit. */
#define MEASURE_SHARE 0.25
/* The rate is taken over the last third of the measuring time: steps of a
 * marching sampler get faster for minutes as the occupancy grid learns
 * where the scene is (on lego several times as many a second after five
 * minutes as in the first), so the latest rate is the best guess of the
 * rest. */
#define WINDOW_START (MEASURE_SHARE * 2.0 / 3.0)
/* They are still getting faster at the fit: a run fitted there alone
 * ended early on lego, and fitted again at half the budget alone, a run
 * on a machine whose steps then turned slower ended late (docs/perf-log/
 * 2026-11-25-lego-ten-minutes-by-the-clock.md).  So the call that
 * fitted fits the length again at these shares of the budget; the last
 * leaves an error in the rate a tenth of the time to act on.  Each takes
 * the rate over the quarter of the time before it, or since the fit before
 * if that is later.  A run that reaches its length before the next share
 * fits it again then: in a one-minute budget of lego at 2048 rays a step
 * the fit took the rate of a grid not yet carved, and the run reached its
 * length at the moment of the fit at half, with half its budget unused. */
static const double refit_shares[] = {0.5, 0.75, 0.9};
#define N_REFITS (sizeof refit_shares / sizeof refit_shares[0])
#define REFIT_WINDOW 0.75
/* A run whose steps turn slower than measured stops this far past the
 * budget rather than running on without bound. */
#define OVERRUN 1.1
/* Held there while measuring, the rate stays at LEARNING_RATE. */
#define NO_DECAY 1e15

/* Steps and saving time at the start of the window a rate is taken over. */
typedef struct rate_window {
    bool marked;
    double time, saving;
    uint64_t done;
} rate_window;

static void window_mark(rate_window *w, const nerf__run *r, double elapsed,
                        double from)
{
    if (!w->marked && elapsed >= from) {
        *w = (rate_window){true, elapsed, r->saving, r->done};
    }
}

/*
 * Steps a second of training alone since the mark: a save inside the
 * window (the first timed one falls there in a 10-minute budget) would
 * lower it noticeably.  One step may outlast the whole window: then the
 * rate since the run's start is all there is.
 */
static double window_rate(const rate_window *w, const nerf__run *r,
                          double elapsed)
{
    const double span = elapsed - w->time - (r->saving - w->saving);
    if (w->marked && r->done > w->done && span > 0.0) {
        return (double)(r->done - w->done) / span;
    }
    return (double)r->done / fmax(elapsed - r->saving, 1e-9);
}

/* The steps the rest of the budget allows at `rate` steps/s. */
static uint64_t steps_for(double rate, double seconds_left)
{
    const double n = floor(rate * fmax(seconds_left, 0.0));
    return n < 1e12 ? (uint64_t)n : (uint64_t)1e12;
}

/*
 * The training time left once saves are taken out, from the last save's
 * duration (none before the first): the share that timed saves will take
 * (a save of the fast preset takes seconds, every 2 minutes, which a
 * length fitted to the whole time left would overrun), and the save that
 * ends the run.
 */
static double training_left(const nerf_trainer *t, const nerf__run *r,
                            double left)
{
    if (!r->saved) {
        return left;
    }
    const double every = t->opts.checkpoint_seconds;
    if (every > 0.0) {
        left *= every / (every + r->save_seconds);
    }
    return left - r->save_seconds;
}

/*
 * Fix the run's length at the step rate over the window: the steps the
 * rest of the budget allows, less the share timed saves will take.  The
 * decay ends there, and the progress reports count to it.
 */
static void fit_length(nerf_trainer *t, nerf__run *r, const rate_window *w,
                       double budget, double elapsed)
{
    nerf_model *m = t->model;
    nerf__schedule *sc = &m->schedule;
    sc->rate = window_rate(w, r, elapsed);
    const double left = training_left(t, r, budget - elapsed);
    sc->total = m->step + steps_for(sc->rate, left);
    m->adam.decay_steps = fmax((double)sc->total, 1.0);
    r->total = r->done + (sc->total - m->step);
}

/* Measure until a share of the budget has passed, then fix the length. */
static int measure_and_fit(nerf_trainer *t, nerf__run *r, double budget,
                           nerf_train_stats *stats_out)
{
    nerf_model *m = t->model;
    nerf__schedule *sc = &m->schedule;
    memset(sc, 0, sizeof *sc);
    sc->state = NERF_SCHEDULE_MEASURING;
    sc->budget = budget;
    m->adam.decay_start = NO_DECAY;
    m->adam.decay_steps = NO_DECAY;
    rate_window w = {0};
    double elapsed = 0.0;
    int rc = NERF_OK;
    while (rc == NERF_OK && (r->done == 0 || elapsed < MEASURE_SHARE * budget)) {
        /* The steps this call is likely to take, for progress bars. */
        r->total = r->done == 0 ? 0
                                : r->done + steps_for((double)r->done / elapsed,
                                                      budget - elapsed);
        rc = nerf__run_step(t, r, stats_out);
        elapsed = nerf__run_elapsed(r);
        window_mark(&w, r, elapsed, WINDOW_START * budget);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    sc->state = NERF_SCHEDULE_FITTED;
    sc->fit_step = m->step;
    m->adam.decay_start = (double)sc->fit_step;
    fit_length(t, r, &w, budget, elapsed);
    nerf__log(&t->env, NERF_LOG_INFO, "trainer: %.1f steps/s after %.0f s: "
              "the learning rate decays from step %llu to %llu, fitted to "
              "a budget of %g s", sc->rate, elapsed,
              (unsigned long long)sc->fit_step, (unsigned long long)sc->total,
              budget);
    return NERF_OK;
}

/*
 * The length again, from the step rate over the window: the decay keeps
 * its start and ends at the new length, so the learning rate moves by a
 * few percent at this step.  Never before the current step.
 */
static void refit(nerf_trainer *t, nerf__run *r, const rate_window *w,
                  double budget, double elapsed)
{
    const nerf__schedule *sc = &t->model->schedule;
    const uint64_t before = sc->total;
    fit_length(t, r, w, budget, elapsed);
    nerf__log(&t->env, NERF_LOG_INFO, "trainer: %.1f steps/s after %.0f s: "
              "the length fitted again, %llu steps instead of %llu",
              sc->rate, elapsed, (unsigned long long)sc->total,
              (unsigned long long)before);
}

NERF_API int nerf_trainer_run_for(nerf_trainer *t, double seconds,
                                  nerf_train_stats *stats_out)
{
    if (t == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_run_for: trainer is "
                           "NULL");
    }
    if (!(seconds > 0.0 && seconds <= 1e12)) { /* also rejects NaN */
        return nerf__error(NERF_EINVAL, "nerf_trainer_run_for: a budget of "
                           "%g s is not a positive finite time", seconds);
    }
    if (t->workers > 1) {
        /* Each worker would fit the length to its own clock, and stop at
         * its own step: the workers would part, or wait on each other. */
        return nerf__error(NERF_EINVAL, "nerf_trainer_run_for: a time budget "
                           "is not supported for a trainer that is one of "
                           "%u workers; give a step count (nerf_trainer_run())",
                           (unsigned)t->workers);
    }
    nerf_model *m = t->model;
    const nerf__schedule *sc = &m->schedule;
    nerf__run r;
    nerf__run_begin(t, &r, sc->state == NERF_SCHEDULE_FITTED &&
                               sc->total > m->step
                           ? sc->total - m->step
                           : 0);
    int rc = NERF_OK;
    /* Only the call that fitted knows how much of the budget is left: a
     * resumed FITTED model trains on to its recorded length. */
    size_t refits = N_REFITS;
    double last_fit = 0.0;
    uint64_t fit_done = 0; /* r.done at the last fit */
    rate_window w = {0}, since_fit = {0};
    if (sc->state != NERF_SCHEDULE_FITTED) {
        rc = measure_and_fit(t, &r, seconds, stats_out);
        refits = 0;
        last_fit = nerf__run_elapsed(&r);
        fit_done = r.done;
    }
    while (rc == NERF_OK) {
        const double elapsed = nerf__run_elapsed(&r);
        window_mark(&since_fit, &r, elapsed, last_fit);
        if (refits < N_REFITS) {
            const double share = refit_shares[refits];
            window_mark(&w, &r, elapsed,
                        fmax(REFIT_WINDOW * share * seconds, last_fit));
            /* Steps that got faster than the rate fitted to reach the
             * length before the next fit: that one comes now, to the
             * rate since the last (if a step was taken since). */
            const bool early = m->step >= sc->total && r.done > fit_done;
            if (early || elapsed >= share * seconds) {
                refit(t, &r, early && !w.marked ? &since_fit : &w, seconds,
                      elapsed);
                refits++;
                last_fit = elapsed;
                fit_done = r.done;
                w.marked = since_fit.marked = false;
                continue; /* the new length may end the run here */
            }
        }
        if (m->step >= sc->total) {
            break;
        }
        if (elapsed > OVERRUN * seconds) {
            rc = nerf__error(NERF_ECANCELLED, "nerf_trainer_run_for: out of "
                             "time at step %llu of the fitted %llu (%.1f s "
                             "of a %g s budget): the steps ran slower than "
                             "measured; training on continues the same run",
                             (unsigned long long)m->step,
                             (unsigned long long)sc->total, elapsed, seconds);
            break;
        }
        rc = nerf__run_step(t, &r, stats_out);
    }
    return nerf__run_end(t, &r, rc);
}
