/* The viewer's starting view and its cameras. */
#include "viewer.h"

#include <math.h>

#include "../common/orbit.h"

/* Used when an LLFF scene's views do not meet at a point. */
#define DEFAULT_FOCUS 4.0

static void column(const nerf_camera *cam, int col, float out[3])
{
    for (int k = 0; k < 3; k++) {
        out[k] = cam->c2w[4 * k + col];
    }
}

static double dot3d(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/*
 * Where the optical axes of two cameras come closest: the reference
 * spiral path aims every view at one focus point, so two of its views
 * pin that point down.  Returns 0 when the axes are (nearly) parallel.
 */
static int axes_meet(const nerf_camera *a, const nerf_camera *b, double out[3])
{
    double p1[3], p2[3], d1[3], d2[3], w[3];
    for (int k = 0; k < 3; k++) {
        p1[k] = a->c2w[4 * k + 3];
        p2[k] = b->c2w[4 * k + 3];
        d1[k] = -a->c2w[4 * k + 2];
        d2[k] = -b->c2w[4 * k + 2];
        w[k] = p1[k] - p2[k];
    }
    double aa = dot3d(d1, d1), bb = dot3d(d1, d2), cc = dot3d(d2, d2);
    double dd = dot3d(d1, w), ee = dot3d(d2, w);
    double denom = aa * cc - bb * bb;
    if (!(denom > 1e-9 * aa * cc)) {
        return 0;
    }
    double s = (bb * ee - cc * dd) / denom, t = (aa * ee - bb * dd) / denom;
    for (int k = 0; k < 3; k++) {
        out[k] = 0.5 * (p1[k] + s * d1[k] + p2[k] + t * d2[k]);
    }
    return 1;
}

/* Distance along cam0's view to where the scene's spiral views meet. */
static double llff_focus(const nerf_dataset *ds, const nerf_camera *cam0)
{
    nerf_camera a, b;
    NERF_CAMERA_INIT(&a);
    NERF_CAMERA_INIT(&b);
    double f[3];
    /* Views 0 and 15 of 120 are a quarter turn apart on the spiral. */
    if (nerf_dataset_spiral_camera(ds, 0, 120, &a) != NERF_OK ||
        nerf_dataset_spiral_camera(ds, 15, 120, &b) != NERF_OK ||
        !axes_meet(&a, &b, f)) {
        return DEFAULT_FOCUS;
    }
    double along = 0.0;
    for (int k = 0; k < 3; k++) {
        along -= (f[k] - cam0->c2w[4 * k + 3]) * cam0->c2w[4 * k + 2];
    }
    return isfinite(along) && along > 1e-2 && along < 1e4 ? along
                                                          : DEFAULT_FOCUS;
}

/* The mean of the cameras' up axes: Blender-style captures circle their
 * object with the camera upright, so this is the scene's up. */
static void mean_up(const nerf_dataset *ds, float up[3])
{
    double sum[3] = {0, 0, 0};
    uint32_t n = nerf_dataset_count(ds);
    for (uint32_t i = 0; i < n; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        if (nerf_dataset_camera(ds, i, &cam) == NERF_OK) {
            for (int k = 0; k < 3; k++) {
                sum[k] += cam.c2w[4 * k + 1];
            }
        }
    }
    double norm = sqrt(dot3d(sum, sum));
    for (int k = 0; k < 3; k++) {
        /* Fall back to Blender's z-up when the cameras disagree. */
        float fallback = k == 2 ? 1.0f : 0.0f;
        up[k] = norm > 1e-3 * n ? (float)(sum[k] / norm) : fallback;
    }
}

int viewer_home(viewer *v)
{
    const float origin[3] = {0, 0, 0};
    float up[3] = {0, 0, 1}, ax[3] = {1, 0, 0};
    v->near = 2.0f;
    v->far = 6.0f;
    if (v->dataset == NULL) {
        /* Where nerf-render's orbit starts, framed as it frames its
         * views: its field of view across the smaller side. */
        const double r = orbit_distance();
        const float eye[3] = {(float)(r * cos(ORBIT_ELEVATION)), 0.0f,
                              (float)(r * sin(ORBIT_ELEVATION))};
        const uint32_t side = v->width < v->height ? v->width : v->height;
        v->focal_ratio = 0.5 * side / v->width / tan(0.5 * ORBIT_FOV);
        orbit_init(&v->home, origin, up, ax, eye);
        v->view = v->home;
        return NERF_OK;
    }
    nerf_camera cam0;
    NERF_CAMERA_INIT(&cam0);
    int rc = nerf_dataset_camera(v->dataset, 0, &cam0);
    if (rc == NERF_OK) {
        rc = nerf_dataset_bounds(v->dataset, &v->near, &v->far);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    v->focal_ratio = (double)cam0.fx / cam0.width;
    float eye[3];
    column(&cam0, 3, eye);
    if (nerf_dataset_get_format(v->dataset) == NERF_DATASET_LLFF) {
        double focus = llff_focus(v->dataset, &cam0);
        float target[3];
        column(&cam0, 1, up);
        column(&cam0, 2, ax);
        for (int k = 0; k < 3; k++) {
            target[k] = (float)(eye[k] - focus * ax[k]);
        }
        orbit_init(&v->home, target, up, ax, eye);
    } else {
        mean_up(v->dataset, up);
        /* Any horizontal start direction will do: yaw is measured from
         * it.  Take the world axis least aligned with up. */
        if (fabsf(up[0]) > 0.9f) {
            ax[0] = 0.0f;
            ax[1] = 1.0f;
        }
        orbit_init(&v->home, origin, up, ax, eye);
    }
    v->view = v->home;
    return NERF_OK;
}

int viewer_camera(const viewer *v, uint32_t w, uint32_t h, nerf_camera *cam)
{
    NERF_CAMERA_INIT(cam);
    cam->width = w;
    cam->height = h;
    /* A reduced preview keeps the full image's field of view, even when
     * rounding changes its aspect ratio slightly. */
    cam->fx = (float)(v->focal_ratio * w);
    cam->fy = (float)(v->focal_ratio * v->width * h / v->height);
    cam->cx = 0.5f * (float)w;
    cam->cy = 0.5f * (float)h;
    return orbit_pose(&v->view, cam);
}
