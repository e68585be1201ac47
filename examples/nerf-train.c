/* nerf-train: train a NeRF on a Blender, LLFF or COLMAP scene. */
#include <nerf.h>

#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "common/cli.h"
#include "common/dist.h"
#include "common/interrupt.h"
#include "common/matmul_name.h"
#include "common/out_folder.h"
#include "common/out_file.h"
#include "common/options.h"
#include "common/opt_table.h"
#include "common/progress.h"
#include "common/scene_setup.h"
#include "common/shared_opts.h"

/* nerf-train-mpi is this program built with common/dist_mpi.c. */
#ifndef PROG
#define PROG "nerf-train"
#endif

static const char about[] =
    "Train a NeRF on the scene in DIR (Blender transforms_*.json, one\n"
    "instant-ngp transforms.json split every 8th frame, LLFF\n"
    "poses_bounds.npy, or a COLMAP model in sparse/0/ beside images/,\n"
    "detected from the folder) and save it to MODEL.\n";

static const char after[] =
    "Ctrl-C (SIGINT) stops after the current step, saves MODEL and exits\n"
    "with status 130 (SIGTERM: 143).\n"
    "nerf-train-mpi (built with Open MPI) takes the same flags under\n"
    "mpirun -np N: each process trains its share of every step's rays and\n"
    "the gradients are summed over MPI; rank 0 prints and saves MODEL;\n"
    "--seconds needs --steps there (docs/distributed.md).\n"
    "MODEL's folder is created if missing; MODEL is tried before training\n"
    "(a file is created beside it and removed); a save that fails leaves\n"
    "the last good MODEL in place, says so and makes the status 1.\n"
    "Examples:\n"
    "  nerf-scene --out scene && nerf-train --data scene --out scene.nerf\n"
    "  nerf-train --data lego --downscale 8 --out lego.nerf --steps 1000 \\\n"
    "      --batch 512\n"
    "  nerf-train --data lego --out lego.nerf --preset fast --seconds 600\n"
    "  nerf-train --data fern --downscale 8 --out fern.nerf --preset fast \\\n"
    "      --steps 4400 --seconds 600\n";

/* The processes of the run: this one alone, or MPI's ranks. */
static dist D;

/* A failure already described on stderr (not a libnerf status). */
#define REPORTED (-1001)


/* The ranges of the options that have no library bound to take. */
#define STEPS_MAX (UINT64_C(1) << 40)
#define BATCH_MAX (1u << 20)
#define BATCH_SAMPLES_MAX (1u << 26)
/* nerf_sampler_options' most samples a ray, coarse or fine. */
#define SAMPLES_MAX 4096

typedef struct run_state {
    progress bar;
    uint64_t first_step;
    double seconds;  /* time limit beside --steps, 0 = none */
    int out_of_time;
} run_state;

static int on_progress(const nerf_progress *p, void *user)
{
    run_state *st = user;
    if (st->seconds > 0.0 && p->elapsed >= st->seconds) {
        st->out_of_time = 1;
    }
    /* Several processes stop together, at the same step, or those that
     * went on would wait for the others forever. */
    double loss = p->loss, psnr = p->psnr;
    int sig = interrupted;
    dist_step_agree(&D, &sig, &st->out_of_time, &loss, &psnr);
    if (sig && !interrupted) {
        interrupted = sig;
    }
    char note[96];
    snprintf(note, sizeof note, "step %llu loss %.5f psnr %.2f",
             (unsigned long long)(st->first_step + p->done), loss, psnr);
    /* Under a budget the total is a projection until the schedule is
     * fitted, then the fitted length; the first step, before any rate is
     * known, has none to show. */
    if (p->total > 0) {
        st->bar.total = p->total > p->done ? p->total : p->done;
    }
    if (D.rank == 0 && p->total > 0) {
        progress_update(&st->bar, p->done, note);
    }
    return interrupted || st->out_of_time ? 1 : 0;
}

typedef struct args {
    const char *data, *out;
    int preset;
    uint64_t steps, downscale, batch, batch_samples, seed, every;
    double lr, lr_final, seconds;
    int resume, overwrite;
    int preset_given;
    int steps_given;
    int lr_given; /* 1: --lr, 2: --lr-final */
    int batch_given, batch_samples_given;
    int random_bg; /* -1: as the preset's model */
    int matmul;    /* nerf_matmul; -1: not given (the fastest fp32) */
    int space;     /* nerf_space; -1: the dataset's */
    int64_t coarse, fine; /* samples a ray; -1: the preset's */
    int64_t render_march; /* --render-march-steps; 0: the library's */
    int appearance_codes;
    int no_masks;
} args;

static const opt_choice spaces[] = {
    {.name = "auto", .id = -1},
    {.name = "box", .id = NERF_SPACE_BOX},
    {.name = "ndc", .id = NERF_SPACE_NDC},
    {.name = "unbounded", .id = NERF_SPACE_UNBOUNDED},
    {.name = NULL},
};

static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    a->preset = NERF_PRESET_TINY;
    a->steps = 2000;
    a->downscale = 1;
    a->every = UINT64_MAX; /* not given: timed saves */
    a->random_bg = -1;
    a->matmul = -1;
    a->space = -1;
    a->coarse = a->fine = -1;
    /* The learning rates' ranges: the library's for the parameters. */
    double lr_lo = 0.0, lr_hi = 0.0, final_lo = 0.0, final_hi = 0.0;
    nerf_param_bounds(NERF_PARAM_LEARNING_RATE, &lr_lo, &lr_hi);
    nerf_param_bounds(NERF_PARAM_LEARNING_RATE_FINAL, &final_lo, &final_hi);
    const opt opts[] = {
        {.name = "--data", OPT_TEXT_TO(&a->data), .flags = OPT_REQUIRED,
         .value = "DIR", .help = "the scene (required)"},
        {.name = "--out", OPT_TEXT_TO(&a->out), .flags = OPT_REQUIRED,
         .value = "MODEL", .help = "the checkpoint to write (required)"},
        {OPT_PRESET(&a->preset), .given = &a->preset_given,
         .help = "network and samples: reference (the paper's; slow on a\n"
                 "CPU), tiny (default) or fast (hash grid and small MLPs)"},
        {.name = "--steps", OPT_INT_IN(&a->steps, 1, STEPS_MAX),
         .given = &a->steps_given, .value = "N",
         .help = "train until the model has taken N steps, the learning\n"
                 "rate decaying over them (default {default}; --resume: the\n"
                 "steps MODEL was given)"},
        {.name = "--seconds",
         OPT_REAL_IN(&a->seconds, 0.0, HUGE_VAL, CLI_ABOVE_MIN), .value = "S",
         .help = "without --steps: train for S seconds, the learning\n"
                 "rate decaying over the steps that time allows (it\n"
                 "holds for the first quarter while the step rate is\n"
                 "measured, and the length is fitted again at a half,\n"
                 "three quarters and nine tenths of the time, or when\n"
                 "the run reaches it before; the\n"
                 "fitted length is saved in MODEL, so\n"
                 "--resume continues the same run bit for bit); with\n"
                 "--steps: stop at whichever comes first (default none)"},
        {OPT_DOWNSCALE(&a->downscale),
         .help = "load images K times smaller (default {default})"},
        {.name = "--batch", OPT_INT_IN(&a->batch, 1, BATCH_MAX),
         .given = &a->batch_given, .value = "N",
         .help = "rays per step (default 2048 for fast, else 1024;\n"
                 "--resume: the batch MODEL was trained with)"},
        {.name = "--seed", OPT_INT_IN(&a->seed, 0, UINT64_MAX), .value = "N",
         .help = "seed of initialisation and sampling (default {default})"},
        {.name = "--lr", OPT_REAL_IN(&a->lr, lr_lo, lr_hi, 0),
         .given = &a->lr_given, .bit = 1, .value = "RATE",
         .help = "initial learning rate, decaying exponentially over the\n"
                 "run (default 5e-4 for reference, 5e-3 for tiny, 1e-2\n"
                 "for fast)"},
        {.name = "--lr-final", OPT_REAL_IN(&a->lr_final, final_lo, final_hi, 0),
         .given = &a->lr_given, .bit = 2, .value = "RATE",
         .help = "the learning rate at the run's last step, at most\n"
                 "--lr (default a tenth of --lr, the paper's)"},
        {.name = "--checkpoint-every", OPT_INT_IN(&a->every, 0, UINT32_MAX),
         .value = "N",
         .help = "save MODEL every N steps (0: only at the\n"
                 "end; default: every 2 minutes of training, since a\n"
                 "save of the fast preset's 140 MB takes seconds)"},
        {.name = "--resume", OPT_FLAG_SETS(&a->resume, 1),
         .help = "continue from MODEL if it exists (same data, preset,\n"
                 "batch and seed give the same result as an unbroken run,\n"
                 "and MODEL keeps its batch unless --batch is given;\n"
                 "default off: start afresh); a --preset other than\n"
                 "MODEL's is refused, and data unlike what MODEL was\n"
                 "trained on is warned about"},
        {OPT_OVERWRITE(&a->overwrite),
         .help = "replace MODEL if it exists (default off: without\n"
                 "--resume or --overwrite, an existing MODEL is refused)"},
        {OPT_NO_MASKS(&a->no_masks),
         .help = "train on every pixel, even those the scene's masks\n"
                 "leave out (default off: masked pixels are never\n"
                 "trained on; docs/formats.md, \"Masks\")"},
        {.name = "--batch-samples",
         OPT_INT_IN(&a->batch_samples, 0, BATCH_SAMPLES_MAX),
         .given = &a->batch_samples_given, .value = "N",
         .help = "a step takes rays until their samples reach N\n"
                 "(--batch is then the most rays a step takes; 0: always\n"
                 "--batch rays; default 131072 for fast without --batch,\n"
                 "else 0; --resume: MODEL's)"},
        {.name = "--appearance-codes", OPT_FLAG_SETS(&a->appearance_codes, 1),
         .help = "learn a small code per training image that takes in\n"
                 "how its exposure and white balance differ from the\n"
                 "other photos' (phone captures); renders use their\n"
                 "mean.  Saved in MODEL; --resume keeps training them\n"
                 "(default off)"},
        {.name = "--random-background", OPT_INT_IN(&a->random_bg, 0, 1),
         .value = "0|1",
         .help = "1: train each ray of images with alpha\n"
                 "(Blender scenes) against a random background colour, so\n"
                 "that empty space cannot pass for the background (default\n"
                 "1 for fast, 0 for the others)"},
        {.name = "--matmul", OPT_CHOICE_OF(&a->matmul, matmul_choices),
         .value = "M",
         .help = "the network's matrix products: fp32 (cblas),\n"
                 "fp32-onednn (fp32 through oneDNN, CPUs with AVX-512)\n"
                 "or bf16 (oneDNN, CPUs with AVX512-BF16; weights stay\n"
                 "fp32).  Default: fp32-onednn for the tiny and\n"
                 "reference presets where it runs, else fp32.  Saved in\n"
                 "MODEL, so --resume, nerf-render and nerf-eval keep it"},
        {.name = "--space", OPT_CHOICE_OF(&a->space, spaces), .value = "S",
         .help = "where the fast preset's grids lie: box (a bounded\n"
                 "scene), ndc (forward-facing), unbounded (all-round with\n"
                 "a far background: space beyond a central cube is\n"
                 "contracted); default {default}, the dataset's (LLFF: ndc,\n"
                 "COLMAP or aabb_scale > 1: unbounded, else box); ndc\n"
                 "on a COLMAP folder places it as LLFF places a\n"
                 "forward-facing capture (any preset)"},
        /* The ranges nerf_sampler_options takes. */
        {.name = "--coarse-samples", OPT_INT_IN(&a->coarse, 2, SAMPLES_MAX),
         .value = "N",
         .help = "stratified samples a ray, {range} (default:\n"
                 "the preset's, 64 for reference, 32 for tiny)"},
        {.name = "--fine-samples", OPT_INT_IN(&a->fine, 0, SAMPLES_MAX),
         .value = "N",
         .help = "hierarchical samples a ray added to them for the\n"
                 "fine network, {range} (0: none, the coarse network's\n"
                 "samples only; default: the preset's, 128 for\n"
                 "reference, 64 for tiny).  Fewer samples train and\n"
                 "render faster, at some cost in quality; both are\n"
                 "saved in MODEL, and the programs that render it use\n"
                 "them.  Not for fast, which places its samples by\n"
                 "marching"},
        {OPT_MARCH_STEPS("--render-march-steps", &a->render_march),
         .help = "fast: record in MODEL that it renders in\n"
                 "steps of its grid's diagonal / N, {range} (it trains\n"
                 "in 1024, forward-facing and all-round scenes in 256):\n"
                 "finer steps integrate each ray more closely and take\n"
                 "longer (default 1280: on lego about 0.1 dB\n"
                 "more than 1024 for a fifth more time a frame;\n"
                 "docs/performance.md); nerf-eval and nerf-render\n"
                 "--march-steps override it"},
        {.name = NULL},
    };
    const opt_program p = {.name = PROG, .opts = opts, .column = 16,
                           .about = about, .after = after};
    if (opt_parse(&p, argc, argv) != 0) {
        return -1;
    }
    if (a->resume && a->overwrite) {
        cli_usage_error(PROG, "--resume continues MODEL, "
                        "--overwrite replaces it: give one");
        return -1;
    }
    if (a->preset == NERF_PRESET_FAST && (a->coarse >= 0 || a->fine >= 0)) {
        cli_usage_error(PROG, "--coarse-samples and --fine-samples set the "
                        "reference and tiny presets' samples; the fast "
                        "preset places its own by marching");
        return -1;
    }
    if (a->coarse == 2 && a->fine != 0) {
        /* The fine samples are drawn from the coarse pass's weights
         * between its samples, which two do not give. */
        cli_usage_error(PROG, "--coarse-samples 2 leaves the fine samples "
                        "nothing to draw from: give at least 3, or "
                        "--fine-samples 0");
        return -1;
    }
    if (a->lr == 0.0) {
        nerf_model_options preset;
        NERF_MODEL_OPTIONS_INIT(&preset);
        nerf_model_options_preset(&preset, a->preset);
        a->lr = preset.learning_rate;
    }
    if (a->lr_final == 0.0) {
        a->lr_final = a->lr / 10;
    }
    /* The schedule, lr (lr_final / lr)^(step / steps), decays: a final
     * rate above the first would make it grow, steeper at every step. */
    if (a->lr_final > a->lr) {
        cli_usage_error(PROG, "--lr-final %g is above the learning rate "
                        "%g%s: the rate decays from --lr to --lr-final "
                        "(equal: it stays constant)", a->lr_final, a->lr,
                        a->lr_given & 1 ? "" : " (the preset's --lr)");
        return -1;
    }
    return 0;
}

/*
 * A model is a network of one shape: training another preset's network
 * from it cannot be done, and silently keeping the model's would be
 * training something else than asked.
 */
static int check_preset(const args *a, const nerf_model *m)
{
    int have = setup_model_preset(m);
    if (!a->preset_given || have == a->preset) {
        return NERF_OK;
    }
    const char *name = opt_choice_name(preset_choices, have);
    fprintf(stderr, PROG ": %s holds a model of %s%s%s, not of "
            "--preset %s: resume it without --preset, or train a new one "
            "with --overwrite\n", a->out, name ? "the " : "",
            name ? name : "no preset's network",
            name ? " preset" : "",
            opt_choice_name(preset_choices, a->preset));
    return SETUP_USAGE;
}

/*
 * An existing MODEL is replaced only when asked: it may be hours of
 * training.  --resume writes over the MODEL it continues, as meant.
 */
static int check_existing(const args *a)
{
    const out_input data = {"--data", a->data};
    return out_file_check(PROG, a->out, a->resume || a->overwrite,
                          "--resume continues it, --overwrite replaces it",
                          &data, 1);
}

/* The checkpoint to resume, loaded before the dataset, whose placement
 * depends on the model's space; *m stays NULL when there is none. */
static int resume_model(const args *a, const nerf_hooks *hooks,
                        nerf_model **m)
{
    if (a->resume && access(a->out, F_OK) == 0) {
        int rc = nerf_model_load(m, a->out, hooks);
        if (rc == NERF_OK) {
            rc = check_preset(a, *m);
        }
        if (rc == NERF_OK && D.rank == 0) {
            fprintf(stderr, PROG ": resuming %s at step %llu\n", a->out,
                    (unsigned long long)nerf_model_step(*m));
            nerf_model_options mo;
            NERF_MODEL_OPTIONS_INIT(&mo);
            nerf_model_get_options(*m, &mo);
            if (a->matmul >= 0 && (uint32_t)a->matmul != mo.matmul) {
                fprintf(stderr, PROG ": --matmul ignored: the model "
                        "keeps the %s products it was saved with\n",
                        matmul_name(mo.matmul));
            }
            if (a->lr_given) {
                fprintf(stderr, PROG ": --lr and --lr-final ignored: the "
                        "model keeps the learning-rate schedule it was "
                        "saved with\n");
            }
            if (a->space >= 0 && (uint32_t)a->space != mo.space) {
                fprintf(stderr, PROG ": --space ignored: the model "
                        "keeps the space it was created with\n");
            }
            if (a->coarse >= 0 || a->fine >= 0) {
                fprintf(stderr, PROG ": --coarse-samples and "
                        "--fine-samples ignored: the model keeps the "
                        "samples it was trained with\n");
            }
        }
        return rc;
    }
    return NERF_OK;
}

/* Without --matmul the library picks the fastest fp32 products for the
 * network (NERF_MATMUL_FP32_FASTEST); oneDNN's is said, since it is not
 * the library's default. */
static void say_matmul(const args *a, const nerf_model *m)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_get_options(m, &mo);
    if (a->matmul < 0 && mo.matmul == NERF_MATMUL_FP32_ONEDNN) {
        fprintf(stderr, PROG ": fp32 products through oneDNN (--matmul "
                "fp32 for cblas)\n");
    }
}

static int create_model(const args *a, const nerf_hooks *hooks,
                        const nerf_dataset *ds, nerf_model **m)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, a->preset);
    mo.seed = a->seed;
    mo.hooks = hooks;
    mo.matmul = a->matmul < 0 ? NERF_MATMUL_FP32_FASTEST : (uint32_t)a->matmul;
    mo.learning_rate = a->lr;
    if (a->preset == NERF_PRESET_FAST && a->matmul >= 0 &&
        mo.matmul != NERF_MATMUL_FP32) {
        /* Asked for, so taken; but said, since it costs the user. */
        fprintf(stderr, PROG ": %s products through oneDNN: the fast "
                "preset trains faster on its own fp32 kernels (--matmul "
                "fp32, the default)\n", matmul_name(mo.matmul));
    }
    if (mo.encoding == NERF_ENCODING_HASHGRID) {
        int rc = setup_model_space(&mo, ds, a->space, PROG);
        if (rc != NERF_OK) {
            return rc;
        }
    } else if (a->space > 0 && a->space != NERF_SPACE_NDC) {
        fprintf(stderr, PROG ": --space applies to the fast preset's "
                "grids; this preset reads coordinates anywhere\n");
    }
    int rc = nerf_model_create(m, &mo);
    if (rc == NERF_OK) {
        say_matmul(a, *m);
        /* The paper's schedule by default: a tenfold exponential decay
         * over the run. */
        rc = nerf_model_set_param(*m, NERF_PARAM_LEARNING_RATE_FINAL,
                                  a->lr_final);
    }
    if (rc == NERF_OK) {
        rc = nerf_model_set_param(*m, NERF_PARAM_DECAY_STEPS, (double)a->steps);
    }
    return rc;
}

/* How the run ends: at a step count, or at a length fitted to --seconds
 * (nerf_trainer_run_for()). */
typedef struct plan {
    int budget;      /* 1: nerf_trainer_run_for(--seconds) */
    uint64_t target; /* otherwise: the step to train to */
} plan;

static int plan_run(const args *a, const nerf_model *m, plan *p)
{
    memset(p, 0, sizeof *p);
    const uint64_t step = nerf_model_step(m);
    nerf_schedule sc;
    memset(&sc, 0, sizeof sc);
    sc.struct_size = sizeof sc;
    nerf_model_schedule(m, &sc);
    if (a->steps_given) {
        p->target = a->steps;
    } else if (a->seconds > 0.0 &&
               (step == 0 || sc.state != NERF_SCHEDULE_STEPS)) {
        p->budget = 1;
    } else if (sc.state == NERF_SCHEDULE_MEASURING) {
        fprintf(stderr, PROG ": %s was saved while its schedule was "
                "being fitted to a time budget: give --seconds (the time "
                "left) or --steps\n", a->out);
        return SETUP_USAGE;
    } else if (step > 0) {
        /* A resumed run goes on to the length it was given. */
        p->target = sc.total_steps;
    } else {
        p->target = a->steps;
    }
    if (p->budget && D.size > 1) {
        /* Each process would fit the schedule to its own clock. */
        fprintf(stderr, PROG ": --seconds without --steps fits the run to "
                "one process's step rate; with %d processes give --steps "
                "(and --seconds to stop early, if wanted)\n", D.size);
        return SETUP_USAGE;
    }
    if (D.rank != 0) {
        return NERF_OK;
    }
    if (p->budget) {
        if (sc.state == NERF_SCHEDULE_FITTED) {
            fprintf(stderr, PROG ": training on to the %llu steps "
                    "fitted to its budget, for at most %g s\n",
                    (unsigned long long)sc.total_steps, a->seconds);
        } else {
            fprintf(stderr, PROG ": training for %g s: the learning "
                    "rate holds for the first quarter, then decays over "
                    "the steps the measured rate allows\n", a->seconds);
        }
    } else if (a->seconds > 0.0 && p->target > step) {
        fprintf(stderr, PROG ": stopping at step %llu or after %g s, "
                "whichever comes first\n", (unsigned long long)p->target,
                a->seconds);
    }
    return NERF_OK;
}

/* After a budget's run: where it stopped, if short of the fitted length. */
static void report_budget(const nerf_model *m, int rc)
{
    nerf_schedule sc;
    memset(&sc, 0, sizeof sc);
    sc.struct_size = sizeof sc;
    nerf_model_schedule(m, &sc);
    if (sc.state != NERF_SCHEDULE_FITTED) {
        return;
    }
    /* The fit itself is logged by the trainer when it happens. */
    if (rc == NERF_ECANCELLED && nerf_model_step(m) < sc.total_steps) {
        fprintf(stderr, PROG ": out of time at step %llu of %llu (the "
                "steps ran slower than measured); --resume trains on to "
                "%llu\n", (unsigned long long)nerf_model_step(m),
                (unsigned long long)sc.total_steps,
                (unsigned long long)sc.total_steps);
    }
}

/*
 * The library's trainer settings for the model (nerf_trainer_options_for():
 * the batch it was trained at, else its preset's; no crop and a random
 * background for a hash-grid model; the finer march it records; timed
 * saves), then what the options change.  A --batch of its own is taken
 * whole, as before 0.9, unless --batch-samples caps it or the model
 * records a cap.
 */
static int trainer_options(const args *a, const nerf_model *m,
                           nerf_trainer_options *to)
{
    to->checkpoint_path = a->out;
    to->checkpoint_every = a->every == UINT64_MAX ? 0 : (uint32_t)a->every;
    int rc = nerf_trainer_options_for(to, m);
    if (rc != NERF_OK) {
        return rc;
    }
    uint32_t rays = 0, samples = 0;
    nerf_model_training_batch(m, &rays, &samples);
    if (a->every != UINT64_MAX) {
        to->checkpoint_seconds = 0.0; /* saves by steps alone, as asked */
    }
    if (a->batch_given) {
        to->batch_rays = (uint32_t)a->batch;
        to->batch_samples = rays ? samples : 0;
    } else if (rays != 0 && D.rank == 0) {
        fprintf(stderr, PROG ": %u rays a step, as %s was trained\n",
                (unsigned)rays, a->out);
    }
    if (a->batch_samples_given) {
        to->batch_samples = (uint32_t)a->batch_samples;
    }
    to->appearance_codes = (uint32_t)a->appearance_codes;
    if (a->random_bg >= 0) {
        to->random_background = a->random_bg;
    }
    if (a->render_march > 0) {
        to->render_march_steps = (uint32_t)a->render_march;
    }
    return NERF_OK;
}

static int run(int argc, char **argv)
{
    cli_blas_single_thread();
    args a;
    if (parse(argc, argv, &a) != 0) {
        return 2;
    }
    if (check_existing(&a) != 0) {
        return 2;
    }
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = PROG;
    if (D.rank != 0) {
        hooks.log_level = NERF_LOG_WARN; /* rank 0 tells the story */
    }

    nerf_dataset *ds = NULL;
    nerf_model *m = NULL;
    nerf_sampler *s = NULL;
    nerf_trainer *t = NULL;
    int rc = resume_model(&a, &hooks, &m);
    const int resumed = m != NULL;
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    dopt.downscale = (uint32_t)a.downscale;
    dopt.forward_facing = setup_forward_facing(m, a.space);
    dopt.ignore_masks = (uint32_t)a.no_masks;
    dopt.hooks = &hooks;
    if (rc == NERF_OK) {
        rc = nerf_dataset_load(&ds, a.data, &dopt);
    }
    if (rc == NERF_OK && m == NULL) {
        rc = create_model(&a, &hooks, ds, &m);
    }
    if (rc == NERF_OK && a.render_march > 0 && !setup_marches(m)) {
        cli_usage_error(PROG, "--render-march-steps sets the steps a model "
                        "of the fast preset is rendered in; %s samples in "
                        "bins, without marching", resumed ? a.out
                                                          : "this preset");
        rc = SETUP_USAGE;
    }
    if (rc == NERF_OK) {
        /* A resumed model keeps its own samples, as a fresh one gets
         * the preset's unless given; a marching one trains in the
         * preset's march, not the finer one it records for rendering. */
        sampler_choice c = SAMPLER_AS_RECORDED;
        c.n_coarse = resumed ? -1 : a.coarse;
        c.n_fine = resumed ? -1 : a.fine;
        c.seed = a.seed;
        c.training = 1;
        rc = setup_sampler(&s, m, ds, &c);
    }
    if (rc == NERF_OK) {
        nerf_trainer_options to;
        NERF_TRAINER_OPTIONS_INIT(&to);
        rc = trainer_options(&a, m, &to);
        to.hooks = &hooks;
        dist_trainer_options(&D, &to);
        /* Made only now, when nothing but the trainer can fail, and
         * before its check of MODEL, which needs the folder. */
        if (rc == NERF_OK) {
            rc = out_make_parent(a.out, PROG) == 0 ? NERF_OK : REPORTED;
        }
        if (rc == NERF_OK) {
            rc = nerf_trainer_create(&t, m, ds, s, &to);
        }
    }
    if (rc != NERF_OK) {
        if (rc != SETUP_USAGE && rc != REPORTED) {
            cli_report(PROG, rc);
        }
        nerf_trainer_destroy(t);
        nerf_dataset_destroy(ds);
        nerf_model_destroy(m);
        nerf_sampler_destroy(s);
        return rc == SETUP_USAGE ? 2 : 1;
    }
    interrupt_catch(D.size == 1);
    plan pl;
    rc = plan_run(&a, m, &pl);
    if (rc != NERF_OK) {
        nerf_trainer_destroy(t);
        nerf_dataset_destroy(ds);
        nerf_model_destroy(m);
        nerf_sampler_destroy(s);
        return 2;
    }
    run_state st;
    st.first_step = nerf_model_step(m);
    /* nerf_trainer_run_for() keeps its own time. */
    st.seconds = pl.budget ? 0.0 : a.seconds;
    st.out_of_time = 0;
    uint64_t todo = pl.target > st.first_step ? pl.target - st.first_step : 0;
    progress_begin(&st.bar, PROG, pl.budget ? 1 : todo);
    nerf_trainer_set_progress(t, on_progress, &st);
    nerf_train_stats stats;
    memset(&stats, 0, sizeof stats);
    stats.struct_size = sizeof stats;
    if (pl.budget) {
        rc = nerf_trainer_run_for(t, a.seconds, &stats);
    } else {
        rc = todo ? nerf_trainer_run(t, todo, &stats) : NERF_OK;
    }
    /* The run ends with a save whatever stopped it; EIO means a save
     * failed (nerf_trainer_run() lets it outrank a cancellation), and
     * another error may have come before it: only OK and a cancellation
     * are sure to be on disk. */
    int saved = rc == NERF_OK || rc == NERF_ECANCELLED;
    /* Interrupted, the run is not done: one line says where it stopped
     * (the bar's line, on a terminal, is ended first). */
    int stopped = rc == NERF_ECANCELLED && interrupted;
    if (D.rank != 0) {
        /* Rank 0 says how the run ended. */
    } else if (interrupted && (stopped || rc == NERF_EIO)) {
        if (st.bar.tty) {
            fputc('\n', stderr);
        }
        fprintf(stderr, PROG ": interrupted at step %llu; %s %s%s\n",
                (unsigned long long)nerf_model_step(m),
                saved ? "saved" : "NOT saved to", a.out,
                saved ? " (resume with --resume)" : "");
    } else {
        char note[4200];
        if (stats.step == 0 && rc == NERF_OK) {
            snprintf(note, sizeof note, "(already at step %llu: nothing to "
                     "train)", (unsigned long long)nerf_model_step(m));
        } else {
            snprintf(note, sizeof note, "(step %llu, train psnr %.2f dB, %s "
                     "%s)", (unsigned long long)nerf_model_step(m), stats.psnr,
                     saved ? "saved" : "NOT saved to", a.out);
        }
        progress_end(&st.bar, note);
    }
    dist_report(&D);
    if (pl.budget && !interrupted) {
        report_budget(m, rc);
        if (rc == NERF_ECANCELLED) {
            rc = NERF_OK; /* the budget was kept */
        }
    }
    if (rc == NERF_EIO) {
        cli_report(PROG, rc);
        fprintf(stderr, PROG ": the save failed: %s keeps the last "
                "checkpoint written whole, if any; steps since are lost\n",
                a.out);
    } else if (rc == NERF_ECANCELLED && st.out_of_time && !interrupted) {
        if (D.rank == 0) {
            fprintf(stderr, PROG ": stopped after %g s as asked, at step "
                    "%llu before step %llu; resume with --resume\n",
                    a.seconds, (unsigned long long)nerf_model_step(m),
                    (unsigned long long)pl.target);
        }
        rc = NERF_OK;
    } else if (rc == NERF_OK && st.seconds > 0.0 && todo > 0) {
        if (D.rank == 0) {
            fprintf(stderr, PROG ": reached step %llu before the %g s "
                    "limit\n", (unsigned long long)pl.target, a.seconds);
        }
    } else if (rc != NERF_OK && !stopped) {
        cli_report(PROG, rc);
    }
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    nerf_dataset_destroy(ds);
    /* As a shell reports a program killed by the signal: 130 for
     * SIGINT. */
    return stopped ? 128 + interrupted : rc == NERF_OK ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (dist_init(&D, &argc, &argv, PROG) != 0) {
        return 1;
    }
    int status = run(argc, argv);
    if (status != 0 && status < 128) {
        /* With other processes, a failure here must end them too: they
         * would wait for this one at the next exchange. */
        dist_fail(&D, status);
    }
    dist_finish(&D);
    return status;
}
