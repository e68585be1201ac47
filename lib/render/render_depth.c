/*
 * Depth in world units: the raw sum(w t) of an image render turned into
 * the expected termination point's distance and camera-space depth.
 */
#include <math.h>
#include <string.h>

#include "camera.h"
#include "renderer.h"

/* Pixels whose rays are made at a time when converting. */
#define RAYS_AT_ONCE 256

/*
 * The ray parameter s (along the camera's unnormalised direction, so the
 * camera-space depth) of the expected termination point, from the raw
 * depth sum(w t) and opacity sum(w).
 */
static double ray_parameter(double raw, double opacity, bool ndc,
                            const float *o, const float *d)
{
    if (!(opacity > 0.0)) {
        return 0.0;
    }
    double t = raw / opacity;
    if (!ndc) {
        return t;
    }
    /* The NDC warp (near plane at world z = -1) gives a ray whose NDC z is
     * -1 + 2 t, i.e. world z = -1 / (1 - t); the warp keeps the ray
     * straight, so the point is where the world ray reaches that z. */
    if (!(t < 1.0)) {
        return INFINITY;
    }
    double z = -1.0 / (1.0 - t);
    return (z - (double)o[2]) / (double)d[2];
}

NERF_API int nerf_renderer_render_depth(nerf_renderer *renderer,
                                        const nerf_camera *camera,
                                        float *rgb_out, float *distance_out,
                                        float *zdepth_out,
                                        float *opacity_out,
                                        size_t pixel_capacity)
{
    static const char fn[] = "nerf_renderer_render_depth";
    if (renderer == NULL) {
        return nerf__error(NERF_EINVAL, "%s: renderer is NULL", fn);
    }
    nerf_camera cam;
    int rc = nerf__camera_read(&cam, camera, fn);
    if (rc != NERF_OK) {
        return rc;
    }
    if (rgb_out == NULL && distance_out == NULL && zdepth_out == NULL &&
        opacity_out == NULL) {
        return nerf__error(NERF_EINVAL, "%s: every output is NULL", fn);
    }
    size_t pixels = (size_t)cam.width * cam.height;
    if (pixel_capacity < pixels) {
        return nerf__error(NERF_EINVAL, "%s: buffers hold %zu pixels, the "
                           "%ux%u image needs %zu", fn, pixel_capacity,
                           cam.width, cam.height, pixels);
    }
    if (distance_out == NULL && zdepth_out == NULL) {
        return nerf_renderer_render_image(renderer, camera, rgb_out, NULL,
                                          opacity_out, pixel_capacity);
    }
    /* The raw depth goes where one of the depths will be, the opacity into
     * the caller's buffer or scratch; both are then converted in place. */
    float *raw = zdepth_out ? zdepth_out : distance_out;
    float *scratch = NULL;
    float *opacity = opacity_out;
    if (opacity == NULL) {
        scratch = nerf__alloc(&renderer->env, pixels * sizeof(float));
        if (scratch == NULL) {
            return NERF_ENOMEM;
        }
        opacity = scratch;
    }
    rc = nerf_renderer_render_image(renderer, camera, rgb_out, raw, opacity,
                                    pixel_capacity);
    if (rc == NERF_OK) {
        const bool ndc = renderer->sampler->opts.ndc != 0;
        float o[3 * RAYS_AT_ONCE], d[3 * RAYS_AT_ONCE];
        for (size_t at = 0; at < pixels; at += RAYS_AT_ONCE) {
            size_t k = pixels - at < RAYS_AT_ONCE ? pixels - at
                                                  : RAYS_AT_ONCE;
            nerf__camera_rays(&cam, at, k, o, d);
            for (size_t i = 0; i < k; i++) {
                const float *di = d + 3 * i;
                double s = ray_parameter(raw[at + i], opacity[at + i], ndc,
                                         o + 3 * i, di);
                double len = sqrt((double)di[0] * di[0] +
                                  (double)di[1] * di[1] +
                                  (double)di[2] * di[2]);
                if (zdepth_out) {
                    zdepth_out[at + i] = (float)s;
                }
                if (distance_out) {
                    distance_out[at + i] = (float)(s * len);
                }
            }
        }
    }
    nerf__free(&renderer->env, scratch);
    return rc;
}
