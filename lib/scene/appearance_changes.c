/*
 * nerf_scene_options.appearance: training photos whose exposure and white
 * balance differ, as a phone's automatic exposure and white balance make
 * them differ between the shots of one walk around.
 *
 * Each training view's channels are scaled by gains drawn for that view:
 * an exposure common to the three channels, 2^u with u uniform in [-1/2,
 * 1/2] (a camera's exposure, half a stop either way, as an sRGB encoding
 * roughly turns it into a scale of the encoded values), times a white
 * balance per channel, 2^v with v uniform in [-0.15, 0.15].  Each
 * channel's gains are then divided by their geometric mean over the
 * training views, so that the training photos' average look is the
 * scene's own, which the validation and test views keep: a model that
 * learns each photo's appearance apart from the scene (as log-gains,
 * model/appearance.h) renders the test views with the mean of what it
 * learned.  Values past 255 clip, as a camera's do.
 */
#include <math.h>

#include "rng.h"
#include "scene_internal.h"

/* Keys the draws apart from the validation views' placement. */
#define APPEARANCE_STREAM UINT64_C(0x61707065)

#define EXPOSURE_STOPS 0.5
#define BALANCE_STOPS 0.15

static void raw_gains(const nerf_scene_options *o, uint32_t i, double g[3])
{
    nerf__rng rng = nerf__rng_make(o->seed ^ APPEARANCE_STREAM, i);
    const double e = 2.0 * nerf__rng_uniform_d(&rng) - 1.0;
    for (int c = 0; c < 3; c++) {
        const double v = 2.0 * nerf__rng_uniform_d(&rng) - 1.0;
        g[c] = exp2(EXPOSURE_STOPS * e + BALANCE_STOPS * v);
    }
}

void nerf__scene_appearance_gains(const nerf_scene_options *o, int split,
                                  uint32_t i, double gains[3])
{
    gains[0] = gains[1] = gains[2] = 1.0;
    if (o->appearance != NERF_SCENE_APPEARANCE_VARIED || split != 0) {
        return;
    }
    double mean[3] = {0.0, 0.0, 0.0};
    for (uint32_t k = 0; k < o->n_train; k++) {
        double g[3];
        raw_gains(o, k, g);
        for (int c = 0; c < 3; c++) {
            mean[c] += log(g[c]) / o->n_train;
        }
    }
    raw_gains(o, i, gains);
    for (int c = 0; c < 3; c++) {
        gains[c] /= exp(mean[c]);
    }
}

void nerf__scene_vary_view(const nerf_scene_options *o, int split,
                           uint32_t i, uint32_t channels, uint8_t *px)
{
    double g[3];
    nerf__scene_appearance_gains(o, split, i, g);
    if (g[0] == 1.0 && g[1] == 1.0 && g[2] == 1.0) {
        return;
    }
    const size_t n = (size_t)o->width * o->height;
    for (size_t p = 0; p < n; p++) {
        uint8_t *v = px + channels * p;
        for (int c = 0; c < 3; c++) {
            const double x = floor(v[c] * g[c] + 0.5);
            v[c] = (uint8_t)(x > 255.0 ? 255.0 : x);
        }
    }
}
