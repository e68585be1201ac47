/*
 * Per-image appearance codes (nerf_trainer_options.appearance_codes): one
 * small learned code per training image that absorbs how that photo's
 * exposure and white balance differ from the others, so that the networks
 * need not explain the difference with geometry (floaters) or with view
 * dependence.
 *
 * A code is a gain per colour channel, kept as its logarithm l, applied
 * to every sample's colour of the rays of its image: c' = e^l c.
 * Exposure and white balance scale each channel of the light a camera
 * records, which an sRGB encoding turns into roughly a scale of each
 * encoded channel, so that a photo's look is three numbers.  (A latent
 * vector into the colour network, as NeRF in the Wild and nerfacto use,
 * can also model light that moves, at a cost per sample; a full colour
 * matrix and offset per photo, tried first, has nine more numbers each
 * for a few rays a step to pin down, and learnt noise.)  The map costs
 * nothing per sample: compositing is linear in the colours, so applying
 * it to a ray's composited colour C (of opacity a, finished on
 * background g) gives the same pixel,
 *
 *     out = e^l (C - (1 - a) g) + (1 - a) g,
 *
 * and the background, which no photo's camera saw, stays as it is.
 *
 * The codes are fixed only up to what the networks can take over: one
 * gain common to all photos (the colours times k, every code minus
 * log k), and gains that vary smoothly from one camera position to the
 * next (the view-dependent colour).  Along those directions the data say
 * nothing, and Adam's normalised steps would let the codes wander; a
 * small pull of every code towards 0 (NERF__CODE_DECAY) settles them on
 * the networks' side, where the test views, which no code belongs to,
 * see them.  Gains that differ from photo to photo at random, as
 * automatic exposure makes them, no smooth function of the camera can
 * take, and the data hold those codes where the photos put them.  The
 * neutral appearance, the one renders use unless asked for a photo's, is
 * the mean of the codes: the photos' average look.
 */
#ifndef NERF_MODEL_APPEARANCE_H
#define NERF_MODEL_APPEARANCE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "env.h"

struct nerf_model;

/* Floats of one code: the red, green and blue log-gains. */
#define NERF__CODE_FLOATS 3u

/*
 * The codes' learning rate, as a multiple of the networks' scheduled one.
 * A code sees only its own photo's few rays a step, and the view-
 * dependent colour learns a photo's look as readily as a code does: at
 * the networks' rate the colour took most of it first.  On the built-in
 * scene with varied photos (tests/train/test_appearance.c, batch 1024,
 * 400 steps of the fast preset, codes learnt from the first step), rates
 * of 1, 3 and 10 times the networks' gave test PSNRs of 29.84, 30.36 and
 * 34.28 dB, against 29.18 without codes.
 */
#define NERF__CODE_RATE 10.0

/*
 * The first steps of a model's training, during which the codes stay as
 * they are while the density takes shape.  A code learnt from the start
 * takes in how a half-formed scene renders each photo, and the view-
 * dependent colour settles around it, so that neither lets go later: on
 * photos that all look alike, codes learnt from the first step cost 1.0
 * and 2.7 dB of test PSNR (seeds 0 and 1, 400 steps), codes held for
 * 100 steps 0.1 dB after 800.
 */
#define NERF__CODE_WARMUP 100u

/* The pull towards 0 added to each code's gradient, per unit of the
 * code: small beside the data's hold on a code that a photo's exposure
 * sets (the loss's curvature in a code is about 3e-3 for a thousand-ray
 * batch over sixty photos), so that it moves such a code by a few per
 * cent of its value; 2e-3 instead cost 6 dB on varied photos. */
#define NERF__CODE_DECAY 1e-4f

/* The most codes a model holds: one per image of the largest dataset. */
#define NERF__CODES_MAX (1u << 20)

typedef struct nerf__appearance {
    uint32_t n;  /* codes: the training images; 0: the model has none */
    /* [n, NERF__CODE_FLOATS] each: the codes, their gradients and their
     * Adam moments, carved from one block. */
    float *code, *grad, *adam_m, *adam_v;
    void *block;
} nerf__appearance;

/* A zeroed set of n codes (gains of 1) for m; NERF_ENOMEM leaves m as it
 * was. */
int nerf__appearance_create(struct nerf_model *m, uint32_t n);
void nerf__appearance_free(const nerf__env *env, nerf__appearance *a);

/* The code of `which`, as nerf_renderer_options.appearance counts
 * (NERF_APPEARANCE_NEUTRAL: the mean of all; i + 1: image i's, i < n),
 * into code[NERF__CODE_FLOATS]. */
void nerf__appearance_pick(const nerf__appearance *a, uint32_t which,
                           float code[NERF__CODE_FLOATS]);

/* NERF_OK when `which` names a code m has (NERF_APPEARANCE_NEUTRAL
 * always), else NERF_EINVAL with a message naming fn. */
int nerf__appearance_check(const struct nerf_model *m, uint32_t which,
                           const char *fn);

/* The Adam step of the codes at step t (1-based) with rate lr, the
 * gradients zeroed as they are read. */
void nerf__appearance_adam(struct nerf_model *m, uint64_t t, double lr);

/*
 * The map on n rays: rgb [n, 3] is the composited colour, opacity [n] its
 * opacity, bg their backgrounds ([n, 3], or NULL for bg_all's one colour
 * for all).  Written in place.
 */
void nerf__appearance_apply(const float code[NERF__CODE_FLOATS], size_t n,
                            float *rgb, const float *opacity,
                            const float *bg, float bg_all);

/*
 * One ray's backward: d_out is dL/d(out) of the pixel the map gave, rgb
 * and opacity the ray's values before it, bg its background.  Adds the
 * code's gradient to grad[NERF__CODE_FLOATS] and writes dL/d(rgb) and
 * dL/d(opacity) of the ray before the map.
 */
void nerf__appearance_backward(const float code[NERF__CODE_FLOATS],
                               const float d_out[3], const float rgb[3],
                               float opacity, const float bg[3],
                               float grad[NERF__CODE_FLOATS], float d_rgb[3],
                               float *d_opacity);

#endif
