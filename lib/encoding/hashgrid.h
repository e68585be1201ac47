/*
 * Multiresolution hash-grid encoding (Mueller et al., "Instant Neural
 * Graphics Primitives with a Multiresolution Hash Encoding", 2022).
 *
 * Conventions of the hash grid (the paper's, not instant-ngp's code):
 * - Positions are mapped to the unit cube by the axis-aligned bound,
 *   u = (x - bound_min) / (bound_max - bound_min) per axis, and clamped to
 *   [0, 1] (NaN counts as 0), so samples outside the bound read the
 *   faces of the grid.  Resolutions count cells across the bound on
 *   each axis: the paper's N_max = 2048 is for a scene scaled into the
 *   unit cube, so for a bound of side s scene units it is 2048 / s cells
 *   per unit (scale N_max with s to keep a world-space resolution).  A
 *   bound that is not a cube gives cells that are not cubes.
 * - Level l has resolution N_l = floor(N_min * b^l) with
 *   b = exp((ln N_max - ln N_min) / (L - 1)), so N_0 = N_min and
 *   N_{L-1} = N_max exactly.  Its vertices sit at u * N_l = 0, 1, ..., N_l
 *   (instant-ngp's code instead uses the scale N_min * b^l - 1 with a
 *   half-cell offset; the two differ only in where vertices fall).
 * - A level with (N_l + 1)^3 <= T vertices is stored densely, vertex
 *   (i, j, k) at entry i + (N_l + 1) (j + (N_l + 1) k); any other level
 *   holds T = 2^log2_table entries addressed by the paper's hash
 *   (i * 1 ^ j * 2654435761 ^ k * 805459861) mod T in 32-bit arithmetic.
 * - The table is level-major, each entry F contiguous floats, and the
 *   output of a sample is level-major too: [level 0 features, level 1
 *   features, ...].
 *
 * The table is a plain float array (one slice of a model's parameters);
 * these functions never allocate it.
 */
#ifndef NERF_ENCODING_HASHGRID_H
#define NERF_ENCODING_HASHGRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define NERF__HASHGRID_MAX_LEVELS 32
#define NERF__HASHGRID_MAX_FEATURES 8
#define NERF__HASHGRID_MAX_LOG2_TABLE 28
/* Positions are floats in [0, 1] scaled by N_l: beyond 2^20 cells the
 * interpolation weight would keep fewer than 4 bits. */
#define NERF__HASHGRID_MAX_RESOLUTION (1u << 20)

/* The paper's prime factors of the spatial hash, for y and z (x is 1). */
#define NERF__HASHGRID_PRIME_Y 2654435761u
#define NERF__HASHGRID_PRIME_Z 805459861u

typedef struct nerf__hashgrid {
    /* Configuration: filled by the caller (see nerf__hashgrid_defaults). */
    uint32_t levels;         /* L */
    uint32_t features;       /* F per level */
    uint32_t log2_table;     /* log2 T, entries of a hashed level */
    uint32_t min_resolution; /* N_min */
    uint32_t max_resolution; /* N_max */
    float bound_min[3], bound_max[3];

    /* Derived by nerf__hashgrid_layout. */
    uint32_t resolution[NERF__HASHGRID_MAX_LEVELS]; /* N_l */
    uint32_t entries[NERF__HASHGRID_MAX_LEVELS];    /* entries of level l */
    bool dense[NERF__HASHGRID_MAX_LEVELS];
    size_t offset[NERF__HASHGRID_MAX_LEVELS]; /* first float of level l */
    size_t count;                             /* floats in the table */
    float inv_extent[3];                      /* 1 / (max - min) */
} nerf__hashgrid;

/*
 * The paper's defaults (L 16, F 2, T 2^19, N 16..2048) over the given
 * bound, laid out.  Returns what nerf__hashgrid_layout returns (only the
 * bound can make it fail).
 */
int nerf__hashgrid_defaults(nerf__hashgrid *hg, const float bound_min[3],
                            const float bound_max[3]);

/*
 * Check the configuration and derive the per-level fields.  Returns
 * NERF_OK, or NERF_EINVAL with the thread's error message set.
 */
int nerf__hashgrid_layout(nerf__hashgrid *hg);

/* Floats per sample that the encoding writes: L * F. */
static inline uint32_t nerf__hashgrid_width(const nerf__hashgrid *hg)
{
    return hg->levels * hg->features;
}

/*
 * The paper's spatial hash of integer vertex (x, y, z), reduced to a
 * table of 2^log2_table entries.
 */
static inline uint32_t nerf__hashgrid_hash(uint32_t x, uint32_t y, uint32_t z,
                                           uint32_t log2_table)
{
    uint32_t h =
        x ^ (y * NERF__HASHGRID_PRIME_Y) ^ (z * NERF__HASHGRID_PRIME_Z);
    return h & ((1u << log2_table) - 1u);
}

/*
 * Entry index inside level l of integer vertex (x, y, z), each in
 * [0, N_l]: the dense index or the hash, whichever the level uses.
 */
uint32_t nerf__hashgrid_index(const nerf__hashgrid *hg, uint32_t level,
                              uint32_t x, uint32_t y, uint32_t z);

/*
 * Uniform in [-1e-4, 1e-4] (the paper's initialisation).  Level l draws
 * from the counter-based stream (seed, stream_base + l), so the values do
 * not depend on the order levels are visited.
 */
void nerf__hashgrid_init(const nerf__hashgrid *hg, float *table, uint64_t seed,
                         uint64_t stream_base);

/*
 * Encode n positions (rows of `in`, stride in_stride floats, 3 used) into
 * rows of `out` (stride out_stride >= L * F floats; the gap is not
 * touched).  Work is split by samples over up to `threads` threads (0 or 1:
 * the calling thread only; the others are created for the call and
 * joined); every output element is computed the same way whatever the
 * split, so the result does not depend on `threads`.
 */
void nerf__hashgrid_forward(const nerf__hashgrid *hg, const float *table,
                            size_t n, const float *in, size_t in_stride,
                            float *out, size_t out_stride, uint32_t threads);

/*
 * Backward of the forward for the same positions: adds
 * sum_samples d_out[s, l F + f] * weight(s, corner) into grad (same layout
 * as the table) at each corner the forward read.  Work is split by levels,
 * each level's gradients accumulated by one thread in sample order, so the
 * result is bit-identical for every thread count.
 */
void nerf__hashgrid_backward(const nerf__hashgrid *hg, size_t n,
                             const float *in, size_t in_stride,
                             const float *d_out, size_t d_stride, float *grad,
                             uint32_t threads);

/*
 * The building blocks of the two calls above, for callers with their own
 * threads: the forward of samples [begin, end) (in and out point at sample
 * 0), and the backward of all n samples at one level.  Distinct levels
 * write disjoint parts of grad, so levels may run concurrently.
 */
void nerf__hashgrid_forward_range(const nerf__hashgrid *hg, const float *table,
                                  size_t begin, size_t end, const float *in,
                                  size_t in_stride, float *out,
                                  size_t out_stride);
void nerf__hashgrid_backward_level(const nerf__hashgrid *hg, uint32_t level,
                                   size_t n, const float *in, size_t in_stride,
                                   const float *d_out, size_t d_stride,
                                   float *grad);

#endif
