/* The random rays of one training step. */
#include "camera.h"
#include "dataset.h"
#include "parallel.h"
#include "prefetch.h"
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

/* How many rays ahead a range fetches the pixels of: the draws scatter
 * the rays over all the images, so each reads two lines no cache holds. */
#define AHEAD 8

typedef struct fill_job {
    nerf_trainer *t;
    uint64_t step;
} fill_job;

/* Rays [begin, end) of the step from their drawn pixels: each its own
 * ray, target and background, apart from the others. */
static void fill_rays(void *ctx, size_t begin, size_t end)
{
    const fill_job *j = ctx;
    nerf_trainer *t = j->t;
    const nerf_dataset *ds = t->dataset;
    const size_t plane = (size_t)t->width * t->height;
    for (size_t r = begin; r < end; r++) {
        if (r + AHEAD < end) {
            const size_t ahead = t->picked[r + AHEAD];
            NERF__PREFETCH(ds->pixels + 3 * ahead, 0, 0);
            if (t->random_bg) {
                NERF__PREFETCH(ds->alpha + ahead, 0, 0);
            }
        }
        const size_t at = t->picked[r];
        const size_t img = at / plane;
        nerf__camera_rays(&t->cameras[img], at - img * plane, 1,
                          t->origins + 3 * r, t->directions + 3 * r);
        const float *src = ds->pixels + 3 * at;
        for (int c = 0; c < 3; c++) {
            t->targets[3 * r + c] = src[c];
        }
        if (t->random_bg) {
            background_target(t, j->step, (uint32_t)r, at);
        }
    }
}

/*
 * A ray whose pixel a mask leaves out is drawn again, from a stream of its
 * own (keyed by the seed, the step and the ray's number, as its background
 * is), until it lands on a kept pixel: the rays stay uniform over the kept
 * pixels, a step's choices still depend on nothing but the seed and the
 * step (so a resumed run draws what an uninterrupted one does), and every
 * ray whose first draw is kept is the ray it is without masks.  A crop
 * (precrop) or images that are nearly all masked could make redrawing
 * slow; after MASK_TRIES draws the ray takes the next kept pixel in
 * storage order instead, which the loader guarantees exists.
 */
#define MASK_TRIES 64u

static size_t redraw_masked(const nerf_trainer *t, uint64_t step, uint32_t r,
                            uint32_t x0, uint32_t y0, uint32_t cw,
                            uint32_t ch, size_t at)
{
    const uint8_t *mask = t->dataset->mask;
    const uint32_t W = t->width, H = t->height;
    nerf__rng rng = nerf__ray_rng(t->model->opts.seed, NERF__STREAM_MASK,
                                  step * t->opts.batch_rays + r);
    for (uint32_t k = 0; k < MASK_TRIES; k++) {
        uint32_t img = (uint32_t)(nerf__rng_uniform_d(&rng) * t->n_images);
        uint32_t x = x0 + (uint32_t)(nerf__rng_uniform_d(&rng) * cw);
        uint32_t y = y0 + (uint32_t)(nerf__rng_uniform_d(&rng) * ch);
        size_t again = ((size_t)img * H + y) * W + x;
        if (mask[again] != 0) {
            return again;
        }
    }
    const size_t n = (size_t)t->n_images * H * W;
    for (size_t k = 1; k < n; k++) {
        size_t i = (at + k) % n;
        if (mask[i] != 0) {
            return i;
        }
    }
    return at;
}

/*
 * The draws come from one stream and are cheap; the rest of a ray (its
 * camera ray, and its pixel and coverage, which are cache misses in the
 * images' hundreds of megabytes) is spread over the cores, so that no
 * step spends milliseconds on one while the others wait.
 */
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
    const uint8_t *mask = t->dataset->mask;
    for (uint32_t r = 0; r < t->opts.batch_rays; r++) {
        uint32_t img = (uint32_t)(nerf__rng_uniform_d(&rng) * t->n_images);
        uint32_t x = x0 + (uint32_t)(nerf__rng_uniform_d(&rng) * cw);
        uint32_t y = y0 + (uint32_t)(nerf__rng_uniform_d(&rng) * ch);
        size_t at = ((size_t)img * H + y) * W + x;
        if (mask != NULL && mask[at] == 0) {
            at = redraw_masked(t, step, r, x0, y0, cw, ch, at);
        }
        t->picked[r] = at;
    }
    fill_job j = {t, step};
    nerf__parallel_for(t->opts.batch_rays, 256, fill_rays, &j);
}
