/*
 * What the marching tests share: a march of a ray set, count and fill, into
 * buffers of their own.  Include after defining N_RAYS.
 */
#ifndef NERF_TESTS_MARCH_FIXTURE_H
#define NERF_TESTS_MARCH_FIXTURE_H

#include <stdlib.h>

#include "march.h"

typedef struct marched {
    size_t offsets[N_RAYS + 1];
    size_t total;
    float *t, *dt, *xyz;
} marched;

static void march(const nerf__occupancy *g, const nerf__march_options *o,
                  const nerf__march_rays *rays, marched *m)
{
    m->total = nerf__march_count(g, o, rays, m->offsets);
    m->t = malloc((m->total + 1) * sizeof(float));
    m->dt = malloc((m->total + 1) * sizeof(float));
    m->xyz = malloc((3 * m->total + 1) * sizeof(float));
    nerf__march_fill(g, o, rays, m->offsets, m->t, m->dt, NULL);
    nerf__march_points(o, rays, m->offsets, m->t, m->xyz);
}

static void unmarch(marched *m)
{
    free(m->t);
    free(m->dt);
    free(m->xyz);
}

#endif
