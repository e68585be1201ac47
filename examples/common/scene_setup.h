/*
 * What the example programs share beyond argument parsing: the sampler
 * that suits a model and a scene, and a renderer for them.
 */
#ifndef NERF_EXAMPLES_SCENE_SETUP_H
#define NERF_EXAMPLES_SCENE_SETUP_H

#include <nerf.h>

/* The nerf_preset whose network shape the model has, or 0 if none. */
int setup_model_preset(const nerf_model *model);

/*
 * The scene space of a hash-grid model for dataset (NULL: BOX): its space
 * and bound, or space (a nerf_space; -1: the dataset's) if given.  NDC
 * suits exactly the forward-facing datasets: asking for it on another, or
 * for another space on one, prints why (as program) and returns
 * SETUP_USAGE, a usage error rather than a nerf status.
 */
#define SETUP_USAGE (-1000)

/*
 * nerf_dataset_options.forward_facing for a scene that model (NULL: one
 * still to be made in space, a nerf_space or -1 for the dataset's) is
 * trained or rendered in: 1 for an NDC model, so that a COLMAP capture is
 * placed for NDC rays as LLFF captures are.
 */
uint32_t setup_forward_facing(const nerf_model *model, int space);
int setup_model_space(nerf_model_options *mo, const nerf_dataset *dataset,
                      int space, const char *program);

/* What a program's flags change of a model's sampling: each count when
 * not negative, the bounds when far > near; the seed; and whether it is
 * for training (nerf_sampler_use). */
typedef struct sampler_choice {
    int64_t n_coarse, n_fine, march_steps;
    float near, far;
    uint64_t seed;
    int training;
} sampler_choice;

/* Nothing changed: the model's own sampling for rendering, seed 0. */
#define SAMPLER_AS_RECORDED {-1, -1, -1, 0.0f, 0.0f, 0, 0}

/*
 * A sampler for rendering or training model on dataset (which may be
 * NULL): the library's for them (nerf_sampler_options_for()), changed as
 * the choice c says.  A march of other steps than the model's scales the
 * cap on a ray's samples with it; a march asked of a model that cannot
 * march is the renderer's to refuse.
 */
int setup_sampler(nerf_sampler **out, const nerf_model *model,
                  const nerf_dataset *dataset, const sampler_choice *c);

/* 1 if model is sampled by marching through its occupancy grid. */
int setup_marches(const nerf_model *model);

/* Renders of a dataset's scene are composited as its images were: on white
 * for Blender scenes (and when there is no dataset), on black for LLFF. */
int setup_white_background(const nerf_dataset *dataset);

/* The same with the model's recorded background when there is no
 * dataset (white for files from before libnerf 0.4 of box models). */
int setup_background(const nerf_model *model, const nerf_dataset *dataset);

#endif
