/* The random rays of one training step. */
#include "camera.h"
#include "dataset.h"
#include "rng.h"
#include "sampler.h"
#include "trainer.h"

/* Keys the stream of ray choices apart from the sampler's streams. */
#define TRAIN_STREAM UINT64_C(0x7472616e)

/*
 * Ray r's random background and its target moved onto it.  The colour is
 * the ray's own draw (keyed by the model's seed, as the ray choices, and
 * by the ray's number across steps, as the sampler's draws), so it does
 * not depend on which rays the others are.  The stored pixel is the
 * block's mean of rgb a + W (1 - a) with W the grey the loader composited
 * onto, and the block's coverage A is the mean of a; straight alpha onto
 * bg is then pixel + (bg - W) (1 - A), up to rounding, without keeping
 * the images' RGBA.
 */
static void background_target(nerf_trainer *t, uint64_t step, uint32_t r,
                              size_t at)
{
    const nerf_dataset *ds = t->dataset;
    nerf__rng rng = nerf__ray_rng(t->model->opts.seed,
                                  NERF__STREAM_BACKGROUND,
                                  step * t->opts.batch_rays + r);
    const float clear = 1.0f - (float)ds->alpha[at] * (1.0f / 65535.0f);
    float *bg = t->backgrounds + 3 * r;
    for (int c = 0; c < 3; c++) {
        bg[c] = nerf__rng_uniform(&rng);
        t->targets[3 * r + c] += (bg[c] - ds->alpha_bg) * clear;
    }
}

void nerf__trainer_pick_rays(nerf_trainer *t, uint64_t step)
{
    const uint32_t W = t->width, H = t->height;
    /* The first steps of 360-degree scenes look only at the central crop:
     * the reference does this so the network locks on to the object before
     * the mostly empty background can make it collapse to all-background. */
    uint32_t x0 = 0, y0 = 0, cw = W, ch = H;
    if (step < t->opts.precrop_steps) {
        cw = (uint32_t)(W * t->opts.precrop_fraction);
        ch = (uint32_t)(H * t->opts.precrop_fraction);
        cw = cw ? cw : 1;
        ch = ch ? ch : 1;
        x0 = (W - cw) / 2;
        y0 = (H - ch) / 2;
    }
    nerf__rng rng = nerf__rng_make(t->model->opts.seed ^ TRAIN_STREAM, step);
    for (uint32_t r = 0; r < t->opts.batch_rays; r++) {
        uint32_t img = (uint32_t)(nerf__rng_uniform_d(&rng) * t->n_images);
        uint32_t x = x0 + (uint32_t)(nerf__rng_uniform_d(&rng) * cw);
        uint32_t y = y0 + (uint32_t)(nerf__rng_uniform_d(&rng) * ch);
        size_t pixel = (size_t)y * W + x;
        nerf__camera_rays(&t->cameras[img], pixel, 1, t->origins + 3 * r,
                          t->directions + 3 * r);
        const float *src = t->dataset->pixels + ((size_t)img * H * W + pixel) * 3;
        for (int c = 0; c < 3; c++) {
            t->targets[3 * r + c] = src[c];
        }
        if (t->random_bg) {
            background_target(t, step, r, (size_t)img * H * W + pixel);
        }
    }
}
