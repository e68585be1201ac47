/*
 * Rounding to bfloat16, shared by the bf16 backend and the fused passes
 * that feed it.  Plain C, so it exists in every build; only bf16 models
 * use it.
 */
#ifndef NERF_MLP_BF16_H
#define NERF_MLP_BF16_H

#include <stdint.h>
#include <string.h>

/*
 * Loops that round are compiled for AVX2 on x86: they only run for bf16
 * models, which exist only where the CPU has AVX512-BF16 (and so AVX2),
 * and AVX2 about doubles their speed over the baseline SSE2.
 */
#if defined(__GNUC__) && defined(__x86_64__)
#define NERF__BF16_WIDE __attribute__((target("avx2")))
#else
#define NERF__BF16_WIDE
#endif

/* Nearest bfloat16, ties to even; NaN stays a (quiet) NaN. */
static inline uint16_t nerf__bf16_from_float(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    if ((u & 0x7fffffffu) > 0x7f800000u) {
        return (uint16_t)((u >> 16) | 0x40u);
    }
    u += 0x7fffu + ((u >> 16) & 1u);
    return (uint16_t)(u >> 16);
}

#endif
