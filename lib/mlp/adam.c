#include "adam.h"

#include <math.h>

#include "parallel.h"

double nerf__adam_rate(const nerf__adam *hp, uint64_t step)
{
    return hp->lr * pow(hp->lr_final / hp->lr, (double)step / hp->decay_steps);
}

typedef struct adam_job {
    float b1, b2, one_b1, one_b2, step, inv_sqrt_c2, eps;
    float *params, *m, *v;
    const float *grads;
} adam_job;

static void adam_range(void *ctx, size_t begin, size_t end)
{
    const adam_job *j = ctx;
    float *restrict params = j->params, *restrict m = j->m, *restrict v = j->v;
    const float *restrict grads = j->grads;
    for (size_t i = begin; i < end; i++) {
        float g = grads[i];
        float mi = j->b1 * m[i] + j->one_b1 * g;
        float vi = j->b2 * v[i] + j->one_b2 * g * g;
        m[i] = mi;
        v[i] = vi;
        params[i] -= j->step * mi / (sqrtf(vi) * j->inv_sqrt_c2 + j->eps);
    }
}

void nerf__adam_update(const nerf__adam *hp, uint64_t t, double lr, size_t n,
                       float *params, const float *grads, float *m, float *v)
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
        .params = params, .m = m, .v = v, .grads = grads,
    };
    nerf__parallel_for(n, 12, adam_range, &j);
}
