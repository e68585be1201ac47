/*
 * Small matrix products without BLAS, for the fused small-MLP path
 * (network_fused.h): every operand is a block of a few hundred samples by
 * at most a few cache lines of columns, already in L1 or L2, where a
 * general sgemm spends more time packing its operands and handing work
 * between threads than multiplying.
 *
 *     C[i, 0:n] = init_i + sum over segments s, k < s.k of
 *                 A_s(i, k) * B[kb + k, 0:n]
 *
 * B is row-major (stride ldb) and its rows follow one another across the
 * segments (kb counts the rows of the segments before); each A element is
 * read as a scalar from a[i * sm + k * sk], so one kernel serves
 * X W^T (B = W^T packed), dY W (B = W) and dY^T X (A = dY read down its
 * columns, B = X).  init_i is C's own row (SMM_ADD), the bias, or zero.
 *
 * Variants: AVX-512, AVX2 with FMA, and portable C (generic vectors);
 * which one runs is chosen when the library is loaded (nerf__smm_default:
 * the widest nerf__isa() allows, and NERF_FUSED may choose another).
 * Every element is one chain of multiply-adds in k order from its initial
 * value, whatever the tiling, so the AVX-512 and AVX2 variants give
 * identical bits (both fuse each multiply-add); the portable one does
 * not fuse (the build says -ffp-contract=off) and differs from them by
 * rounding only.
 */
#ifndef NERF_MLP_SMM_H
#define NERF_MLP_SMM_H

#include <stddef.h>
#include <stdint.h>

typedef struct nerf__smm_seg {
    const float *a;
    size_t sm, sk; /* strides of A's rows (i) and columns (k) */
    uint32_t k;
} nerf__smm_seg;

#define NERF__SMM_MAX_SEGS 2

/* Flags */
#define NERF__SMM_ADD 1u  /* start from C (else from bias, or zero) */
#define NERF__SMM_RELU 2u /* max(., 0) on the result */

void nerf__smm(size_t m, uint32_t n, const nerf__smm_seg *seg, int n_seg,
               const float *b, size_t ldb, const float *bias, unsigned flags,
               float *c, size_t ldc);

enum {
    NERF__SMM_OFF = 0, /* no fused path: products through cblas */
    NERF__SMM_PORTABLE = 1,
    NERF__SMM_AVX2 = 2,
    NERF__SMM_AVX512 = 3,
};

/* The fastest kernels this processor runs (never NERF__SMM_OFF). */
int nerf__smm_best(void);
/* What the library uses unless told otherwise, chosen when it is loaded:
 * nerf__smm_best() where that has AVX2, else NERF__SMM_OFF; NERF_FUSED=0
 * gives NERF__SMM_OFF, NERF_FUSED=1 nerf__smm_best() (common/dispatch.h). */
int nerf__smm_default(void);
/* Whether `variant` runs here and nerf__isa() allows it (NERF__SMM_OFF
 * always does). */
int nerf__smm_supported(int variant);
/* The variant in use (NERF__SMM_OFF: the fused path is off). */
int nerf__smm_variant(void);
/*
 * Use `variant` from now on, process-wide; for tests and A/B timings, not
 * to be called while other threads run networks.  Returns 0, or -1 (and
 * changes nothing) if the processor lacks it.
 */
int nerf__smm_use(int variant);

#endif
