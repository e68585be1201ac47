/*
 * The weights averaged over the last steps of a schedule
 * (NERF_PARAM_AVERAGE_STEPS).  Mueller et al. evaluate an exponential
 * moving average of the weights (decay 0.95) rather than the weights
 * themselves; libnerf keeps that average over the last steps before the
 * schedule's end (NERF_PARAM_DECAY_STEPS) and makes it the model's
 * weights at the step that reaches the end, so that a saved model renders
 * with it and nothing else needs a second copy.  A checkpoint saved while
 * the average runs carries it (docs/formats.md, "average"), so that a
 * resumed run ends with the same weights as the unbroken one.
 */
#ifndef NERF_MODEL_AVERAGE_H
#define NERF_MODEL_AVERAGE_H

#include <stdbool.h>
#include <stdint.h>

struct nerf_model;

/* The fast preset's NERF_PARAM_AVERAGE_STEPS: 0.95^100 leaves the
 * weights at the window's start under 1% of the average. */
#define NERF__AVERAGE_STEPS_FAST 100.0

/* Each step keeps this much of the average before it. */
#define NERF__AVERAGE_DECAY 0.95f

/* Bytes of the section's head: f64 average steps, u32 running (0 or 1),
 * u32 reserved 0; the average's floats follow while it runs. */
#define NERF__AVERAGE_HEAD 16u

/*
 * Before the optimiser step that takes the model to step + 1: the buffer
 * that step's average needs.  NERF_OK, or NERF_ENOMEM with nothing
 * changed.
 */
int nerf__average_reserve(struct nerf_model *m);

/* After the optimiser step: fold the new weights into the average, and at
 * the schedule's end make the average the weights. */
void nerf__average_step(struct nerf_model *m);

/* Whether a model needs the section, and its body's size. */
bool nerf__average_saved(const struct nerf_model *m);
uint64_t nerf__average_size(const struct nerf_model *m);

/* The section's head; the checkpoint writes the floats after it. */
void nerf__average_store_head(unsigned char *p, const struct nerf_model *m);

/* From a section body of len bytes into m (whose n_params is set): the
 * parameter, and when running, the buffer the caller fills with the
 * floats after the head.  NULL, or why the body is corrupt.  *oom is set
 * when the average could not be allocated. */
const char *nerf__average_parse(const unsigned char *p, uint64_t len,
                                struct nerf_model *m, bool *oom);

/* Release the average's buffer. */
void nerf__average_free(struct nerf_model *m);

#endif
