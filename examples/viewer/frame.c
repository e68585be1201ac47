#include "frame.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

const opt_choice view_modes[] = {
    {.name = "rgb", .id = VIEW_RGB},
    {.name = "depth", .id = VIEW_DEPTH},
    {.name = "opacity", .id = VIEW_OPACITY},
    {.name = NULL},
};

const char *view_mode_name(view_mode mode)
{
    const char *name = opt_choice_name(view_modes, (int)mode);
    return name != NULL ? name : "rgb";
}

static int frame_reserve(frame *f, size_t pixels)
{
    if (pixels <= f->capacity) {
        return NERF_OK;
    }
    frame_free(f);
    f->rgb = malloc(pixels * 3 * sizeof(float));
    f->depth = malloc(pixels * sizeof(float));
    f->opacity = malloc(pixels * sizeof(float));
    f->grey = malloc(pixels * sizeof(float));
    if (!f->rgb || !f->depth || !f->opacity || !f->grey) {
        frame_free(f);
        return NERF_ENOMEM;
    }
    f->capacity = pixels;
    return NERF_OK;
}

int frame_render(frame *f, nerf_renderer *r, const nerf_bake *bake,
                 const nerf_camera *cam)
{
    size_t pixels = (size_t)cam->width * cam->height;
    int rc = frame_reserve(f, pixels);
    if (rc != NERF_OK) {
        return rc;
    }
    f->width = cam->width;
    f->height = cam->height;
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    rc = bake ? nerf_bake_render_image(bake, cam, f->rgb, f->depth,
                                       f->opacity, f->capacity)
              : nerf_renderer_render_image(r, cam, f->rgb, f->depth,
                                           f->opacity, f->capacity);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    f->seconds = (double)(t1.tv_sec - t0.tv_sec) +
                 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    return rc;
}

const float *frame_view(frame *f, view_mode mode, float near, float far,
                        uint32_t *channels_out)
{
    size_t n = (size_t)f->width * f->height;
    switch (mode) {
    case VIEW_OPACITY: *channels_out = 1; return f->opacity;
    case VIEW_DEPTH:
        /* Expected depth is sum(w t), not divided by opacity: divide here
         * so half-transparent edges show the depth of what they hit. */
        for (size_t k = 0; k < n; k++) {
            float a = f->opacity[k];
            float d = a > 1e-3f ? f->depth[k] / a : far;
            f->grey[k] = a > 1e-3f ? 1.0f - (d - near) / (far - near) : 0.0f;
        }
        *channels_out = 1;
        return f->grey;
    default: *channels_out = 3; return f->rgb;
    }
}

static uint8_t to_byte(float v)
{
    /* NaN fails both comparisons and ends up 0, as in nerf_image_write_png. */
    if (!(v > 0.0f)) {
        return 0;
    }
    if (v >= 1.0f) {
        return 255;
    }
    return (uint8_t)(v * 255.0f + 0.5f);
}

void frame_to_rgb8(frame *f, view_mode mode, float near, float far,
                   uint8_t *out)
{
    uint32_t channels;
    const float *src = frame_view(f, mode, near, far, &channels);
    size_t n = (size_t)f->width * f->height;
    for (size_t k = 0; k < n; k++) {
        for (int c = 0; c < 3; c++) {
            out[3 * k + c] = to_byte(src[channels == 3 ? 3 * k + c : k]);
        }
    }
}

void frame_free(frame *f)
{
    free(f->rgb);
    free(f->depth);
    free(f->opacity);
    free(f->grey);
    f->rgb = f->depth = f->opacity = f->grey = NULL;
    f->capacity = 0;
}
