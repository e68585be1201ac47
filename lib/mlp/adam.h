/* Adam with bias correction, and the paper's exponential learning rate. */
#ifndef NERF_MLP_ADAM_H
#define NERF_MLP_ADAM_H

#include <stddef.h>
#include <stdint.h>

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
 * Corrected updates: the bias corrections of each parameter by the number
 * of updates it has had rather than by the step, as Mueller et al.'s
 * optimiser corrects a hash table's entries.  A parameter that a step
 * touches for the k-th time is corrected as if it were step k: with
 * corrections by a large step, a rarely touched one would move by up to
 * 2.1 times lr in its first tens of updates, its moments still being
 * mostly the zeros they started from.  Each parameter keeps r1 =
 * beta1^k and r2 = beta2^k (1 before its first update; each update
 * multiplies them by the betas, and flushes them to 0 below 2^-26), so
 * that the loop needs no power and no lookup and vectorises.  Otherwise
 * as NERF__ADAM_SPARSE, without weight decay:
 *   p -= lr (m / (1 - r1)) / (sqrt(v / (1 - r2)) + eps).
 */
void nerf__adam_update_corrected(const nerf__adam *hp, double lr, size_t n,
                                 float *params, float *grads, float *m,
                                 float *v, float *r1, float *r2);

/* The same through the kernel of instruction set isa (common/dispatch.h;
 * never wider than the processor's), whatever NERF_ISA says: for the
 * tests that hold the kernels to the same bits. */
void nerf__adam_update_corrected_isa(int isa, const nerf__adam *hp,
                                     double lr, size_t n, float *params,
                                     float *grads, float *m, float *v,
                                     float *r1, float *r2);

#endif
