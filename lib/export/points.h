/* The struct behind nerf_points. */
#ifndef NERF_EXPORT_POINTS_H
#define NERF_EXPORT_POINTS_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"

struct nerf_points {
    nerf__env env;
    size_t count;
    size_t capacity;
    float *positions; /* count x 3 */
    uint8_t *colours; /* count x 3 */
    float *normals;   /* count x 3; (0, 0, 0): none */
};

#endif
