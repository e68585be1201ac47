#include "smm.h"

#include "dispatch.h"
#include "multiversion.h"

#include <stdatomic.h>
#include <stdbool.h>
#include <string.h>

typedef struct job {
    const nerf__smm_seg *seg;
    int n_seg;
    const float *b;
    size_t ldb;
    const float *bias;
    unsigned flags;
    float *c;
    size_t ldc;
} job;


/* ---- portable ------------------------------------------------------------
 * Tiles of 4 rows by 2 vectors of 4 floats through the compilers' generic
 * vectors (SSE2 on x86-64, NEON on aarch64, scalar code elsewhere); plain
 * C loops where the compiler has no vector extension. */

#if defined(__GNUC__)
typedef float v4 __attribute__((vector_size(16)));
typedef int32_t v4i __attribute__((vector_size(16)));

#define PR 4
#define PV 2

static NERF__ALWAYS_INLINE v4 load4(const float *p, int n)
{
    v4 x = {0.0f, 0.0f, 0.0f, 0.0f};
    if (n >= 4) {
        memcpy(&x, p, sizeof x);
    } else {
        for (int i = 0; i < n; i++) {
            x[i] = p[i];
        }
    }
    return x;
}

static NERF__ALWAYS_INLINE void store4(float *p, v4 x, int n)
{
    if (n >= 4) {
        memcpy(p, &x, sizeof x);
    } else {
        for (int i = 0; i < n; i++) {
            p[i] = x[i];
        }
    }
}

#define GRID4x2(OP)                                                         \
    OP(0, 0) OP(0, 1) OP(1, 0) OP(1, 1) OP(2, 0) OP(2, 1) OP(3, 0) OP(3, 1)

/* R rows, V vectors, the last holding `tail` columns (1 to 4). */
static NERF__ALWAYS_INLINE void
tile_portable(const job *j, size_t i0, const int R,
              uint32_t n0, const int V,
              const int tail)
{
    const bool add = j->flags & NERF__SMM_ADD;
    float *const c = j->c + i0 * j->ldc + n0;
    const size_t ldc = j->ldc;
    const v4 zero = {0.0f, 0.0f, 0.0f, 0.0f};
#define W4(v) ((v) == V - 1 ? tail : 4)
#define DECL(r, v) v4 c##r##v = zero;
    GRID4x2(DECL)
#undef DECL
#define INIT(r, v)                                                          \
    if ((r) < R && (v) < V) {                                               \
        if (add) {                                                          \
            c##r##v = load4(c + (r) * ldc + 4 * (v), W4(v));                \
        } else if (j->bias) {                                               \
            c##r##v = load4(j->bias + n0 + 4 * (v), W4(v));                 \
        }                                                                   \
    }
    GRID4x2(INIT)
#undef INIT
    const float *brow = j->b + n0;
    for (int s = 0; s < j->n_seg; s++) {
        const nerf__smm_seg *sg = &j->seg[s];
        const float *a = sg->a + i0 * sg->sm;
        const size_t sm = sg->sm, sk = sg->sk;
        for (uint32_t k = 0; k < sg->k; k++, brow += j->ldb, a += sk) {
            const v4 b0 = load4(brow, W4(0));
            const v4 b1 = V > 1 ? load4(brow + 4, W4(1)) : b0;
#define FMA(r, v)                                                           \
    if ((r) < R && (v) < V) {                                               \
        c##r##v += a[(r) * sm] * b##v;                                      \
    }
            GRID4x2(FMA)
#undef FMA
        }
    }
    const bool relu = j->flags & NERF__SMM_RELU;
#define STORE(r, v)                                                         \
    if ((r) < R && (v) < V) {                                               \
        v4 y = c##r##v;                                                     \
        if (relu) { /* NaN and -0 give +0, as x > 0 ? x : 0 */              \
            y = (v4)((v4i)y & (y > zero));                                  \
        }                                                                   \
        store4(c + (r) * ldc + 4 * (v), y, W4(v));                          \
    }
    GRID4x2(STORE)
#undef STORE
#undef W4
}

#define CASEP(R, V)                                                         \
    case ((R) - 1) * PV + (V) - 1:                                          \
        if (tail == 4) {                                                    \
            tile_portable(j, i0, R, n0, V, 4);                              \
        } else {                                                            \
            tile_portable(j, i0, R, n0, V, tail);                           \
        }                                                                   \
        break

static void run_portable(const job *j, size_t m, uint32_t n)
{
    for (size_t i0 = 0; i0 < m; i0 += PR) {
        const int R = m - i0 < PR ? (int)(m - i0) : PR;
        for (uint32_t n0 = 0; n0 < n; n0 += 4 * PV) {
            const uint32_t cols = n - n0 < 4 * PV ? n - n0 : 4 * PV;
            const int V = (int)((cols + 3) / 4);
            const int tail = (int)(cols - 4 * (uint32_t)(V - 1));
            switch ((R - 1) * PV + V - 1) {
            CASEP(1, 1); CASEP(1, 2);
            CASEP(2, 1); CASEP(2, 2);
            CASEP(3, 1); CASEP(3, 2);
            CASEP(4, 1); CASEP(4, 2);
            default:
                break;
            }
        }
    }
}
#undef GRID4x2

#else /* no vector extension: one element at a time */

static void run_portable(const job *j, size_t m, uint32_t n)
{
    for (size_t i = 0; i < m; i++) {
        for (uint32_t col = 0; col < n; col++) {
            float acc = j->flags & NERF__SMM_ADD ? j->c[i * j->ldc + col]
                        : j->bias                ? j->bias[col]
                                                 : 0.0f;
            size_t kb = 0;
            for (int s = 0; s < j->n_seg; s++) {
                const nerf__smm_seg *sg = &j->seg[s];
                for (uint32_t k = 0; k < sg->k; k++) {
                    acc += sg->a[i * sg->sm + k * sg->sk] *
                           j->b[(kb + k) * j->ldb + col];
                }
                kb += sg->k;
            }
            if (j->flags & NERF__SMM_RELU) {
                acc = acc > 0.0f ? acc : 0.0f;
            }
            j->c[i * j->ldc + col] = acc;
        }
    }
}
#endif

/* ---- x86: AVX-512 and AVX2 -----------------------------------------------
 * Compiled whatever the build's baseline (target attributes), and run only
 * where the processor has the instructions.  Each tile keeps its R x V
 * accumulators in registers; R and V are constants in every call of the
 * inlined tile, so the compiler unrolls it completely. */

#if defined(__x86_64__) && defined(__GNUC__)
#define SMM_X86 1
#include <immintrin.h>

#define T512 __attribute__((target("avx512f,avx2,fma")))
#define T256 __attribute__((target("avx2,fma")))

/* AVX-512: up to 6 rows by 4 vectors of 16 (64 columns); the tail is
 * masked, which costs nothing on loads and stores.  The accumulators are
 * named variables, not an array: compilers keep an array that lives across
 * the segment loop in memory. */
#define R512 6
#define V512 4

/* OP(r, v) for every accumulator of the tile; OP tests r < R, v < V. */
#define GRID6x4(OP)                                                         \
    OP(0, 0) OP(0, 1) OP(0, 2) OP(0, 3) OP(1, 0) OP(1, 1) OP(1, 2) OP(1, 3) \
    OP(2, 0) OP(2, 1) OP(2, 2) OP(2, 3) OP(3, 0) OP(3, 1) OP(3, 2) OP(3, 3) \
    OP(4, 0) OP(4, 1) OP(4, 2) OP(4, 3) OP(5, 0) OP(5, 1) OP(5, 2) OP(5, 3)

static NERF__ALWAYS_INLINE T512 void
tile512(const job *j, size_t i0, const int R,
        uint32_t n0, const int V,
        __mmask16 last)
{
    const __mmask16 m0 = V == 1 ? last : 0xffff, m1 = V == 2 ? last : 0xffff;
    const __mmask16 m2 = V == 3 ? last : 0xffff, m3 = last;
    const bool add = j->flags & NERF__SMM_ADD;
    float *const c = j->c + i0 * j->ldc + n0;
    const size_t ldc = j->ldc;
#define DECL(r, v) __m512 c##r##v = _mm512_setzero_ps();
    GRID6x4(DECL)
#undef DECL
#define INIT(r, v)                                                          \
    if ((r) < R && (v) < V) {                                               \
        if (add) {                                                          \
            c##r##v = _mm512_maskz_loadu_ps(m##v, c + (r) * ldc + 16 * (v)); \
        } else if (j->bias) {                                               \
            c##r##v = _mm512_maskz_loadu_ps(m##v, j->bias + n0 + 16 * (v)); \
        }                                                                   \
    }
    GRID6x4(INIT)
#undef INIT
    const float *brow = j->b + n0;
    for (int s = 0; s < j->n_seg; s++) {
        const nerf__smm_seg *sg = &j->seg[s];
        const float *a = sg->a + i0 * sg->sm;
        const size_t sm = sg->sm, sk = sg->sk;
        for (uint32_t k = 0; k < sg->k; k++, brow += j->ldb, a += sk) {
            const __m512 b0 = _mm512_maskz_loadu_ps(m0, brow);
            const __m512 b1 = V > 1 ? _mm512_maskz_loadu_ps(m1, brow + 16)
                                    : b0;
            const __m512 b2 = V > 2 ? _mm512_maskz_loadu_ps(m2, brow + 32)
                                    : b0;
            const __m512 b3 = V > 3 ? _mm512_maskz_loadu_ps(m3, brow + 48)
                                    : b0;
#define FMA(r, v)                                                           \
    if ((r) < R && (v) < V) {                                               \
        c##r##v =                                                           \
            _mm512_fmadd_ps(_mm512_set1_ps(a[(r) * sm]), b##v, c##r##v);    \
    }
            GRID6x4(FMA)
#undef FMA
        }
    }
    /* max(x, 0) gives its second operand when x is NaN or -0: +0, as the
     * C path's x > 0 ? x : 0. */
    const bool relu = j->flags & NERF__SMM_RELU;
#define STORE(r, v)                                                         \
    if ((r) < R && (v) < V) {                                               \
        _mm512_mask_storeu_ps(c + (r) * ldc + 16 * (v), m##v,               \
                              relu ? _mm512_max_ps(c##r##v,                 \
                                                   _mm512_setzero_ps())     \
                                   : c##r##v);                              \
    }
    GRID6x4(STORE)
#undef STORE
}

#define CASE512(R, V)                                                       \
    case ((R) - 1) * V512 + (V) - 1:                                        \
        tile512(j, i0, R, n0, V, last);                                     \
        break

static T512 void run512(const job *j, size_t m, uint32_t n)
{
    for (size_t i0 = 0; i0 < m; i0 += R512) {
        const int R = m - i0 < R512 ? (int)(m - i0) : R512;
        for (uint32_t n0 = 0; n0 < n; n0 += 16 * V512) {
            const uint32_t cols = n - n0 < 16 * V512 ? n - n0 : 16 * V512;
            const int V = (int)((cols + 15) / 16);
            const __mmask16 last =
                (__mmask16)((1u << (cols - 16 * (uint32_t)(V - 1))) - 1u);
            switch ((R - 1) * V512 + V - 1) {
            CASE512(1, 1); CASE512(1, 2); CASE512(1, 3); CASE512(1, 4);
            CASE512(2, 1); CASE512(2, 2); CASE512(2, 3); CASE512(2, 4);
            CASE512(3, 1); CASE512(3, 2); CASE512(3, 3); CASE512(3, 4);
            CASE512(4, 1); CASE512(4, 2); CASE512(4, 3); CASE512(4, 4);
            CASE512(5, 1); CASE512(5, 2); CASE512(5, 3); CASE512(5, 4);
            CASE512(6, 1); CASE512(6, 2); CASE512(6, 3); CASE512(6, 4);
            default:
                break;
            }
        }
    }
}

/* AVX2: 16 registers hold 4 rows by 2 vectors of 8 (16 columns), the two
 * B vectors and the broadcasts.  A column count that is not a multiple of
 * 8 goes through masked loads and stores in its last vector. */
#define R256 4
#define V256 2

#define GRID4x2(OP)                                                         \
    OP(0, 0) OP(0, 1) OP(1, 0) OP(1, 1) OP(2, 0) OP(2, 1) OP(3, 0) OP(3, 1)

static NERF__ALWAYS_INLINE T256 void
tile256(const job *j, size_t i0, const int R,
        uint32_t n0, const int V,
        const int masked, __m256i last)
{
#define LOAD256(v, p)                                                       \
    (masked && (v) == V - 1 ? _mm256_maskload_ps((p), last)                 \
                            : _mm256_loadu_ps(p))
    const bool add = j->flags & NERF__SMM_ADD;
    float *const c = j->c + i0 * j->ldc + n0;
    const size_t ldc = j->ldc;
#define DECL(r, v) __m256 c##r##v = _mm256_setzero_ps();
    GRID4x2(DECL)
#undef DECL
#define INIT(r, v)                                                          \
    if ((r) < R && (v) < V) {                                               \
        if (add) {                                                          \
            c##r##v = LOAD256(v, c + (r) * ldc + 8 * (v));                  \
        } else if (j->bias) {                                               \
            c##r##v = LOAD256(v, j->bias + n0 + 8 * (v));                   \
        }                                                                   \
    }
    GRID4x2(INIT)
#undef INIT
    const float *brow = j->b + n0;
    for (int s = 0; s < j->n_seg; s++) {
        const nerf__smm_seg *sg = &j->seg[s];
        const float *a = sg->a + i0 * sg->sm;
        const size_t sm = sg->sm, sk = sg->sk;
        for (uint32_t k = 0; k < sg->k; k++, brow += j->ldb, a += sk) {
            const __m256 b0 = LOAD256(0, brow);
            const __m256 b1 = V > 1 ? LOAD256(1, brow + 8) : b0;
#define FMA(r, v)                                                           \
    if ((r) < R && (v) < V) {                                               \
        c##r##v = _mm256_fmadd_ps(_mm256_broadcast_ss(a + (r) * sm), b##v,  \
                                  c##r##v);                                 \
    }
            GRID4x2(FMA)
#undef FMA
        }
    }
    const bool relu = j->flags & NERF__SMM_RELU;
#define STORE(r, v)                                                         \
    if ((r) < R && (v) < V) {                                               \
        const __m256 y = relu ? _mm256_max_ps(c##r##v, _mm256_setzero_ps()) \
                              : c##r##v;                                    \
        if (masked && (v) == V - 1) {                                       \
            _mm256_maskstore_ps(c + (r) * ldc + 8 * (v), last, y);          \
        } else {                                                            \
            _mm256_storeu_ps(c + (r) * ldc + 8 * (v), y);                   \
        }                                                                   \
    }
    GRID4x2(STORE)
#undef STORE
#undef LOAD256
}

#define CASE256(R, V)                                                       \
    case ((R) - 1) * V256 + (V) - 1:                                        \
        if (masked) {                                                       \
            tile256(j, i0, R, n0, V, 1, last);                              \
        } else {                                                            \
            tile256(j, i0, R, n0, V, 0, last);                              \
        }                                                                   \
        break

static T256 void run256(const job *j, size_t m, uint32_t n)
{
    for (size_t i0 = 0; i0 < m; i0 += R256) {
        const int R = m - i0 < R256 ? (int)(m - i0) : R256;
        for (uint32_t n0 = 0; n0 < n; n0 += 8 * V256) {
            const uint32_t cols = n - n0 < 8 * V256 ? n - n0 : 8 * V256;
            const int V = (int)((cols + 7) / 8);
            const int tail = (int)(cols - 8 * (uint32_t)(V - 1)); /* 1..8 */
            const int masked = tail != 8;
            const __m256i last = _mm256_cmpgt_epi32(
                _mm256_set1_epi32(tail),
                _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
            switch ((R - 1) * V256 + V - 1) {
            CASE256(1, 1); CASE256(1, 2);
            CASE256(2, 1); CASE256(2, 2);
            CASE256(3, 1); CASE256(3, 2);
            CASE256(4, 1); CASE256(4, 2);
            default:
                break;
            }
        }
    }
}
#endif /* x86 */

/* ---- the choice ---------------------------------------------------------- */

static atomic_int in_use = NERF__SMM_OFF;

int nerf__smm_supported(int variant)
{
    switch (variant) {
    case NERF__SMM_OFF:
    case NERF__SMM_PORTABLE:
        return 1;
#if defined(SMM_X86)
    case NERF__SMM_AVX2:
        return nerf__isa() >= NERF__ISA_AVX2;
    case NERF__SMM_AVX512:
        return nerf__isa() >= NERF__ISA_AVX512;
#endif
    default:
        return 0;
    }
}

int nerf__smm_best(void)
{
    for (int v = NERF__SMM_AVX512; v > NERF__SMM_PORTABLE; v--) {
        if (nerf__smm_supported(v)) {
            return v;
        }
    }
    return NERF__SMM_PORTABLE;
}

/*
 * The portable kernels are no faster than the BLAS's own (about equal to
 * OpenBLAS's SSE kernels on x86, docs/perf-log/
 * 2026-11-26-fused-small-mlp-and-step-floor.md), so without AVX2
 * the layers keep going through the BLAS, unless NERF_FUSED says which.
 */
int nerf__smm_default(void)
{
    const int v = nerf__smm_best();
    switch (nerf__fused_override()) {
    case 0:
        return NERF__SMM_OFF;
    case 1:
        return v;
    default:
        return v >= NERF__SMM_AVX2 ? v : NERF__SMM_OFF;
    }
}

/* Chosen once when the library is loaded; nerf__smm_use() overrides. */
__attribute__((constructor)) static void choose_variant(void)
{
    atomic_store(&in_use, nerf__smm_default());
}

int nerf__smm_variant(void)
{
    return atomic_load_explicit(&in_use, memory_order_relaxed);
}

int nerf__smm_use(int variant)
{
    if (!nerf__smm_supported(variant)) {
        return -1;
    }
    atomic_store(&in_use, variant);
    return 0;
}

void nerf__smm(size_t m, uint32_t n, const nerf__smm_seg *seg, int n_seg,
               const float *b, size_t ldb, const float *bias, unsigned flags,
               float *c, size_t ldc)
{
    const job j = {seg, n_seg, b, ldb, bias, flags, c, ldc};
    if (m == 0 || n == 0) {
        return;
    }
    switch (nerf__smm_variant()) {
#if defined(SMM_X86)
    case NERF__SMM_AVX512:
        run512(&j, m, n);
        return;
    case NERF__SMM_AVX2:
        run256(&j, m, n);
        return;
#endif
    default:
        run_portable(&j, m, n);
        return;
    }
}
