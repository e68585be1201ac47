#include "llff_poses.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TWO_PI 6.28318530717958647692

/* The reference's constants: smallest bound maps to 1/BOUND_FACTOR. */
#define BOUND_FACTOR 0.75
#define SPIRAL_TURNS 2.0
#define SPIRAL_ZRATE 0.5

static void normalize3(double v[3])
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (n > 0.0) {
        v[0] /= n;
        v[1] /= n;
        v[2] /= n;
    }
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/*
 * The camera frame looking back along z with the given rough up vector:
 * x = normalize(up x z), y = normalize(z x x).
 */
static void view_matrix(const double z_in[3], const double up[3],
                        const double pos[3], double out[12])
{
    double z[3] = {z_in[0], z_in[1], z_in[2]};
    double x[3], y[3];
    normalize3(z);
    cross3(up, z, x);
    normalize3(x);
    cross3(z, x, y);
    normalize3(y);
    for (int r = 0; r < 3; r++) {
        out[4 * r + 0] = x[r];
        out[4 * r + 1] = y[r];
        out[4 * r + 2] = z[r];
        out[4 * r + 3] = pos[r];
    }
}

void nerf__llff_row_pose(const double *row, double c2w[12])
{
    /* row holds the 3x5 matrix row-major: element (r, c) at 5 r + c. */
    for (int r = 0; r < 3; r++) {
        const double *m = row + 5 * r;
        c2w[4 * r + 0] = m[1];
        c2w[4 * r + 1] = -m[0];
        c2w[4 * r + 2] = m[2];
        c2w[4 * r + 3] = m[3];
    }
}

void nerf__llff_average_pose(const double *poses, size_t n, double out[12])
{
    double centre[3] = {0.0, 0.0, 0.0}, z[3] = {0.0, 0.0, 0.0};
    double up[3] = {0.0, 0.0, 0.0};
    for (size_t i = 0; i < n; i++) {
        const double *p = poses + 12 * i;
        for (int r = 0; r < 3; r++) {
            centre[r] += p[4 * r + 3];
            z[r] += p[4 * r + 2];
            up[r] += p[4 * r + 1];
        }
    }
    for (int r = 0; r < 3; r++) {
        centre[r] /= (double)n;
    }
    view_matrix(z, up, centre, out);
}

double nerf__llff_normalize(double *poses, double *bounds, size_t n)
{
    double lo = bounds[0];
    for (size_t i = 1; i < 2 * n; i++) {
        lo = bounds[i] < lo ? bounds[i] : lo;
    }
    double scale = 1.0 / (lo * BOUND_FACTOR);
    for (size_t i = 0; i < n; i++) {
        for (int r = 0; r < 3; r++) {
            poses[12 * i + 4 * r + 3] *= scale;
        }
        bounds[2 * i] *= scale;
        bounds[2 * i + 1] *= scale;
    }
    /*
     * The average pose is a rigid transform (orthonormal rotation A, centre
     * c), so its inverse is [A^T | -A^T c]: apply that to every pose.
     */
    double avg[12];
    nerf__llff_average_pose(poses, n, avg);
    for (size_t i = 0; i < n; i++) {
        double *p = poses + 12 * i;
        double q[12];
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 4; c++) {
                double s = 0.0;
                for (int k = 0; k < 3; k++) {
                    double v = p[4 * k + c];
                    if (c == 3) {
                        v -= avg[4 * k + 3];
                    }
                    s += avg[4 * k + r] * v;
                }
                q[4 * r + c] = s;
            }
        }
        memcpy(p, q, sizeof q);
    }
    return scale;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* NumPy's default percentile: linear interpolation between order stats. */
static double percentile(double *v, size_t n, double q)
{
    qsort(v, n, sizeof *v, compare_double);
    double pos = q * (double)(n - 1);
    size_t lo = (size_t)floor(pos);
    size_t hi = lo + 1 < n ? lo + 1 : lo;
    return v[lo] + (v[hi] - v[lo]) * (pos - (double)lo);
}

void nerf__llff_spiral_setup(const double *poses, const double *bounds,
                             size_t n, double *scratch, nerf__spiral *out)
{
    nerf__llff_average_pose(poses, n, out->c2w);
    double up[3] = {0.0, 0.0, 0.0};
    double lo = bounds[0], hi = bounds[0];
    for (size_t i = 0; i < n; i++) {
        for (int r = 0; r < 3; r++) {
            up[r] += poses[12 * i + 4 * r + 1];
        }
        for (int k = 0; k < 2; k++) {
            double b = bounds[2 * i + k];
            lo = b < lo ? b : lo;
            hi = b > hi ? b : hi;
        }
    }
    normalize3(up);
    memcpy(out->up, up, sizeof up);
    /*
     * Focus on a depth between the closest content (0.9 x nearest bound)
     * and "infinity" (5 x farthest), weighted 3:1 towards infinity in
     * disparity, as the reference does.
     */
    double close_depth = lo * 0.9, inf_depth = hi * 5.0, dt = 0.75;
    out->focus = 1.0 / ((1.0 - dt) / close_depth + dt / inf_depth);
    for (int r = 0; r < 3; r++) {
        for (size_t i = 0; i < n; i++) {
            scratch[i] = fabs(poses[12 * i + 4 * r + 3]);
        }
        out->radii[r] = percentile(scratch, n, 0.9);
    }
}

/* out = M (3x4) applied to the homogeneous point p. */
static void transform_point(const double m[12], const double p[4],
                            double out[3])
{
    for (int r = 0; r < 3; r++) {
        out[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] +
                 m[4 * r + 3] * p[3];
    }
}

void nerf__llff_spiral_pose(const nerf__spiral *s, uint32_t index,
                            uint32_t n_views, double c2w[12])
{
    double theta = TWO_PI * SPIRAL_TURNS * (double)index / (double)n_views;
    double local[4] = {cos(theta) * s->radii[0], -sin(theta) * s->radii[1],
                       -sin(theta * SPIRAL_ZRATE) * s->radii[2], 1.0};
    double target_local[4] = {0.0, 0.0, -s->focus, 1.0};
    double centre[3], target[3], z[3];
    transform_point(s->c2w, local, centre);
    transform_point(s->c2w, target_local, target);
    for (int r = 0; r < 3; r++) {
        z[r] = centre[r] - target[r];
    }
    view_matrix(z, s->up, centre, c2w);
}
