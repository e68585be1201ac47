/*
 * The struct behind nerf_model, and the internal calls the renderer and the
 * trainer use to run the networks with activations kept for backward.
 */
#ifndef NERF_MODEL_H
#define NERF_MODEL_H

#include <stdatomic.h>
#include <stdbool.h>

#include "adam.h"
#include "appearance.h"
#include "env.h"
#include "fingerprint.h"
#include "network.h"
#include "schedule.h"

/* lib/occupancy/occupancy.h: the grid a hash-grid model owns and the
 * samplers below the renderer march through. */
struct nerf__occupancy;

struct nerf_model {
    nerf__env env;
    nerf_model_options opts; /* as created; opts.hooks is NULL */
    nerf__network nets[2];   /* coarse, fine */
    uint32_t n_nets;         /* 1 without a fine network */
    size_t n_params;         /* both networks */
    /* One flat vector each, networks back to back, so the optimiser and
     * the checkpoint see the whole model as four arrays. */
    float *params;
    float *grads;
    float *adam_m;
    float *adam_v;
    uint64_t step;           /* optimiser steps taken */
    /* Hash-grid models: the Adam corrections of each table parameter by
     * its own count k of updates (adam.h, corrected updates): beta1^k for
     * the tables of both networks back to back, then beta2^k likewise
     * (2 n_table floats, 1 before a first update); NULL without a hash
     * grid.  A model resumed from a
     * checkpoint of a libnerf before 0.10, which kept none, goes on
     * correcting by the step (corrected false), as the run it continues
     * did. */
    float *adam_r;
    size_t n_table;
    bool corrected;
    /* Whether grads may hold anything but zeros: the Adam step zeroes
     * them as it reads them, so that training needs no separate pass. */
    bool grads_dirty;
    nerf__adam adam;
    /* How the schedule in adam came about: a time budget's fit, or plain
     * parameters (schedule.h). */
    nerf__schedule schedule;
    /* Hash-grid models: the occupancy grid over [-bound, bound]^3 that a
     * marching sampler skips empty space with (NULL otherwise).  Its EMA
     * and update counter are training state, saved in checkpoints. */
    struct nerf__occupancy *grid;
    /* NERF_MATMUL_BF16 and FP32_ONEDNN: the oneDNN primitives (and for
     * bf16 the rounded weights) that both networks' products use
     * (mlp/gemm_onednn.h); NULL for cblas fp32. */
    struct nerf__onednn *onednn;
    /* The data the model was last trained on, as the trainer recorded it
     * (or a checkpoint carried it): not known for a model never trained
     * by a trainer.  Resuming on other data is warned about. */
    nerf__fingerprint data;
    /* Loaded from a weights-only export (nerf_model_export()): adam_m and
     * adam_v are zeros, not state a run could resume from. */
    bool weights_only;
    /* What rendering the model needs, as its trainer recorded it (the
     * sampling layer's nerf_model_render_settings() reads it; checkpoints
     * keep it).  Only the fields a render uses are set; valid when
     * has_render. */
    bool has_render;
    nerf_sampler_options render_sampler;
    uint32_t render_white;
    /* The batch its trainer took (nerf_trainer_options.batch_rays and
     * batch_samples; checkpoints keep it), so that a resume can take the
     * same one: a run goes on bit for bit only at the batch it began
     * with.  batch_rays 0: nothing recorded. */
    uint32_t batch_rays, batch_samples;
    /* The average of the weights over the schedule's last steps
     * (average.h): allocated for them, and running once its first step
     * has been taken. */
    float *average;
    bool averaging;
    /* Whether every weight is finite (finite.c): not known yet, yes or
     * no.  Found on first asking after the weights change, kept till the
     * next change; atomic because renderers on several threads may ask
     * one model at once. */
    atomic_int finite;
    /* Per-image appearance codes (appearance.h): none until a trainer
     * with appearance_codes adds them, or a checkpoint carries them. */
    nerf__appearance appearance;
    /* The file the model was loaded from, for messages that name it;
     * NULL for a model created or imported. */
    char *source;
};

/* The most rays and samples a training step takes
 * (nerf_trainer_options.batch_rays, batch_samples). */
#define NERF__BATCH_RAYS_MAX (1u << 20)
#define NERF__BATCH_SAMPLES_MAX (1u << 26)

/* Samples per block in nerf_model_query(): bounds its memory (about 10 MB
 * for the reference network) while keeping each sgemm large.  A query of
 * more samples makes the calls that queries of its blocks would. */
#define NERF__QUERY_BLOCK 4096

/* Cells per axis of a model's occupancy grid. */
#define NERF__MODEL_GRID_RESOLUTION 128u

/* Validate options (already read into a full-size struct). */
int nerf__model_check_options(const nerf_model_options *o);

/*
 * Parameters a model of these (validated) options has, computed without
 * allocating, so a loader can check a file's claims before trusting them.
 */
size_t nerf__model_options_param_count(const nerf_model_options *o);

/*
 * Allocate a model for opts with zeroed parameters and optimiser state
 * (no initialisation): the loaders fill it.  A hash-grid model gets a
 * fresh occupancy grid.  env is copied.
 */
int nerf__model_alloc(nerf_model **out, const nerf_model_options *opts,
                      const nerf__env *env);

/*
 * Build a model from the checkpoint image data[0, size), as
 * nerf_model_load() does after reading the file; path only names the
 * source in messages.  Kept separate so that the parser can be exercised
 * from memory (the fuzz targets do).
 */
int nerf__checkpoint_parse(const nerf__env *env, const char *path,
                           const unsigned char *data, size_t size,
                           nerf_model **out);

/* Network index for a public nerf_network value; -1 if absent. */
int nerf__model_network(const nerf_model *m, int network);

/*
 * Forward n samples through a network, keeping activations in ws for
 * nerf__model_backward().  Grows ws if needed (the only allocation).
 */
int nerf__model_forward(const nerf_model *m, int network, nerf__workspace *ws,
                        size_t n, const float *positions,
                        const float *directions, float *rgb_out,
                        float *sigma_out);

/*
 * Density of network `network` at n points (as nerf__model_forward()'s
 * sigma, without the colour branch), through ws, which grows if needed.
 */
int nerf__model_density(const nerf_model *m, int network, nerf__workspace *ws,
                        size_t n, const float *positions, float *sigma_out);

/*
 * Forward n samples for rendering: no activations kept, ws sized for n
 * samples exactly (it grows if needed, and keeps its memory otherwise).
 */
int nerf__model_evaluate(const nerf_model *m, int network,
                         nerf__workspace *ws, size_t n,
                         const float *positions, const float *directions,
                         float *rgb_out, float *sigma_out);

/*
 * nerf__model_evaluate() in two halves (network.h's nerf__network_head()
 * and nerf__network_colour()), for a renderer that colours only the
 * samples its compositing will use: the densities of n samples, then the
 * colours of the first n_colour rows of ws->head after the caller has
 * moved the rows it wants there.  nerf__model_head() sizes ws as
 * nerf__model_evaluate() does; nerf__model_colour() takes ws as the head
 * left it (n_colour at most its n) and never allocates.
 */
int nerf__model_head(const nerf_model *m, int network, nerf__workspace *ws,
                     size_t n, const float *positions, float *sigma_out);
int nerf__model_colour(const nerf_model *m, int network, nerf__workspace *ws,
                       size_t n_colour, const float *directions,
                       float *rgb_out);

/*
 * Grow ws to hold at least n samples of network `network` (with keep, the
 * activations that nerf__model_backward() needs), for callers whose batch
 * sizes vary and that reserve with headroom.
 */
int nerf__model_reserve(const nerf_model *m, int network, nerf__workspace *ws,
                        size_t n, bool keep);

/* The allocator and log sink the model's workspaces are sized with; a
 * caller that outlives the model keeps a copy to release them. */
const nerf__env *nerf__model_env(const nerf_model *m);

/* Whether the networks take view directions (both or neither do). */
bool nerf__model_uses_viewdirs(const nerf_model *m);
/* Whether evaluating the model goes through the BLAS (or oneDNN), whose
 * own threads then share the cores, rather than through the fused path's
 * kernels alone (mlp/network_fused.h). */
bool nerf__model_uses_blas(const nerf_model *m);

/*
 * Whether a sample's outputs so far were computed from that sample alone,
 * the same bits whatever other samples shared its products: true on the
 * fused path, and through oneDNN while all its primitives were brgemm
 * (mlp/gemm_onednn.h); false through the CBLAS, whose kernels may round a
 * row by its product's size and its place in it (mlp/gemm.h).  Ask after
 * the evaluations it is to vouch for.
 */
bool nerf__model_rows_alone(nerf_model *m);

/* The space the model's networks and grid work in (space.h): a world
 * point reaches them through nerf__space_to_domain(). */
const nerf__space *nerf__model_space(const nerf_model *m);

/* The space of a model of these (validated) options. */
void nerf__model_options_space(const nerf_model_options *o,
                               nerf__space *space);

/* The occupancy grid of a hash-grid model; NULL for the others. */
const struct nerf__occupancy *nerf__model_grid(const nerf_model *m);

/* Accumulate the gradients of the forward held in ws into m->grads. */
int nerf__model_backward(nerf_model *m, int network, nerf__workspace *ws,
                         const float *d_rgb, const float *d_sigma);

/*
 * Every writer of m->params calls this after writing (the optimiser step,
 * creation, loading, importing): a bf16 model rounds its weights again
 * before its next product.  Cheap; nothing happens for an fp32 model.
 */
void nerf__model_weights_changed(nerf_model *m);

/*
 * Weights that are not finite (finite.c): a run that diverged.
 * nerf__model_finite() says whether all are, scanning the weights once
 * after each change; nerf__model_check_finite() returns NERF_OK, or
 * NERF_EINVAL with a message from fn naming the model's file, how many
 * are not finite and where the first is; nerf__model_nonfinite_text()
 * writes that count and place ("3 of 5000 weights are NaN or infinite,
 * the first in the coarse network's trunk layer 0 weights [row 0,
 * column 5]"); nerf__model_warn_nonfinite() logs it as a warning naming
 * path, as a load does.  nerf__model_weights_changed() makes the answer
 * unknown again (nerf__model_finite_unknown()).
 */
bool nerf__model_finite(const nerf_model *m);
int nerf__model_check_finite(const nerf_model *m, const char *fn);
void nerf__model_nonfinite_text(const nerf_model *m, char *buf, size_t size);
void nerf__model_warn_nonfinite(const nerf_model *m, const char *path);
void nerf__model_finite_unknown(nerf_model *m);

void nerf__model_zero_grad(nerf_model *m);
/* Zero the gradients unless they are known to be zero already. */
void nerf__model_clear_grad(nerf_model *m);

/* Take one Adam step with the scheduled learning rate; step++.  NERF_OK,
 * or NERF_ENOMEM (the average of the weights, average.h) with nothing
 * changed. */
int nerf__model_adam_step(nerf_model *m);

#endif
