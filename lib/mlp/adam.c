#include "adam.h"

#include <math.h>
#include <stdbool.h>

#include "multiversion.h"
#include "parallel.h"

double nerf__adam_rate(const nerf__adam *hp, uint64_t step)
{
    const double t = (double)step;
    if (t <= hp->decay_start) {
        return hp->lr;
    }
    /* Subtracting a decay_start of 0 leaves both terms exact, so a plain
     * schedule gives the rates it gave before decay_start existed. */
    const double span = fmax(hp->decay_steps - hp->decay_start, 1.0);
    return hp->lr * pow(hp->lr_final / hp->lr, (t - hp->decay_start) / span);
}

typedef struct adam_job {
    float b1, b2, one_b1, one_b2, step, inv_sqrt_c2, eps, decay;
    bool sparse;
    float *params, *m, *v, *grads;
} adam_job;

/* The update of parameter i with gradient g (weight decay included), the
 * job's scalars copied into locals so that the compiler can keep them in
 * registers across the stores. */
#define ADAM_LOCALS(j)                                                        \
    float *restrict params = (j)->params, *restrict m = (j)->m;              \
    float *restrict v = (j)->v, *restrict grads = (j)->grads;                \
    const float b1 = (j)->b1, b2 = (j)->b2, one_b1 = (j)->one_b1;            \
    const float one_b2 = (j)->one_b2, step = (j)->step;                      \
    const float inv_sqrt_c2 = (j)->inv_sqrt_c2, eps = (j)->eps;              \
    const float decay = (j)->decay

#define ADAM_ONE(i, g)                                                        \
    do {                                                                      \
        float g_ = (g) + decay * params[i];                                   \
        float m_ = b1 * m[i] + one_b1 * g_;                                   \
        float v_ = b2 * v[i] + one_b2 * g_ * g_;                              \
        m[i] = m_;                                                            \
        v[i] = v_;                                                            \
        params[i] -= step * m_ / (sqrtf(v_) * inv_sqrt_c2 + eps);             \
    } while (0)

NERF__MULTIVERSION static void adam_dense(void *ctx, size_t begin, size_t end)
{
    ADAM_LOCALS((const adam_job *)ctx);
    for (size_t i = begin; i < end; i++) {
        ADAM_ONE(i, grads[i]);
        grads[i] = 0.0f;
    }
}

/* With masked stores (AVX2, AVX-512) this loop vectorises: untouched
 * entries are read once and never written. */
NERF__MULTIVERSION static void adam_sparse(void *ctx, size_t begin,
                                           size_t end)
{
    ADAM_LOCALS((const adam_job *)ctx);
    for (size_t i = begin; i < end; i++) {
        float g = grads[i];
        if (g != 0.0f) {
            ADAM_ONE(i, g);
            grads[i] = 0.0f;
        }
    }
}

void nerf__adam_update(const nerf__adam *hp, uint64_t t, double lr, size_t n,
                       float *params, float *grads, float *m, float *v,
                       unsigned flags)
{
    /* 1 - beta in double: 1 - 0.999f would be off by 1e-5 relative. */
    const double c1 = 1.0 - pow(hp->beta1, (double)t);
    const double c2 = 1.0 - pow(hp->beta2, (double)t);
    /* Fold the corrections into two scalars so the loop does one sqrt and
     * one divide per parameter. */
    adam_job j = {
        .b1 = (float)hp->beta1,
        .b2 = (float)hp->beta2,
        .one_b1 = (float)(1.0 - hp->beta1),
        .one_b2 = (float)(1.0 - hp->beta2),
        .step = (float)(lr / c1),
        .inv_sqrt_c2 = (float)(1.0 / sqrt(c2)),
        .eps = (float)hp->eps,
        .decay = (flags & NERF__ADAM_DECAY) ? (float)hp->weight_decay : 0.0f,
        .params = params, .m = m, .v = v, .grads = grads,
    };
    nerf__parallel_for(n, 4, (flags & NERF__ADAM_SPARSE) ? adam_sparse
                                                          : adam_dense, &j);
}
