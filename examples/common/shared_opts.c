#include "shared_opts.h"

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
