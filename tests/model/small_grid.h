/*
 * The fast preset's shape at a size a unit test can afford: two hash-grid
 * levels of 2^10 entries up to resolution 32, so that the table's sparse
 * updates and the occupancy grid are in without 12 million parameters.
 */
#ifndef NERF_TEST_SMALL_GRID_H
#define NERF_TEST_SMALL_GRID_H

#include "nerf.h"

static inline void small_grid_options(nerf_model_options *o)
{
    NERF_MODEL_OPTIONS_INIT(o);
    nerf_model_options_preset(o, NERF_PRESET_FAST);
    o->hash_levels = 2;
    o->hash_log2_size = 10;
    o->hash_max_resolution = 32;
}

#endif
