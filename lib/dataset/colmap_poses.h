/*
 * Pose arithmetic between COLMAP's convention (world-to-camera Hamilton
 * quaternion qw qx qy qz and translation t, OpenCV camera axes: x right,
 * y down, z forward) and the library's (3x4 camera-to-world, row-major,
 * OpenGL axes: x right, y up, z back), and the centring and scaling of a
 * COLMAP scene (docs/formats.md, "COLMAP").
 */
#ifndef NERF_DATASET_COLMAP_POSES_H
#define NERF_DATASET_COLMAP_POSES_H

#include <stddef.h>

/* Rotation matrix (row-major 3x3) of a unit quaternion w x y z. */
void nerf__quat_to_matrix(const double q[4], double r[9]);

/* Unit quaternion w x y z, w >= 0, of a rotation matrix. */
void nerf__matrix_to_quat(const double r[9], double q[4]);

/* COLMAP's (q, t) as a camera-to-world matrix in OpenGL axes. */
void nerf__colmap_to_c2w(const double q[4], const double t[3],
                         double c2w[12]);

/* The inverse: (q, t) of a camera-to-world matrix in OpenGL axes, whose
 * rotation must be orthonormal. */
void nerf__c2w_to_colmap(const double c2w[12], double q[4], double t[3]);

/*
 * The similarity that puts a COLMAP scene into the library's space,
 * x' = scale * rot (x - centre).
 */
typedef struct nerf__similarity {
    double centre[3];
    double rot[9];
    double scale;
} nerf__similarity;

/*
 * The rule of docs/formats.md: centre = the per-axis median of the sparse
 * points (n_points >= 8), else the mean camera position; rot turns the
 * cameras' mean up vector onto +z; scale puts the farthest camera at
 * distance 1 from the centre.  poses are n camera-to-world matrices,
 * points n_points xyz triples; scratch holds max(n, n_points) doubles.
 */
void nerf__colmap_similarity(const double *poses, size_t n,
                             const double *points, size_t n_points,
                             double *scratch, nerf__similarity *out);

/* Apply the similarity to a pose (rotation and position). */
void nerf__similarity_pose(const nerf__similarity *s, double c2w[12]);

#endif
