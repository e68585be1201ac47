/*
 * One rendered view: colour, depth and opacity of every pixel, kept
 * together so that switching what is shown never needs a new render.
 */
#ifndef NERF_VIEWER_FRAME_H
#define NERF_VIEWER_FRAME_H

#include <stddef.h>
#include <stdint.h>

#include <nerf.h>

#include "../common/opt_table.h"

typedef enum view_mode {
    VIEW_RGB = 0,
    VIEW_DEPTH = 1,
    VIEW_OPACITY = 2
} view_mode;

typedef struct frame {
    uint32_t width, height;
    size_t capacity; /* pixels each buffer holds */
    float *rgb;      /* width x height x 3 */
    float *depth;    /* width x height */
    float *opacity;  /* width x height */
    float *grey;     /* scratch for the depth view */
    double seconds;  /* time the last render took */
} frame;

/* The modes' names, "rgb", "depth" and "opacity", as --view's choices. */
extern const opt_choice view_modes[];
const char *view_mode_name(view_mode mode);

/* Render cam (whose size the frame takes) with r, or from bake when it
 * is not NULL.  Returns a libnerf status; NERF_ECANCELLED leaves a
 * partial frame. */
int frame_render(frame *f, nerf_renderer *r, const nerf_bake *bake,
                 const nerf_camera *cam);

/*
 * The pixels of one view as floats in [0, 1]: RGB (3 channels) or grey
 * (1 channel).  Depth is shown as in nerf-render: near white, far black,
 * between near and far, where there is nothing (opacity ~0) black.
 */
const float *frame_view(frame *f, view_mode mode, float near, float far,
                        uint32_t *channels_out);

/* The same as 8-bit RGB for display: width x height x 3 bytes. */
void frame_to_rgb8(frame *f, view_mode mode, float near, float far,
                   uint8_t *out);

void frame_free(frame *f);

#endif
