/*
 * Where each pixel's ray may meet bricks (bake.h): the surface cells
 * drawn into the image as boxes, each pixel keeping the least and the
 * greatest distance of the boxes that cover it.
 *
 * Most of a bake's render was spent crossing empty space: on lego at
 * 640x480, four rays in five meet no brick at all, and each took about
 * eight skips through the distance field to learn it.  Drawing the few
 * tens of thousands of surface cells costs a millisecond or two, and
 * tells those rays at once, and the others where to begin and end.
 */
#include <math.h>

#include "bake.h"
#include "parallel.h"

/* (The drawing loop's minima and maxima are written out: fminf and fmaxf
 * are calls at the baseline's flags, and these values are never NaN.) */

/* Cells grow by this fraction of their edge on each side before they
 * are drawn, and the pixels they cover by PIXEL_MARGIN, far above the
 * rounding of the rays' arithmetic (relative 1e-6 of the scene). */
#define CELL_MARGIN 0.01
#define PIXEL_MARGIN 0.01f

/* A camera's view of the grid: camera-space coordinates (x, y, and the
 * depth along the axis, as nerf_camera's rays scale them) of the grid's
 * origin and of one cell's edges. */
typedef struct view {
    const nerf_bake *b;
    const nerf_camera *cam;
    float *near, *far;
    float origin[3], edge[3][3];
    float centre[3];
    float half;         /* 0.5, or 0 for NERF_CAMERA_PIXEL_CORNER */
    uint32_t blocks_x, blocks_y;
    uint32_t bands;     /* block rows split into this many tasks */
    /* The least near and the greatest far distance of the cells that
     * cross the camera's plane, which bound every pixel: each band's. */
    float floor_of[64], ceil_of[64];
} view;

/* Whether the camera-to-world rotation of cam can be inverted (a camera
 * need not be a rotation; its rays are R (x, y, -1)), into inv. */
static bool invert(const float c2w[12], double inv[3][3])
{
    const double m[3][3] = {{c2w[0], c2w[1], c2w[2]},
                            {c2w[4], c2w[5], c2w[6]},
                            {c2w[8], c2w[9], c2w[10]}};
    const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    const double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    if (!(fabs(det) > 1e-12)) {
        return false;
    }
    const double s = 1.0 / det;
    inv[0][0] = c00 * s;
    inv[1][0] = c01 * s;
    inv[2][0] = c02 * s;
    inv[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * s;
    inv[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * s;
    inv[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * s;
    inv[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * s;
    inv[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * s;
    inv[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * s;
    return true;
}

/* Whether a brick may lie within two cells of the camera's centre (or
 * so close that rounding could put it among them), from the distance
 * field: the distance of the grid's cell nearest the centre is at most
 * the centre's own, so a centre whose nearest cell is more than two from
 * any brick is too. */
static bool among_bricks(const nerf_bake *b, const float c[3])
{
    size_t cell = 0;
    for (int a = 2; a >= 0; a--) {
        const double u = ((double)c[a] - b->lo[a]) * b->inv_cell[a];
        if (!(u > -2.0 && u < (double)b->res + 2.0)) {
            return false;
        }
        const double v = u < 0.0 ? 0.0 : fmin(floor(u), b->res - 1.0);
        cell = cell * b->res + (size_t)v;
    }
    return b->empty[cell] <= 2;
}

/* Distances from p to the nearest and the farthest point of the box
 * [lo, hi]. */
static void box_distances(const float p[3], const float lo[3],
                          const float hi[3], float *near, float *far)
{
    float s = 0.0f, f = 0.0f;
    for (int a = 0; a < 3; a++) {
        const float d = fmaxf(fmaxf(lo[a] - p[a], p[a] - hi[a]), 0.0f);
        const float e = fmaxf(fabsf(lo[a] - p[a]), fabsf(p[a] - hi[a]));
        s += d * d;
        f += e * e;
    }
    *near = sqrtf(s);
    *far = sqrtf(f);
}

/* Draw every surface cell into the block rows of band `band`. */
static void draw_band(void *ctx, size_t band)
{
    view *v = ctx;
    const nerf_bake *b = v->b;
    const nerf_camera *cam = v->cam;
    const uint32_t w = cam->width, h = cam->height, bw = v->blocks_x;
    const uint32_t rows = v->blocks_y;
    const uint32_t row0 = (uint32_t)((uint64_t)rows * band / v->bands);
    const uint32_t row1 = (uint32_t)((uint64_t)rows * (band + 1) / v->bands);
    /* The pixels of the band's blocks. */
    const float top = (float)(row0 * NERF__BAKE_HIT_BLOCK);
    const float bottom = (float)(row1 * NERF__BAKE_HIT_BLOCK < h
                                     ? row1 * NERF__BAKE_HIT_BLOCK - 1
                                     : h - 1);
    const uint32_t n = b->res;
    const float m = (float)CELL_MARGIN, side = 1.0f + 2.0f * (float)CELL_MARGIN;
    float floor_near = INFINITY, ceil_far = 0.0f;
    for (size_t s = 0; s < b->n_surface; s++) {
        const uint32_t c = b->surface[s];
        const float at[3] = {(float)(c % n) - m, (float)(c / n % n) - m,
                             (float)(c / n / n) - m};
        float q0[3];
        for (int r = 0; r < 3; r++) {
            q0[r] = v->origin[r] + at[0] * v->edge[0][r] +
                    at[1] * v->edge[1][r] + at[2] * v->edge[2][r];
        }
        float ulo = INFINITY, uhi = -INFINITY, vlo = INFINITY, vhi = -INFINITY;
        bool behind = false;
        for (int k = 0; k < 8; k++) {
            float q[3];
            for (int r = 0; r < 3; r++) {
                q[r] = q0[r] + (float)(k & 1) * side * v->edge[0][r] +
                       (float)(k >> 1 & 1) * side * v->edge[1][r] +
                       (float)(k >> 2) * side * v->edge[2][r];
            }
            /* Depth along the camera's axis: q[2] is -depth. */
            if (!(q[2] < -1e-6f)) {
                behind = true;
                break;
            }
            const float inv = -1.0f / q[2];
            const float px = cam->cx + cam->fx * q[0] * inv - v->half;
            const float py = cam->cy - cam->fy * q[1] * inv - v->half;
            ulo = px < ulo ? px : ulo;
            uhi = px > uhi ? px : uhi;
            vlo = py < vlo ? py : vlo;
            vhi = py > vhi ? py : vhi;
        }
        if (!behind &&
            !(uhi + PIXEL_MARGIN >= 0.0f && vhi + PIXEL_MARGIN >= top &&
              ulo - PIXEL_MARGIN <= (float)(w - 1) &&
              vlo - PIXEL_MARGIN <= bottom)) {
            continue;
        }
        float lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = b->lo[a] + at[a] * b->cell[a];
            hi[a] = lo[a] + side * b->cell[a];
        }
        float dist, dist_far;
        box_distances(v->centre, lo, hi, &dist, &dist_far);
        if (behind) {
            /* Part of it is beside or behind the camera: its image has no
             * bounds, and every ray may meet it between these. */
            floor_near = fminf(floor_near, dist);
            ceil_far = fmaxf(ceil_far, dist_far);
            continue;
        }
        /* The blocks holding the pixels whose centres it covers. */
        const uint32_t x0 = ulo - PIXEL_MARGIN <= 0.0f
                                ? 0
                                : (uint32_t)ceilf(ulo - PIXEL_MARGIN) /
                                      NERF__BAKE_HIT_BLOCK;
        const uint32_t x1 = uhi + PIXEL_MARGIN >= (float)(w - 1)
                                ? bw - 1
                                : (uint32_t)(uhi + PIXEL_MARGIN) /
                                      NERF__BAKE_HIT_BLOCK;
        const uint32_t y0 = vlo - PIXEL_MARGIN <= top
                                ? row0
                                : (uint32_t)ceilf(vlo - PIXEL_MARGIN) /
                                      NERF__BAKE_HIT_BLOCK;
        const uint32_t y1 = vhi + PIXEL_MARGIN >= bottom
                                ? row1 - 1
                                : (uint32_t)(vhi + PIXEL_MARGIN) /
                                      NERF__BAKE_HIT_BLOCK;
        for (uint32_t y = y0; y <= y1; y++) {
            float *row = v->near + (size_t)y * bw;
            float *row_far = v->far + (size_t)y * bw;
            for (uint32_t x = x0; x <= x1; x++) {
                row[x] = dist < row[x] ? dist : row[x];
                row_far[x] = dist_far > row_far[x] ? dist_far : row_far[x];
            }
        }
    }
    v->floor_of[band] = floor_near;
    v->ceil_of[band] = ceil_far;
}

bool nerf__bake_first_hits(const nerf_bake *b, const nerf_camera *cam,
                           float *near, float *far)
{
    if (b->ndc || cam->k1 != 0.0f || cam->k2 != 0.0f || cam->p1 != 0.0f ||
        cam->p2 != 0.0f || cam->k3 != 0.0f) {
        return false;
    }
    view v = {.b = b, .cam = cam, .near = near, .far = far};
    double inv[3][3];
    if (!invert(cam->c2w, inv)) {
        return false;
    }
    for (int a = 0; a < 3; a++) {
        v.centre[a] = cam->c2w[4 * a + 3];
    }
    if (among_bricks(b, v.centre)) {
        return false;
    }
    for (int r = 0; r < 3; r++) {
        double o = 0.0;
        for (int a = 0; a < 3; a++) {
            o += inv[r][a] * ((double)b->lo[a] - v.centre[a]);
            v.edge[a][r] = (float)(inv[r][a] * b->cell[a]);
        }
        v.origin[r] = (float)o;
    }
    v.half = cam->flags & NERF_CAMERA_PIXEL_CORNER ? 0.0f : 0.5f;
    v.blocks_x = nerf__bake_hit_blocks(cam->width);
    v.blocks_y = nerf__bake_hit_blocks(cam->height);
    const size_t blocks = (size_t)v.blocks_x * v.blocks_y;
    for (size_t p = 0; p < blocks; p++) {
        near[p] = INFINITY;
        far[p] = 0.0f;
    }
    unsigned threads = nerf__parallel_threads();
    threads = threads > 64 ? 64 : threads;
    v.bands = threads < v.blocks_y ? threads : v.blocks_y;
    nerf__parallel_blocks(v.bands, 50 * b->n_surface, draw_band, &v);
    float floor_near = INFINITY, ceil_far = 0.0f;
    for (uint32_t i = 0; i < v.bands; i++) {
        floor_near = fminf(floor_near, v.floor_of[i]);
        ceil_far = fmaxf(ceil_far, v.ceil_of[i]);
    }
    if (floor_near < INFINITY) {
        for (size_t p = 0; p < blocks; p++) {
            near[p] = fminf(near[p], floor_near);
            far[p] = fmaxf(far[p], ceil_far);
        }
    }
    return true;
}
