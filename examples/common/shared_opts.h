/*
 * The options several programs take, declared here once: each program's
 * table names one with its storage and writes only its own help text
 * (which may say more about it in that program), e.g.
 *
 *     {OPT_DOWNSCALE(&a->downscale), .help = "load images K times ..."}
 */
#ifndef NERF_EXAMPLES_SHARED_OPTS_H
#define NERF_EXAMPLES_SHARED_OPTS_H

#include <nerf.h>

#include "cli.h"
#include "opt_table.h"

/* nerf_dataset_options.downscale's largest factor. */
#define CLI_DOWNSCALE_MAX 256

/* The largest --skip (every K-th view of a split). */
#define CLI_SKIP_MAX 100000

/* The most steps a march takes across its grid's diagonal: the sampler's
 * range of march_steps. */
#define CLI_MARCH_STEPS_MAX 65536

/* nerf_dataset_options.split's names: train, val, test. */
extern const opt_choice split_choices[];

/* nerf_model_options_preset()'s names: tiny, reference, fast. */
extern const opt_choice preset_choices[];

/* --model MODEL: the checkpoint a program reads. */
#define OPT_MODEL(p)                                                           \
    .name = "--model", OPT_TEXT_TO(p), .flags = OPT_REQUIRED,                  \
    .value = "MODEL", .help = "the checkpoint nerf-train saved (required)"

/* --overwrite: what a run writes may replace what exists (out_file.h);
 * each program's help says what that is. */
#define OPT_OVERWRITE(p) .name = "--overwrite", OPT_FLAG_SETS(p, 1)

/* --downscale K: the dataset's images reduced K times. */
#define OPT_DOWNSCALE(p)                                                       \
    .name = "--downscale", OPT_INT_IN(p, 1, CLI_DOWNSCALE_MAX), .value = "K"

/* --split S: which of the scene's splits. */
#define OPT_SPLIT(p)                                                           \
    .name = "--split", OPT_CHOICE_OF(p, split_choices), .value = "S"

/* --skip K: every K-th view of the split. */
#define OPT_SKIP(p)                                                            \
    .name = "--skip", OPT_INT_IN(p, 1, CLI_SKIP_MAX), .value = "K"

/* --march-steps N (nerf-train: --render-march-steps): a march's steps
 * across its grid's diagonal. */
#define OPT_MARCH_STEPS(name_, p)                                              \
    .name = (name_), OPT_INT_IN(p, 1, CLI_MARCH_STEPS_MAX), .value = "N"

/* --width W, --height H of a rendered image. */
#define OPT_IMAGE_SIDE(name_, p, value_)                                       \
    .name = (name_), OPT_INT_IN(p, 1, NERF_IMAGE_MAX_SIDE), .value = (value_)

/* --preset P: the network and samples of a new model. */
#define OPT_PRESET(p)                                                          \
    .name = "--preset", OPT_CHOICE_OF(p, preset_choices), .value = "P"

/* --no-masks: a scene's masks are ignored (nerf_dataset_options.
 * ignore_masks). */
#define OPT_NO_MASKS(p) .name = "--no-masks", OPT_FLAG_SETS(p, 1)

/* The largest training image --appearance names. */
#define NERF_APPEARANCE_IMAGE_MAX 1000000

/* --appearance A: which of the model's appearance codes renders use,
 * "neutral" or a training image's number, into a uint32_t as
 * nerf_renderer_options.appearance counts. */
int opt_read_appearance(const char *program, const opt *o, const char *v);
#define OPT_APPEARANCE(p)                                                      \
    .name = "--appearance", OPT_CUSTOM_READ(p, opt_read_appearance),           \
    .value = "A"

/* What renders of m with appearance `which` look like, in words. */
void appearance_text(const nerf_model *m, uint32_t which, char *buf,
                     size_t size);

#endif
