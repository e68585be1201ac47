/*
 * nerf-render's --path orbit keeps the object whole: every corner of the
 * built-in scene's bounding box, and of a cube just inside the sphere the
 * orbit is framed on, projects inside every frame, for frames of several
 * aspect ratios, tall and wide.  The margin holds by construction (a
 * corner at radius r < bound lies within the cone of half-angle
 * asin(r / distance) < ORBIT_FOV / 2), far above float rounding.
 */
#include <math.h>
#include <stdio.h>

#include <nerf.h>

#include "common/orbit.h"

/* The solids of lib/scene/field.c: the torus spans x and y to 0.8 + 0.12,
 * z from -0.55 - 0.12; the sphere at z 0.45 of radius 0.25 tops it. */
static const double scene_box[2][3] = {{-0.92, -0.92, -0.67},
                                       {0.92, 0.92, 0.70}};

static int failures;

/* Whether the world point x projects into cam's frame, in front of it. */
static int in_frame(const nerf_camera *cam, const double x[3])
{
    double v[3], d[3] = {0, 0, 0};
    for (int r = 0; r < 3; r++) {
        v[r] = x[r] - cam->c2w[4 * r + 3];
    }
    for (int k = 0; k < 3; k++) {
        for (int r = 0; r < 3; r++) {
            d[k] += cam->c2w[4 * r + k] * v[r];
        }
    }
    if (!(d[2] < 0.0)) {
        return 0;
    }
    double u = cam->cx + cam->fx * d[0] / -d[2];
    double w = cam->cy - cam->fy * d[1] / -d[2];
    return u >= 0.0 && u <= cam->width && w >= 0.0 && w <= cam->height;
}

static void check_box(const char *name, const double box[2][3], uint32_t w,
                      uint32_t h)
{
    const uint32_t n = 40;
    for (uint32_t i = 0; i < n; i++) {
        nerf_camera cam;
        if (orbit_camera(i, n, w, h, &cam) != NERF_OK) {
            printf("FAIL orbit_camera(%u, %u, %u, %u): %s\n", i, n, w, h,
                   nerf_last_error());
            failures++;
            return;
        }
        for (int c = 0; c < 8; c++) {
            const double x[3] = {box[c & 1][0], box[(c >> 1) & 1][1],
                                 box[(c >> 2) & 1][2]};
            if (!in_frame(&cam, x)) {
                printf("FAIL %s: corner (%g, %g, %g) outside view %u of "
                       "%ux%u\n", name, x[0], x[1], x[2], i, w, h);
                failures++;
                return;
            }
        }
    }
}

int main(void)
{
    static const uint32_t sizes[][2] = {{100, 100}, {640, 480}, {480, 640},
                                        {1920, 1080}, {90, 300}, {301, 7}};
    /* A cube whose corners are 1% inside the sphere of orbit_bound(). */
    const double s = 0.99 * orbit_bound() / sqrt(3.0);
    const double cube[2][3] = {{-s, -s, -s}, {s, s, s}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        check_box("built-in scene", scene_box, sizes[k][0], sizes[k][1]);
        check_box("cube in the bound", cube, sizes[k][0], sizes[k][1]);
    }
    if (failures == 0) {
        printf("ok   the orbit keeps the object whole at every aspect "
               "ratio (distance %.3f)\n", orbit_distance());
    }
    return failures ? 1 : 0;
}
