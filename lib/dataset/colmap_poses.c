#include "colmap_poses.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void nerf__quat_to_matrix(const double q[4], double r[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = 1 - 2 * (y * y + z * z);
    r[1] = 2 * (x * y - z * w);
    r[2] = 2 * (x * z + y * w);
    r[3] = 2 * (x * y + z * w);
    r[4] = 1 - 2 * (x * x + z * z);
    r[5] = 2 * (y * z - x * w);
    r[6] = 2 * (x * z - y * w);
    r[7] = 2 * (y * z + x * w);
    r[8] = 1 - 2 * (x * x + y * y);
}

/* Shepperd's method: divide by the largest of the four candidates. */
void nerf__matrix_to_quat(const double r[9], double q[4])
{
    double tr = r[0] + r[4] + r[8];
    double d[4] = {tr, r[0], r[4], r[8]};
    int k = 0;
    for (int i = 1; i < 4; i++) {
        k = d[i] > d[k] ? i : k;
    }
    double s;
    if (k == 0) {
        s = 2.0 * sqrt(1.0 + tr);
        q[0] = 0.25 * s;
        q[1] = (r[7] - r[5]) / s;
        q[2] = (r[2] - r[6]) / s;
        q[3] = (r[3] - r[1]) / s;
    } else if (k == 1) {
        s = 2.0 * sqrt(1.0 + r[0] - r[4] - r[8]);
        q[0] = (r[7] - r[5]) / s;
        q[1] = 0.25 * s;
        q[2] = (r[1] + r[3]) / s;
        q[3] = (r[2] + r[6]) / s;
    } else if (k == 2) {
        s = 2.0 * sqrt(1.0 + r[4] - r[0] - r[8]);
        q[0] = (r[2] - r[6]) / s;
        q[1] = (r[1] + r[3]) / s;
        q[2] = 0.25 * s;
        q[3] = (r[5] + r[7]) / s;
    } else {
        s = 2.0 * sqrt(1.0 + r[8] - r[0] - r[4]);
        q[0] = (r[3] - r[1]) / s;
        q[1] = (r[2] + r[6]) / s;
        q[2] = (r[5] + r[7]) / s;
        q[3] = 0.25 * s;
    }
    double sign = q[0] < 0.0 ? -1.0 : 1.0;
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int i = 0; i < 4; i++) {
        q[i] *= sign / n;
    }
}

/*
 * R is world-to-camera, so the camera's axes in world space are the rows
 * of R (the columns of R^T) and its centre is -R^T t.  OpenCV's y and z
 * flip to give OpenGL's.
 */
void nerf__colmap_to_c2w(const double q[4], const double t[3],
                         double c2w[12])
{
    static const double flip[3] = {1.0, -1.0, -1.0};
    double r[9];
    nerf__quat_to_matrix(q, r);
    for (int row = 0; row < 3; row++) {
        for (int col = 0; col < 3; col++) {
            c2w[4 * row + col] = r[3 * col + row] * flip[col];
        }
        c2w[4 * row + 3] = -(r[row] * t[0] + r[3 + row] * t[1] +
                             r[6 + row] * t[2]);
    }
}

void nerf__c2w_to_colmap(const double c2w[12], double q[4], double t[3])
{
    static const double flip[3] = {1.0, -1.0, -1.0};
    double r[9];
    for (int row = 0; row < 3; row++) {
        for (int col = 0; col < 3; col++) {
            r[3 * row + col] = c2w[4 * col + row] * flip[row];
        }
    }
    for (int row = 0; row < 3; row++) {
        t[row] = -(r[3 * row] * c2w[3] + r[3 * row + 1] * c2w[7] +
                   r[3 * row + 2] * c2w[11]);
    }
    nerf__matrix_to_quat(r, q);
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, size_t n)
{
    qsort(v, n, sizeof *v, compare_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The rotation turning the unit vector u onto +z (Rodrigues' formula). */
static void rotation_to_z(const double u[3], double r[9])
{
    /* axis = u x z = (u1, -u0, 0), sin = |axis|, cos = u2 */
    double ax = u[1], ay = -u[0], c = u[2];
    double s = sqrt(ax * ax + ay * ay);
    memset(r, 0, 9 * sizeof *r);
    if (s < 1e-12) {
        /* Already +z, or -z: turn half a turn about x. */
        double f = c > 0.0 ? 1.0 : -1.0;
        r[0] = 1.0;
        r[4] = f;
        r[8] = f;
        return;
    }
    ax /= s;
    ay /= s;
    double k[9] = {0, 0, ay, 0, 0, -ax, -ay, ax, 0}; /* [axis]x */
    double k2[9];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            k2[3 * i + j] = k[3 * i] * k[j] + k[3 * i + 1] * k[3 + j] +
                            k[3 * i + 2] * k[6 + j];
        }
    }
    for (int i = 0; i < 9; i++) {
        r[i] = (i % 4 == 0 ? 1.0 : 0.0) + s * k[i] + (1.0 - c) * k2[i];
    }
}

void nerf__colmap_similarity(const double *poses, size_t n,
                             const double *points, size_t n_points,
                             double *scratch, nerf__similarity *out)
{
    for (int a = 0; a < 3; a++) {
        if (n_points >= 8) {
            for (size_t i = 0; i < n_points; i++) {
                scratch[i] = points[3 * i + a];
            }
            out->centre[a] = median(scratch, n_points);
        } else {
            double s = 0.0;
            for (size_t i = 0; i < n; i++) {
                s += poses[12 * i + 4 * a + 3];
            }
            out->centre[a] = s / (double)n;
        }
    }
    double up[3] = {0.0, 0.0, 0.0};
    for (size_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            up[a] += poses[12 * i + 4 * a + 1];
        }
    }
    double len = sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
    if (len > 1e-6 * (double)n) {
        for (int a = 0; a < 3; a++) {
            up[a] /= len;
        }
        rotation_to_z(up, out->rot);
    } else {
        /* The cameras agree on no up direction: keep COLMAP's axes. */
        memset(out->rot, 0, sizeof out->rot);
        out->rot[0] = out->rot[4] = out->rot[8] = 1.0;
    }
    double far = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d2 = 0.0;
        for (int a = 0; a < 3; a++) {
            double d = poses[12 * i + 4 * a + 3] - out->centre[a];
            d2 += d * d;
        }
        far = d2 > far ? d2 : far;
    }
    far = sqrt(far);
    /* One camera on the centre (a lone image): any scale is as good. */
    out->scale = far > 1e-9 ? 1.0 / far : 1.0;
}

void nerf__similarity_pose(const nerf__similarity *s, double c2w[12])
{
    double out[12];
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            out[4 * r + c] = s->rot[3 * r] * c2w[c] +
                             s->rot[3 * r + 1] * c2w[4 + c] +
                             s->rot[3 * r + 2] * c2w[8 + c];
        }
        double p = 0.0;
        for (int k = 0; k < 3; k++) {
            p += s->rot[3 * r + k] * (c2w[4 * k + 3] - s->centre[k]);
        }
        out[4 * r + 3] = s->scale * p;
    }
    memcpy(c2w, out, sizeof out);
}
