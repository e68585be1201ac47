/*
 * A model baked for fast renders (nerf_bake_*, include/nerf.h): on each
 * occupied cell of its occupancy grid, a brick of (k + 1)^3 corner points
 * of a k x k x k voxel lattice, each holding the density and the
 * coefficients of spherical harmonics that give the colour seen from any
 * direction.  A render looks up and interpolates the corners around each
 * sample instead of evaluating the networks: 8 reads of one record where
 * the networks read 64 table entries and run three layers.
 *
 * Bricks keep their own corners (the faces they share with a neighbour
 * are stored twice) so that every sample's eight corners are in one
 * brick: one lookup a sample, at the cost of (k + 1)^3 / k^3 of the
 * memory (about twice for k = 4).
 *
 * Values are bfloat16 (the upper half of a float): 8 bits of mantissa, a
 * relative error of 2^-9, far below what a colour of 8 bits or a density
 * inside exp() resolves, for half the memory of floats.
 */
#ifndef NERF_BAKE_BAKE_H
#define NERF_BAKE_BAKE_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "appearance.h"
#include "env.h"
#include "nerf.h"

/* Largest sh_degree: 9 coefficients a channel, 28 values a point. */
#define NERF__BAKE_MAX_DEGREE 2u
#define NERF__BAKE_MAX_COEFS 9u

struct nerf_bake {
    nerf__env env;
    uint32_t res;          /* occupancy cells per axis */
    uint32_t k;            /* voxels per cell edge */
    uint32_t corners;      /* (k + 1)^3 points a brick */
    uint32_t degree;       /* sh_degree */
    uint32_t coefs;        /* (degree + 1)^2 a channel */
    uint32_t stride;       /* values a point: 1 + 3 coefs */
    float lo[3], hi[3];
    /* The box of the cells with bricks: rays start and end on it. */
    float used_lo[3], used_hi[3];
    float inv_cell[3];     /* res / (hi - lo) */
    float cell[3];         /* (hi - lo) / res */
    int32_t *brick_of;     /* [res^3]: brick index, -1 for none */
    /* [res^3]: 0 for a cell with a brick, else its distance in cells
     * (Chebyshev, capped at 255) to the nearest one: a ray in a cell at
     * distance d crosses the cube of cells within d - 1 of it without
     * looking (bake_space.c). */
    uint8_t *empty;
    /* The cells with a brick that touch a cell without one (or the
     * grid's side): a ray that does not start among the bricks meets one
     * of these first (bake_hits.c). */
    uint32_t *surface;
    size_t n_surface;
    /* Whether renders start rays at bounds of their first brick from the
     * surface cells (a test turns it off to compare). */
    bool first_hits;
    uint16_t *data;        /* [bricks][corners][stride] bfloat16 */
    uint64_t bricks;
    uint64_t points;       /* points whose colour was fitted */
    float step;            /* world distance between samples */
    float inv_step;        /* 1 / step */
    float t_near, t_far;   /* the model's range of t */
    /* A forward-facing model's rays are marched in NDC, the frustum's
     * (focal 0: the camera's own, as nerf_renderer_render_image()). */
    bool ndc;
    float ndc_focal, ndc_width, ndc_height;
    float background;      /* 1 white, 0 black */
    bool appearance;       /* whether code maps the colours */
    float code[NERF__CODE_FLOATS];
};

/* Round to nearest, ties to even; the values baked are finite. */
static inline uint16_t nerf__bf16_from(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    u += 0x7fffu + ((u >> 16) & 1u);
    return (uint16_t)(u >> 16);
}

static inline float nerf__bf16_to(uint16_t h)
{
    uint32_t u = (uint32_t)h << 16;
    float x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/*
 * The fit of colours seen in n_dirs directions to spherical harmonics of
 * degree: dirs [n_dirs, 3] unit directions spread evenly over the cap of
 * the sphere within max_angle (radians, up to pi: the whole sphere) of
 * -z, and proj [coefs, n_dirs], the least-squares projection, so that a
 * point's coefficients for one channel are proj times its colours in
 * dirs.  NERF_ENOMEM, or NERF_EINVAL if the directions cannot determine
 * the coefficients.
 */
int nerf__bake_fit_init(const nerf__env *env, uint32_t degree,
                        uint32_t n_dirs, double max_angle, float **dirs,
                        float **proj);

/* The n = (degree + 1)^2 basis values of a unit direction d. */
void nerf__bake_basis(uint32_t degree, const float d[3], float *y);

/* Pixels along each side of the squares that share bounds. */
#define NERF__BAKE_HIT_BLOCK 4u

static inline uint32_t nerf__bake_hit_blocks(uint32_t pixels)
{
    return (pixels + NERF__BAKE_HIT_BLOCK - 1) / NERF__BAKE_HIT_BLOCK;
}

/*
 * For each square of NERF__BAKE_HIT_BLOCK pixels a side of cam (row by
 * row, nerf__bake_hit_blocks() of them across and down), distances along
 * its pixels' rays (from the camera's centre, in world units) before near
 * and after far of which they meet no cell with a brick: near INFINITY
 * where they meet none.  A ray
 * that meets a brick meets a surface cell first and last, so the surface
 * cells' boxes bound it.  False, with near and far untouched, when the
 * bounds cannot be had cheaply: lens distortion, a model in NDC, a camera
 * among the bricks.
 */
bool nerf__bake_first_hits(const nerf_bake *b, const nerf_camera *cam,
                           float *near, float *far);

/* Fill b->empty, b->surface and the box of the bricks from b->brick_of. */
int nerf__bake_empty_space(nerf_bake *b);

/* Fill the bricks of b (brick_of, data, bricks, points) from model. */
int nerf__bake_bricks(nerf_bake *b, const struct nerf_model *model,
                      const nerf_bake_options *o);

#endif
