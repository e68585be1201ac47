/* The least-squares fit of a point's colours to spherical harmonics. */
#include <math.h>

#include "bake.h"
#include "error.h"
#include "sh.h"

void nerf__bake_basis(uint32_t degree, const float d[3], float *y)
{
    /* The encoding counts bands, not the degree. */
    nerf__sh_forward(degree + 1, 1, d, 3, y, NERF__BAKE_MAX_COEFS);
}

/* n directions on a Fibonacci spiral over the cap within max_angle of
 * -z: each covers about the same area of it, so no view direction in the
 * cap is far from a fitted one. */
static void spiral(uint32_t n, double max_angle, float *dirs)
{
    const double golden = 3.14159265358979323846 * (3.0 - sqrt(5.0));
    const double height = 1.0 - cos(max_angle);
    for (uint32_t i = 0; i < n; i++) {
        double z = -1.0 + height * (i + 0.5) / n;
        double r = sqrt(1.0 - z * z);
        double phi = golden * i;
        dirs[3 * i] = (float)(r * cos(phi));
        dirs[3 * i + 1] = (float)(r * sin(phi));
        dirs[3 * i + 2] = (float)z;
    }
}

/* In place: the Cholesky factor L of the m x m matrix a (lower half), or
 * false when a is not positive definite enough to invert. */
static bool cholesky(double *a, uint32_t m)
{
    for (uint32_t j = 0; j < m; j++) {
        double s = a[j * m + j];
        for (uint32_t p = 0; p < j; p++) {
            s -= a[j * m + p] * a[j * m + p];
        }
        if (!(s > 1e-9)) {
            return false;
        }
        a[j * m + j] = sqrt(s);
        for (uint32_t i = j + 1; i < m; i++) {
            double t = a[i * m + j];
            for (uint32_t p = 0; p < j; p++) {
                t -= a[i * m + p] * a[j * m + p];
            }
            a[i * m + j] = t / a[j * m + j];
        }
    }
    return true;
}

int nerf__bake_fit_init(const nerf__env *env, uint32_t degree,
                        uint32_t n_dirs, double max_angle, float **dirs_out,
                        float **proj_out)
{
    const uint32_t m = (degree + 1) * (degree + 1);
    float *dirs = nerf__alloc(env, (size_t)n_dirs * 3 * sizeof(float));
    float *proj = nerf__alloc(env, (size_t)m * n_dirs * sizeof(float));
    double *y = nerf__alloc(env, (size_t)n_dirs * NERF__BAKE_MAX_COEFS *
                                     sizeof(double));
    if (dirs == NULL || proj == NULL || y == NULL) {
        nerf__free(env, dirs);
        nerf__free(env, proj);
        nerf__free(env, y);
        return NERF_ENOMEM;
    }
    spiral(n_dirs, max_angle, dirs);
    for (uint32_t d = 0; d < n_dirs; d++) {
        float yf[NERF__BAKE_MAX_COEFS];
        nerf__bake_basis(degree, dirs + 3 * d, yf);
        for (uint32_t k = 0; k < m; k++) {
            y[d * NERF__BAKE_MAX_COEFS + k] = yf[k];
        }
    }
    /* Normal equations: (Y^T Y) c = Y^T rgb, so proj = (Y^T Y)^-1 Y^T. */
    double a[NERF__BAKE_MAX_COEFS * NERF__BAKE_MAX_COEFS];
    for (uint32_t i = 0; i < m; i++) {
        for (uint32_t j = 0; j < m; j++) {
            double s = 0.0;
            for (uint32_t d = 0; d < n_dirs; d++) {
                s += y[d * NERF__BAKE_MAX_COEFS + i] *
                     y[d * NERF__BAKE_MAX_COEFS + j];
            }
            a[i * m + j] = s;
        }
    }
    int rc = NERF_OK;
    if (!cholesky(a, m)) {
        rc = nerf__error(NERF_EINVAL, "nerf_bake_create: %u directions do "
                         "not determine spherical harmonics of degree %u",
                         (unsigned)n_dirs, (unsigned)degree);
    }
    for (uint32_t d = 0; rc == NERF_OK && d < n_dirs; d++) {
        /* Solve L L^T x = y_d: column d of proj. */
        double x[NERF__BAKE_MAX_COEFS];
        for (uint32_t i = 0; i < m; i++) {
            double t = y[d * NERF__BAKE_MAX_COEFS + i];
            for (uint32_t p = 0; p < i; p++) {
                t -= a[i * m + p] * x[p];
            }
            x[i] = t / a[i * m + i];
        }
        for (uint32_t i = m; i-- > 0;) {
            double t = x[i];
            for (uint32_t p = i + 1; p < m; p++) {
                t -= a[p * m + i] * x[p];
            }
            x[i] = t / a[i * m + i];
        }
        for (uint32_t i = 0; i < m; i++) {
            proj[(size_t)i * n_dirs + d] = (float)x[i];
        }
    }
    nerf__free(env, y);
    if (rc != NERF_OK) {
        nerf__free(env, dirs);
        nerf__free(env, proj);
        return rc;
    }
    *dirs_out = dirs;
    *proj_out = proj;
    return NERF_OK;
}
