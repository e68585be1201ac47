/*
 * The machine's peak fp32 multiply-add rate: independent chains of fused
 * multiply-adds in registers, on every thread of the library's pool at
 * once.  The widest vectors the CPU has are chosen at run time (AVX-512,
 * then AVX2 with FMA); a build for another architecture, or a CPU without
 * them, measures what the compiler makes of a portable loop, which is the
 * peak that build can reach.
 */
#include <string.h>

#include "nerf-bench.h"

/* Twelve chains: an FMA's latency (4 cycles) times two FMA ports, and a
 * margin, so that the chains never wait for each other. */
#define CHAINS 12

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define HAVE_X86_KERNELS 1

__attribute__((target("avx512f"))) static float fma_avx512(uint64_t iters)
{
    __m512 a[CHAINS];
    const __m512 x = _mm512_set1_ps(0.9999999f), y = _mm512_set1_ps(1e-7f);
    for (int c = 0; c < CHAINS; c++) {
        a[c] = _mm512_set1_ps(1.0f + (float)c);
    }
    for (uint64_t i = 0; i < iters; i++) {
        for (int c = 0; c < CHAINS; c++) {
            a[c] = _mm512_fmadd_ps(a[c], x, y);
        }
    }
    __m512 s = a[0];
    for (int c = 1; c < CHAINS; c++) {
        s = _mm512_add_ps(s, a[c]);
    }
    return _mm512_reduce_add_ps(s);
}

__attribute__((target("avx2,fma"))) static float fma_avx2(uint64_t iters)
{
    __m256 a[CHAINS];
    const __m256 x = _mm256_set1_ps(0.9999999f), y = _mm256_set1_ps(1e-7f);
    for (int c = 0; c < CHAINS; c++) {
        a[c] = _mm256_set1_ps(1.0f + (float)c);
    }
    for (uint64_t i = 0; i < iters; i++) {
        for (int c = 0; c < CHAINS; c++) {
            a[c] = _mm256_fmadd_ps(a[c], x, y);
        }
    }
    float out[8];
    __m256 s = a[0];
    for (int c = 1; c < CHAINS; c++) {
        s = _mm256_add_ps(s, a[c]);
    }
    _mm256_storeu_ps(out, s);
    return out[0] + out[1] + out[2] + out[3] + out[4] + out[5] + out[6] +
           out[7];
}
#endif

/* 8 lanes of CHAINS chains, for the compiler to vectorise as it can. */
static float fma_portable(uint64_t iters)
{
    float a[CHAINS][8];
    for (int c = 0; c < CHAINS; c++) {
        for (int l = 0; l < 8; l++) {
            a[c][l] = 1.0f + (float)c;
        }
    }
    for (uint64_t i = 0; i < iters; i++) {
        for (int c = 0; c < CHAINS; c++) {
            for (int l = 0; l < 8; l++) {
                a[c][l] = a[c][l] * 0.9999999f + 1e-7f;
            }
        }
    }
    float s = 0.0f;
    for (int c = 0; c < CHAINS; c++) {
        for (int l = 0; l < 8; l++) {
            s += a[c][l];
        }
    }
    return s;
}

typedef struct peak_job {
    float (*kernel)(uint64_t);
    uint64_t iters;
    float sink[64];
} peak_job;

static void peak_block(void *ctx, size_t block)
{
    peak_job *j = ctx;
    j->sink[block % 64] = j->kernel(j->iters);
}

double peak_gflops(const char **isa_out)
{
    float (*kernel)(uint64_t) = fma_portable;
    int lanes = 8;
    const char *isa = "portable C";
#ifdef HAVE_X86_KERNELS
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f")) {
        kernel = fma_avx512;
        lanes = 16;
        isa = "AVX-512";
    } else if (__builtin_cpu_supports("avx2") &&
               __builtin_cpu_supports("fma")) {
        kernel = fma_avx2;
        lanes = 8;
        isa = "AVX2+FMA";
    }
#endif
    *isa_out = isa;
    const size_t threads = nerf__parallel_threads();
    peak_job job;
    memset(&job, 0, sizeof job);
    job.kernel = kernel;
    job.iters = 1u << 16;
    /* Grow the run to a tenth of a second, then keep the best of three. */
    for (;;) {
        double t0 = now();
        nerf__parallel_blocks(threads, (size_t)1 << 30, peak_block, &job);
        if (now() - t0 >= 0.1 || job.iters >= ((uint64_t)1 << 40)) {
            break;
        }
        job.iters *= 2;
    }
    const double flops =
        2.0 * CHAINS * lanes * (double)job.iters * (double)threads;
    double best = 0.0;
    for (int run = 0; run < 3; run++) {
        double t0 = now();
        nerf__parallel_blocks(threads, (size_t)1 << 30, peak_block, &job);
        const double rate = flops / (now() - t0);
        best = rate > best ? rate : best;
    }
    return best * 1e-9;
}
