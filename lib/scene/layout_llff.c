/*
 * The LLFF layout of the forward-facing capture: images/ and
 * poses_bounds.npy as LLFF's imgs2poses writes them, so that the LLFF
 * loader reads the built-in scene as it reads fern.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "file_io.h"
#include "npy.h"
#include "scene_image.h"
#include "scene_internal.h"

/* A row: the 3x5 [down | right | back | centre | (H, W, focal)], row-major,
 * then the near and far bounds. */
#define ROW 17

/* LLFF takes the bounds as these percentiles of its points' depths. */
#define NEAR_PERCENTILE 0.1
#define FAR_PERCENTILE 99.9

static int compare_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* NumPy's default percentile (linear between order statistics) of v,
 * which it sorts. */
static double percentile(float *v, size_t n, double q)
{
    qsort(v, n, sizeof *v, compare_float);
    double pos = q / 100.0 * (double)(n - 1);
    size_t lo = (size_t)pos;
    size_t hi = lo + 1 < n ? lo + 1 : lo;
    return v[lo] + (v[hi] - v[lo]) * (pos - (double)lo);
}

static void fill_row(const nerf_camera *cam, float *zdepth, size_t pixels,
                     double *row)
{
    const float *m = cam->c2w;
    const double hwf[3] = {cam->height, cam->width, cam->fx};
    for (int r = 0; r < 3; r++) {
        /* Our columns are [right, up, back]; LLFF's [down, right, back]. */
        row[5 * r + 0] = -m[4 * r + 1];
        row[5 * r + 1] = m[4 * r + 0];
        row[5 * r + 2] = m[4 * r + 2];
        row[5 * r + 3] = m[4 * r + 3];
        row[5 * r + 4] = hwf[r];
    }
    row[15] = percentile(zdepth, pixels, NEAR_PERCENTILE);
    row[16] = percentile(zdepth, pixels, FAR_PERCENTILE);
}

int nerf__scene_write_llff(const char *dir, const nerf_scene_options *o,
                           const nerf__env *env, uint8_t *px)
{
    const nerf__scene_look look = nerf__scene_look_of(o);
    const uint32_t n = o->n_train + o->n_test;
    const size_t pixels = (size_t)o->width * o->height;
    char path[4096];
    snprintf(path, sizeof path, "%s/images", dir);
    int rc = nerf__scene_make_dir(path);
    double *rows = rc == NERF_OK ? nerf__calloc(env, n, ROW * sizeof *rows)
                                 : NULL;
    float *zdepth = rc == NERF_OK ? nerf__calloc(env, pixels, sizeof *zdepth)
                                  : NULL;
    if (rc == NERF_OK && (rows == NULL || zdepth == NULL)) {
        rc = NERF_ENOMEM;
    }
    for (uint32_t i = 0; i < n && rc == NERF_OK; i++) {
        nerf_camera cam;
        nerf__scene_forward_camera(o, 0, i, n, &cam);
        nerf__scene_render_view(&cam, &look, o->threads, px, zdepth);
        /* Zero-padded, so that sorting the names gives the capture order
         * (the loader pairs the sorted names with the rows). */
        snprintf(path, sizeof path, "%s/images/image%05u", dir, (unsigned)i);
        rc = nerf__scene_image_write(env, path, o, look.channels, px);
        fill_row(&cam, zdepth, pixels, rows + (size_t)ROW * i);
    }
    if (rc == NERF_OK) {
        snprintf(path, sizeof path, "%s/poses_bounds.npy", dir);
        rc = nerf__npy_write_f8(env, path, rows, n, ROW);
    }
    if (rc == NERF_OK) {
        nerf__log(env, NERF_LOG_INFO, "scene: wrote %u forward-facing views "
                  "of %ux%u to %s (LLFF layout)", (unsigned)n, o->width,
                  o->height, dir);
    }
    nerf__free(env, rows);
    nerf__free(env, zdepth);
    return rc;
}
