/*
 * The struct behind nerf_renderer and the chunked, threaded driver that
 * image and ray rendering share.
 */
#ifndef NERF_RENDER_RENDERER_H
#define NERF_RENDER_RENDERER_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>

#include "render_batch.h"

/*
 * Rays per network call when rendering.  Batches always start at multiples
 * of this from the first ray of a call, whatever the chunk size and thread
 * count, so every ray meets the same matrix products and results are
 * bitwise reproducible.  64 rays give sgemm 2k-12k rows per pass with the
 * presets, which keeps it efficient, and bound a worker's memory (about
 * 50 MB for the reference network at 64 + 128 samples).
 */
#define NERF__RENDER_BLOCK 64

/* Upper bound of nerf_renderer_options.threads. */
#define NERF__MAX_THREADS 1024u

/* What one worker thread owns. */
typedef struct nerf__worker {
    nerf__batch batch;
    float origins[3 * NERF__RENDER_BLOCK];
    float directions[3 * NERF__RENDER_BLOCK];
    float rgb[3 * NERF__RENDER_BLOCK];
    float depth[NERF__RENDER_BLOCK], opacity[NERF__RENDER_BLOCK];
} nerf__worker;

struct nerf_renderer {
    nerf__env env;
    nerf_renderer_options opts; /* as created; opts.hooks is NULL */
    const nerf_model *model;
    const nerf_sampler *sampler;
    nerf_sampler *own_sampler;  /* made from the model's render settings
                                   when the caller gave none; else NULL */
    float noise_std;            /* raw_noise_std resolved */
    uint32_t threads;           /* resolved, >= 1 */
    size_t chunk;               /* rays per chunk, a multiple of the block */
    atomic_int cancel;
    nerf_progress_cb progress;
    void *progress_user;
    nerf__worker **workers;     /* created on demand, kept until destroy */
    uint32_t n_workers;
};

/* Whether nerf_renderer_cancel() (or the progress callback) asked the
 * running call to stop.  Chunk functions check it between blocks. */
static inline bool nerf__renderer_cancelled(const nerf_renderer *r)
{
    return atomic_load(&((nerf_renderer *)r)->cancel) != 0;
}

/*
 * Render work of one chunk: items first .. first + count - 1 (rays),
 * count <= the renderer's chunk, first a multiple of it.  Returns a status
 * (setting the thread's error message on failure).
 */
typedef int (*nerf__chunk_fn)(void *job, nerf__worker *w, size_t first,
                              size_t count);

/* Make sure the renderer has `count` workers (render_pool.c). */
int nerf__renderer_ensure_workers(nerf_renderer *r, uint32_t count);

/*
 * Run fn over n items in chunks, on the renderer's threads, reporting
 * progress on the calling thread and honouring nerf_renderer_cancel().
 * A worker's failure is re-raised on the calling thread.
 */
int nerf__renderer_run(nerf_renderer *r, size_t n, nerf__chunk_fn fn,
                       void *job);

/* The evaluation setup of a renderer (no randomness, no noise). */
void nerf__renderer_eval_setup(const nerf_renderer *r,
                               nerf__render_setup *s);

/* Tests: the renderer's workers march with *t from now on (NULL: as
 * outside tests); see nerf__march_test. */
int nerf__renderer_set_march_test(nerf_renderer *r,
                                  const nerf__march_test *t);

#endif
