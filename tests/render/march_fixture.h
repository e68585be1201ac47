/*
 * What the marching tests share: a march of a ray set, count and fill, into
 * buffers of their own.  Include after defining N_RAYS.
 */
#ifndef NERF_TESTS_MARCH_FIXTURE_H
#define NERF_TESTS_MARCH_FIXTURE_H

#include <stdlib.h>
#include <string.h>

#include "env.h"
#include "march.h"

typedef struct marched {
    size_t offsets[N_RAYS + 1];
    uint32_t next_step[N_RAYS];
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
    nerf__march_fill(g, o, rays, m->offsets, m->t, m->dt, m->next_step);
    nerf__march_points(o, rays, m->offsets, m->t, m->xyz);
}

static void unmarch(marched *m)
{
    free(m->t);
    free(m->dt);
    free(m->xyz);
}

/*
 * March rays again `piece` samples at a time, each piece resuming where
 * the last stopped, against the whole march `all` of the same rays and
 * options: returns the samples (t and dt) and resume points that differ,
 * 0 when the pieces give exactly the whole march; *pieces counts them.
 */
static size_t march_in_pieces(const nerf__occupancy *g,
                              nerf__march_options o, nerf__march_rays rays,
                              const marched *all, uint32_t piece,
                              size_t *pieces)
{
    static uint32_t step[N_RAYS];
    static size_t got[N_RAYS];
    memset(step, 0, sizeof step);
    memset(got, 0, sizeof got);
    nerf__env env;
    nerf__env_default(&env);
    nerf__march_samples ms;
    nerf__march_samples_init(&ms, &env);
    rays.first_step = step;
    o.max_samples = piece;
    size_t bad = 0;
    for (*pieces = 0; *pieces < 1000; ++*pieces) {
        if (nerf__march_run(g, &o, &rays, &ms) != NERF_OK) {
            bad++;
            break;
        }
        if (ms.total == 0) {
            break;
        }
        for (size_t k = 0; k < N_RAYS; k++) {
            size_t n = ms.offsets[k + 1] - ms.offsets[k];
            size_t full = all->offsets[k + 1] - all->offsets[k];
            if (got[k] + n > full) {
                bad++;
                continue;
            }
            const size_t at = all->offsets[k] + got[k];
            bad += memcmp(ms.t + ms.offsets[k], all->t + at,
                          n * sizeof(float)) != 0;
            bad += memcmp(ms.dt + ms.offsets[k], all->dt + at,
                          n * sizeof(float)) != 0;
            got[k] += n;
            /* Cut rays resume; finished ones say so. */
            bad += (n == piece) != (ms.next_step[k] != NERF__MARCH_DONE);
            step[k] = ms.next_step[k];
        }
    }
    for (size_t k = 0; k < N_RAYS; k++) {
        bad += got[k] != all->offsets[k + 1] - all->offsets[k];
    }
    nerf__march_samples_release(&ms);
    return bad;
}

/*
 * nerf__march_run() of rays (first_step: from[k], or 0 when from is NULL)
 * against count and fill of the same: returns the offsets, samples (t and
 * dt, bit for bit) and next steps that differ, 0 when they all agree;
 * *long_rays counts the rays with more than NERF__MARCH_SLOT_ROOM samples,
 * which the one walk continues.
 */
static size_t one_walk_differences(const nerf__occupancy *g,
                                   const nerf__march_options *o,
                                   nerf__march_rays rays,
                                   const uint32_t *from, size_t *long_rays)
{
    static marched m;
    *long_rays = 0;
    rays.first_step = from;
    march(g, o, &rays, &m);
    nerf__env env;
    nerf__env_default(&env);
    nerf__march_samples ms;
    nerf__march_samples_init(&ms, &env);
    size_t bad = nerf__march_run(g, o, &rays, &ms) != NERF_OK;
    if (!bad) {
        bad += ms.n_rays != rays.n || ms.total != m.total;
        bad += memcmp(ms.offsets, m.offsets, sizeof m.offsets) != 0;
        bad += memcmp(ms.next_step, m.next_step, sizeof m.next_step) != 0;
    }
    if (!bad) {
        bad += memcmp(ms.t, m.t, m.total * sizeof(float)) != 0;
        bad += memcmp(ms.dt, m.dt, m.total * sizeof(float)) != 0;
    }
    for (size_t k = 0; k < rays.n; k++) {
        const size_t n = m.offsets[k + 1] - m.offsets[k];
        *long_rays += n > NERF__MARCH_SLOT_ROOM;
    }
    nerf__march_samples_release(&ms);
    unmarch(&m);
    return bad;
}

#endif