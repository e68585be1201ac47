#include "dispatch.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define DISPATCH_X86 1
#endif

static struct {
    int isa_cpu;
    int isa;
    int fused;        /* -1: unset */
    int fp32_onednn;
    char said[160];   /* for nerf_build_info() */
} chosen;

static pthread_once_t once = PTHREAD_ONCE_INIT;

static int cpu_level(void)
{
#if defined(DISPATCH_X86)
    __builtin_cpu_init();
    const int avx2 = __builtin_cpu_supports("avx2") &&
                     __builtin_cpu_supports("fma");
    if (avx2 && __builtin_cpu_supports("avx512f")) {
        return NERF__ISA_AVX512;
    }
    return avx2 ? NERF__ISA_AVX2 : NERF__ISA_BASELINE;
#else
    return NERF__ISA_BASELINE;
#endif
}

/* Index of value in names (case-insensitive), or -1. */
static int lookup(const char *value, const char *const *names, int n)
{
    for (int i = 0; i < n; i++) {
        if (strcasecmp(value, names[i]) == 0) {
            return i;
        }
    }
    return -1;
}

/* Read one variable: its index among names, or fallback when unset; an
 * unknown value is noted in chosen.said and gives fallback too. */
static int read_var(const char *var, const char *const *names, int n,
                    int fallback)
{
    const char *value = getenv(var);
    if (value == NULL || value[0] == '\0') {
        return fallback;
    }
    const int i = lookup(value, names, n);
    const size_t used = strlen(chosen.said);
    /* A value too long for the note is cut: the note is for people. */
    snprintf(chosen.said + used, sizeof chosen.said - used, "%s%s=%.24s%s",
             used ? ", " : "", var, value, i < 0 ? " (ignored)" : "");
    return i < 0 ? fallback : i;
}

static void choose(void)
{
    static const char *const isas[] = {"baseline", "avx2", "avx512"};
    static const char *const flags[] = {"0", "1"};
    static const char *const products[] = {"cblas", "onednn"};
    chosen.isa_cpu = cpu_level();
    const int cap = read_var("NERF_ISA", isas, 3, NERF__ISA_AVX512);
    chosen.isa = cap < chosen.isa_cpu ? cap : chosen.isa_cpu;
    chosen.fused = read_var("NERF_FUSED", flags, 2, -1);
    chosen.fp32_onednn = read_var("NERF_FP32_PRODUCTS", products, 2, 0);
}

int nerf__isa(void)
{
    pthread_once(&once, choose);
    return chosen.isa;
}

int nerf__isa_cpu(void)
{
    pthread_once(&once, choose);
    return chosen.isa_cpu;
}

const char *nerf__isa_name(int isa)
{
    switch (isa) {
    case NERF__ISA_AVX512:
        return "avx512";
    case NERF__ISA_AVX2:
        return "avx2";
    default:
        return "baseline";
    }
}

int nerf__fused_override(void)
{
    pthread_once(&once, choose);
    return chosen.fused;
}

int nerf__fp32_onednn_override(void)
{
    pthread_once(&once, choose);
    return chosen.fp32_onednn;
}

const char *nerf__dispatch_overrides(void)
{
    pthread_once(&once, choose);
    return chosen.said;
}
