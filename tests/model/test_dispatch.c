/*
 * The kernels the library picks, and the environment variables that pick
 * others (common/dispatch.h, docs/dispatch.md).  meson runs this program
 * under several settings of NERF_ISA, NERF_FUSED and NERF_FP32_PRODUCTS;
 * it works out from the processor and the variables, on its own, what the
 * library must have chosen.
 */
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "../harness.h"
#include "dispatch.h"
#include "gemm_onednn.h"
#include "model.h"
#include "smm.h"

/* The processor's level, asked the compiler's way. */
static int cpu_has(void)
{
#if defined(__x86_64__) && defined(__GNUC__)
    __builtin_cpu_init();
    if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) {
        return NERF__ISA_BASELINE;
    }
    return __builtin_cpu_supports("avx512f") ? NERF__ISA_AVX512
                                              : NERF__ISA_AVX2;
#else
    return NERF__ISA_BASELINE;
#endif
}

static const char *var(const char *name)
{
    const char *v = getenv(name);
    return v && v[0] ? v : NULL;
}

/* NERF_ISA's cap, or -1 when unset or not understood. */
static int isa_cap(void)
{
    const char *v = var("NERF_ISA");
    static const char *const names[] = {"baseline", "avx2", "avx512"};
    for (int i = 0; v && i < 3; i++) {
        if (strcasecmp(v, names[i]) == 0) {
            return i;
        }
    }
    return -1;
}

TEST(isa_follows_the_processor_and_the_cap)
{
    const int cpu = cpu_has(), cap = isa_cap();
    const int want = cap >= 0 && cap < cpu ? cap : cpu;
    printf("  processor %s, NERF_ISA %s: kernels %s\n", nerf__isa_name(cpu),
           var("NERF_ISA") ? var("NERF_ISA") : "unset",
           nerf__isa_name(nerf__isa()));
    CHECK_EQ_INT(nerf__isa_cpu(), cpu);
    CHECK_EQ_INT(nerf__isa(), want);
    /* The small products follow the same cap. */
    CHECK_EQ_INT(nerf__smm_supported(NERF__SMM_AVX2),
                 want >= NERF__ISA_AVX2);
    CHECK_EQ_INT(nerf__smm_supported(NERF__SMM_AVX512),
                 want >= NERF__ISA_AVX512);
    CHECK(nerf__smm_supported(NERF__SMM_PORTABLE));
}

TEST(fused_path_follows_nerf_fused)
{
    const int best = nerf__smm_best();
    const char *v = var("NERF_FUSED");
    int want = best >= NERF__SMM_AVX2 ? best : NERF__SMM_OFF;
    if (v && strcmp(v, "0") == 0) {
        want = NERF__SMM_OFF;
    } else if (v && strcmp(v, "1") == 0) {
        want = best;
    }
    CHECK_EQ_INT(nerf__smm_default(), want);
    CHECK_EQ_INT(nerf__smm_variant(), want);
}

/* Whether the library understands `value` for variable i of VARS. */
static const char *const VARS[] = {"NERF_ISA", "NERF_FUSED",
                                   "NERF_FP32_PRODUCTS"};

static int understood(int i, const char *value)
{
    static const char *const values[][4] = {
        {"baseline", "avx2", "avx512", NULL},
        {"0", "1", NULL, NULL},
        {"cblas", "onednn", NULL, NULL},
    };
    for (int k = 0; values[i][k]; k++) {
        if (strcasecmp(value, values[i][k]) == 0) {
            return 1;
        }
    }
    return 0;
}

/* nerf_build_info() names the kernels and every variable that was set,
 * marking those it did not understand. */
TEST(build_info_says_what_was_chosen)
{
    const char *info = nerf_build_info();
    char want[64];
    snprintf(want, sizeof want, "; kernels %s", nerf__isa_name(nerf__isa()));
    printf("  %s\n", info);
    CHECK(strstr(info, want) != NULL);
    for (int i = 0; i < 3; i++) {
        const char *v = var(VARS[i]);
        char said[96], ignored[112];
        snprintf(said, sizeof said, "%s=%s", VARS[i], v ? v : "");
        snprintf(ignored, sizeof ignored, "%s (ignored)", said);
        CHECK((v != NULL) == (strstr(info, said) != NULL));
        CHECK((v && !understood(i, v)) == (strstr(info, ignored) != NULL));
    }
    CHECK(info == nerf_build_info());
}

/* NERF_FP32_PRODUCTS=onednn moves fp32 models to oneDNN where it can,
 * and the model still says fp32. */
TEST(fp32_products_follow_the_variable)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_TINY));
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m == NULL) {
        return;
    }
    const char *v = var("NERF_FP32_PRODUCTS");
    const int asked = v && strcasecmp(v, "onednn") == 0;
    const int can = nerf__onednn_supported(NERF_MATMUL_FP32_ONEDNN, NULL);
    printf("  fp32 products: %s\n", m->onednn ? "oneDNN" : "CBLAS");
    CHECK_EQ_INT(m->onednn != NULL, asked && can);
    CHECK_EQ_INT(m->opts.matmul, NERF_MATMUL_FP32);
    nerf_model_destroy(m);
}

int main(void)
{
    RUN(isa_follows_the_processor_and_the_cap);
    RUN(fused_path_follows_nerf_fused);
    RUN(build_info_says_what_was_chosen);
    RUN(fp32_products_follow_the_variable);
    HARNESS_EXIT();
}
