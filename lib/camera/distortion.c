/* OpenCV (Brown-Conrady) lens distortion and its iterative inverse. */
#include "distortion.h"

#include <math.h>
#include <stdio.h>

/* Halvings of a Newton step that would not reduce the residual. */
#define MAX_HALVINGS 8

void nerf__lens_of(const nerf_camera *cam, nerf__lens *lens)
{
    lens->k1 = cam->k1;
    lens->k2 = cam->k2;
    lens->p1 = cam->p1;
    lens->p2 = cam->p2;
    lens->k3 = cam->k3;
}

bool nerf__lens_distorts(const nerf_camera *cam)
{
    return cam->k1 != 0.0f || cam->k2 != 0.0f || cam->p1 != 0.0f ||
           cam->p2 != 0.0f || cam->k3 != 0.0f;
}

const char *nerf__lens_problem(const double k[5], char *buf, size_t size)
{
    static const char *const names[5] = {"k1", "k2", "p1", "p2", "k3"};
    for (int i = 0; i < 5; i++) {
        if (!isfinite(k[i])) {
            snprintf(buf, size, "distortion %s is not finite", names[i]);
            return buf;
        }
        if (!(fabs(k[i]) <= NERF__DISTORTION_MAX_ABS)) {
            snprintf(buf, size, "distortion %s %g is beyond +-%g", names[i],
                     k[i], NERF__DISTORTION_MAX_ABS);
            return buf;
        }
    }
    return NULL;
}

void nerf__distort(const nerf__lens *l, double x, double y, double *xd,
                   double *yd)
{
    double r2 = x * x + y * y;
    double radial = 1.0 + r2 * (l->k1 + r2 * (l->k2 + r2 * l->k3));
    *xd = x * radial + 2.0 * l->p1 * x * y + l->p2 * (r2 + 2.0 * x * x);
    *yd = y * radial + l->p1 * (r2 + 2.0 * y * y) + 2.0 * l->p2 * x * y;
}

/* Squared distance of (x, y)'s distortion from the target. */
static double residual(const nerf__lens *l, double x, double y, double xd,
                       double yd, double f[2])
{
    double dx, dy;
    nerf__distort(l, x, y, &dx, &dy);
    f[0] = dx - xd;
    f[1] = dy - yd;
    double e = f[0] * f[0] + f[1] * f[1];
    return isfinite(e) ? e : INFINITY;
}

bool nerf__undistort(const nerf__lens *l, double xd, double yd, double *x,
                     double *y)
{
    const double tol2 = NERF__UNDISTORT_TOLERANCE * NERF__UNDISTORT_TOLERANCE;
    double px = xd, py = yd, f[2];
    double e = residual(l, px, py, xd, yd, f);
    for (int it = 0; it < NERF__UNDISTORT_ITERATIONS && e > tol2; it++) {
        double r2 = px * px + py * py;
        double radial = 1.0 + r2 * (l->k1 + r2 * (l->k2 + r2 * l->k3));
        double g = l->k1 + r2 * (2.0 * l->k2 + 3.0 * r2 * l->k3);
        double a = radial + 2.0 * px * px * g + 2.0 * l->p1 * py +
                   6.0 * l->p2 * px;
        double b = 2.0 * px * py * g + 2.0 * l->p1 * px + 2.0 * l->p2 * py;
        double d = radial + 2.0 * py * py * g + 6.0 * l->p1 * py +
                   2.0 * l->p2 * px;
        double det = a * d - b * b; /* the Jacobian is symmetric */
        if (!(fabs(det) > 1e-300) || !isfinite(det)) {
            break; /* on the fold: no direction to go */
        }
        double sx = -(d * f[0] - b * f[1]) / det;
        double sy = -(a * f[1] - b * f[0]) / det;
        /* Past the fold of a strong barrel lens a full step can overshoot
         * onto the far branch; shorter steps keep to the near one. */
        bool moved = false;
        double lambda = 1.0;
        for (int h = 0; h <= MAX_HALVINGS && !moved; h++, lambda *= 0.5) {
            double nx = px + lambda * sx, ny = py + lambda * sy, nf[2];
            double ne = residual(l, nx, ny, xd, yd, nf);
            if (ne < e) {
                px = nx;
                py = ny;
                e = ne;
                f[0] = nf[0];
                f[1] = nf[1];
                moved = true;
            }
        }
        if (!moved) {
            break; /* a local minimum: the best iterate is where we are */
        }
    }
    *x = px;
    *y = py;
    return e <= tol2;
}

bool nerf__camera_project(const nerf_camera *cam, const double p[3],
                          double *u, double *v)
{
    const float *m = cam->c2w;
    double q[3];
    for (int c = 0; c < 3; c++) {
        /* R^T (p - t): the columns of R are the camera's axes. */
        q[c] = 0.0;
        for (int r = 0; r < 3; r++) {
            q[c] += (double)m[4 * r + c] * (p[r] - (double)m[4 * r + 3]);
        }
    }
    if (!(q[2] < 0.0)) {
        return false;
    }
    /* OpenGL camera axes (y up, looking down -z) to OpenCV's. */
    double x = q[0] / -q[2], y = -q[1] / -q[2], xd, yd;
    nerf__lens lens;
    nerf__lens_of(cam, &lens);
    nerf__distort(&lens, x, y, &xd, &yd);
    *u = cam->cx + cam->fx * xd;
    *v = cam->cy + cam->fy * yd;
    return true;
}
