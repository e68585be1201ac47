/* The weights averaged over the last steps of a schedule (average.h). */
#include "average.h"

#include <string.h>

#include "byteorder.h"
#include "error.h"
#include "model.h"

/* Whether step s (1-based, the step just taken) is one of the last
 * average_steps steps up to the schedule's end. */
static bool in_window(const nerf_model *m, uint64_t s)
{
    const double k = m->adam.average_steps;
    const double end = m->adam.decay_steps;
    return k > 0.0 && (double)s <= end && (double)s + k > end;
}

int nerf__average_reserve(nerf_model *m)
{
    if (m->average != NULL || !in_window(m, m->step + 1)) {
        return NERF_OK;
    }
    m->average = nerf__alloc(&m->env, m->n_params * sizeof(float));
    return m->average ? NERF_OK
                      : nerf__error(NERF_ENOMEM, "out of memory for the "
                                    "average of the weights");
}

void nerf__average_free(nerf_model *m)
{
    nerf__free(&m->env, m->average);
    m->average = NULL;
    m->averaging = false;
}

void nerf__average_step(nerf_model *m)
{
    const uint64_t s = m->step;
    if (!in_window(m, s) || m->average == NULL) {
        /* Also when a refit moved the end: the average starts afresh at
         * the new window's first step. */
        m->averaging = false;
        return;
    }
    float *a = m->average;
    const float *p = m->params;
    const size_t n = m->n_params;
    if (!m->averaging) {
        memcpy(a, p, n * sizeof *a);
        m->averaging = true;
    } else {
        const float d = NERF__AVERAGE_DECAY, e = 1.0f - NERF__AVERAGE_DECAY;
        for (size_t i = 0; i < n; i++) {
            a[i] = d * a[i] + e * p[i];
        }
    }
    if ((double)s + 1.0 > m->adam.decay_steps) {
        /* The schedule's last step.  The moments stay as the optimiser
         * left them: a run that goes on past the end (a refit, or a
         * resume with more steps) goes on from the average. */
        memcpy(m->params, a, n * sizeof *a);
        nerf__average_free(m);
    }
}

bool nerf__average_saved(const nerf_model *m)
{
    return m->adam.average_steps > 0.0 || m->averaging;
}

uint64_t nerf__average_size(const nerf_model *m)
{
    return NERF__AVERAGE_HEAD +
           (m->averaging ? 4 * (uint64_t)m->n_params : 0);
}

void nerf__average_store_head(unsigned char *p, const nerf_model *m)
{
    nerf__store_lef64(p, m->adam.average_steps);
    nerf__store_le32(p + 8, m->averaging ? 1u : 0u);
    nerf__store_le32(p + 12, 0);
}

const char *nerf__average_parse(const unsigned char *p, uint64_t len,
                                nerf_model *m, bool *oom)
{
    *oom = false;
    if (len < NERF__AVERAGE_HEAD) {
        return "the average section is too short";
    }
    const double k = nerf__load_lef64(p);
    const uint32_t running = nerf__load_le32(p + 8);
    /* The bounds nerf_model_set_param() gives the parameter. */
    if (!(k >= 0.0 && k <= 1e15) || running > 1 ||
        nerf__load_le32(p + 12) != 0) {
        return "the average section holds a value out of range";
    }
    const uint64_t want = NERF__AVERAGE_HEAD +
                          (running ? 4 * (uint64_t)m->n_params : 0);
    if (len != want) {
        return "the average section has the wrong size";
    }
    m->adam.average_steps = k;
    if (running) {
        m->average = nerf__alloc(&m->env, m->n_params * sizeof(float));
        if (m->average == NULL) {
            *oom = true;
            return "out of memory for the average of the weights";
        }
        m->averaging = true;
    }
    return NULL;
}
