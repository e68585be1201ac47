/* nerf_bake_render_image(): marching the bake's bricks (bake.h). */
#include <math.h>

#include "bake.h"
#include "box_span.h"
#include "camera.h"
#include "ndc.h"
#include "error.h"
#include "parallel.h"

#define FN "nerf_bake_render_image"
/* Pixels along each side of a task's square of the image. */
#define TILE_SIDE 16u
/* A ray stops once less than this of its light can still get through,
 * and what is left takes the colour of its last sample: a pixel moves by
 * at most this (of a range of 1) from the ray marched to the end.  The
 * networks' march stops at 1e-4 (instant-ngp's threshold); here, on lego
 * at 640x480, 1e-2 takes a fifth fewer samples and scores the same
 * against the networks' renders to 0.01 dB. */
#define MIN_TRANSMITTANCE 1e-2f
/* In steps; far above the rounding of an exit (relative 1e-7 of a
 * distance of at most some thousands of steps). */
#define SKIP_MARGIN 0.01f

typedef struct ray_out {
    float rgb[3];
    float depth;
    float opacity;
} ray_out;

/* Distance along the ray from o to where it leaves the box [blo, bhi]
 * it is in, given the inverses of its unit direction (an axis the ray
 * runs along gives an infinity or a NaN, which the comparison passes
 * over; written out because fminf is a call at the baseline's flags). */
static inline float exit_of(const float o[3], const float inv[3],
                            const float blo[3], const float bhi[3])
{
    float s = INFINITY;
    for (int a = 0; a < 3; a++) {
        const float e = ((inv[a] >= 0.0f ? bhi[a] : blo[a]) - o[a]) * inv[a];
        s = e < s ? e : s;
    }
    return s;
}

/* Where a sample reads its corners: the first of the eight (the others
 * are one step along x, y and z from it) and the weights along each
 * axis of the far ones. */
typedef struct corners {
    const uint16_t *base;
    float f[3];
} corners;

/* The corners of the sample at lattice coordinates u (in occupancy
 * cells) of cell c, in brick `brick`; their cache lines are fetched
 * while other rays take their steps. */
static inline void find_corners(const nerf_bake *b, int32_t brick,
                                const float u[3], const uint32_t c[3],
                                corners *q)
{
    const uint32_t k = b->k, e = k + 1, stride = b->stride;
    uint32_t v[3];
    for (int a = 0; a < 3; a++) {
        float l = (u[a] - (float)c[a]) * (float)k;
        l = l < 0.0f ? 0.0f : l;
        uint32_t i = (uint32_t)l;
        i = i > k - 1 ? k - 1 : i;
        v[a] = i;
        q->f[a] = l - (float)i < 1.0f ? l - (float)i : 1.0f;
    }
    q->base = b->data + ((size_t)brick * b->corners +
                         v[0] + e * (v[1] + e * v[2])) * stride;
    const size_t dy = (size_t)e * stride, dz = (size_t)e * e * stride;
    /* Two corners a row: from the first value of one to the last of the
     * other. */
    const size_t last = 2 * (size_t)stride - 1;
    for (int i = 0; i < 4; i++) {
        const uint16_t *row = q->base + (i & 1) * dy + (i >> 1) * dz;
        __builtin_prefetch(row);
        __builtin_prefetch(row + last);
    }
}

/*
 * A sample from its corners: its density, and its colour as the
 * density-weighted mean of its corners' (a corner baked empty has no
 * colour to give).  Returns the density; rgb is set when it is positive.
 */
static float sample(const nerf_bake *b, const corners *q, const float *y,
                    float rgb[3])
{
    const uint32_t e = b->k + 1, stride = b->stride;
    const uint16_t *base = q->base;
    const float *f = q->f;
    const size_t dy = (size_t)e * stride, dz = (size_t)e * e * stride;
    const uint16_t *at[8];
    float w[8];
    float sigma = 0.0f;
    for (int i = 0; i < 8; i++) {
        const int x = i & 1, yy = i >> 1 & 1, z = i >> 2;
        at[i] = base + x * stride + yy * dy + z * dz;
        const float wx = x ? f[0] : 1.0f - f[0];
        const float wy = yy ? f[1] : 1.0f - f[1];
        const float wz = z ? f[2] : 1.0f - f[2];
        w[i] = wx * wy * wz * nerf__bf16_to(at[i][0]);
        sigma += w[i];
    }
    if (!(sigma > 0.0f)) {
        return 0.0f;
    }
    /* The corners' coefficients, weighted, then the basis once. */
    float acc[1 + 3 * NERF__BAKE_MAX_COEFS] = {0.0f};
    for (int i = 0; i < 8; i++) {
        if (w[i] > 0.0f) {
            for (uint32_t j = 1; j < stride; j++) {
                acc[j] += w[i] * nerf__bf16_to(at[i][j]);
            }
        }
    }
    const float inv_sigma = 1.0f / sigma;
    for (uint32_t ch = 0; ch < 3; ch++) {
        const float *qc = acc + 1 + ch * b->coefs;
        float x = 0.0f;
        for (uint32_t j = 0; j < b->coefs; j++) {
            x += qc[j] * y[j];
        }
        x *= inv_sigma;
        rgb[ch] = x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x;
    }
    return sigma;
}

/* A ray on its way through the bake. */
typedef struct ray {
    float o[3], dn[3], inv[3]; /* origin, unit direction, its inverses */
    float s0, s1, len;         /* the span marched, |d| */
    float T;                   /* transmittance so far */
    uint32_t i;                /* the next sample: s0 + (i + 0.5) step */
    bool live;
    bool found;                /* sample i is in a brick, at its corners */
    corners at;
    float y[NERF__BAKE_MAX_COEFS]; /* the colours' basis along dn */
    ray_out out;
} ray;

/* The first sample of r at or past distance s, less SKIP_MARGIN of a
 * step so that rounding cannot jump over one beyond it; UINT32_MAX past
 * any sample. */
static inline uint32_t sample_from(const nerf_bake *b, const ray *r, float s)
{
    const float next =
        floorf((s - r->s0) * b->inv_step - 0.5f - SKIP_MARGIN) + 1.0f;
    return next < (float)UINT32_MAX ? (next > 0.0f ? (uint32_t)next : 0u)
                                    : UINT32_MAX;
}

/* Set r up for the ray o + t d, seen along the unit direction view: live
 * when it crosses the box of the bricks within the model's range of t;
 * it meets no brick before distance near or after far (from o, along the
 * ray). */
static void ray_begin(const nerf_bake *b, const float o[3], const float d[3],
                      const float view[3], float near, float far, ray *r)
{
    memset(&r->out, 0, sizeof r->out);
    r->live = false;
    if (!(near < INFINITY)) {
        return;
    }
    const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0.0f)) {
        return;
    }
    for (int a = 0; a < 3; a++) {
        r->o[a] = o[a];
        r->dn[a] = d[a] / len;
        r->inv[a] = 1.0f / r->dn[a];
    }
    float s0, s1;
    if (!nerf__box_span(r->o, r->dn, b->used_lo, b->used_hi, &s0, &s1)) {
        return;
    }
    s0 = fmaxf(s0, b->t_near * len);
    s1 = fminf(fminf(s1, b->t_far * len), far);
    if (!(s0 < s1)) {
        return;
    }
    r->s0 = s0;
    r->s1 = s1;
    r->len = len;
    r->T = 1.0f;
    r->i = near > s0 ? sample_from(b, r, near) : 0;
    r->live = r->i != UINT32_MAX;
    r->found = false;
    nerf__bake_basis(b->degree, view, r->y);
}

/* Take sample i of r, found in a brick on its last turn, and composite
 * it.  Clears r->live when no light gets through any more. */
static void take_sample(const nerf_bake *b, ray *r)
{
    const float dt = b->step;
    const float s = r->s0 + ((float)r->i + 0.5f) * dt;
    r->found = false;
    r->i++;
    float rgb[3];
    const float sigma = sample(b, &r->at, r->y, rgb);
    if (sigma > 0.0f) {
        const float alpha = 1.0f - expf(-sigma * dt);
        const float weight = r->T * alpha;
        for (int ch = 0; ch < 3; ch++) {
            r->out.rgb[ch] += weight * rgb[ch];
        }
        r->out.depth += weight * (s / r->len);
        r->out.opacity += weight;
        r->T *= 1.0f - alpha;
        if (r->T < MIN_TRANSMITTANCE) {
            for (int ch = 0; ch < 3; ch++) {
                r->out.rgb[ch] += r->T * rgb[ch];
            }
            r->out.depth += r->T * (s / r->len);
            r->out.opacity += r->T;
            r->live = false;
        }
    }
}

/* Where sample i of a live ray falls: in empty space, which it skips, or
 * in a brick, whose corners it fetches for its next turn.  Clears
 * r->live past the end of the ray. */
static void find_sample(const nerf_bake *b, ray *r)
{
    const float s = r->s0 + ((float)r->i + 0.5f) * b->step;
    if (!(s < r->s1)) {
        r->live = false;
        return;
    }
    const float res = (float)b->res;
    float u[3];
    uint32_t c[3];
    for (int a = 0; a < 3; a++) {
        u[a] = (r->o[a] + s * r->dn[a] - b->lo[a]) * b->inv_cell[a];
        u[a] = u[a] < 0.0f ? 0.0f : u[a] >= res ? nextafterf(res, 0.0f) : u[a];
        c[a] = (uint32_t)u[a];
    }
    const size_t cell = c[0] + (size_t)b->res * (c[1] + (size_t)b->res * c[2]);
    const uint32_t far = b->empty[cell];
    if (far > 0) {
        /* Leave the cube of empty cells around this one. */
        float blo[3], bhi[3];
        for (int a = 0; a < 3; a++) {
            blo[a] = b->lo[a] + ((float)c[a] - (float)(far - 1)) * b->cell[a];
            bhi[a] = b->lo[a] + ((float)c[a] + (float)far) * b->cell[a];
        }
        /* At worst a sample in an empty cell is taken again, and skips. */
        const uint32_t next =
            sample_from(b, r, exit_of(r->o, r->inv, blo, bhi));
        if (next == UINT32_MAX) {
            r->live = false;
            return;
        }
        r->i = next > r->i + 1 ? next : r->i + 1;
        return;
    }
    const int32_t brick = b->brick_of[cell];
    if (brick < 0) {
        r->i++; /* Only when the distances are not set: a test's. */
        return;
    }
    find_corners(b, brick, u, c, &r->at);
    r->found = true;
}

/* A live ray's turn: the sample found on its last turn, and a look for
 * the next, whose corners arrive while the other rays take theirs. */
static inline void ray_step(const nerf_bake *b, ray *r)
{
    if (r->found) {
        take_sample(b, r);
        if (!r->live) {
            return;
        }
    }
    find_sample(b, r);
}

typedef struct render_job {
    const nerf_bake *b;
    const nerf_camera *cam;
    const float *near, *far; /* nerf__bake_first_hits(), or NULL */
    uint32_t hit_blocks_x;
    uint32_t tiles_x;      /* tiles across the image */
    float ndc_focal, ndc_width, ndc_height; /* the frustum of NDC */
    float *rgb, *depth, *opacity;
} render_job;

/* Tiles of TILE_SIDE x TILE_SIDE pixels: their rays meet the same bricks,
 * which stay in cache from one ray to the next (rows of pixels would
 * fetch each brick once a row). */
static void render_tiles(void *ctx, size_t begin, size_t end)
{
    const render_job *j = ctx;
    const nerf_bake *b = j->b;
    const uint32_t w = j->cam->width, h = j->cam->height;
    float o[3 * TILE_SIDE], d[3 * TILE_SIDE], rgb[3 * TILE_SIDE];
    float view[3 * TILE_SIDE];
    float op[TILE_SIDE];
    for (size_t t = begin; t < end; t++) {
        const uint32_t x0 = (uint32_t)(t % j->tiles_x) * TILE_SIDE;
        const uint32_t y0 = (uint32_t)(t / j->tiles_x) * TILE_SIDE;
        const uint32_t n = w - x0 < TILE_SIDE ? w - x0 : TILE_SIDE;
        for (uint32_t row = y0; row < y0 + TILE_SIDE && row < h; row++) {
            const size_t first = (size_t)row * w + x0;
            /* The row's squares of shared bounds. */
            const float *near = NULL, *far = NULL;
            if (j->near != NULL) {
                const size_t at = (size_t)(row / NERF__BAKE_HIT_BLOCK) *
                                  j->hit_blocks_x;
                near = j->near + at;
                far = j->far + at;
            }
            nerf__camera_rays(j->cam, first, n, o, d);
            /* The colours' view directions are the camera's rays', in
             * NDC too (the networks were trained so). */
            for (uint32_t i = 0; i < n; i++) {
                const float *di = d + 3 * i;
                const float len =
                    sqrtf(di[0] * di[0] + di[1] * di[1] + di[2] * di[2]);
                for (int a = 0; a < 3; a++) {
                    view[3 * i + a] = di[a] / len;
                }
            }
            if (b->ndc) {
                nerf__ndc_rays(j->ndc_focal, j->ndc_width, j->ndc_height,
                               1.0f, n, o, d, o, d);
            }
            ray rays[TILE_SIDE];
            for (uint32_t i = 0; i < n; i++) {
                ray_begin(b, o + 3 * i, d + 3 * i, view + 3 * i,
                          near ? near[(x0 + i) / NERF__BAKE_HIT_BLOCK] : 0.0f,
                          far ? far[(x0 + i) / NERF__BAKE_HIT_BLOCK]
                              : INFINITY,
                          &rays[i]);
            }
            /* The row's rays a step each in turn: their chains of loads
             * and branches overlap, where one ray at a time waits on
             * each. */
            for (bool any = true; any;) {
                any = false;
                for (uint32_t i = 0; i < n; i++) {
                    if (rays[i].live) {
                        ray_step(b, &rays[i]);
                        any = true;
                    }
                }
            }
            for (uint32_t i = 0; i < n; i++) {
                const ray_out *r = &rays[i].out;
                for (int ch = 0; ch < 3; ch++) {
                    rgb[3 * i + ch] =
                        r->rgb[ch] + (1.0f - r->opacity) * b->background;
                }
                op[i] = r->opacity;
                if (j->depth) {
                    j->depth[first + i] = r->depth;
                }
            }
            if (b->appearance) {
                nerf__appearance_apply(b->code, n, rgb, op, NULL,
                                       b->background);
            }
            if (j->rgb) {
                memcpy(j->rgb + 3 * first, rgb, 3 * n * sizeof(float));
            }
            if (j->opacity) {
                memcpy(j->opacity + first, op, n * sizeof(float));
            }
        }
    }
}

NERF_API int nerf_bake_render_image(const nerf_bake *bake,
                                    const nerf_camera *camera,
                                    float *rgb_out, float *depth_out,
                                    float *opacity_out,
                                    size_t pixel_capacity)
{
    if (bake == NULL || camera == NULL) {
        return nerf__error(NERF_EINVAL, FN ": NULL %s",
                           bake ? "camera" : "bake");
    }
    if (rgb_out == NULL && depth_out == NULL && opacity_out == NULL) {
        return nerf__error(NERF_EINVAL, FN ": every output is NULL");
    }
    nerf_camera cam;
    int rc = nerf__camera_read(&cam, camera, FN);
    if (rc != NERF_OK) {
        return rc;
    }
    const size_t pixels = (size_t)cam.width * cam.height;
    if (pixel_capacity < pixels) {
        return nerf__error(NERF_EINVAL, FN ": capacity %zu is below the "
                           "camera's %zu pixels", pixel_capacity, pixels);
    }
    const uint32_t tx = (cam.width + TILE_SIDE - 1) / TILE_SIDE;
    const uint32_t ty = (cam.height + TILE_SIDE - 1) / TILE_SIDE;
    render_job j = {.b = bake, .cam = &cam, .tiles_x = tx, .rgb = rgb_out,
                    .depth = depth_out, .opacity = opacity_out,
                    .ndc_focal = bake->ndc_focal,
                    .ndc_width = bake->ndc_width,
                    .ndc_height = bake->ndc_height};
    if (bake->ndc && bake->ndc_focal == 0.0f) {
        /* No scene frustum recorded: the camera's own. */
        j.ndc_focal = cam.fx;
        j.ndc_width = (float)cam.width;
        j.ndc_height = (float)cam.height;
    }
    /* Without the bounds (or the memory for them) rays march from the
     * box of the bricks: slower, the same pixels. */
    float *near = NULL;
    if (bake->first_hits) {
        j.hit_blocks_x = nerf__bake_hit_blocks(cam.width);
        const size_t blocks =
            (size_t)j.hit_blocks_x * nerf__bake_hit_blocks(cam.height);
        near = nerf__alloc(&bake->env, 2 * blocks * sizeof(float));
        if (near != NULL &&
            nerf__bake_first_hits(bake, &cam, near, near + blocks)) {
            j.near = near;
            j.far = near + blocks;
        }
    }
    /* A tile's rays cost from a few hundred operations (empty) to tens of
     * thousands (opaque surfaces). */
    nerf__parallel_for((size_t)tx * ty, 64 * 1000, render_tiles, &j);
    nerf__free(&bake->env, near);
    return NERF_OK;
}
