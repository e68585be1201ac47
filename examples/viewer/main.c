/* nerf-viewer: look at a trained model interactively, or render one view. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#include "../common/cli.h"
#include "../common/options.h"
#include "../common/opt_table.h"
#include "../common/out_file.h"
#include "../common/progress.h"
#include "../common/scene_setup.h"
#include "../common/shared_opts.h"
#include "viewer.h"

#define PROG "nerf-viewer"

static const char about[] =
    "Show MODEL in a window, rendered from a camera you move with the mouse.\n";

static const char after[] =
    "Mouse: left drag orbits, right drag or shift + left drag pans, the\n"
    "wheel zooms.  Keys: 1 colour, 2 depth, 3 opacity, r reset the view,\n"
    "q or Esc quit.  While the view moves it is drawn from the bake\n"
    "(--bake), or at a reduced resolution, then refined when it stops.\n"
    "Examples:\n"
    "  nerf-viewer --model lego.nerf\n"
    "  nerf-viewer --model fern.nerf --data fern --downscale 8 --width 320\n"
    "  nerf-viewer --model lego.nerf --screenshot lego.png --view depth\n"
    "  nerf-viewer --model lego.nerf --data lego --width 640 --fly 10\n";

/* Default image width when none is given. */
#define DEFAULT_WIDTH 640
/* While the view moves, a marching model is drawn in this fraction of
 * the still view's march steps (docs/viewer.md, "Figures"). */
#define PREVIEW_MARCH_DIVISOR 4

typedef struct args {
    const char *model, *data, *screenshot;
    uint64_t width, height, downscale;
    int downscale_given, overwrite;
    int mode;
    int64_t march;         /* -1: the model's */
    int64_t preview_march; /* -1: march / PREVIEW_MARCH_DIVISOR */
    double quit_after, fly;
    int64_t bake; /* subdivisions; -1: the library's default (6) when the
                   * model can be baked */
} args;

static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    a->downscale = 1;
    a->march = -1;
    a->preview_march = -1;
    a->bake = -1;
    const opt opts[] = {
        {OPT_MODEL(&a->model)},
        {.name = "--data", OPT_TEXT_TO(&a->data), .value = "DIR",
         .help = "the scene MODEL was trained on: its cameras choose\n"
                 "the start view, its bounds the samples (Blender-like\n"
                 "scenes circle the origin; LLFF scenes start at the\n"
                 "first camera).  Default none: a Blender-like scene."},
        {OPT_DOWNSCALE(&a->downscale), .given = &a->downscale_given,
         .help = "with --data: load its images K times smaller\n"
                 "(default {default})"},
        {OPT_IMAGE_SIDE("--width", &a->width, "W"),
         .head = "--width W, --height H",
         .help = "image size (default " CLI_STR(DEFAULT_WIDTH)
                 " wide, the data's\n"
                 "aspect ratio); while the view moves it is drawn\n"
                 "smaller, as small as the model's speed needs"},
        {OPT_IMAGE_SIDE("--height", &a->height, "H")},
        {.name = "--view", OPT_CHOICE_OF(&a->mode, view_modes),
         .value = "MODE",
         .help = "what to show first: rgb, depth or opacity (default\n"
                 "{default})"},
        {OPT_MARCH_STEPS("--march-steps", &a->march),
         .help = "march a marching model (the fast preset) in steps of\n"
                 "its grid's diagonal / N, {range} (default: the N\n"
                 "MODEL records, 1280 for fast): coarser draws\n"
                 "faster, as nerf-render --march-steps"},
        {OPT_MARCH_STEPS("--preview-march", &a->preview_march),
         .help = "while the view moves, march a marching model in N\n"
                 "steps, {range} (default: a quarter of the still\n"
                 "view's): coarser moves faster, at a cost in detail"},
        {.name = "--bake", OPT_INT_IN(&a->bake, 0, 16), .value = "K",
         .help = "bake MODEL at load, K voxels along each cell of its\n"
                 "grid, {range}, and draw the moving view from the bake\n"
                 "at up to full size (0: do not; default: 6 for a model\n"
                 "that can be baked, the fast preset in a box)"},
        {.name = "--screenshot", OPT_TEXT_TO(&a->screenshot),
         .value = "FILE",
         .help = "render the start view to FILE (PNG) and exit,\n"
                 "without opening a window (default: open one)"},
        {OPT_OVERWRITE(&a->overwrite),
         .help = "with --screenshot: replace FILE if it exists (default\n"
                 "off: an existing FILE is refused; MODEL never is)"},
        {.name = "--fly", OPT_REAL_IN(&a->fly, 0.0, HUGE_VAL, CLI_ABOVE_MIN),
         .value = "S",
         .help = "fly the view along a path for S seconds without a\n"
                 "person (a turn around the scene; with LLFF --data, a\n"
                 "small loop), refine where it stops, close, then print\n"
                 "each frame's time and PSNR against the full render\n"
                 "and a summary (default: the mouse moves the view)"},
        {.name = "--quit-after",
         OPT_REAL_IN(&a->quit_after, 0.0, HUGE_VAL, CLI_ABOVE_MIN),
         .value = "S",
         .help = "close the window after S seconds and print what was\n"
                 "rendered (for tests; default: stay open)"},
        {.name = NULL},
    };
    const opt_program p = {.name = PROG, .opts = opts, .column = 18,
                           .about = about, .after = after};
    if (opt_parse(&p, argc, argv) != 0) {
        return -1;
    }
    if (a->overwrite && a->screenshot == NULL) {
        cli_usage_error(PROG, "--overwrite goes with --screenshot");
        return -1;
    }
    const out_input inputs[2] = {{"--model", a->model}, {"--data", a->data}};
    if (a->screenshot != NULL &&
        out_file_check(PROG, a->screenshot, a->overwrite, NULL, inputs, 2) !=
            0) {
        return -1;
    }
    if (a->bake > 0 && a->screenshot != NULL) {
        cli_usage_error(PROG, "--bake is for a window's moving views; "
                        "--screenshot draws the still view");
        return -1;
    }
    if (a->preview_march >= 0 && a->screenshot != NULL) {
        cli_usage_error(PROG, "--preview-march is for a window; "
                        "--screenshot draws the still view");
        return -1;
    }
    if (a->fly > 0.0 && a->screenshot != NULL) {
        cli_usage_error(PROG, "--fly flies in a window; --screenshot opens "
                        "none");
        return -1;
    }
    if (a->downscale_given && a->data == NULL) {
        cli_usage_error("nerf-viewer", "--downscale shrinks the images of "
                        "--data; without --data, give --width/--height");
        return -1;
    }
    return 0;
}

/* The image size: as asked, else DEFAULT_WIDTH wide with the aspect ratio
 * of the data's images (square without data). */
static void choose_size(const args *a, viewer *v)
{
    uint32_t dw = 1, dh = 1;
    if (v->dataset) {
        nerf_dataset_image_size(v->dataset, &dw, &dh);
    }
    uint64_t w = a->width, h = a->height;
    if (w == 0 && h == 0) {
        w = DEFAULT_WIDTH;
    }
    if (w == 0) {
        w = (h * dw + dh / 2) / dh;
    } else if (h == 0) {
        h = (w * dh + dw / 2) / dw;
    }
    v->width = (uint32_t)(w > 0 ? (w < 16384 ? w : 16384) : 1);
    v->height = (uint32_t)(h > 0 ? (h < 16384 ? h : 16384) : 1);
}

/* The previews' own sampler and renderer, for a marching model whose
 * previews march coarser than its still views (or --preview-march). */
static int open_previews(const args *a, const nerf_renderer_options *ro,
                         viewer *v)
{
    int64_t steps = a->preview_march;
    if (steps < 0) {
        if (!setup_marches(v->model)) {
            return NERF_OK;
        }
        nerf_sampler_options so;
        NERF_SAMPLER_OPTIONS_INIT(&so);
        int rc = nerf_sampler_options_for(&so, v->model, v->dataset,
                                          NERF_SAMPLER_FOR_RENDERING);
        if (rc != NERF_OK) {
            return rc;
        }
        int64_t full = a->march >= 0 ? a->march : (int64_t)so.march_steps;
        steps = full / PREVIEW_MARCH_DIVISOR > 0
                    ? full / PREVIEW_MARCH_DIVISOR
                    : 1;
        if (steps == full) {
            return NERF_OK;
        }
    }
    sampler_choice c = SAMPLER_AS_RECORDED;
    c.march_steps = steps;
    int rc = setup_sampler(&v->preview_sampler, v->model, v->dataset, &c);
    if (rc == NERF_OK) {
        rc = nerf_renderer_create(&v->preview_renderer, v->model,
                                  v->preview_sampler, ro);
    }
    return rc;
}

/* The bake the previews draw from: asked for with --bake K, or by
 * default where the model allows one (otherwise the previews go on with
 * the networks, and say why). */
static int open_bake(const args *a, const nerf_hooks *hooks, viewer *v)
{
    if (a->bake == 0) {
        return NERF_OK;
    }
    nerf_bake_options o;
    NERF_BAKE_OPTIONS_INIT(&o);
    if (a->bake > 0) {
        o.subdivisions = (uint32_t)a->bake;
    }
    if (a->march >= 0) {
        o.march_steps = (uint32_t)a->march;
    }
    progress_reports bar = {.label = "nerf-viewer: baking"};
    o.progress = progress_on_report;
    o.progress_user = &bar;
    o.hooks = hooks;
    int rc = nerf_bake_create(&v->bake, v->model, &o);
    progress_reports_end(&bar);
    if (rc != NERF_OK && a->bake < 0) {
        fprintf(stderr, "nerf-viewer: moving views use the networks: %s\n",
                nerf_last_error());
        return NERF_OK;
    }
    return rc;
}

static int open_scene(const args *a, const nerf_hooks *hooks, viewer *v)
{
    int rc = nerf_model_load(&v->model, a->model, hooks);
    if (rc == NERF_OK && a->data) {
        nerf_dataset_options dopt;
        NERF_DATASET_OPTIONS_INIT(&dopt);
        dopt.downscale = (uint32_t)a->downscale;
        /* Every LLFF image, so that camera 0 is the scene's first one
         * (the held-out test views include it). */
        dopt.llff_holdout = 0;
        dopt.forward_facing = setup_forward_facing(v->model, -1);
        dopt.hooks = hooks;
        rc = nerf_dataset_load(&v->dataset, a->data, &dopt);
    }
    if (rc == NERF_OK) {
        sampler_choice c = SAMPLER_AS_RECORDED;
        c.march_steps = a->march;
        rc = setup_sampler(&v->sampler, v->model, v->dataset, &c);
    }
    if (rc == NERF_OK) {
        nerf_renderer_options ro;
        NERF_RENDERER_OPTIONS_INIT(&ro);
        ro.white_background = (uint32_t)setup_background(v->model,
                                                           v->dataset);
        /* The window checks for input after every chunk: small chunks keep
         * it responsive even with the slow reference networks. */
        ro.chunk_rays = a->screenshot ? ro.chunk_rays : 64;
        ro.hooks = hooks;
        rc = nerf_renderer_create(&v->renderer, v->model, v->sampler, &ro);
        if (rc == NERF_OK && a->screenshot == NULL) {
            rc = open_previews(a, &ro, v);
        }
        if (rc == NERF_OK && a->screenshot == NULL) {
            rc = open_bake(a, hooks, v);
        }
    }
    if (rc == NERF_OK) {
        /* The home view's framing depends on the image's shape. */
        choose_size(a, v);
        rc = viewer_home(v);
    }
    return rc;
}

static int screenshot(viewer *v, const char *path)
{
    frame f;
    memset(&f, 0, sizeof f);
    nerf_camera cam;
    int rc = viewer_camera(v, v->width, v->height, &cam);
    if (rc == NERF_OK) {
        rc = frame_render(&f, v->renderer, NULL, &cam);
    }
    if (rc == NERF_OK) {
        uint32_t channels;
        const float *pixels =
            frame_view(&f, v->mode, v->near, v->far, &channels);
        rc = nerf_image_write_png(path, f.width, f.height, channels, pixels);
    }
    if (rc == NERF_OK) {
        fprintf(stderr, "nerf-viewer: wrote %s (%ux%u %s, %.2f s)\n", path,
                f.width, f.height, view_mode_name(v->mode), f.seconds);
    }
    frame_free(&f);
    return rc;
}

int main(int argc, char **argv)
{
    cli_blas_single_thread();
    args a;
    if (parse(argc, argv, &a) != 0) {
        return 2;
    }
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = "nerf-viewer";

    viewer v;
    memset(&v, 0, sizeof v);
    v.mode = (view_mode)a.mode;
    v.quit_after = a.quit_after;
    v.fly_seconds = a.fly;
    int status = 0;
    int rc = open_scene(&a, &hooks, &v);
    if (rc == NERF_OK) {
        if (a.screenshot) {
            rc = screenshot(&v, a.screenshot);
        } else {
            status = viewer_run_window(&v);
        }
    }
    if (rc != NERF_OK) {
        cli_report("nerf-viewer", rc);
        status = 1;
    }
    nerf_bake_destroy(v.bake);
    nerf_renderer_destroy(v.preview_renderer);
    nerf_sampler_destroy(v.preview_sampler);
    nerf_renderer_destroy(v.renderer);
    nerf_sampler_destroy(v.sampler);
    nerf_dataset_destroy(v.dataset);
    nerf_model_destroy(v.model);
    return status;
}
