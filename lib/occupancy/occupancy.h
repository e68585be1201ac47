/*
 * Occupancy grid for ray marching (instant-ngp's density grid): R^3 cells
 * over an axis-aligned bound [lo, hi], each with an exponential moving
 * average of the density seen in it and one occupancy bit.  The marcher
 * (march.h) places no samples in cells whose bit is clear.
 *
 * Layout: cell (i, j, k), i along x, is index i + R (j + R k); its bit is
 * bit (index % 64) of word index / 64.  A coarse level keeps one bit per
 * block of 8^3 cells, set when any cell of the block is occupied, so that
 * the marcher crosses empty space a block at a time; it is derived from
 * the bits whenever they change here, which is why loading goes through
 * nerf__occupancy_restore().  Cell (i, j, k) covers
 * [lo + i h, lo + (i + 1) h) per axis with h = (hi - lo) / R.  A point is
 * mapped to its cell by one rule, nerf__occupancy_cell(), which every user
 * of the grid (the marcher included) shares, so "the sample's cell" means
 * the same thing everywhere.  Points outside the bound (and NaN) have no
 * cell and count as empty.
 *
 * Threshold.  A cell matters to a render only through the opacity it gives
 * one marching step, alpha = 1 - exp(-sigma dt).  A cell is occupied when
 * that alpha could exceed alpha_min = 0.01, i.e. when its density exceeds
 *   sigma_min = -ln(1 - alpha_min) / dt,
 * with dt the marcher's step in world units (nerf__march_step()).  With
 * instant-ngp's step, sqrt(3)/1024 of a unit cube, this is 5.95 per unit,
 * the "0.01 * 1024 / sqrt(3)" = 5.91 instant-ngp uses (it takes alpha ~
 * sigma dt); in world units it scales with 1 / (bound size), e.g. 1.98 for
 * the [-1.5, 1.5]^3 bound of the Blender scenes.  As in instant-ngp, the
 * threshold applied is min(sigma_min, mean EMA over all cells), so that a
 * young network whose densities are all still small does not empty the
 * grid.
 *
 * A fresh grid has every bit set (and every EMA 0): a marcher used before
 * the first update samples the whole bound, and the first update, which
 * refreshes every occupied cell, refreshes them all.
 *
 * Queries and marches only read the grid and may run on any number of
 * threads at once, but not while an update, rebuild, reset or restore
 * writes it.
 */
#ifndef NERF_OCCUPANCY_OCCUPANCY_H
#define NERF_OCCUPANCY_OCCUPANCY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "env.h"

#define NERF__OCCUPANCY_MAX_RESOLUTION 1024u
/* Cells per block edge of the coarse level is 2^this. */
#define NERF__OCCUPANCY_BLOCK_SHIFT 3u
/* Steps across the bound's diagonal (instant-ngp's NERF_STEPS). */
#define NERF__MARCH_STEPS_DEFAULT 1024u
/* One step's opacity above which a cell is occupied. */
#define NERF__OCCUPANCY_ALPHA_DEFAULT 0.01f

/*
 * Density at n world points: xyz[n, 3] in, sigma_out[n] out (densities in
 * world units, >= 0; negative values are harmless, NaN is ignored).
 * Returns 0, or a nerf status to abort the update with.
 */
typedef int (*nerf__density_fn)(void *ctx, size_t n, const float *xyz,
                                float *sigma_out);

typedef struct nerf__occupancy_options {
    uint32_t resolution;     /* R, cells per axis (1 .. 1024); default 128 */
    float lo[3], hi[3];      /* the bound, lo < hi per axis */
    float decay;             /* EMA decay per update, (0, 1]; default 0.95 */
    /* Density above which a cell is occupied (world units).  Default:
     * nerf__occupancy_threshold(0.01, nerf__march_step(lo, hi, 1024)). */
    float density_threshold;
    uint64_t seed;           /* keys the jitter of the update points */
    size_t chunk;            /* points per density call; default 65536 */
} nerf__occupancy_options;

typedef struct nerf__occupancy {
    nerf__env env;
    nerf__occupancy_options opts;
    uint32_t res;
    size_t cells;            /* R^3 */
    size_t words;            /* ceil(R^3 / 64) */
    float lo[3], hi[3];
    float cell_size[3];      /* (hi - lo) / R */
    float inv_cell[3];       /* R / (hi - lo) */
    float *ema;              /* [cells] */
    uint64_t *bits;          /* [words]; bits past the last cell are 0 */
    uint32_t coarse_res;     /* ceil(R / 8) blocks per axis */
    uint64_t *coarse;        /* [ceil(coarse_res^3 / 64)] block bits */
    /* Updates done so far: the index of the next one, which keys its
     * random draws.  A checkpoint stores it with the EMA and bits. */
    uint64_t updates;
    /* Figures of the last update (or rebuild). */
    float mean;              /* mean EMA over all cells */
    float threshold;         /* min(density_threshold, mean) */
    size_t occupied;         /* cells whose bit is set */
    size_t evaluated;        /* cells whose density the update sampled */
    /* private scratch */
    uint64_t *sel;           /* [words] cells chosen for this update */
    uint32_t *chunk_cells;   /* [chunk] */
    float *chunk_xyz;        /* [chunk, 3] */
    float *chunk_sigma;      /* [chunk] */
    double *block_sum;       /* [blocks] */
    size_t blocks;
} nerf__occupancy;

/* World distance between marching samples: diagonal of the bound / steps. */
float nerf__march_step(const float lo[3], const float hi[3], uint32_t steps);

/* Density whose opacity over one step of length dt is alpha:
 * -ln(1 - alpha) / dt. */
float nerf__occupancy_threshold(float alpha, float dt);

/* Defaults (see nerf__occupancy_options) for the bound [lo, hi]. */
void nerf__occupancy_defaults(nerf__occupancy_options *o, const float lo[3],
                              const float hi[3]);

/*
 * A new grid, every cell occupied.  Memory: 4 R^3 bytes of EMA, R^3 / 4
 * bytes of bits and selection (R^3 / 2048 of coarse bits), 20 bytes per
 * chunk point.  Returns NERF_OK,
 * NERF_EINVAL (bad options) or NERF_ENOMEM, with the thread's error set.
 */
int nerf__occupancy_create(const nerf__env *env,
                           const nerf__occupancy_options *o,
                           nerf__occupancy **out);
void nerf__occupancy_destroy(nerf__occupancy *g);

/* Back to the fresh state: EMA 0, every bit set, update counter 0. */
void nerf__occupancy_reset(nerf__occupancy *g);

/*
 * One refresh of the grid, instant-ngp's schedule:
 *  - the cells sampled are every occupied cell plus each other cell with
 *    probability n_random / R^3 (so n_random of them in expectation;
 *    n_random >= R^3 samples every cell, as during warm-up);
 *  - a sampled cell takes the density at one point drawn uniformly inside
 *    it, from the stream keyed by (seed, update index, cell);
 *  - every cell's EMA becomes max(EMA * decay, new density), the new
 *    density of a cell not sampled counting as 0;
 *  - bit = EMA > min(density_threshold, mean EMA).
 * Densities are asked for in chunks of at most opts.chunk points, from the
 * calling thread, in increasing cell order; the result depends only on
 * the seed, the update index and the densities, not on threads.
 * If density() fails, its status is returned with the EMA of the cells
 * already refreshed updated and the rest unchanged; bits and the update
 * counter are unchanged.
 */
int nerf__occupancy_update(nerf__occupancy *g, nerf__density_fn density,
                           void *ctx, size_t n_random);

/*
 * Recompute the bits, mean and threshold from the EMA, as an update does
 * (all bits set while the update counter is 0).  For a checkpoint that
 * stores only the EMA and the counter.
 */
void nerf__occupancy_rebuild_bits(nerf__occupancy *g);

/* The state to serialise, with g->updates: the arrays in place and their
 * sizes in bytes (host byte order). */
static inline const float *nerf__occupancy_ema(const nerf__occupancy *g,
                                               size_t *bytes)
{
    *bytes = g->cells * sizeof(float);
    return g->ema;
}

static inline const uint64_t *nerf__occupancy_bits(const nerf__occupancy *g,
                                                   size_t *bytes)
{
    *bytes = g->words * sizeof(uint64_t);
    return g->bits;
}

/*
 * Load a saved state into a grid of the same resolution: the EMA, the
 * bits (NULL: rebuilt from the EMA, see nerf__occupancy_rebuild_bits) and
 * the update counter.  NERF_EFORMAT (nothing changed) if a size does not
 * match this grid's.
 */
int nerf__occupancy_restore(nerf__occupancy *g, const float *ema,
                            size_t ema_bytes, const uint64_t *bits,
                            size_t bits_bytes, uint64_t updates);

/*
 * The cell of world point p: true and *index set when p is inside the
 * bound.  Every query of the grid goes through this rule.
 */
static inline bool nerf__occupancy_cell(const nerf__occupancy *g,
                                        const float p[3], uint32_t ijk[3],
                                        size_t *index)
{
    const float r = (float)g->res;
    for (int a = 0; a < 3; a++) {
        float u = (p[a] - g->lo[a]) * g->inv_cell[a];
        /* Written so that NaN fails too. */
        if (!(u >= 0.0f && u < r)) {
            return false;
        }
        ijk[a] = (uint32_t)u;
    }
    *index = ijk[0] + (size_t)g->res * (ijk[1] + (size_t)g->res * ijk[2]);
    return true;
}

static inline bool nerf__occupancy_bit(const nerf__occupancy *g,
                                       size_t index)
{
    return (g->bits[index >> 6] >> (index & 63)) & 1u;
}

/* Whether the block holding cell ijk has any occupied cell. */
static inline bool nerf__occupancy_block_bit(const nerf__occupancy *g,
                                             const uint32_t ijk[3])
{
    const uint32_t s = NERF__OCCUPANCY_BLOCK_SHIFT;
    const size_t rc = g->coarse_res;
    size_t b = (ijk[0] >> s) + rc * ((ijk[1] >> s) + rc * (ijk[2] >> s));
    return (g->coarse[b >> 6] >> (b & 63)) & 1u;
}

/* Whether world point p lies in an occupied cell (false outside). */
static inline bool nerf__occupancy_occupied(const nerf__occupancy *g,
                                            const float p[3])
{
    uint32_t ijk[3];
    size_t index;
    return nerf__occupancy_cell(g, p, ijk, &index) &&
           nerf__occupancy_bit(g, index);
}

/* sigma[i] = 0 for each of the n points (points: [n, 3]) in a cell g
 * marks empty: what a march that skips those cells would have given them
 * (the marching render's test setting zero_empty). */
void nerf__occupancy_zero_empty(const nerf__occupancy *g, size_t n,
                                const float *points, float *sigma);

#endif
