/* The schedule record of a model: its checkpoint section and its getter. */
#include "schedule.h"

#include <stddef.h>
#include <string.h>

#include "byteorder.h"
#include "error.h"
#include "model.h"

bool nerf__schedule_saved(const nerf__schedule *s, double decay_start)
{
    return s->state != NERF_SCHEDULE_STEPS || decay_start != 0.0;
}

void nerf__schedule_store(unsigned char *p, const nerf__schedule *s,
                          double decay_start)
{
    nerf__store_le32(p, s->state);
    nerf__store_le32(p + 4, 0);
    nerf__store_lef64(p + 8, decay_start);
    nerf__store_lef64(p + 16, s->budget);
    nerf__store_lef64(p + 24, s->rate);
    nerf__store_le64(p + 32, s->fit_step);
    nerf__store_le64(p + 40, s->total);
}

static bool in_range(double x, double max)
{
    return x >= 0.0 && x <= max; /* also false for NaN */
}

const char *nerf__schedule_parse(const unsigned char *p, uint64_t len,
                                 nerf__schedule *s, double *decay_start)
{
    if (len != NERF__SCHEDULE_SIZE) {
        return "the schedule section has the wrong size";
    }
    s->state = nerf__load_le32(p);
    *decay_start = nerf__load_lef64(p + 8);
    s->budget = nerf__load_lef64(p + 16);
    s->rate = nerf__load_lef64(p + 24);
    s->fit_step = nerf__load_le64(p + 32);
    s->total = nerf__load_le64(p + 40);
    if (s->state > NERF_SCHEDULE_FITTED || nerf__load_le32(p + 4) != 0) {
        return "the schedule section holds an unknown state or a non-zero "
               "reserved field";
    }
    /* The bounds nerf_model_set_param() gives the step parameters. */
    if (!in_range(*decay_start, 1e15) || !in_range(s->budget, 1e12) ||
        !in_range(s->rate, 1e12) || s->fit_step > s->total ||
        s->total > (uint64_t)1e15) {
        return "the schedule section holds a value out of range";
    }
    return NULL;
}

NERF_API int nerf_model_schedule(const nerf_model *model, nerf_schedule *out)
{
    if (model == NULL || out == NULL ||
        out->struct_size < offsetof(nerf_schedule, budget_seconds) ||
        out->struct_size > 65536) {
        return nerf__error(NERF_EINVAL, "nerf_model_schedule: %s",
                           model && out ? "struct_size is invalid"
                                        : "NULL argument");
    }
    const nerf__schedule *s = &model->schedule;
    nerf_schedule full;
    memset(&full, 0, sizeof full);
    full.struct_size = out->struct_size;
    full.state = s->state;
    full.budget_seconds = s->budget;
    full.steps_per_second = s->rate;
    full.fit_step = s->fit_step;
    full.total_steps = s->state == NERF_SCHEDULE_STEPS
                           ? (uint64_t)model->adam.decay_steps
                           : s->total;
    const size_t n = out->struct_size < sizeof full ? out->struct_size
                                                    : sizeof full;
    memcpy(out, &full, n);
    return NERF_OK;
}
