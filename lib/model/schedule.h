/*
 * How a model's learning-rate schedule came about (nerf_schedule): a time
 * budget fits the run's length while it trains, and a checkpoint must
 * carry that fit so that a resumed run ends where the unbroken one would.
 * Checkpoints keep it in a required section (docs/formats.md, "schedule"),
 * written only for models trained under a budget: an older libnerf, which
 * would hold no decay start, must refuse them rather than resume them on
 * another schedule.
 */
#ifndef NERF_MODEL_SCHEDULE_H
#define NERF_MODEL_SCHEDULE_H

#include <stdbool.h>
#include <stdint.h>

#include "nerf.h"

typedef struct nerf__schedule {
    uint32_t state; /* nerf_schedule_state */
    double budget, rate;
    uint64_t fit_step, total;
} nerf__schedule;

/* Bytes of the section's body: u32 state, u32 reserved 0, f64 decay start,
 * f64 budget seconds, f64 steps per second, u64 fit step, u64 total. */
#define NERF__SCHEDULE_SIZE 48u

/* Whether a model with this record and decay start needs the section. */
bool nerf__schedule_saved(const nerf__schedule *s, double decay_start);

void nerf__schedule_store(unsigned char *p, const nerf__schedule *s,
                          double decay_start);

/* From a section body of len bytes; NULL, or why the body is corrupt. */
const char *nerf__schedule_parse(const unsigned char *p, uint64_t len,
                                 nerf__schedule *s, double *decay_start);

#endif
