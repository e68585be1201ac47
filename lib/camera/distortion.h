/*
 * Lens distortion of nerf_camera: OpenCV's (Brown-Conrady) model with
 * radial k1, k2, k3 and tangential p1, p2, acting on normalised image
 * coordinates in OpenCV axes (x right, y down).  Pixels record distorted
 * coordinates; rays go through the undistorted ones.
 */
#ifndef NERF_CAMERA_DISTORTION_H
#define NERF_CAMERA_DISTORTION_H

#include <stdbool.h>

#include "nerf.h"

/*
 * The largest |coefficient| a camera may have.  Calibrated lenses stay
 * within a few units (strong wide-angle barrel: k1 about -0.5); the bound
 * only refuses garbage, as the limits of camera sanity do.
 */
#define NERF__DISTORTION_MAX_ABS 1e3

/* Newton iterations of the inverse, and when it stops early: a residual
 * under 1e-9 normalised units is far below a float ray's resolution
 * (6e-8 at the image edge), and costs at most one step more than 1e-7. */
#define NERF__UNDISTORT_ITERATIONS 20
#define NERF__UNDISTORT_TOLERANCE 1e-9

/* The five coefficients in the order of nerf_camera: k1, k2, p1, p2, k3. */
typedef struct nerf__lens {
    double k1, k2, p1, p2, k3;
} nerf__lens;

/* The camera's coefficients. */
void nerf__lens_of(const nerf_camera *cam, nerf__lens *lens);

/* Whether any coefficient is non-zero. */
bool nerf__lens_distorts(const nerf_camera *cam);

/*
 * Why coefficients cannot be used ("k1 is not finite", into buf), or NULL.
 * The order of k is that of nerf__lens.
 */
const char *nerf__lens_problem(const double k[5], char *buf, size_t size);

/* Undistorted normalised (x, y) to distorted (OpenCV axes). */
void nerf__distort(const nerf__lens *lens, double x, double y, double *xd,
                   double *yd);

/*
 * The inverse: the undistorted point whose distortion is (xd, yd), by
 * Newton's method on the 2x2 Jacobian from (xd, yd), with step halving
 * when a step would not reduce the residual.  Returns true when the
 * residual fell under NERF__UNDISTORT_TOLERANCE; otherwise (a point
 * beyond the fold of a strong barrel lens, which nothing distorts onto)
 * *x, *y are the iterate of smallest residual.
 */
bool nerf__undistort(const nerf__lens *lens, double xd, double yd, double *x,
                     double *y);

/*
 * Pixel coordinates (column, row; corners as the camera's flags say, so
 * that the ray of pixel floor(u), floor(v) passes through a point that
 * projects to its centre) of the world point p, through the camera's
 * lens.  Returns false for a point not in front of the camera.
 */
bool nerf__camera_project(const nerf_camera *cam, const double p[3],
                          double *u, double *v);

#endif
