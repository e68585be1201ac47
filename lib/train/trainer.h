/*
 * The struct behind nerf_trainer: what one optimisation step needs besides
 * the model, whose step counter and weights are the whole training state.
 * Every random draw of step k is keyed by k (and the model's seed), so a
 * run resumed from a checkpoint at step k continues exactly as an
 * uninterrupted one.
 */
#ifndef NERF_TRAIN_TRAINER_H
#define NERF_TRAIN_TRAINER_H

#include <stdatomic.h>

#include "render_batch.h"

struct nerf_trainer {
    nerf__env env;
    nerf_trainer_options opts; /* as created; hooks NULL, path copied */
    char *checkpoint_path;     /* owned copy, or NULL */
    nerf_model *model;
    const nerf_dataset *dataset;
    const nerf_sampler *sampler;
    nerf_camera *cameras;      /* one per image, validated */
    uint32_t n_images, width, height;
    bool white;
    float noise_std;
    nerf__render_setup setup;
    nerf__batch batch;
    /* [batch_rays, 3] each: the rays and target colours of the step, and
     * the loss gradient of each pass's colours. */
    float *origins, *directions, *targets;
    /* [batch_rays]: the pixel each ray of the step was drawn at, counted
     * across all the images (pick_rays.c). */
    size_t *picked;
    float *rgb[NERF__PASSES], *d_rgb[NERF__PASSES];
    /* random_background on a dataset with alpha: [batch_rays, 3], the
     * colour each ray's target and render are finished on (else NULL). */
    bool random_bg;
    float *backgrounds;
    nerf_progress_cb progress;
    void *progress_user;
    atomic_int cancel;
    /* A marching sampler: the model's occupancy grid is refreshed when
     * nerf__grid_due() says, its density queried through density_ws
     * (from the model's allocator). */
    bool march;
    nerf__workspace density_ws;
    /* Data-parallel training (workers.c): the worker count (1 alone),
     * what the hooks are told, whether the weights were compared before
     * the first step, and with batch_samples and a marching sampler the
     * sample counts of the whole batch [batch_rays + 1]. */
    uint32_t workers;
    nerf_exchange exchange;
    bool checked;
    size_t *march_offsets;
    /* A model with appearance codes (appearance_step.c): each pass's
     * colours before the map [batch_rays, 3], opacities and their loss
     * gradients [batch_rays]. */
    bool codes;
    struct {
        float *rgb, *opacity, *d_opacity;
    } coded[NERF__PASSES];
};

/*
 * instant-ngp's schedule of occupancy-grid updates: every 16 steps, and
 * every cell during the first 256 steps, while the density is still
 * taking shape everywhere.  After that an update evaluates the occupied
 * cells and a random 1/NERF__GRID_RANDOM_DIV of all cells, where
 * instant-ngp takes a quarter: its steps train on 2^18 samples, ours on
 * a few tens of thousands, so a quarter of the 2M cells every 16 steps
 * cost as much as training itself.  On lego, in the same training time,
 * a sixteenth gave more steps and a higher test PSNR than a quarter
 * (docs/perf-log/2026-11-24-lego-curve-and-what-the-changes-bought.md):
 * cells that leave the grid are found again more slowly, but the empty
 * ones, no longer refreshed as often, fall out of it sooner.  For the
 * same reason the updates after the first 256 steps come every 32 steps:
 * a refresh was still a noticeable share of a late step, and lego's test
 * PSNR after 10,000 steps did not drop (docs/perf-log/
 * 2026-11-29-0.10.5-to-0.10.8.md, "0.10.6").
 */
#define NERF__GRID_EVERY_WARMUP 16u
#define NERF__GRID_EVERY 32u
#define NERF__GRID_WARMUP 256u
#define NERF__GRID_RANDOM_DIV 16u

/* Whether the trainer updates the grid before step `step`. */
static inline bool nerf__grid_due(uint64_t step)
{
    return step % (step < NERF__GRID_WARMUP ? NERF__GRID_EVERY_WARMUP
                                            : NERF__GRID_EVERY) == 0;
}

/* Cells of `cells` an update at `step` evaluates at random besides the
 * occupied ones: the rule above, for the trainer and its benchmark. */
static inline size_t nerf__grid_random_cells(uint64_t step, size_t cells)
{
    return step < NERF__GRID_WARMUP ? cells : cells / NERF__GRID_RANDOM_DIV;
}

/* Fill the trainer's rays and targets (and with random_bg their
 * backgrounds) for step `step`. */
void nerf__trainer_pick_rays(nerf_trainer *t, uint64_t step);

/* Refresh the model's occupancy grid as the schedule says for the
 * model's current step (nothing between updates). */
int nerf__trainer_update_grid(nerf_trainer *t);

/* The density source of those refreshes (a nerf__density_fn whose ctx is
 * the trainer): the model's density-only pass on the trainer's density
 * workspace. */
int nerf__trainer_grid_density(void *ctx, size_t n, const float *xyz,
                               float *sigma);

/*
 * A run of steps (nerf_trainer_run(), nerf_trainer_run_for()): each step
 * followed by the periodic checkpoint, the progress report (done of
 * total) and the cancellation check, and a final save at the end.
 */
typedef struct nerf__run {
    double start;            /* monotonic seconds */
    uint64_t done, total;    /* steps taken by this run; total reported */
    nerf_train_stats last;   /* of the last step */
    double last_save;        /* run seconds when the last save ended */
    double saving;           /* run seconds spent saving, in all */
    double save_seconds;     /* how long the last save took */
    uint64_t saved_step;     /* the model's step at the last save */
    bool saved;              /* whether this run has saved yet */
} nerf__run;

void nerf__run_begin(nerf_trainer *t, nerf__run *r, uint64_t total);
double nerf__run_elapsed(const nerf__run *r);
/* One step and what follows it; NERF_ECANCELLED when asked to stop. */
int nerf__run_step(nerf_trainer *t, nerf__run *r, nerf_train_stats *stats_out);
/* The final save, folded into the run's status rc. */
int nerf__run_end(nerf_trainer *t, nerf__run *r, int rc);

/* The rays of a step this worker trains on: [lo, hi) of the `all` the
 * whole step takes (alone: all of them). */
typedef struct nerf__share {
    size_t all, lo, hi;
} nerf__share;

/* What the hooks are told of the model (its sparse ranges); at creation. */
void nerf__trainer_exchange_init(nerf_trainer *t);
/* This worker's share of step `step`, whose rays have been picked; sets
 * the setup's first_ray to the batch's first. */
void nerf__trainer_share(nerf_trainer *t, uint64_t step, nerf__share *s);
/* The gradient hook on the model's gradients, if there is one. */
int nerf__trainer_exchange(nerf_trainer *t, uint64_t step, size_t rays,
                           size_t all);
/* The checksum comparison, when checksum_every says (or `first`). */
int nerf__trainer_check_workers(nerf_trainer *t, bool first);

/*
 * Appearance codes (appearance_step.c).  At creation: add the codes a
 * model needs (or check its own against the dataset) and the buffers.  In
 * a step, on the share's n rays from ray lo: map each pass's colours by
 * their images' codes, and take the loss gradients back through the map
 * (into d_rgb in place, the opacities' gradients, the codes' gradients).
 */
int nerf__trainer_appearance_setup(nerf_trainer *t);
void nerf__trainer_appearance_free(nerf_trainer *t);
void nerf__trainer_appearance_forward(nerf_trainer *t, uint32_t passes,
                                      size_t lo, size_t n);
void nerf__trainer_appearance_backward(nerf_trainer *t, uint32_t passes,
                                       size_t lo, size_t n, size_t all);

/*
 * Record the trainer's dataset in its model (model->data), first warning
 * through the trainer's log when the model records other data
 * (data_record.c).
 */
void nerf__trainer_record_data(nerf_trainer *t);

/* The same for the trainer's batch (model->batch_rays, batch_samples),
 * warning when a model that has taken steps was trained at another. */
void nerf__trainer_record_batch(nerf_trainer *t);

#endif
