/*
 * Scene spaces: where world points sit in the domain that a bounded
 * encoding (the hash grid) and the occupancy grid are laid over.
 *
 * - WORLD: no domain.  The frequency encoding of the reference networks
 *   reads world coordinates as they are, and every point may hold density.
 * - BOX: the axis-aligned box [lo, hi] (the Blender scenes' bound).  The
 *   domain is the box itself, in world units; a point outside it holds
 *   nothing (density 0), because a bounded encoding would only repeat the
 *   values of its faces along every ray leaving the box.
 * - NDC: a box too, but of normalised device coordinates: the sampler
 *   warps a forward-facing scene's rays into NDC before anything samples
 *   them (as the reference does), so the points the networks and the grid
 *   see are already NDC points.  Depth z spans [-1, 1] (near plane to
 *   infinity); x and y get a margin beyond the reference frustum's [-1, 1]
 *   because the other cameras of a capture see a little past it.
 * - CONTRACT: unbounded scenes.  The cube [-inner, inner]^3 is kept as it
 *   is and everything outside it is pulled into the shell up to
 *   [-2 inner, 2 inner]^3 by mip-NeRF 360's contraction taken in the
 *   max-norm: c(x) = (2 - inner / |x|) inner x / |x| with |x| = max_a |x_a|.
 *   The max-norm makes the image of space exactly the cube [lo, hi] that
 *   the grids cover (the Euclidean norm would leave their corners, 48% of
 *   the cube, unused).  The domain is the contracted space: the networks
 *   and the occupancy grid work on contracted points, and world points are
 *   mapped at the edges (the marcher, nerf_model_query) by
 *   nerf__space_to_domain().
 */
#ifndef NERF_SPACE_SPACE_H
#define NERF_SPACE_SPACE_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>

typedef enum nerf__space_kind {
    NERF__SPACE_WORLD = 0,
    NERF__SPACE_BOX = 1,
    NERF__SPACE_NDC = 2,
    NERF__SPACE_CONTRACT = 3,
} nerf__space_kind;

typedef struct nerf__space {
    uint32_t kind;      /* nerf__space_kind */
    float lo[3], hi[3]; /* the domain, lo < hi per axis (not WORLD) */
    float inner;        /* CONTRACT: half side of the uncontracted cube */
} nerf__space;

void nerf__space_world(nerf__space *s);

/* The cube [-half, half]^3. */
void nerf__space_cube(nerf__space *s, float half);

/* NDC: x and y within [-half, half], z within [-1, 1]. */
void nerf__space_ndc(nerf__space *s, float half);

/* Contraction of everything outside [-inner, inner]^3 into
 * [-2 inner, 2 inner]^3. */
void nerf__space_contract(nerf__space *s, float inner);

/* The max-norm max_a |p_a|. */
static inline float nerf__space_norm(const float *p)
{
    float r = fabsf(p[0]);
    r = fabsf(p[1]) > r ? fabsf(p[1]) : r;
    return fabsf(p[2]) > r ? fabsf(p[2]) : r;
}

/*
 * World point p to the domain point q (q may alias p): the contraction
 * for CONTRACT, the identity otherwise.  NaN stays NaN, and an infinite
 * coordinate gives NaN: both are outside every domain.
 */
static inline void nerf__space_to_domain(const nerf__space *s, const float *p,
                                         float *q)
{
    float f = 1.0f;
    if (s->kind == NERF__SPACE_CONTRACT) {
        const float r = nerf__space_norm(p);
        if (r > s->inner) {
            f = (2.0f - s->inner / r) * (s->inner / r);
        }
    }
    q[0] = p[0] * f;
    q[1] = p[1] * f;
    q[2] = p[2] * f;
}

/* Domain point q back to the world point p (the inverse of the above;
 * points on the outer faces of a CONTRACT domain map to infinity). */
void nerf__space_from_domain(const nerf__space *s, const float *q, float *p);

/*
 * Whether domain point p is in the domain.  Inclusive on both faces; NaN
 * is outside a box.  Inline: the network asks once per sample.
 */
static inline bool nerf__space_contains(const nerf__space *s, const float *p)
{
    if (s->kind == NERF__SPACE_WORLD) {
        return true;
    }
    for (int a = 0; a < 3; a++) {
        if (!(p[a] >= s->lo[a] && p[a] <= s->hi[a])) {
            return false;
        }
    }
    return true;
}

#endif
