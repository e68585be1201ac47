#include "adam.h"

#include <math.h>

double nerf__adam_rate(const nerf__adam *hp, uint64_t step)
{
    return hp->lr * pow(hp->lr_final / hp->lr, (double)step / hp->decay_steps);
}

void nerf__adam_update(const nerf__adam *hp, uint64_t t, double lr, size_t n,
                       float *params, const float *grads, float *m, float *v)
{
    /* 1 - beta in double: 1 - 0.999f would be off by 1e-5 relative. */
    const float b1 = (float)hp->beta1, b2 = (float)hp->beta2;
    const float one_b1 = (float)(1.0 - hp->beta1);
    const float one_b2 = (float)(1.0 - hp->beta2);
    /* Fold the corrections into two scalars so the loop does one sqrt and
     * one divide per parameter. */
    const double c1 = 1.0 - pow(hp->beta1, (double)t);
    const double c2 = 1.0 - pow(hp->beta2, (double)t);
    const float step = (float)(lr / c1);
    const float inv_sqrt_c2 = (float)(1.0 / sqrt(c2));
    const float eps = (float)hp->eps;
    for (size_t i = 0; i < n; i++) {
        float g = grads[i];
        float mi = b1 * m[i] + one_b1 * g;
        float vi = b2 * v[i] + one_b2 * g * g;
        m[i] = mi;
        v[i] = vi;
        params[i] -= step * mi / (sqrtf(vi) * inv_sqrt_c2 + eps);
    }
}
