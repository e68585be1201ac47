/* Training to a time budget: the measured fit, the held rate, the recorded
 * length, the fits again at a half, three quarters and nine tenths of the
 * budget or when the length is reached before, and resuming bit for bit
 * after the fit. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "model.h"
#include "train_fixture.h"

static fixture fx;

static nerf_trainer *make_trainer(nerf_model *m, nerf_sampler *s)
{
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 32;
    nerf_trainer *t = NULL;
    if (nerf_trainer_create(&t, m, fx.train, s, &o) != NERF_OK) {
        printf("  nerf_trainer_create: %s\n", nerf_last_error());
    }
    return t;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static struct timespec timespec_of(double seconds)
{
    struct timespec ts;
    ts.tv_sec = (time_t)seconds;
    ts.tv_nsec = (long)((seconds - (double)ts.tv_sec) * 1e9);
    return ts;
}

static nerf_schedule schedule_of(const nerf_model *m)
{
    nerf_schedule sc;
    memset(&sc, 0, sizeof sc);
    sc.struct_size = sizeof sc;
    CHECK_OK(nerf_model_schedule(m, &sc));
    return sc;
}

static double param(const nerf_model *m, int key)
{
    double v = -1.0;
    CHECK_OK(nerf_model_get_param(m, key, &v));
    return v;
}

/* What a progress callback saw of the schedule, and where it stops. */
typedef struct watch {
    nerf_model *m;
    int measuring_steps, measuring_at_lr0;
    int fitted_seen;
    uint64_t stop_after_fit; /* cancel this many steps after the fit */
    int stop_at_first;       /* cancel at the first report */
} watch;

static int on_progress(const nerf_progress *p, void *user)
{
    watch *w = user;
    nerf_schedule sc = schedule_of(w->m);
    if (sc.state == NERF_SCHEDULE_MEASURING) {
        w->measuring_steps++;
        w->measuring_at_lr0 += nerf_model_learning_rate(w->m) ==
                               param(w->m, NERF_PARAM_LEARNING_RATE);
    } else if (sc.state == NERF_SCHEDULE_FITTED) {
        w->fitted_seen = 1;
        CHECK(p->total >= p->done);
        if (w->stop_after_fit &&
            nerf_model_step(w->m) >= sc.fit_step + w->stop_after_fit) {
            return 1;
        }
    }
    return w->stop_at_first;
}

/*
 * run_for(budget) to the fitted length.  On a busy machine the steps after
 * the fit can run slower than those measured: the run then stops a tenth
 * past the budget, saying so, and a second call trains on to the length.
 */
static int run_to_the_end(nerf_trainer *t, nerf_model *m, double budget)
{
    int rc = nerf_trainer_run_for(t, budget, NULL);
    if (rc == NERF_ECANCELLED &&
        strstr(nerf_last_error(), "out of time") != NULL) {
        CHECK(nerf_model_step(m) < schedule_of(m).total_steps);
        printf("  out of time at step %llu: going on\n",
               (unsigned long long)nerf_model_step(m));
        nerf_trainer_set_progress(t, NULL, NULL);
        rc = nerf_trainer_run_for(t, 30.0, NULL);
    }
    return rc;
}

TEST(fits_the_length_and_ends_there)
{
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(2);
    nerf_trainer *t = make_trainer(m, s);
    CHECK(schedule_of(m).state == NERF_SCHEDULE_STEPS);
    watch w = {.m = m};
    nerf_trainer_set_progress(t, on_progress, &w);
    const double budget = 1.5, t0 = now();
    int rc = nerf_trainer_run_for(t, budget, NULL);
    const double took = now() - t0;
    if (rc == NERF_ECANCELLED) {
        CHECK(strstr(nerf_last_error(), "out of time") != NULL);
        nerf_trainer_set_progress(t, NULL, NULL);
        rc = run_to_the_end(t, m, 30.0);
    }
    CHECK_OK(rc);
    nerf_schedule sc = schedule_of(m);
    CHECK(sc.state == NERF_SCHEDULE_FITTED);
    CHECK(sc.budget_seconds == budget);
    CHECK(sc.steps_per_second > 0.0);
    CHECK(sc.fit_step > 0 && sc.fit_step <= sc.total_steps);
    CHECK(nerf_model_step(m) == sc.total_steps);
    CHECK(param(m, NERF_PARAM_DECAY_START) == (double)sc.fit_step);
    CHECK(param(m, NERF_PARAM_DECAY_STEPS) == (double)sc.total_steps);
    /* The rate held through the measuring, and decayed to the final one
     * by the end. */
    CHECK(w.measuring_steps > 0 && w.measuring_at_lr0 == w.measuring_steps);
    /* (A machine so slow that the budget had no step left after the fit
     * trains none at the decayed rates.) */
    if (sc.total_steps > sc.fit_step) {
        CHECK(w.fitted_seen);
        CHECK(fabs(nerf_model_learning_rate(m) /
                       param(m, NERF_PARAM_LEARNING_RATE_FINAL) - 1.0) < 1e-9);
    }
    /* Never past the budget and its tenth by more than a step and the
     * bookkeeping around it. */
    CHECK(took < 1.1 * budget + 1.0);
    printf("  %llu steps, fitted at %llu (%.0f steps/s), in %.2f s of %.2f\n",
           (unsigned long long)sc.total_steps, (unsigned long long)sc.fit_step,
           sc.steps_per_second, took, budget);
    /* A fitted model is done: another call takes no step. */
    CHECK_OK(nerf_trainer_run_for(t, budget, NULL));
    CHECK(nerf_model_step(m) == sc.total_steps);
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

TEST(resume_after_the_fit_is_bit_identical)
{
    char path[600];
    snprintf(path, sizeof path, "%s/budget.nerf", fx.dir);
    nerf_sampler *s = tiny_sampler(3);
    nerf_model *whole = tiny_model(4);
    nerf_trainer *t = make_trainer(whole, s);
    watch w = {.m = whole, .stop_after_fit = 1};
    nerf_trainer_set_progress(t, on_progress, &w);
    /* Long enough that the step after the fit does not reach half of it,
     * where the length would be fitted again (on a sanitized build on a
     * busy machine, steps have taken half a second). */
    CHECK(nerf_trainer_run_for(t, 4.0, NULL) == NERF_ECANCELLED);
    nerf_schedule cut = schedule_of(whole);
    CHECK(cut.state == NERF_SCHEDULE_FITTED);
    CHECK(nerf_model_step(whole) < cut.total_steps);
    CHECK_OK(nerf_model_save(whole, path));
    /* The unbroken run: on to the recorded length, whatever the budget. */
    nerf_trainer_set_progress(t, NULL, NULL);
    CHECK_OK(nerf_trainer_run_for(t, 30.0, NULL));
    CHECK(nerf_model_step(whole) == cut.total_steps);
    nerf_trainer_destroy(t);

    nerf_model *resumed = NULL;
    CHECK_OK(nerf_model_load(&resumed, path, NULL));
    if (resumed) {
        nerf_schedule sc = schedule_of(resumed);
        CHECK(sc.state == NERF_SCHEDULE_FITTED && sc.total_steps == cut.total_steps &&
              sc.fit_step == cut.fit_step &&
              sc.steps_per_second == cut.steps_per_second &&
              sc.budget_seconds == cut.budget_seconds);
        CHECK(param(resumed, NERF_PARAM_DECAY_START) == (double)cut.fit_step);
        t = make_trainer(resumed, s);
        CHECK_OK(nerf_trainer_run_for(t, 30.0, NULL));
        nerf_trainer_destroy(t);
        CHECK(nerf_model_step(resumed) == cut.total_steps);
        CHECK(memcmp(whole->params, resumed->params,
                     whole->n_params * sizeof(float)) == 0);
        CHECK(memcmp(whole->adam_v, resumed->adam_v,
                     whole->n_params * sizeof(float)) == 0);
    }
    nerf_model_destroy(resumed);
    nerf_model_destroy(whole);
    nerf_sampler_destroy(s);
}

/* Steps that turn slower after the fit, as on a machine that got busy. */
typedef struct slowing {
    nerf_model *m;
    uint64_t first_total; /* the first fit's length */
    struct timespec pause;
} slowing;

static int slow_after_the_fit(const nerf_progress *p, void *user)
{
    (void)p;
    slowing *w = user;
    nerf_schedule sc = schedule_of(w->m);
    if (sc.state != NERF_SCHEDULE_FITTED) {
        return 0;
    }
    if (w->first_total == 0) {
        w->first_total = sc.total_steps;
        /* Four steps' time asleep after each: five times slower. */
        w->pause = timespec_of(4.0 / sc.steps_per_second);
    }
    nanosleep(&w->pause, NULL);
    return 0;
}

/*
 * The second fit, at half the budget: with steps five times slower than
 * the first fit measured, the length shrinks to about a fifth of what was
 * left (a run fitted once would stop a tenth past its budget, short of its
 * length), and the run ends there.  On a machine so busy that even the
 * slowed steps vary by a fifth, it may still run out of time: that is
 * said, and a second call trains on.
 */
TEST(fits_again_at_half_the_budget)
{
    nerf_sampler *s = tiny_sampler(9);
    nerf_model *m = tiny_model(10);
    nerf_trainer *t = make_trainer(m, s);
    slowing w = {.m = m};
    nerf_trainer_set_progress(t, slow_after_the_fit, &w);
    const double budget = 2.0, t0 = now();
    int rc = nerf_trainer_run_for(t, budget, NULL);
    const double took = now() - t0;
    nerf_schedule sc = schedule_of(m);
    CHECK(sc.state == NERF_SCHEDULE_FITTED);
    CHECK(w.first_total > sc.fit_step);
    /* Fitted again to the slower rate: well under what was left. */
    CHECK((double)(sc.total_steps - sc.fit_step) <
          0.6 * (double)(w.first_total - sc.fit_step));
    CHECK(param(m, NERF_PARAM_DECAY_START) == (double)sc.fit_step);
    CHECK(param(m, NERF_PARAM_DECAY_STEPS) == (double)sc.total_steps);
    printf("  fitted at step %llu to %llu steps, then to %llu; %.2f s of "
           "%.2f\n", (unsigned long long)sc.fit_step,
           (unsigned long long)w.first_total,
           (unsigned long long)sc.total_steps, took, budget);
    if (rc == NERF_OK) {
        CHECK(took < 1.1 * budget + 0.5);
    } else {
        CHECK(rc == NERF_ECANCELLED &&
              strstr(nerf_last_error(), "out of time") != NULL);
        printf("  %s\n", nerf_last_error());
        nerf_trainer_set_progress(t, NULL, NULL);
        rc = run_to_the_end(t, m, budget);
    }
    CHECK_OK(rc);
    CHECK(nerf_model_step(m) == sc.total_steps);
    if (sc.total_steps > sc.fit_step) {
        CHECK(fabs(nerf_model_learning_rate(m) /
                       param(m, NERF_PARAM_LEARNING_RATE_FINAL) - 1.0) < 1e-9);
    }
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/* Steps that turn slower late in the run, after the fit at half the
 * budget; and the fits the log reports. */
typedef struct slowing_late {
    double start, from; /* slow from this many seconds after start */
    struct timespec pause;
} slowing_late;

static int slow_late(const nerf_progress *p, void *user)
{
    (void)p;
    slowing_late *w = user;
    if (now() - w->start >= w->from) {
        nanosleep(&w->pause, NULL);
    }
    return 0;
}

static void count_refits(int level, const char *msg, void *user)
{
    (void)level;
    int *refits = user;
    *refits += strstr(msg, "the length fitted again") != NULL;
}

/* The time of a plain step, from a few steps of another model. */
static double step_seconds(nerf_sampler *s, uint64_t seed)
{
    nerf_model *probe = tiny_model(seed);
    nerf_trainer *pt = make_trainer(probe, s);
    const double t0 = now();
    CHECK_OK(nerf_trainer_run(pt, 5, NULL));
    const double step = (now() - t0) / 5.0;
    nerf_trainer_destroy(pt);
    nerf_model_destroy(probe);
    return step;
}

/* What a run to a budget did, its "fitted again" log lines counted. */
typedef struct budget_run {
    int rc, refits;
    double took;
    nerf_schedule sc;
} budget_run;

static budget_run run_counting_refits(nerf_trainer *t, nerf_model *m,
                                      double budget)
{
    budget_run b = {0};
    nerf_log_set_default(count_refits, &b.refits, NERF_LOG_INFO);
    const double t0 = now();
    b.rc = nerf_trainer_run_for(t, budget, NULL);
    b.took = now() - t0;
    nerf_log_set_default(NULL, NULL, NERF_LOG_INFO);
    b.sc = schedule_of(m);
    printf("  %d fits again, %llu steps, %.2f s of %.2f (%s)\n", b.refits,
           (unsigned long long)b.sc.total_steps, b.took, budget,
           b.rc == NERF_OK ? "ended" : nerf_last_error());
    CHECK(b.sc.state == NERF_SCHEDULE_FITTED);
    return b;
}

/*
 * Ended at its length within a tenth past the budget and a few steps: not
 * a tighter time, a busy machine's steps vary by more than the last fit
 * can foresee.  Or, on a machine so busy that even the slowed steps vary
 * by a fifth, out of time, and said so.
 */
static void check_ended(const budget_run *b, const nerf_model *m,
                        double budget, double step)
{
    if (b->rc == NERF_OK) {
        CHECK(nerf_model_step(m) == b->sc.total_steps);
        CHECK(b->took < 1.1 * budget + 5.0 * step);
    } else {
        CHECK(b->rc == NERF_ECANCELLED &&
              strstr(nerf_last_error(), "out of time") != NULL);
    }
}

/*
 * Steps five times slower from 0.6 of the budget on, which the fit at half
 * the budget cannot see: fitted no later, the run would go on to a tenth
 * past its budget.  The fits at three quarters and nine tenths shorten it
 * to the time left.  (With a step that outlasts the time left at 0.9, the
 * run ends at the fit at 0.75: two fits again, not three.)
 */
TEST(fits_again_late_in_the_budget)
{
    nerf_sampler *s = tiny_sampler(11);
    nerf_model *m = tiny_model(12);
    nerf_trainer *t = make_trainer(m, s);
    const double step = step_seconds(s, 12);
    /* Enough steps in the last tenth for the fit at 0.9 to have room. */
    const double budget = fmax(2.0, 150.0 * step);
    slowing_late w = {.from = 0.6 * budget, .pause = timespec_of(4.0 * step)};
    nerf_trainer_set_progress(t, slow_late, &w);
    w.start = now();
    const budget_run b = run_counting_refits(t, m, budget);
    CHECK(b.refits >= 2 && b.refits <= 3);
    check_ended(&b, m, budget, step);
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/* Steps slowed while the rate is measured, as a marching sampler's are
 * before its grid knows where the scene is. */
typedef struct slow_first {
    nerf_model *m;
    struct timespec pause;
} slow_first;

static int slow_while_measuring(const nerf_progress *p, void *user)
{
    (void)p;
    slow_first *w = user;
    if (schedule_of(w->m).state == NERF_SCHEDULE_MEASURING) {
        nanosleep(&w->pause, NULL);
    }
    return 0;
}

/*
 * Steps five times faster after the fit than measured: the fitted length
 * is reached at about 0.4 of the budget, before the fit at half.  Fitted
 * again then, to the rate since the fit, the run goes on to its budget;
 * without, it ended there.
 */
TEST(fits_again_when_the_steps_get_faster)
{
    nerf_sampler *s = tiny_sampler(13);
    nerf_model *m = tiny_model(14);
    nerf_trainer *t = make_trainer(m, s);
    const double step = step_seconds(s, 14);
    const double budget = fmax(2.0, 150.0 * step);
    slow_first w = {.m = m, .pause = timespec_of(4.0 * step)};
    nerf_trainer_set_progress(t, slow_while_measuring, &w);
    const budget_run b = run_counting_refits(t, m, budget);
    CHECK(b.refits >= 1);
    CHECK(b.took > 0.8 * budget);
    check_ended(&b, m, budget, step);
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/* Saved before its fit, a model measures again when resumed. */
TEST(measuring_resumes_by_measuring)
{
    char path[600];
    snprintf(path, sizeof path, "%s/measuring.nerf", fx.dir);
    nerf_sampler *s = tiny_sampler(5);
    nerf_model *m = tiny_model(6);
    nerf_trainer *t = make_trainer(m, s);
    watch w = {.m = m, .stop_at_first = 1};
    nerf_trainer_set_progress(t, on_progress, &w);
    CHECK(nerf_trainer_run_for(t, 5.0, NULL) == NERF_ECANCELLED);
    CHECK(schedule_of(m).state == NERF_SCHEDULE_MEASURING);
    CHECK_OK(nerf_model_save(m, path));
    nerf_trainer_destroy(t);
    nerf_model *resumed = NULL;
    CHECK_OK(nerf_model_load(&resumed, path, NULL));
    if (resumed) {
        nerf_schedule sc = schedule_of(resumed);
        CHECK(sc.state == NERF_SCHEDULE_MEASURING && sc.budget_seconds == 5.0);
        CHECK(nerf_model_learning_rate(resumed) ==
              param(resumed, NERF_PARAM_LEARNING_RATE));
        t = make_trainer(resumed, s);
        CHECK_OK(run_to_the_end(t, resumed, 0.3));
        nerf_trainer_destroy(t);
        sc = schedule_of(resumed);
        CHECK(sc.state == NERF_SCHEDULE_FITTED && sc.budget_seconds == 0.3);
        CHECK(nerf_model_step(resumed) == sc.total_steps);
    }
    nerf_model_destroy(resumed);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

TEST(plain_schedule_and_bad_arguments)
{
    nerf_sampler *s = tiny_sampler(7);
    nerf_model *m = tiny_model(8);
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, 1234.0));
    nerf_schedule sc = schedule_of(m);
    CHECK(sc.state == NERF_SCHEDULE_STEPS && sc.total_steps == 1234 &&
          sc.fit_step == 0 && sc.budget_seconds == 0.0);
    /* An older caller's smaller struct gets its fields only. */
    nerf_schedule small;
    memset(&small, 0xff, sizeof small);
    small.struct_size = 8;
    CHECK_OK(nerf_model_schedule(m, &small));
    CHECK(small.state == NERF_SCHEDULE_STEPS);
    CHECK(small.total_steps == UINT64_MAX);
    small.struct_size = 4;
    CHECK(nerf_model_schedule(m, &small) == NERF_EINVAL);
    CHECK(nerf_model_schedule(NULL, &sc) == NERF_EINVAL);
    nerf_trainer *t = make_trainer(m, s);
    const double bad[] = {0.0, -1.0, NAN, INFINITY};
    for (int i = 0; i < 4; i++) {
        CHECK(nerf_trainer_run_for(t, bad[i], NULL) == NERF_EINVAL);
    }
    CHECK(strstr(nerf_last_error(), "not a positive finite time") != NULL);
    CHECK(nerf_trainer_run_for(NULL, 1.0, NULL) == NERF_EINVAL);
    CHECK(nerf_model_step(m) == 0);
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

/*
 * Time spent saving is not training time: the fit leaves it out of the
 * measured rate, and leaves the share of the time left that timed saves
 * will take out of the length.  Saving after every step, the saves take
 * all the time there is, so the length is the fit's own step.
 */
TEST(saves_are_not_training_time)
{
    char path[600];
    snprintf(path, sizeof path, "%s/budget.nerf", fx.dir);
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(2);
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 32;
    o.checkpoint_path = path;
    o.checkpoint_seconds = 1e-9;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &o));
    if (t) {
        CHECK_OK(nerf_trainer_run_for(t, 0.5, NULL));
        nerf_schedule sc = schedule_of(m);
        CHECK(sc.state == NERF_SCHEDULE_FITTED);
        CHECK(sc.fit_step > 0);
        CHECK_EQ_INT(sc.total_steps, sc.fit_step);
        CHECK_EQ_INT(nerf_model_step(m), sc.fit_step);
        CHECK_EQ_INT(fixture_saved_step(path), sc.fit_step);
    }
    remove(path);
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

int main(void)
{
    if (fixture_open(&fx, 16, 4, 0) != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    RUN(fits_the_length_and_ends_there);
    RUN(fits_again_at_half_the_budget);
    RUN(fits_again_late_in_the_budget);
    RUN(fits_again_when_the_steps_get_faster);
    RUN(resume_after_the_fit_is_bit_identical);
    RUN(measuring_resumes_by_measuring);
    RUN(plain_schedule_and_bad_arguments);
    RUN(saves_are_not_training_time);
    fixture_close(&fx);
    HARNESS_EXIT();
}
