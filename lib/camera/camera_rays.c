/* Cameras in the OpenGL convention and their rays. */
#include <math.h>
#include <stdbool.h>
#include <string.h>

#include "camera.h"
#include "distortion.h"
#include "error.h"
#include "options.h"

#define MAX_SIDE 65536u

static void camera_defaults(nerf_camera *c)
{
    memset(c, 0, sizeof *c);
    c->struct_size = sizeof *c;
    c->c2w[0] = c->c2w[5] = c->c2w[10] = 1.0f;
}

NERF_API int nerf_camera_init(nerf_camera *camera, size_t struct_size)
{
    nerf_camera d;
    camera_defaults(&d);
    return nerf__options_init(camera, struct_size, &d, sizeof d,
                              "nerf_camera");
}

int nerf__camera_read(nerf_camera *out, const nerf_camera *in, const char *fn)
{
    if (in == NULL) {
        return nerf__error(NERF_EINVAL, "%s: camera is NULL", fn);
    }
    camera_defaults(out);
    int rc = nerf__options_read(out, sizeof *out, in, "nerf_camera");
    if (rc != NERF_OK) {
        return nerf__error_prefix(rc, fn);
    }
    const char *what = NULL;
    char text[96];
    const double lens[5] = {out->k1, out->k2, out->p1, out->p2, out->k3};
    bool pose_finite = true;
    for (int k = 0; k < 12; k++) {
        pose_finite = pose_finite && isfinite(out->c2w[k]);
    }
    if (out->flags & ~NERF_CAMERA_PIXEL_CORNER) {
        what = "unknown flags";
    } else if (out->width < 1 || out->width > MAX_SIDE || out->height < 1 ||
               out->height > MAX_SIDE) {
        what = "width and height must be 1..65536";
    } else if (!(isfinite(out->fx) && out->fx > 0.0f && isfinite(out->fy) &&
                 out->fy > 0.0f)) {
        what = "fx and fy must be positive and finite";
    } else if (!isfinite(out->cx) || !isfinite(out->cy)) {
        what = "cx and cy must be finite";
    } else if (!pose_finite) {
        what = "c2w has a NaN or infinite entry";
    } else {
        what = nerf__lens_problem(lens, text, sizeof text);
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "%s: invalid camera: %s", fn, what);
    }
    return NERF_OK;
}

int nerf__camera_write(nerf_camera *out, const nerf_camera *cam,
                       const char *fn)
{
    uint32_t size = out->struct_size;
    if (size < offsetof(nerf_camera, cy) + sizeof out->cy || size > 65536) {
        return nerf__error(NERF_EINVAL, "%s: camera struct_size %u is "
                           "invalid (initialise it with nerf_camera_init)",
                           fn, (unsigned)size);
    }
    size_t n = size < sizeof *cam ? size : sizeof *cam;
    memcpy((char *)out + sizeof cam->struct_size,
           (const char *)cam + sizeof cam->struct_size,
           n - sizeof cam->struct_size);
    return NERF_OK;
}

/* The world direction of camera-space (x, y, -1), y up. */
static inline void rotate(const float *m, const float d[3], float *out)
{
    for (int r = 0; r < 3; r++) {
        /* Summed in the reference's order, so rays match it bitwise. */
        out[r] = d[0] * m[4 * r] + d[1] * m[4 * r + 1] + d[2] * m[4 * r + 2];
    }
}

/*
 * Through a lens: the pixel records the distorted normalised point, the
 * ray goes through the undistorted one.  In double, so that the inverse
 * converges far below a float's resolution.  A pixel that nothing
 * distorts onto (beyond the fold of a strong barrel lens) gets the ray of
 * the point whose distortion comes closest to it.
 */
static void lens_rays(const nerf_camera *cam, size_t first, size_t n,
                      float off, float *origins, float *directions)
{
    const float *m = cam->c2w;
    nerf__lens lens;
    nerf__lens_of(cam, &lens);
    for (size_t k = 0; k < n; k++) {
        size_t p = first + k;
        double i = (double)(p % cam->width) + off;
        double j = (double)(p / cam->width) + off;
        double x, y;
        nerf__undistort(&lens, (i - cam->cx) / cam->fx,
                        (j - cam->cy) / cam->fy, &x, &y);
        const float d[3] = {(float)x, (float)-y, -1.0f};
        rotate(m, d, directions + 3 * k);
        for (int r = 0; r < 3; r++) {
            origins[3 * k + r] = m[4 * r + 3];
        }
    }
}

void nerf__camera_rays(const nerf_camera *cam, size_t first, size_t n,
                       float *origins, float *directions)
{
    const float *m = cam->c2w;
    const float off = (cam->flags & NERF_CAMERA_PIXEL_CORNER) ? 0.0f : 0.5f;
    if (nerf__lens_distorts(cam)) {
        lens_rays(cam, first, n, off, origins, directions);
        return;
    }
    for (size_t k = 0; k < n; k++) {
        size_t p = first + k;
        float i = (float)(p % cam->width) + off;
        float j = (float)(p / cam->width) + off;
        float d[3] = {(i - cam->cx) / cam->fx, -(j - cam->cy) / cam->fy, -1.0f};
        rotate(m, d, directions + 3 * k);
        for (int r = 0; r < 3; r++) {
            origins[3 * k + r] = m[4 * r + 3];
        }
    }
}

NERF_API int nerf_camera_rays(const nerf_camera *camera, size_t first,
                              size_t n, float *origins_out,
                              float *directions_out)
{
    nerf_camera cam;
    int rc = nerf__camera_read(&cam, camera, "nerf_camera_rays");
    if (rc != NERF_OK) {
        return rc;
    }
    size_t pixels = (size_t)cam.width * cam.height;
    if (first > pixels || n > pixels - first) {
        return nerf__error(NERF_EINVAL, "nerf_camera_rays: pixels %zu + %zu "
                           "are beyond the %ux%u image", first, n, cam.width,
                           cam.height);
    }
    if (n > 0 && (origins_out == NULL || directions_out == NULL)) {
        return nerf__error(NERF_EINVAL, "nerf_camera_rays: NULL output");
    }
    nerf__camera_rays(&cam, first, n, origins_out, directions_out);
    return NERF_OK;
}
