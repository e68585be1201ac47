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
    float *params, *m, *v, *grads;
    /* Counted updates: the counts, and the table's corrections (the step
     * above is then the bare learning rate). */
    uint16_t *counts;
    const float *inv_c1, *inv_sqrt_c2s;
    uint32_t last;
} adam_job;

/* The update of parameter i with gradient g (weight decay included), the
 * job's scalars copied into locals so that the compiler can keep them in
 * registers across the stores. */
#define ADAM_LOCALS(j)                                                        \
    float *restrict params = (j)->params, *restrict m = (j)->m;              \
    float *restrict v = (j)->v, *restrict grads = (j)->grads;                \
    const float b1 = (j)->b1, b2 = (j)->b2, one_b1 = (j)->one_b1;            \
    const float one_b2 = (j)->one_b2, step = (j)->step;                      \
    const float eps = (j)->eps, decay = (j)->decay

/* The update of parameter i with gradient g, step size s and correction
 * c2 of the root. */
#define ADAM_ONE(i, g, s, c2)                                                 \
    do {                                                                      \
        float g_ = (g) + decay * params[i];                                   \
        float m_ = b1 * m[i] + one_b1 * g_;                                   \
        float v_ = b2 * v[i] + one_b2 * g_ * g_;                              \
        m[i] = m_;                                                            \
        v[i] = v_;                                                            \
        params[i] -= (s) * m_ / (sqrtf(v_) * (c2) + eps);                     \
    } while (0)

NERF__MULTIVERSION static void adam_dense(void *ctx, size_t begin, size_t end)
{
    ADAM_LOCALS((const adam_job *)ctx);
    const float inv_sqrt_c2 = ((const adam_job *)ctx)->inv_sqrt_c2;
    for (size_t i = begin; i < end; i++) {
        ADAM_ONE(i, grads[i], step, inv_sqrt_c2);
        grads[i] = 0.0f;
    }
}

/* With masked stores (AVX2, AVX-512) this loop vectorises: untouched
 * entries are read once and never written. */
NERF__MULTIVERSION static void adam_sparse(void *ctx, size_t begin,
                                           size_t end)
{
    ADAM_LOCALS((const adam_job *)ctx);
    const float inv_sqrt_c2 = ((const adam_job *)ctx)->inv_sqrt_c2;
    for (size_t i = begin; i < end; i++) {
        float g = grads[i];
        if (g != 0.0f) {
            ADAM_ONE(i, g, step, inv_sqrt_c2);
            grads[i] = 0.0f;
        }
    }
}

/* Entries a counted update gathers before updating them. */
#define COUNTED_BLOCK 256

/*
 * A step touches a random-looking seventh of a fine level's entries, so
 * a loop that branches on each gradient mispredicts often, and one whose
 * body reads the corrections' table does not vectorise.  So each block
 * first lists its touched entries without a branch, then updates them.
 */
NERF__MULTIVERSION static void adam_counted(void *ctx, size_t begin,
                                            size_t end)
{
    const adam_job *j = ctx;
    ADAM_LOCALS(j);
    uint16_t *restrict counts = j->counts;
    const float *inv_c1 = j->inv_c1, *inv_sqrt_c2 = j->inv_sqrt_c2s;
    const uint32_t last = j->last;
    uint32_t touched[COUNTED_BLOCK];
    for (size_t b = begin; b < end; b += COUNTED_BLOCK) {
        const size_t n = end - b < COUNTED_BLOCK ? end - b : COUNTED_BLOCK;
        size_t nt = 0;
        for (size_t i = 0; i < n; i++) {
            touched[nt] = (uint32_t)i;
            nt += grads[b + i] != 0.0f;
        }
        for (size_t t = 0; t < nt; t++) {
            const size_t i = b + touched[t];
            uint32_t k = counts[i];
            k += k < NERF__ADAM_COUNT_MAX;
            counts[i] = (uint16_t)k;
            const uint32_t at = k < last ? k : last;
            ADAM_ONE(i, grads[i], step * inv_c1[at], inv_sqrt_c2[at]);
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

/* Whether the corrections at count k are exactly 1 in float. */
static bool corrections_done(const nerf__adam *hp, uint32_t k)
{
    const double c1 = 1.0 - pow(hp->beta1, (double)k);
    const double c2 = 1.0 - pow(hp->beta2, (double)k);
    return (float)(1.0 / c1) == 1.0f && (float)(1.0 / sqrt(c2)) == 1.0f;
}

int nerf__adam_table_fit(const nerf__env *env, nerf__adam_table *t,
                         const nerf__adam *hp)
{
    if (t->len > 0 && t->beta1 == hp->beta1 && t->beta2 == hp->beta2) {
        return NERF_OK;
    }
    /* The corrections fall monotonically to 1: bisect for the first count
     * at which both are 1, so that the table holds only the counts that
     * differ (1,588 with the fast preset's betas). */
    uint32_t lo = 1, hi = NERF__ADAM_COUNT_MAX;
    if (corrections_done(hp, lo)) {
        hi = lo;
    }
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (corrections_done(hp, mid)) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    const uint32_t len = hi + 1;
    float *inv_c1 = nerf__calloc(env, 2 * (size_t)len, sizeof(float));
    if (inv_c1 == NULL) {
        return NERF_ENOMEM;
    }
    float *inv_sqrt_c2 = inv_c1 + len;
    inv_c1[0] = inv_sqrt_c2[0] = 1.0f; /* no update has count 0 */
    for (uint32_t k = 1; k < len; k++) {
        inv_c1[k] = (float)(1.0 / (1.0 - pow(hp->beta1, (double)k)));
        inv_sqrt_c2[k] = (float)(1.0 / sqrt(1.0 - pow(hp->beta2,
                                                      (double)k)));
    }
    nerf__adam_table_free(env, t);
    *t = (nerf__adam_table){hp->beta1, hp->beta2, len, inv_c1, inv_sqrt_c2};
    return NERF_OK;
}

void nerf__adam_table_free(const nerf__env *env, nerf__adam_table *t)
{
    nerf__free(env, t->inv_c1);
    *t = (nerf__adam_table){0};
}

void nerf__adam_update_counted(const nerf__adam *hp,
                               const nerf__adam_table *t, double lr, size_t n,
                               float *params, float *grads, float *m,
                               float *v, uint16_t *counts)
{
    adam_job j = {
        .b1 = (float)hp->beta1,
        .b2 = (float)hp->beta2,
        .one_b1 = (float)(1.0 - hp->beta1),
        .one_b2 = (float)(1.0 - hp->beta2),
        .step = (float)lr,
        .eps = (float)hp->eps,
        .params = params, .m = m, .v = v, .grads = grads,
        .counts = counts,
        .inv_c1 = t->inv_c1, .inv_sqrt_c2s = t->inv_sqrt_c2,
        .last = t->len - 1,
    };
    nerf__parallel_for(n, 4, adam_counted, &j);
}
