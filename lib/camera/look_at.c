/* Camera poses from an eye, a target and an up direction. */
#include <math.h>
#include <stddef.h>

#include "camera.h"
#include "error.h"

static int normalise(double v[3])
{
    double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(n > 1e-12) || !isfinite(n)) {
        return -1;
    }
    v[0] /= n;
    v[1] /= n;
    v[2] /= n;
    return 0;
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

NERF_API int nerf_camera_look_at(nerf_camera *camera, const float eye[3],
                                 const float target[3], const float up[3])
{
    if (camera == NULL || eye == NULL || target == NULL || up == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_camera_look_at: NULL argument");
    }
    if (camera->struct_size < offsetof(nerf_camera, fx)) {
        return nerf__error(NERF_EINVAL, "nerf_camera_look_at: struct_size %u "
                           "is too small (initialise with nerf_camera_init)",
                           (unsigned)camera->struct_size);
    }
    /* OpenGL convention: the camera looks down its -z axis, so +z points
     * from the target back to the eye. */
    double z[3] = {(double)eye[0] - target[0], (double)eye[1] - target[1],
                   (double)eye[2] - target[2]};
    double u[3] = {up[0], up[1], up[2]}, x[3], y[3];
    if (normalise(z) != 0) {
        return nerf__error(NERF_EINVAL, "nerf_camera_look_at: eye and target "
                           "coincide (or are not finite)");
    }
    cross(u, z, x);
    if (normalise(x) != 0) {
        return nerf__error(NERF_EINVAL, "nerf_camera_look_at: up is parallel "
                           "to the viewing direction (or zero)");
    }
    cross(z, x, y);
    for (int r = 0; r < 3; r++) {
        camera->c2w[4 * r + 0] = (float)x[r];
        camera->c2w[4 * r + 1] = (float)y[r];
        camera->c2w[4 * r + 2] = (float)z[r];
        camera->c2w[4 * r + 3] = eye[r];
    }
    return NERF_OK;
}
