#include "adam.h"

#include <math.h>
#include <stdbool.h>
#if defined(NERF_HAVE_CLONES)
#  include <immintrin.h>
#endif

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
    float *r1, *r2; /* corrected updates: each parameter's beta^k */
    int isa;        /* corrected updates: the kernel's (common/dispatch.h) */
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

NERF__CLONED(adam_dense, (void *ctx, size_t begin, size_t end),
             (ctx, begin, end))
{
    ADAM_LOCALS((const adam_job *)ctx);
    for (size_t i = begin; i < end; i++) {
        ADAM_ONE(i, grads[i]);
        grads[i] = 0.0f;
    }
}

/* With masked stores (AVX2, AVX-512) this loop vectorises: untouched
 * entries are read once and never written. */
NERF__CLONED(adam_sparse, (void *ctx, size_t begin, size_t end),
             (ctx, begin, end))
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

/* The loop it precedes never reaches one element through two of its
 * arrays.  Not told so, gcc checks six arrays' overlap at run time, more
 * checks than it vectorises behind, restrict or not.  (clang's own
 * pragma for this turns a loop it cannot vectorise, as under the
 * sanitizers, into a warning, and so an error with -Werror.) */
#if defined(__GNUC__) && !defined(__clang__)
#  define NERF__NO_ALIAS_LOOP _Pragma("GCC ivdep")
#else
#  define NERF__NO_ALIAS_LOOP
#endif

/* Vectorises as adam_sparse does (masked stores) where the instruction
 * set has them: the corrections are each parameter's own, but come from
 * its own stored powers, with no lookup. */
static NERF__ALWAYS_INLINE void
corrected_loop(const adam_job *j, size_t begin, size_t end,
               float *restrict params, float *restrict grads, float *restrict m,
               float *restrict v, float *restrict r1, float *restrict r2)
{
    const float b1 = j->b1, b2 = j->b2, one_b1 = j->one_b1;
    const float one_b2 = j->one_b2, step = j->step, eps = j->eps;
    NERF__NO_ALIAS_LOOP
    for (size_t i = begin; i < end; i++) {
        float g = grads[i];
        if (g != 0.0f) {
            /* Once beta^k is below 2^-26, 1 - beta^k is 1 in float:
             * flushing it to 0 there changes no correction and keeps it
             * from going subnormal, which is slow on some processors.
             * (A product with the comparison, not a conditional: gcc
             * vectorises the loop only so.) */
            float s1 = b1 * r1[i], s2 = b2 * r2[i];
            s1 *= (float)(s1 >= 0x1p-26f);
            s2 *= (float)(s2 >= 0x1p-26f);
            r1[i] = s1;
            r2[i] = s2;
            float m_ = b1 * m[i] + one_b1 * g;
            float v_ = b2 * v[i] + one_b2 * g * g;
            m[i] = m_;
            v[i] = v_;
            params[i] -= step * (m_ / (1.0f - s1)) /
                         (sqrtf(v_ / (1.0f - s2)) + eps);
            grads[i] = 0.0f;
        }
    }
}

#define CORRECTED_ARGS(j)                                                     \
    (j)->params, (j)->grads, (j)->m, (j)->v, (j)->r1, (j)->r2

static void corrected_portable(const adam_job *j, size_t begin, size_t end)
{
    corrected_loop(j, begin, end, CORRECTED_ARGS(j));
}

#if defined(NERF_HAVE_CLONES)
__attribute__((target("avx2"))) static void
corrected_avx2(const adam_job *j, size_t begin, size_t end)
{
    corrected_loop(j, begin, end, CORRECTED_ARGS(j));
}

#define T512 __attribute__((target("avx512f")))

/*
 * Sixteen parameters from i on, of which the lanes in live are in the
 * range.  Written out rather than left to the compiler: on the fast
 * preset's table with one line in eight touched, as late in a lego run,
 * gcc's own AVX-512 loop took 1.5 to 1.9 times as long as this
 * (docs/perf-log/2026-12-03-adam-kernel-by-hand.md).  Blocks here are
 * aligned on the gradients' cache lines, so that a touched line is one
 * block, and one with no gradient set costs a load and a test.  The
 * operations are corrected_loop()'s, in its order, each rounded once:
 * the same bits.
 */
static inline __attribute__((always_inline)) T512 void
corrected16(const adam_job *j, size_t i, __mmask16 live)
{
    const __m512 zero = _mm512_setzero_ps();
    const __m512 g = _mm512_maskz_loadu_ps(live, j->grads + i);
    /* Not equal, or unordered: a NaN gradient is an update, as in C. */
    const __mmask16 k = _mm512_mask_cmp_ps_mask(live, g, zero, _CMP_NEQ_UQ);
    if (k == 0) {
        return;
    }
    const __m512 b1 = _mm512_set1_ps(j->b1), b2 = _mm512_set1_ps(j->b2);
    const __m512 one = _mm512_set1_ps(1.0f), tiny = _mm512_set1_ps(0x1p-26f);
    __m512 s1 = _mm512_mul_ps(b1, _mm512_maskz_loadu_ps(k, j->r1 + i));
    __m512 s2 = _mm512_mul_ps(b2, _mm512_maskz_loadu_ps(k, j->r2 + i));
    s1 = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(s1, tiny, _CMP_GE_OQ), s1);
    s2 = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(s2, tiny, _CMP_GE_OQ), s2);
    _mm512_mask_storeu_ps(j->r1 + i, k, s1);
    _mm512_mask_storeu_ps(j->r2 + i, k, s2);
    const __m512 m_ = _mm512_add_ps(
        _mm512_mul_ps(b1, _mm512_maskz_loadu_ps(k, j->m + i)),
        _mm512_mul_ps(_mm512_set1_ps(j->one_b1), g));
    const __m512 v_ = _mm512_add_ps(
        _mm512_mul_ps(b2, _mm512_maskz_loadu_ps(k, j->v + i)),
        _mm512_mul_ps(_mm512_mul_ps(_mm512_set1_ps(j->one_b2), g), g));
    _mm512_mask_storeu_ps(j->m + i, k, m_);
    _mm512_mask_storeu_ps(j->v + i, k, v_);
    const __m512 num = _mm512_mul_ps(_mm512_set1_ps(j->step),
                                     _mm512_div_ps(m_, _mm512_sub_ps(one, s1)));
    const __m512 den = _mm512_add_ps(
        _mm512_sqrt_ps(_mm512_div_ps(v_, _mm512_sub_ps(one, s2))),
        _mm512_set1_ps(j->eps));
    const __m512 p = _mm512_maskz_loadu_ps(k, j->params + i);
    _mm512_mask_storeu_ps(j->params + i, k,
                          _mm512_sub_ps(p, _mm512_div_ps(num, den)));
    _mm512_mask_storeu_ps(j->grads + i, k, zero);
}

/* Blocks aligned on the gradients' cache lines, the array every block
 * reads. */
T512 static void corrected_avx512(const adam_job *j, size_t begin, size_t end)
{
    size_t i = begin;
    const size_t misaligned = ((uintptr_t)(j->grads + i) / sizeof(float)) % 16;
    if (misaligned != 0 && i < end) {
        const size_t lanes = end - i < 16 - misaligned ? end - i
                                                       : 16 - misaligned;
        corrected16(j, i, (__mmask16)((1u << lanes) - 1));
        i += lanes;
    }
    for (; i + 16 <= end; i += 16) {
        corrected16(j, i, 0xffff);
    }
    if (i < end) {
        corrected16(j, i, (__mmask16)((1u << (end - i)) - 1));
    }
}
#endif

static void adam_corrected(void *ctx, size_t begin, size_t end)
{
    const adam_job *j = ctx;
#if defined(NERF_HAVE_CLONES)
    switch (j->isa) {
    case NERF__ISA_AVX512:
        corrected_avx512(j, begin, end);
        return;
    case NERF__ISA_AVX2:
        corrected_avx2(j, begin, end);
        return;
    default:
        break;
    }
#endif
    corrected_portable(j, begin, end);
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

void nerf__adam_update_corrected(const nerf__adam *hp, double lr, size_t n,
                                 float *params, float *grads, float *m,
                                 float *v, float *r1, float *r2)
{
    nerf__adam_update_corrected_isa(nerf__isa(), hp, lr, n, params, grads, m,
                                    v, r1, r2);
}

void nerf__adam_update_corrected_isa(int isa, const nerf__adam *hp,
                                     double lr, size_t n, float *params,
                                     float *grads, float *m, float *v,
                                     float *r1, float *r2)
{
    adam_job j = {
        .b1 = (float)hp->beta1,
        .b2 = (float)hp->beta2,
        .one_b1 = (float)(1.0 - hp->beta1),
        .one_b2 = (float)(1.0 - hp->beta2),
        .step = (float)lr,
        .eps = (float)hp->eps,
        .params = params, .m = m, .v = v, .grads = grads,
        .r1 = r1, .r2 = r2,
        .isa = isa < nerf__isa_cpu() ? isa : nerf__isa_cpu(),
    };
    nerf__parallel_for(n, 4, adam_corrected, &j);
}
