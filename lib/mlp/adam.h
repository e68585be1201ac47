/* Adam with bias correction, and the paper's exponential learning rate. */
#ifndef NERF_MLP_ADAM_H
#define NERF_MLP_ADAM_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"

typedef struct nerf__adam {
    double lr;          /* initial learning rate */
    double lr_final;    /* rate reached after decay_steps */
    double decay_steps;
    double beta1, beta2, eps;
    double weight_decay; /* L2 on the ranges updated with NERF__ADAM_DECAY */
    /* The rate holds at lr until this step, then decays to lr_final at
     * decay_steps: a time budget measures its step rate at lr before it
     * knows over how many steps to decay (0: decay from the start). */
    double decay_start;
    /* The weights become their average over this many last steps before
     * decay_steps (model/average.h); 0: off. */
    double average_steps;
} nerf__adam;

/* lr(step) = lr (lr_final / lr)^((step - decay_start) / (decay_steps -
 * decay_start)) from decay_start on (lr before), continuing past
 * decay_steps as the reference does.  With decay_start 0, the paper's
 * lr (lr_final / lr)^(step / decay_steps). */
double nerf__adam_rate(const nerf__adam *hp, uint64_t step);

/* How nerf__adam_update() treats its range. */
enum {
    /* Add weight_decay * p to each gradient (an L2 penalty): the layers
     * of a hash-grid model, as Mueller et al. regularise them. */
    NERF__ADAM_DECAY = 1u,
    /*
     * Leave parameters whose gradient is exactly zero as they are, moments
     * included: a hash table, most of whose entries no sample of a step
     * touches.  Mueller et al.'s optimiser does the same; dense Adam
     * would keep moving untouched entries on their stale momentum, and
     * would cost a full pass over tens of millions of entries per step.
     */
    NERF__ADAM_SPARSE = 2u
};

/*
 * One Adam update of n parameters at step t (1-based, the step being
 * taken), with learning rate lr:
 *   m = b1 m + (1 - b1) g,  v = b2 v + (1 - b2) g^2,
 *   p -= lr * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps).
 * This is Algorithm 1 of Kingma and Ba, also PyTorch's form; eps is added
 * to the bias-corrected root.  flags: NERF__ADAM_*.  The gradients are
 * zeroed as they are consumed, which saves the next step a pass over them.
 */
void nerf__adam_update(const nerf__adam *hp, uint64_t t, double lr, size_t n,
                       float *params, float *grads, float *m, float *v,
                       unsigned flags);

/*
 * Counted updates: the bias corrections of an entry by the number of
 * updates it has had (counts[i]) rather than by the step, as Mueller et
 * al.'s optimiser corrects a hash table's entries.  An entry that a step
 * touches for the k-th time is corrected as if it were step k, so a rarely
 * touched entry takes steps of about lr, where corrections by a large step
 * t would let its few gradients move it by up to twice that.  Counts stop
 * at NERF__ADAM_COUNT_MAX, where any beta below 0.9997 has made both
 * corrections exactly 1 in float.
 */
#define NERF__ADAM_COUNT_MAX 65535u

/* The corrections by count, for one pair of betas: entry k holds
 * 1 / (1 - beta1^k) and 1 / sqrt(1 - beta2^k); a count past the last entry
 * reads the last, where both have reached 1 (or the count its maximum). */
typedef struct nerf__adam_table {
    double beta1, beta2;
    uint32_t len;       /* entries; 0 before the first fit */
    float *inv_c1;
    float *inv_sqrt_c2;
} nerf__adam_table;

/* Make t hold the corrections for hp's betas, unless it already does.
 * NERF_OK, or NERF_ENOMEM with t unchanged. */
int nerf__adam_table_fit(const nerf__env *env, nerf__adam_table *t,
                         const nerf__adam *hp);
void nerf__adam_table_free(const nerf__env *env, nerf__adam_table *t);

/*
 * One sparse update (NERF__ADAM_SPARSE, without weight decay) of n
 * parameters with learning rate lr, each touched one corrected by its own
 * count, which it increments.  t must be fitted to hp's betas.
 */
void nerf__adam_update_counted(const nerf__adam *hp,
                               const nerf__adam_table *t, double lr, size_t n,
                               float *params, float *grads, float *m,
                               float *v, uint16_t *counts);

#endif
