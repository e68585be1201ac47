/*
 * nerf-viewer's state, shared by the headless screenshot path (main.c)
 * and the interactive window (window.c).
 */
#ifndef NERF_VIEWER_VIEWER_H
#define NERF_VIEWER_VIEWER_H

#include <stdint.h>

#include <nerf.h>

#include "frame.h"
#include "orbit.h"

typedef struct viewer {
    nerf_model *model;
    nerf_dataset *dataset; /* NULL without --data */
    nerf_sampler *sampler;
    nerf_renderer *renderer;
    /* Previews while the view moves: a marching model's coarser march;
     * NULL: previews use sampler and renderer. */
    nerf_sampler *preview_sampler;
    nerf_renderer *preview_renderer;
    /* The model baked (--bake): previews render from it, at up to the
     * full size; NULL: they render with the networks. */
    nerf_bake *bake;
    orbit home;             /* the view 'r' returns to */
    orbit view;             /* the current view */
    double focal_ratio;     /* focal length / image width */
    float near, far;        /* depth range shown by the depth view */
    uint32_t width, height; /* full-resolution image size */
    view_mode mode;
    double quit_after; /* seconds; 0: run until asked to quit */
    double fly_seconds; /* --fly: the path's length; 0: no path */
} viewer;

/*
 * Choose the home view: for a Blender-like scene, an orbit around the
 * origin starting at the dataset's first camera (or, without a dataset,
 * where nerf-render's orbit starts); for an LLFF scene, the first camera,
 * circling a point in front of it where the scene's views converge.
 * Needs the image size (width, height) set.
 */
int viewer_home(viewer *v);

/* A camera of w x h pixels for the current view. */
int viewer_camera(const viewer *v, uint32_t w, uint32_t h, nerf_camera *cam);

/* Open a window and run until the user quits (or quit_after passes).
 * Returns the process exit status. */
int viewer_run_window(viewer *v);

#endif
