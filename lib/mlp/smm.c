#include "smm.h"

#include <stdatomic.h>
#include <stdbool.h>

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

#if defined(__GNUC__)
#define ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define ALWAYS_INLINE inline
#endif

/* ---- portable ------------------------------------------------------------
 * A tile of PR rows by PN columns in plain C, which the compiler vectorises
 * for whatever the build targets. */

#define PR 4
#define PN 16

static ALWAYS_INLINE void tile_portable(const job *j, size_t i0, size_t rows,
                                        uint32_t n0, uint32_t cols)
{
    float acc[PR][PN];
    for (size_t r = 0; r < rows; r++) {
        const float *init = j->flags & NERF__SMM_ADD
                                ? j->c + (i0 + r) * j->ldc + n0
                                : j->bias ? j->bias + n0 : NULL;
        for (uint32_t c = 0; c < cols; c++) {
            acc[r][c] = init ? init[c] : 0.0f;
        }
    }
    const float *brow = j->b + n0;
    for (int s = 0; s < j->n_seg; s++) {
        const nerf__smm_seg *sg = &j->seg[s];
        const float *a = sg->a + i0 * sg->sm;
        for (uint32_t k = 0; k < sg->k; k++, brow += j->ldb, a += sg->sk) {
            for (size_t r = 0; r < rows; r++) {
                const float x = a[r * sg->sm];
                for (uint32_t c = 0; c < cols; c++) {
                    acc[r][c] += x * brow[c];
                }
            }
        }
    }
    for (size_t r = 0; r < rows; r++) {
        float *out = j->c + (i0 + r) * j->ldc + n0;
        for (uint32_t c = 0; c < cols; c++) {
            float v = acc[r][c];
            if (j->flags & NERF__SMM_RELU) {
                v = v > 0.0f ? v : 0.0f;
            }
            out[c] = v;
        }
    }
}

static void run_portable(const job *j, size_t m, uint32_t n)
{
    for (size_t i0 = 0; i0 < m; i0 += PR) {
        for (uint32_t n0 = 0; n0 < n; n0 += PN) {
            /* Constant bounds for the whole tiles, so that they unroll. */
            if (m - i0 >= PR && n - n0 >= PN) {
                tile_portable(j, i0, PR, n0, PN);
            } else {
                tile_portable(j, i0, m - i0 < PR ? m - i0 : PR, n0,
                              n - n0 < PN ? n - n0 : PN);
            }
        }
    }
}

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
 * masked, which costs nothing on loads and stores. */
#define R512 6
#define V512 4

static ALWAYS_INLINE T512 void tile512(const job *j, size_t i0, const int R,
                                       uint32_t n0, const int V,
                                       __mmask16 last)
{
    __m512 acc[R512][V512];
    __mmask16 mk[V512];
    for (int v = 0; v < V; v++) {
        mk[v] = v == V - 1 ? last : (__mmask16)0xffff;
    }
    for (int r = 0; r < R; r++) {
        for (int v = 0; v < V; v++) {
            if (j->flags & NERF__SMM_ADD) {
                acc[r][v] = _mm512_maskz_loadu_ps(
                    mk[v], j->c + (i0 + r) * j->ldc + n0 + 16 * v);
            } else if (j->bias) {
                acc[r][v] = _mm512_maskz_loadu_ps(mk[v], j->bias + n0 + 16 * v);
            } else {
                acc[r][v] = _mm512_setzero_ps();
            }
        }
    }
    const float *brow = j->b + n0;
    for (int s = 0; s < j->n_seg; s++) {
        const nerf__smm_seg *sg = &j->seg[s];
        const float *a = sg->a + i0 * sg->sm;
        const size_t sm = sg->sm, sk = sg->sk;
        for (uint32_t k = 0; k < sg->k; k++, brow += j->ldb, a += sk) {
            __m512 bv[V512];
            for (int v = 0; v < V; v++) {
                bv[v] = _mm512_maskz_loadu_ps(mk[v], brow + 16 * v);
            }
            for (int r = 0; r < R; r++) {
                const __m512 x = _mm512_set1_ps(a[r * sm]);
                for (int v = 0; v < V; v++) {
                    acc[r][v] = _mm512_fmadd_ps(x, bv[v], acc[r][v]);
                }
            }
        }
    }
    for (int r = 0; r < R; r++) {
        for (int v = 0; v < V; v++) {
            __m512 y = acc[r][v];
            if (j->flags & NERF__SMM_RELU) {
                /* The second operand when either is NaN or both are zero:
                 * NaN and -0 give +0, as the C path's v > 0 ? v : 0. */
                y = _mm512_max_ps(y, _mm512_setzero_ps());
            }
            _mm512_mask_storeu_ps(j->c + (i0 + r) * j->ldc + n0 + 16 * v,
                                  mk[v], y);
        }
    }
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

static ALWAYS_INLINE T256 void tile256(const job *j, size_t i0, const int R,
                                       uint32_t n0, const int V,
                                       const int masked, __m256i last)
{
#define LOAD256(v, p)                                                       \
    (masked && (v) == V - 1 ? _mm256_maskload_ps((p), last)                 \
                            : _mm256_loadu_ps(p))
    __m256 acc[R256][V256];
    for (int r = 0; r < R; r++) {
        for (int v = 0; v < V; v++) {
            if (j->flags & NERF__SMM_ADD) {
                acc[r][v] = LOAD256(v, j->c + (i0 + r) * j->ldc + n0 + 8 * v);
            } else if (j->bias) {
                acc[r][v] = LOAD256(v, j->bias + n0 + 8 * v);
            } else {
                acc[r][v] = _mm256_setzero_ps();
            }
        }
    }
    const float *brow = j->b + n0;
    for (int s = 0; s < j->n_seg; s++) {
        const nerf__smm_seg *sg = &j->seg[s];
        const float *a = sg->a + i0 * sg->sm;
        const size_t sm = sg->sm, sk = sg->sk;
        for (uint32_t k = 0; k < sg->k; k++, brow += j->ldb, a += sk) {
            __m256 bv[V256];
            for (int v = 0; v < V; v++) {
                bv[v] = LOAD256(v, brow + 8 * v);
            }
            for (int r = 0; r < R; r++) {
                const __m256 x = _mm256_broadcast_ss(a + r * sm);
                for (int v = 0; v < V; v++) {
                    acc[r][v] = _mm256_fmadd_ps(x, bv[v], acc[r][v]);
                }
            }
        }
    }
    for (int r = 0; r < R; r++) {
        for (int v = 0; v < V; v++) {
            __m256 y = acc[r][v];
            if (j->flags & NERF__SMM_RELU) {
                y = _mm256_max_ps(y, _mm256_setzero_ps());
            }
            float *p = j->c + (i0 + r) * j->ldc + n0 + 8 * v;
            if (masked && v == V - 1) {
                _mm256_maskstore_ps(p, last, y);
            } else {
                _mm256_storeu_ps(p, y);
            }
        }
    }
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
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case NERF__SMM_AVX512:
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx512f") &&
               __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
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

/* Chosen once when the library is loaded; nerf__smm_use() overrides. */
__attribute__((constructor)) static void choose_variant(void)
{
    atomic_store(&in_use, nerf__smm_best());
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
