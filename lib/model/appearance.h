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
 * nothing, and the codes could wander with the networks; a small pull of
 * every code towards 0 (NERF__CODE_PRIOR) settles them on the networks'
 * side, where the test views, which no code belongs to,
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
 * How the codes learn.  A code's loss is, near its best, a quadratic in
 * it whose curvature the rays of its photo give as plainly as its slope
 * (Gauss-Newton: the sum of the map's squared derivatives times the
 * loss's 2/(3 rays)), so that slope over curvature is the distance to the
 * photo's best gain.  Each step moves a code a fraction NERF__CODE_STEP of
 * that distance, taken from running means (NERF__CODE_MEMORY) of the
 * slope and the curvature over the steps its photo was drawn in: a
 * photo's few rays a step give a noisy distance, the means a steadier
 * one.  A step in units of the distance is the same for every scene,
 * batch and image count, and it is small where the data say little,
 * which Adam, whose normalised steps are of the learning rate's size
 * whatever the slope, is not: with Adam at 10 times the networks' rate
 * (libnerf 0.13.0) the codes of photos that all look alike wandered by
 * 0.5 to 0.9% from step to step and cost 0.10 to 0.30 dB of test PSNR
 * (0.20 on average; tests/train/test_appearance.c's scene, seeds 0 to
 * 3, 16 test views); with these steps and the prior below, 0.11 on
 * average and 0.22 at most, for as much gain on varied photos or more
 * (bench/bench_captures.c; docs/api-notes.md).  Steps of 0.3 and 0.03 of
 * the distance did about as well as 0.1.
 */
#define NERF__CODE_STEP 0.1f
#define NERF__CODE_MEMORY 0.9f

/*
 * The first steps of a model's training, during which the codes stay as
 * they are while the density takes shape.  A code learnt from the start
 * takes in how a half-formed scene renders each photo, and the view-
 * dependent colour settles around it, so that neither lets go later: on
 * photos that all look alike, codes learnt from the first step cost 1.0
 * and 2.7 dB of test PSNR (seeds 0 and 1, 400 steps, Adam), codes held
 * for 100 steps 0.1 dB after 800.
 */
#define NERF__CODE_WARMUP 100u

/*
 * The pull towards 0: a prior whose curvature is this over the number of
 * codes, added to each code's in a step its photo is drawn in.  The loss
 * is a mean over the batch, so that a photo's share of a step's
 * curvature in its code is about 2/3 E[x^2] / images (x the map's
 * derivative, a ray's colour in front of its background): the prior is
 * then a fixed share of it whatever the batch and the number of photos:
 * about a fifth early in training on the built-in scene, less later and
 * on photos that the subject fills.  It keeps a code whose rays give it
 * almost no curvature (they hit little but background) from steps that
 * slope over curvature would make huge, and settles the directions the
 * data leave free (above) on the networks' side; it also shrinks the gain a photo sets,
 * by that share of its logarithm, so that a photo's own render
 * (NERF_APPEARANCE_OF) shows a little less of its difference than the
 * photo has.  A prior as a share of the step's mean curvature instead
 * (0.05 of it) let the codes of photos alike drift with the view-
 * dependent colour (0.29 dB lost on seed 3), and a larger share (0.2)
 * took back 0.5 to 0.8 dB of what varied photos gain.
 */
#define NERF__CODE_PRIOR 6e-3f

/* The most codes a model holds: one per image of the largest dataset. */
#define NERF__CODES_MAX (1u << 20)

typedef struct nerf__appearance {
    uint32_t n;  /* codes: the training images; 0: the model has none */
    /* [n, NERF__CODE_FLOATS] each, carved from one block: the codes; the
     * step's slopes and curvatures, summed over its rays; and their
     * running means, which checkpoints keep. */
    float *code, *grad, *curv, *mean_grad, *mean_curv;
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

/* The codes' step at the model's step t (1-based), the step's slopes and
 * curvatures zeroed as they are read. */
void nerf__appearance_step(struct nerf_model *m, uint64_t t);

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
 * and opacity the ray's values before it, bg its background, and
 * loss_curv the loss's second derivative in a pixel's channel.  Adds the
 * code's slope to grad[NERF__CODE_FLOATS] and its Gauss-Newton curvature
 * to curv[NERF__CODE_FLOATS], and writes dL/d(rgb) and dL/d(opacity) of
 * the ray before the map.
 */
void nerf__appearance_backward(const float code[NERF__CODE_FLOATS],
                               const float d_out[3], const float rgb[3],
                               float opacity, const float bg[3],
                               float grad[NERF__CODE_FLOATS], float d_rgb[3],
                               float *d_opacity, float loss_curv,
                               float curv[NERF__CODE_FLOATS]);

#endif
