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
} nerf__adam;

/* lr(step) = lr (lr_final / lr)^(step / decay_steps), continuing past it
 * as the reference does. */
double nerf__adam_rate(const nerf__adam *hp, uint64_t step);

/*
 * One Adam update of n parameters at step t (1-based, the step being
 * taken), with learning rate lr:
 *   m = b1 m + (1 - b1) g,  v = b2 v + (1 - b2) g^2,
 *   p -= lr * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps).
 * This is Algorithm 1 of Kingma and Ba, also PyTorch's form; eps is added
 * to the bias-corrected root.
 */
void nerf__adam_update(const nerf__adam *hp, uint64_t t, double lr, size_t n,
                       float *params, const float *grads, float *m, float *v);

#endif
