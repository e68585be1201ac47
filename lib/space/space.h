/*
 * Scene spaces: where world points sit in the domain that a bounded
 * encoding (the hash grid) and the occupancy grid are laid over.
 *
 * Two kinds exist today:
 * - WORLD: no domain.  The frequency encoding of the reference networks
 *   reads world coordinates as they are, and every point may hold density.
 * - BOX: the axis-aligned box [lo, hi] (the Blender scenes' bound).  The
 *   domain is the box itself, in world units; a point outside it holds
 *   nothing (density 0), because a bounded encoding would only repeat the
 *   values of its faces along every ray leaving the box.
 *
 * The network asks its space whether a point is in the domain, and the
 * model lays its hash grid and occupancy grid over the space's box, so the
 * spaces still to come (NDC for forward-facing captures, a contraction of
 * the far field for unbounded ones) slot in here: each maps world points
 * into its box, and the encoding, the grid and the marcher see only the
 * box.
 */
#ifndef NERF_SPACE_SPACE_H
#define NERF_SPACE_SPACE_H

#include <stdbool.h>
#include <stdint.h>

typedef enum nerf__space_kind {
    NERF__SPACE_WORLD = 0,
    NERF__SPACE_BOX = 1,
} nerf__space_kind;

typedef struct nerf__space {
    uint32_t kind;      /* nerf__space_kind */
    float lo[3], hi[3]; /* BOX: the domain, lo < hi per axis */
} nerf__space;

void nerf__space_world(nerf__space *s);

/* The cube [-half, half]^3. */
void nerf__space_cube(nerf__space *s, float half);

/*
 * Whether point p is in the domain.  Inclusive on both faces; NaN is
 * outside a box.  Inline: the network asks once per sample.
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
