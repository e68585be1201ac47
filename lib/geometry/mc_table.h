/*
 * The marching-cubes case table, built at first use from the cube's
 * topology rather than written out: for each of the 256 inside/outside
 * patterns of a cube's corners, the triangles (as cube-edge triples) of
 * the surface crossing it.
 *
 * Corner c sits at (c & 1, c >> 1 & 1, c >> 2 & 1).  Edges 0..3 run
 * along x (from corners 0, 2, 4, 6), 4..7 along y (from 0, 1, 4, 5),
 * 8..11 along z (from 0, 1, 2, 3).  A corner is inside when its density
 * is above the threshold.
 *
 * On each face of the cube the crossing points are joined so that, on a
 * face with two diagonal inside corners, the inside corners are kept
 * apart.  The choice depends on the face's four corners only, so the two
 * cubes sharing a face always join its points alike and the surface has
 * no holes; the joined segments, followed round the cube, close into
 * loops that are fanned into triangles.  Triangles wind counter-clockwise
 * seen from outside the solid (their normals point to lower density).
 */
#ifndef NERF_GEOMETRY_MC_TABLE_H
#define NERF_GEOMETRY_MC_TABLE_H

#include <stdint.h>

/* At most 12 crossing points in a cube, each loop of k of them giving
 * k - 2 triangles. */
#define NERF__MC_MAX_TRIANGLES 10

typedef struct nerf__mc_case {
    uint8_t n_triangles;
    uint8_t edges[NERF__MC_MAX_TRIANGLES][3];
} nerf__mc_case;

/* The two corners of edge e (0..11), low corner first. */
void nerf__mc_edge_corners(int e, int *a, int *b);

/* The table, indexed by the pattern sum over inside corners c of 1 << c.
 * Built once, thread-safely, at the first call. */
const nerf__mc_case *nerf__mc_table(void);

/* Loops the table builder could not triangulate without a chord across a
 * face and fanned instead (0: the tests check it). */
int nerf__mc_table_fans(void);

#endif
