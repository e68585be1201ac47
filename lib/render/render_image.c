/* Whole-image rendering of a camera into caller buffers. */
#include <math.h>
#include <string.h>

#include "camera.h"
#include "renderer.h"

typedef struct image_job {
    const nerf_renderer *r;
    nerf__render_setup setup;
    nerf_camera cam;
    float *rgb;
    uint8_t *rgb8;
    float *depth, *opacity;
} image_job;

static uint8_t to_byte(float c)
{
    if (!(c > 0.0f)) {
        return 0; /* also NaN */
    }
    if (c >= 1.0f) {
        return 255;
    }
    return (uint8_t)(c * 255.0f + 0.5f);
}

static int image_chunk(void *p, nerf__worker *w, size_t first, size_t count)
{
    image_job *job = p;
    for (size_t at = first; at < first + count; at += NERF__RENDER_BLOCK) {
        if (nerf__renderer_cancelled(job->r)) {
            return nerf__error(NERF_ECANCELLED, "render cancelled");
        }
        size_t k = first + count - at;
        k = k < NERF__RENDER_BLOCK ? k : NERF__RENDER_BLOCK;
        nerf__camera_rays(&job->cam, at, k, w->origins, w->directions);
        nerf__render_setup s = job->setup;
        s.first_ray = at;
        nerf__pass_out out[NERF__PASSES];
        memset(out, 0, sizeof out);
        nerf__pass_out *last = &out[nerf__sampler_last_pass(s.sampler)];
        if (job->rgb) {
            last->rgb = job->rgb + 3 * at;
        } else if (job->rgb8) {
            last->rgb = w->rgb;
        }
        last->depth = job->depth ? job->depth + at : NULL;
        last->opacity = job->opacity ? job->opacity + at : NULL;
        int rc = nerf__render_batch(&w->batch, &s, k, w->origins,
                                    w->directions, out);
        if (rc != NERF_OK) {
            return rc;
        }
        if (job->rgb8) {
            for (size_t i = 0; i < 3 * k; i++) {
                job->rgb8[3 * at + i] = to_byte(w->rgb[i]);
            }
        }
    }
    return NERF_OK;
}

static int render_image(nerf_renderer *r, const nerf_camera *camera,
                        float *rgb, uint8_t *rgb8, float *depth,
                        float *opacity, size_t capacity, const char *fn)
{
    if (r == NULL) {
        return nerf__error(NERF_EINVAL, "%s: renderer is NULL", fn);
    }
    image_job job;
    int rc = nerf__camera_read(&job.cam, camera, fn);
    if (rc != NERF_OK) {
        return rc;
    }
    if (rgb == NULL && rgb8 == NULL && depth == NULL && opacity == NULL) {
        return nerf__error(NERF_EINVAL, "%s: every output is NULL", fn);
    }
    size_t pixels = (size_t)job.cam.width * job.cam.height;
    if (capacity < pixels) {
        return nerf__error(NERF_EINVAL, "%s: buffers hold %zu pixels, the "
                           "%ux%u image needs %zu", fn, capacity,
                           job.cam.width, job.cam.height, pixels);
    }
    nerf__renderer_eval_setup(r, &job.setup);
    if (r->sampler->opts.ndc && job.setup.ndc_focal == 0.0f) {
        /* No scene frustum: the camera's own, as the reference does when
         * it renders at the training resolution. */
        job.setup.ndc_focal = job.cam.fx;
        job.setup.ndc_width = (float)job.cam.width;
        job.setup.ndc_height = (float)job.cam.height;
    }
    job.r = r;
    job.rgb = rgb;
    job.rgb8 = rgb8;
    job.depth = depth;
    job.opacity = opacity;
    return nerf__renderer_run(r, pixels, image_chunk, &job);
}

NERF_API int nerf_renderer_render_image(nerf_renderer *renderer,
                                        const nerf_camera *camera,
                                        float *rgb_out, float *depth_out,
                                        float *opacity_out,
                                        size_t pixel_capacity)
{
    return render_image(renderer, camera, rgb_out, NULL, depth_out,
                        opacity_out, pixel_capacity,
                        "nerf_renderer_render_image");
}

NERF_API int nerf_renderer_render_image_u8(nerf_renderer *renderer,
                                           const nerf_camera *camera,
                                           uint8_t *rgb_out,
                                           float *depth_out,
                                           float *opacity_out,
                                           size_t pixel_capacity)
{
    if (rgb_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_renderer_render_image_u8: "
                           "rgb_out is NULL");
    }
    return render_image(renderer, camera, NULL, rgb_out, depth_out,
                        opacity_out, pixel_capacity,
                        "nerf_renderer_render_image_u8");
}
