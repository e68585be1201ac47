/*
 * The weights averaged over the schedule's last steps
 * (NERF_PARAM_AVERAGE_STEPS): the average against one kept by hand, the
 * weights it replaces at the end, and checkpoints saved while it runs.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../harness.h"
#include "average.h"
#include "model.h"
#include "small_grid.h"

static char tmpdir[] = "/tmp/nerf-average-XXXXXX";

static nerf_model *small_grid_model(void)
{
    nerf_model_options o;
    small_grid_options(&o);
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    return m;
}

/* One optimiser step on gradients that differ from step to step and touch
 * a third of the entries. */
static void take_step(nerf_model *m)
{
    nerf__model_zero_grad(m);
    const double k = (double)m->step;
    for (size_t i = 0; i < m->n_params; i += 3) {
        m->grads[i] = (float)cos(0.37 * (double)i + k);
    }
    CHECK_OK(nerf__model_adam_step(m));
}

static double param(const nerf_model *m, int key)
{
    double v = -1.0;
    CHECK_OK(nerf_model_get_param(m, key, &v));
    return v;
}

TEST(defaults_by_preset)
{
    nerf_model *m = small_grid_model();
    if (m) {
        CHECK(param(m, NERF_PARAM_AVERAGE_STEPS) == 100.0);
    }
    nerf_model_destroy(m);
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m) {
        /* The paper's models train as the reference does. */
        CHECK(param(m, NERF_PARAM_AVERAGE_STEPS) == 0.0);
    }
    nerf_model_destroy(m);
    double lo = -1.0, hi = -1.0;
    CHECK_OK(nerf_param_bounds(NERF_PARAM_AVERAGE_STEPS, &lo, &hi));
    CHECK(lo == 0.0 && hi == 1e15);
}

/* Up to the window the weights are those of a model that does not
 * average; at the end they are the average of the window's weights,
 * which a copy kept here computes the same way. */
TEST(the_last_step_takes_the_average)
{
    nerf_model *m = small_grid_model(), *plain = small_grid_model();
    if (m == NULL || plain == NULL) {
        nerf_model_destroy(m);
        nerf_model_destroy(plain);
        return;
    }
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, 10.0));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_AVERAGE_STEPS, 4.0));
    CHECK_OK(nerf_model_set_param(plain, NERF_PARAM_DECAY_STEPS, 10.0));
    CHECK_OK(nerf_model_set_param(plain, NERF_PARAM_AVERAGE_STEPS, 0.0));
    const size_t n = m->n_params, bytes = n * sizeof(float);
    float *want = malloc(bytes);
    for (int s = 1; s <= 10 && want; s++) {
        take_step(m);
        take_step(plain);
        if (s < 10) {
            CHECK(memcmp(m->params, plain->params, bytes) == 0);
            /* Steps 7 to 10 are the window's. */
            CHECK(m->averaging == (s >= 7));
        }
        if (s == 7) {
            memcpy(want, plain->params, bytes);
        } else if (s > 7) {
            const float d = NERF__AVERAGE_DECAY;
            for (size_t i = 0; i < n; i++) {
                want[i] = d * want[i] + (1.0f - d) * plain->params[i];
            }
        }
    }
    size_t off = 0, moved = 0;
    for (size_t i = 0; want && i < n; i++) {
        off += fabsf(m->params[i] - want[i]) > 1e-6f * (1.0f + fabsf(want[i]));
        moved += m->params[i] != plain->params[i];
    }
    CHECK_EQ_INT(off, 0);
    CHECK(moved > n / 4);
    /* The moments are the optimiser's, and the buffer is given back. */
    CHECK(memcmp(m->adam_m, plain->adam_m, bytes) == 0);
    CHECK(!m->averaging && m->average == NULL);
    /* Past the end, training goes on from the average without one. */
    take_step(m);
    CHECK(!m->averaging && m->average == NULL);
    CHECK_EQ_INT(nerf_model_step(m), 11);
    free(want);
    nerf_model_destroy(m);
    nerf_model_destroy(plain);
}

/* Saved before and inside the window and loaded again, a model ends with
 * the same weights as the one that went on. */
TEST(a_resumed_model_ends_the_same)
{
    char path[512];
    snprintf(path, sizeof path, "%s/avg.nerf", tmpdir);
    for (int cut = 3; cut <= 8; cut += 5) {
        nerf_model *m = small_grid_model();
        if (m == NULL) {
            return;
        }
        CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, 10.0));
        CHECK_OK(nerf_model_set_param(m, NERF_PARAM_AVERAGE_STEPS, 4.0));
        for (int s = 1; s <= cut; s++) {
            take_step(m);
        }
        CHECK_OK(nerf_model_save(m, path));
        nerf_model *back = NULL;
        CHECK_OK(nerf_model_load(&back, path, NULL));
        if (back == NULL) {
            nerf_model_destroy(m);
            return;
        }
        CHECK(param(back, NERF_PARAM_AVERAGE_STEPS) == 4.0);
        CHECK(back->averaging == (cut >= 7));
        for (int s = cut + 1; s <= 10; s++) {
            take_step(m);
            take_step(back);
        }
        const size_t bytes = m->n_params * sizeof(float);
        CHECK(memcmp(m->params, back->params, bytes) == 0);
        CHECK(memcmp(m->adam_v, back->adam_v, bytes) == 0);
        nerf_model_destroy(back);
        nerf_model_destroy(m);
    }
}

/* A schedule whose end moves (a budget fitted again) starts the average
 * afresh in the new window; one moved before the window never starts it. */
TEST(a_moved_end_starts_afresh)
{
    nerf_model *m = small_grid_model(), *plain = small_grid_model();
    if (m == NULL || plain == NULL) {
        nerf_model_destroy(m);
        nerf_model_destroy(plain);
        return;
    }
    nerf_model *both[2] = {m, plain};
    for (int k = 0; k < 2; k++) {
        CHECK_OK(nerf_model_set_param(both[k], NERF_PARAM_DECAY_STEPS, 6.0));
        CHECK_OK(nerf_model_set_param(both[k], NERF_PARAM_AVERAGE_STEPS,
                                      k == 0 ? 3.0 : 0.0));
    }
    for (int s = 1; s <= 5; s++) {
        take_step(m);
        take_step(plain);
    }
    CHECK(m->averaging);
    for (int k = 0; k < 2; k++) {
        CHECK_OK(nerf_model_set_param(both[k], NERF_PARAM_DECAY_STEPS, 20.0));
    }
    const size_t bytes = m->n_params * sizeof(float);
    for (int s = 6; s <= 17; s++) {
        take_step(m);
        take_step(plain);
        CHECK(!m->averaging);
    }
    /* The average never reached the weights. */
    CHECK(memcmp(m->params, plain->params, bytes) == 0);
    take_step(m);
    CHECK(m->averaging);
    nerf_model_destroy(m);
    nerf_model_destroy(plain);
}

int main(void)
{
    if (mkdtemp(tmpdir) == NULL) {
        perror("mkdtemp");
        return 1;
    }
    RUN(defaults_by_preset);
    RUN(the_last_step_takes_the_average);
    RUN(a_resumed_model_ends_the_same);
    RUN(a_moved_end_starts_afresh);
    char path[512];
    snprintf(path, sizeof path, "%s/avg.nerf", tmpdir);
    unlink(path);
    rmdir(tmpdir);
    HARNESS_EXIT();
}
