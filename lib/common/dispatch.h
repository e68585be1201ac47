/*
 * Which of its own kernels the library runs, and the environment variables
 * that choose otherwise (docs/dispatch.md).  The processor decides by
 * default; the variables exist so that one machine can run the test suites
 * through every kernel another machine would pick, and so that a bug report
 * can rule a kernel in or out:
 *
 *   NERF_ISA=avx512|avx2|baseline  the widest x86 instruction set the
 *                                  element-wise clones and the small
 *                                  products may use (never wider than the
 *                                  processor's);
 *   NERF_FUSED=0|1                 small networks through the per-layer
 *                                  BLAS path (0) or the fused kernels (1,
 *                                  the portable ones where NERF_ISA or the
 *                                  processor has no AVX2);
 *   NERF_FP32_PRODUCTS=cblas|onednn
 *                                  what computes the products of fp32
 *                                  models (NERF_MATMUL_FP32): the CBLAS,
 *                                  the default, or oneDNN where
 *                                  nerf_matmul_supported() has it.
 *
 * Each is read once, on first use.  A value that is not one of those above
 * is ignored and said so in nerf_build_info().
 */
#ifndef NERF_COMMON_DISPATCH_H
#define NERF_COMMON_DISPATCH_H

enum {
    NERF__ISA_BASELINE = 0, /* the build's own target (x86-64: SSE2) */
    NERF__ISA_AVX2 = 1,     /* AVX2 and FMA */
    NERF__ISA_AVX512 = 2,   /* AVX-512 F (with AVX2 and FMA) */
};

/* The instruction set the library's kernels use: the processor's, capped
 * by NERF_ISA.  NERF__ISA_BASELINE on other processors than x86-64. */
int nerf__isa(void);

/* What the processor runs, whatever NERF_ISA says. */
int nerf__isa_cpu(void);

/* "avx512", "avx2" or "baseline". */
const char *nerf__isa_name(int isa);

/* NERF_FUSED: 0 or 1, or -1 when unset (the library decides). */
int nerf__fused_override(void);

/* NERF_FP32_PRODUCTS=onednn: 1, else 0. */
int nerf__fp32_onednn_override(void);

/*
 * What the variables above asked for and what was ignored, in a few
 * words for nerf_build_info(): "" when none is set.  Static.
 */
const char *nerf__dispatch_overrides(void);

#endif
