/*
 * Ray marching through an occupancy grid (instant-ngp's sampler).
 *
 * Along ray o + t d, samples sit on the lattice
 *   t_k = t_start + u dt_t + k dt_t,   k = 0, 1, ...
 * with t_start = max(near, entry into the bound), u = 0 or, with jitter,
 * a uniform in [0, 1) per ray, and dt_t = step / |d| (step is a world
 * distance, so the sample spacing in space is the same for every ray).
 * Only lattice points with t < min(far, exit from the bound) that fall in
 * an occupied cell (nerf__occupancy_occupied) are kept, at most
 * max_samples of them.  Each lattice point kept is tested by that rule
 * on its own world point, so no sample ever lies in an empty cell.  From
 * a point in an empty cell the ray is walked through the grid (empty
 * 8^3 blocks a block at a time, empty cells of occupied blocks a cell at
 * a time, a DDA in lattice units) to the next occupied cell, and the
 * march resumes at the first lattice point past the entry into it less
 * 1/16 of a step, a margin that keeps rounding at the faces from jumping
 * over a point.  So the samples are exactly the lattice points in
 * occupied cells, with or without skipping (skip_empty = false keeps every
 * lattice point inside the bound, for reference renders).
 *
 * Step: instant-ngp marches its unit cube in steps of sqrt(3) / 1024, 1024
 * steps across the diagonal; nerf__march_step(lo, hi, 1024) keeps that
 * rule for any bound: step = |hi - lo| / 1024.  For the Blender bound
 * [-1.5, 1.5]^3 that is 0.0051, about 4.4 steps per cell of a 128^3 grid
 * along an axis.
 *
 * Output is packed: the samples of ray k are entries offsets[k] ..
 * offsets[k + 1] - 1 of t (ray parameter, so the point is o + t d) and dt
 * (the world length each sample stands for, step, which is what
 * compositing takes as delta).  Marching is two passes over the same
 * per-ray loop, count then fill, so the layout is fixed before any sample
 * is written and does not depend on threads; both passes run over the
 * thread pool by rays.  (nerf__march_run() marches each ray once into a
 * slot of its own instead and continues the few that fill it, with the
 * same result.)  No memory is allocated except by nerf__march_run(),
 * which grows reusable buffers.
 *
 * Contracted spaces (options.contract = inner > 0; space.h's CONTRACT):
 * the grid lies over contracted space, [-2 inner, 2 inner]^3, and a
 * sample's cell is that of its contracted point.  A straight ray is curved
 * there, and evenly spaced world samples would put hundreds in one far
 * cell, so the lattice is even in a warped distance s instead of t.  With
 * u = t |d| the world distance along the ray, u0 the start and u_c the
 * ray's exit from the cube [-inner, inner]^3 (u0 if it misses the cube):
 *   s(u) = u                              for u <= u_c,
 *   s(u) = u_c + D - D^2 / (u + a)        beyond, D = u_c + a,
 * with a = max-norm of the ray's origin.  s is continuous with slope 1 at
 * u_c, and its slope D^2 / (u + a)^2 falls as the contraction's radial
 * scale inner^2 / r^2 does for a ray leaving the centre (r ~ u + a), so
 * the samples come out about evenly spaced in contracted space: a ray from
 * inside the cube to infinity has about D / step of them beyond the cube.
 * Lattice point k sits at s = u0 + (k + jitter) step; its dt is the world
 * length step ds/du stands for.  Inside the cube, from an origin inside
 * it, contraction is the identity and the march is the linear one above,
 * empty-space skipping included; beyond, each lattice point's cell is
 * tested in turn.
 */
#ifndef NERF_SAMPLING_MARCH_H
#define NERF_SAMPLING_MARCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "env.h"
#include "occupancy.h"

typedef struct nerf__march_options {
    /* World distance between samples, > 0.  A ray whose path through
     * the bound is 2^24 steps or more gets no samples. */
    float step;
    uint32_t max_samples;  /* per ray; 0 = no limit */
    bool skip_empty;       /* false: keep every lattice point in the bound */
    bool jitter;           /* random offset per ray (training) */
    /* The offset of ray first_ray + k comes from the stream keyed by
     * (seed, iteration, first_ray + k): a training step passes its step
     * number so every step draws afresh, and reruns draw the same. */
    uint64_t seed;
    uint64_t iteration;
    /* > 0: the grid lies over contracted space (see above) with this
     * half side of the uncontracted cube; 0: over world space. */
    float contract;
} nerf__march_options;

/* Defaults for grid g: step nerf__march_step(lo, hi, 1024), no limit,
 * skipping, no jitter, seed 0. */
void nerf__march_defaults(nerf__march_options *o, const nerf__occupancy *g);

typedef struct nerf__march_rays {
    size_t n;
    const float *origins;   /* [n, 3] */
    const float *dirs;      /* [n, 3], any non-zero length */
    const float *near;      /* [n]; NULL: near_all for every ray */
    const float *far;       /* [n]; NULL: far_all for every ray */
    float near_all, far_all;
    uint64_t first_ray;     /* ray k draws from stream first_ray + k */
    /* [n]: the lattice index k each ray starts from (NULL: 0), to continue
     * a march that max_samples cut (see nerf__march_fill's next_step). */
    const uint32_t *first_step;
} nerf__march_rays;

/* next_step of a ray that has no samples left. */
#define NERF__MARCH_DONE UINT32_MAX

/*
 * Pass 1: offsets[n + 1] receives the prefix sums of the per-ray counts
 * (offsets[0] = 0); returns the total.
 */
size_t nerf__march_count(const nerf__occupancy *g,
                         const nerf__march_options *o,
                         const nerf__march_rays *rays, size_t *offsets);

/*
 * Pass 2: the samples into t[total] and dt[total] at the offsets of the
 * count pass of the same arguments (the grid unchanged in between).
 * next_step[n] (may be NULL) receives, for a ray cut by max_samples, the
 * lattice index after its last sample, and NERF__MARCH_DONE for the
 * others: marching again from there (first_step) continues with exactly
 * the samples an uncut march would have produced next.  A renderer
 * marches a few samples per ray, evaluates and composites them, and
 * continues only the rays that are not yet opaque.
 */
void nerf__march_fill(const nerf__occupancy *g, const nerf__march_options *o,
                      const nerf__march_rays *rays, const size_t *offsets,
                      float *t, float *dt, uint32_t *next_step);

/* Sample positions o + t d in the grid's space (contracted with
 * o->contract), xyz[total, 3], computed exactly as the marcher computed
 * them for their occupancy test. */
void nerf__march_points(const nerf__march_options *o,
                        const nerf__march_rays *rays, const size_t *offsets,
                        const float *t, float *xyz);

/* Packed samples in buffers that grow on demand and are reused. */
typedef struct nerf__march_samples {
    size_t n_rays, total;
    size_t *offsets;        /* [n_rays + 1] */
    float *t, *dt;          /* [total] */
    uint32_t *next_step;    /* [n_rays] (see nerf__march_fill) */
    /* private: the one-walk march's slots and its per-ray counts */
    nerf__env env;
    size_t cap_rays, cap_samples, cap_slots;
    float *slot_t, *slot_dt;
    uint32_t *slot_count;   /* [n_rays] */
    size_t *more;           /* [n_rays + 1]: the counts past the slots,
                             * then where those samples go */
} nerf__march_samples;

void nerf__march_samples_init(nerf__march_samples *s, const nerf__env *env);
void nerf__march_samples_release(nerf__march_samples *s);

/*
 * The samples of rays into s: the packed layout of count and fill, bit for
 * bit, in about half their marching.  Each ray is marched once into a slot
 * of its own, of max_samples when rays times max_samples is at most
 * NERF__MARCH_ONE_PASS_ROOM (a renderer's rounds of a few samples a ray),
 * else of NERF__MARCH_SLOT_ROOM; the rays that fill a slot short of
 * max_samples are then counted and filled from where their slot stopped,
 * and the slots packed around them.  A batch whose slots would exceed
 * NERF__MARCH_SLOT_CAP samples is counted, then filled.  NERF_OK or
 * NERF_ENOMEM (s then holds no batch).
 */
#define NERF__MARCH_ONE_PASS_ROOM 65536u
/* Most rays of a training batch have fewer samples than this (lego in
 * nerf-bench's fast steps: 35 a ray on average), so few are walked
 * twice. */
#define NERF__MARCH_SLOT_ROOM 64u
#define NERF__MARCH_SLOT_CAP (1u << 21)
int nerf__march_run(const nerf__occupancy *g, const nerf__march_options *o,
                    const nerf__march_rays *rays, nerf__march_samples *s);

#endif
