#include "matmul_name.h"

#include <string.h>

#include <nerf.h>

const opt_choice matmul_choices[] = {
    {.name = "fp32", .id = NERF_MATMUL_FP32},
    {.name = "bf16", .id = NERF_MATMUL_BF16},
    {.name = "fp32-onednn", .id = NERF_MATMUL_FP32_ONEDNN},
    {.name = NULL},
};

int matmul_parse(const char *name)
{
    for (const opt_choice *c = matmul_choices; c->name != NULL; c++) {
        if (strcmp(name, c->name) == 0) {
            return c->id;
        }
    }
    return -1;
}

const char *matmul_name(uint32_t kind)
{
    for (const opt_choice *c = matmul_choices; c->name != NULL; c++) {
        if ((uint32_t)c->id == kind) {
            return c->name;
        }
    }
    return "unknown";
}
