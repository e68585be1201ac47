#include "shared_opts.h"

#include <stdio.h>
#include <string.h>

#include "options.h"

const opt_choice split_choices[] = {
    {.name = "train", .id = NERF_SPLIT_TRAIN},
    {.name = "val", .id = NERF_SPLIT_VAL},
    {.name = "test", .id = NERF_SPLIT_TEST},
    {.name = NULL},
};

const opt_choice preset_choices[] = {
    {.name = "tiny", .id = NERF_PRESET_TINY},
    {.name = "reference", .id = NERF_PRESET_REFERENCE},
    {.name = "fast", .id = NERF_PRESET_FAST},
    {.name = NULL},
};

int opt_read_appearance(const char *program, const opt *o, const char *v)
{
    uint32_t *to = o->to;
    if (strcmp(v, "neutral") == 0) {
        *to = NERF_APPEARANCE_NEUTRAL;
        return 0;
    }
    uint64_t i = 0;
    if (cli_int_option(program, o->name, v, 0, NERF_APPEARANCE_IMAGE_MAX,
                       &i) != 0) {
        return -1;
    }
    *to = NERF_APPEARANCE_OF(i);
    return 0;
}

void appearance_text(const nerf_model *m, uint32_t which, char *buf,
                     size_t size)
{
    uint32_t n = 0;
    nerf_model_appearance_count(m, &n);
    if (n == 0) {
        snprintf(buf, size, "the model's own (it has no appearance codes)");
    } else if (which == NERF_APPEARANCE_NEUTRAL) {
        snprintf(buf, size, "neutral (the mean of the %u training images' "
                 "codes)", (unsigned)n);
    } else {
        snprintf(buf, size, "training image %u's code", (unsigned)which - 1);
    }
}
