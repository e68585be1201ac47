#include "matmul_name.h"

#include <string.h>

#include <nerf.h>

static const char *const names[] = {
    [NERF_MATMUL_FP32] = "fp32",
    [NERF_MATMUL_BF16] = "bf16",
    [NERF_MATMUL_FP32_ONEDNN] = "fp32-onednn",
};

int matmul_parse(const char *name)
{
    for (int k = 0; k < (int)(sizeof names / sizeof names[0]); k++) {
        if (strcmp(name, names[k]) == 0) {
            return k;
        }
    }
    return -1;
}

const char *matmul_name(uint32_t kind)
{
    return kind < sizeof names / sizeof names[0] ? names[kind] : "unknown";
}
