/*
 * nerf-export depth and nerf-export points: world-unit depth maps and
 * point clouds from rendered views of a model, the scene's own cameras.
 */
#include <nerf.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/cli.h"
#include "common/interrupt.h"
#include "common/options.h"
#include "common/opt_table.h"
#include "common/out_folder.h"
#include "common/out_file.h"
#include "common/progress.h"
#include "common/scene_setup.h"
#include "common/shared_opts.h"
#include "export.h"

static const char depth_about[] =
    "Render the views of a split of the scene MODEL was trained on (or the\n"
    "cameras of a file) and write\n"
    "for each, into DIR (created if missing), float32 NumPy arrays of shape\n"
    "(height, width), row 0 at the top (docs/formats.md):\n"
    "  NNN_distance.npy  distance in world units from the camera centre to\n"
    "                    the ray's expected termination point (sum(w t) /\n"
    "                    sum(w) along the ray, so divided by the opacity)\n"
    "  NNN_zdepth.npy    the same point's depth along the camera's optical\n"
    "                    axis (camera-space -z), world units\n"
    "  NNN_opacity.npy   sum(w) in [0, 1]: 0 sees only the background\n"
    "Both depths are 0 where the opacity is 0.  For a forward-facing (LLFF,\n"
    "NDC) model the NDC depth is converted back to world units.  NNN is the\n"
    "view's index in the split (000, K, 2K, ... with --skip K) or in the\n"
    "file.\n";

static const char depth_after[] =
    "Examples:\n"
    "  nerf-export depth --model lego.nerf --data lego --downscale 4 \\\n"
    "      --skip 10 --out lego-depth\n"
    "  python3 -c \"import numpy; d = numpy.load('lego-depth/000_zdepth.npy')\"\n";

static const char points_about[] =
    "Render the views of a split of the scene MODEL was trained on (or the\n"
    "cameras of a file) and write\n"
    "one point per ray whose opacity reaches T, at the ray's expected\n"
    "termination point, with the ray's colour and a normal estimated from\n"
    "the neighbouring rays' points (0 0 0 where none can be: at the image's\n"
    "depth discontinuities and beside rays without a point), as a PLY file\n"
    "(written to a temporary name, then renamed).\n";

static const char points_after[] =
    "Ctrl-C stops at once; nothing is written.\n"
    "Examples:\n"
    "  nerf-export points --model lego.nerf --data lego --downscale 2 \\\n"
    "      --stride 2 --out lego-points.ply\n"
    "  nerf-export points --model fern.nerf --data fern --downscale 8 \\\n"
    "      --opacity 0.5 --ascii --out fern.ply\n";

/* Stopped by a signal, and said so. */
#define INTERRUPTED 2
/* A failure already described on stderr. */
#define REPORTED 1

/* The largest --stride: every K-th pixel's ray in each direction. */
#define STRIDE_MAX 1024

typedef struct args {
    const char *program;
    const char *model, *data, *out, *poses;
    uint64_t split, skip, downscale;
    int data_options; /* --split, --skip or --downscale given */
    int overwrite;
    /* depth */
    int png;
    /* points */
    uint64_t max_points, stride;
    double opacity;
    int ascii;
} args;

/* --poses in the help of each. */
static const char depth_poses[] =
    "render the cameras of a camera path file instead, as\n"
    "nerf-render --poses reads it; the file must give the\n"
    "image size and intrinsics (a transforms.json with w,\n"
    "h and camera_angle_x or fl_x) (default none)";
static const char points_poses[] =
    "use the cameras of a camera path file instead, as\n"
    "nerf-render --poses reads it; the file must give the\n"
    "image size and intrinsics (default none)";

/* 0, or -1 after a usage error (printed). */
static int parse(int argc, char **argv, args *a, int points)
{
    opt opts[16];
    size_t n = 0;
    opts[n++] = (opt){OPT_MODEL(&a->model)};
    opts[n++] = (opt){
        .name = "--data", OPT_TEXT_TO(&a->data), .flags = OPT_ONE_OF,
        .value = "DIR",
        .help = "the scene MODEL was trained on: its views (default:\n"
                "required unless --poses gives the views); with\n"
                "--poses only its bounds, background and placement"};
    opts[n++] = (opt){.name = "--poses", OPT_TEXT_TO(&a->poses),
                      .flags = OPT_ONE_OF, .value = "FILE",
                      .help = points ? points_poses : depth_poses};
    opts[n++] = (opt){
        .name = "--out", OPT_TEXT_TO(&a->out), .flags = OPT_REQUIRED,
        .value = points ? "FILE" : "DIR",
        .help = points ? "the PLY file (required; its folder is made if "
                         "missing)"
                       : "the output folder (required)"};
    opts[n++] = (opt){OPT_SPLIT(&a->split), .given = &a->data_options,
                      .help = "train, val or test (default {default})"};
    opts[n++] = (opt){
        OPT_SKIP(&a->skip), .given = &a->data_options,
        .help = "only every K-th view of the split (default {default}: all)"};
    opts[n++] = (opt){
        OPT_DOWNSCALE(&a->downscale), .given = &a->data_options,
        .help = "load the scene's cameras K times smaller (default "
                "{default})"};
    if (points) {
        opts[n++] = (opt){
            .name = "--max-points",
            OPT_INT_IN(&a->max_points, 1, UINT64_MAX / 2), .value = "N",
            .help = "at most N points, thinned evenly in ray order\n"
                    "(default {default})"};
        opts[n++] = (opt){
            .name = "--stride", OPT_INT_IN(&a->stride, 1, STRIDE_MAX),
            .value = "K",
            .help = "one ray per K x K pixels of each view (default "
                    "{default})"};
        opts[n++] = (opt){
            .name = "--opacity", OPT_REAL_IN(&a->opacity, 0.0, 1.0, 0),
            .value = "T",
            .help = "the least opacity of a ray that gives a point, in\n"
                    "{range} (default {default})"};
        opts[n++] = (opt){
            .name = "--ascii", OPT_FLAG_SETS(&a->ascii, 1),
            .help = "an ASCII PLY (default binary little-endian)"};
    } else {
        opts[n++] = (opt){
            .name = "--png", OPT_FLAG_SETS(&a->png, 1),
            .help = "also write 8-bit previews, as nerf-render --depth does:\n"
                    "NNN_depth.png (z depth from the scene's near bound,\n"
                    "white, to its far bound, black; black where the\n"
                    "opacity is below 0.001) and NNN_opacity.png (the\n"
                    "default)"};
        opts[n++] = (opt){.name = "--no-png", OPT_FLAG_SETS(&a->png, 0),
                          .help = "write the .npy arrays only"};
    }
    opts[n++] = (opt){
        OPT_OVERWRITE(&a->overwrite),
        .help = points ? "replace FILE if it exists (default off: an existing\n"
                         "FILE is refused; an input never is replaced)"
                       : "replace the views' files if DIR holds them already\n"
                         "(default off: any one there is refused before\n"
                         "rendering; an input never is replaced)"};
    opts[n] = (opt){.name = NULL};
    const opt_program p = {.name = a->program, .opts = opts,
                           .column = points ? 18 : 17,
                           .about = points ? points_about : depth_about,
                           .after = points ? points_after : depth_after};
    if (opt_parse(&p, argc, argv) != 0) {
        return -1;
    }
    /* Refused rather than ignored: the user meant something by them. */
    if (a->poses && a->data_options) {
        cli_usage_error(a->program, "--split, --skip and --downscale "
                        "choose the views of --data; with --poses they "
                        "would change nothing");
        return -1;
    }
    return 0;
}

/* What both subcommands render with: the model, the scene's views and a
 * renderer set up as nerf-render sets it up for them. */
typedef struct views {
    nerf_hooks hooks;
    nerf_model *model;
    nerf_dataset *ds;          /* NULL with --poses alone */
    nerf_camera_path *poses;   /* NULL without --poses */
    nerf_sampler *sampler;
    nerf_renderer *renderer;
} views;

static uint32_t view_count(const views *v)
{
    return v->poses ? nerf_camera_path_count(v->poses)
                    : nerf_dataset_count(v->ds);
}

static int view_camera(const views *v, uint32_t i, nerf_camera *cam)
{
    NERF_CAMERA_INIT(cam);
    return v->poses ? nerf_camera_path_camera(v->poses, i, cam)
                    : nerf_dataset_camera(v->ds, i, cam);
}

/* The number of view i in the file names: its index in the split (which
 * --skip thins) or in the file. */
static uint64_t view_number(const args *a, uint32_t i)
{
    return a->poses ? i : (uint64_t)i * a->skip;
}

static int open_views(const args *a, views *v)
{
    memset(v, 0, sizeof *v);
    NERF_HOOKS_INIT(&v->hooks);
    v->hooks.log_cb = cli_log;
    v->hooks.log_user = (void *)a->program;
    int rc = nerf_model_load(&v->model, a->model, &v->hooks);
    if (rc == NERF_OK && a->poses) {
        nerf_camera_path_options po;
        NERF_CAMERA_PATH_OPTIONS_INIT(&po);
        po.hooks = &v->hooks;
        rc = nerf_camera_path_load(&v->poses, a->poses, &po);
    }
    if (rc == NERF_OK && a->data) {
        nerf_dataset_options dopt;
        NERF_DATASET_OPTIONS_INIT(&dopt);
        dopt.split = (uint32_t)a->split;
        dopt.skip = (uint32_t)a->skip;
        dopt.downscale = (uint32_t)a->downscale;
        dopt.forward_facing = setup_forward_facing(v->model, -1);
        dopt.hooks = &v->hooks;
        rc = nerf_dataset_load(&v->ds, a->data, &dopt);
    }
    if (rc == NERF_OK && view_count(v) == 0) {
        fprintf(stderr, "%s: %s: no views to render\n", a->program,
                a->poses ? a->poses : a->data);
        return REPORTED;
    }
    if (rc == NERF_OK) {
        const sampler_choice c = SAMPLER_AS_RECORDED;
        rc = setup_sampler(&v->sampler, v->model, v->ds, &c);
    }
    if (rc == NERF_OK) {
        nerf_renderer_options ro;
        NERF_RENDERER_OPTIONS_INIT(&ro);
        ro.white_background = (uint32_t)setup_background(v->model, v->ds);
        ro.hooks = &v->hooks;
        rc = nerf_renderer_create(&v->renderer, v->model, v->sampler, &ro);
    }
    return rc;
}

static void close_views(views *v)
{
    nerf_renderer_destroy(v->renderer);
    nerf_sampler_destroy(v->sampler);
    nerf_dataset_destroy(v->ds);
    nerf_camera_path_destroy(v->poses);
    nerf_model_destroy(v->model);
}

/* The exit status of a run that ended with rc. */
static int finish(const args *a, int rc)
{
    if (rc == NERF_ECANCELLED && interrupted) {
        fprintf(stderr, "\n%s: interrupted\n", a->program);
        return 128 + interrupted;
    }
    if (rc != NERF_OK && rc != REPORTED) {
        cli_report(a->program, rc);
    }
    return rc == NERF_OK ? 0 : 1;
}

typedef struct bar_state {
    progress bar;
    uint64_t before; /* pixels of the views already rendered */
} bar_state;

static int on_depth_progress(const nerf_progress *p, void *user)
{
    bar_state *b = user;
    progress_update(&b->bar, b->before + p->done, "pixels");
    return interrupted ? 1 : 0;
}

static int on_points_progress(const nerf_progress *p, void *user)
{
    progress_update(user, p->done, "rays");
    return interrupted ? 1 : 0;
}

/* The file of view in dir holding name ("zdepth.npy", "depth.png"). */
static void view_path(char *path, size_t size, const char *dir, uint64_t view,
                      const char *name)
{
    snprintf(path, size, "%s/%03llu_%s", dir, (unsigned long long)view, name);
}

static int write_npy(const char *dir, uint64_t view, const char *name,
                     const float *data, uint32_t w, uint32_t h)
{
    char path[4200];
    view_path(path, sizeof path, dir, view, name);
    const size_t shape[2] = {h, w};
    return nerf_npy_write_float(path, data, shape, 2);
}

/* What depth writes for each view: the arrays, then the previews. */
static const char *const depth_files[] = {"distance.npy", "zdepth.npy",
                                          "opacity.npy", "opacity.png",
                                          "depth.png"};
#define DEPTH_ARRAYS 3

/* Every file the views will be written to, new or replaced as told, and
 * none an input: found before anything is rendered. */
static int check_depth_targets(const args *a, const views *v)
{
    const out_input inputs[3] = {
        {"--model", a->model}, {"--data", a->data}, {"--poses", a->poses}};
    size_t kinds = a->png ? sizeof depth_files / sizeof depth_files[0]
                          : DEPTH_ARRAYS;
    for (uint32_t i = 0; i < view_count(v); i++) {
        for (size_t k = 0; k < kinds; k++) {
            char path[4200];
            view_path(path, sizeof path, a->out, view_number(a, i),
                      depth_files[k]);
            if (out_file_check(a->program, path, a->overwrite, NULL, inputs,
                               3) != 0) {
                return -1;
            }
        }
    }
    return 0;
}

/* The previews of nerf-render --depth, from the z depth. */
static int write_previews(const args *a, uint64_t view, float *z,
                          const float *opacity, uint32_t w, uint32_t h,
                          float near, float far, int ndc)
{
    char path[4200];
    view_path(path, sizeof path, a->out, view, depth_files[DEPTH_ARRAYS]);
    int rc = nerf_image_write_png(path, w, h, 1, opacity);
    for (size_t k = 0; k < (size_t)w * h; k++) {
        /* An NDC scene's bounds are NDC depths: 1 - 1 / z for a camera
         * looking down the scene's -z, as LLFF poses nearly do. */
        float d = opacity[k] > 1e-3f ? (ndc ? 1.0f - 1.0f / z[k] : z[k])
                                     : far;
        z[k] = 1.0f - (d - near) / (far - near);
    }
    view_path(path, sizeof path, a->out, view, depth_files[DEPTH_ARRAYS + 1]);
    return rc == NERF_OK ? nerf_image_write_png(path, w, h, 1, z) : rc;
}

static int depth_views(const args *a, views *v)
{
    uint32_t n = view_count(v), w = 0, h = 0;
    size_t largest = 0;
    uint64_t total = 0;
    for (uint32_t i = 0; i < n; i++) {
        nerf_camera cam;
        int rc = view_camera(v, i, &cam);
        if (rc != NERF_OK) {
            return rc;
        }
        size_t px = (size_t)cam.width * cam.height;
        largest = px > largest ? px : largest;
        total += px;
    }
    float *buf = malloc(largest * 3 * sizeof(float));
    if (buf == NULL) {
        fprintf(stderr, "%s: cannot allocate the buffers of %zu pixels\n",
                a->program, largest);
        return REPORTED;
    }
    float *dist = buf, *z = buf + largest, *op = buf + 2 * largest;
    /* The previews' scale: the sampler's range, the scene's bounds. */
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_model_render_settings(v->model, &so, NULL);
    float near = so.t_near, far = so.t_far;
    int ndc = so.ndc != 0;
    if (v->ds) {
        nerf_dataset_bounds(v->ds, &near, &far);
        ndc = nerf_dataset_is_ndc(v->ds) == 1;
    }
    bar_state b;
    b.before = 0;
    progress_begin(&b.bar, a->program, total);
    nerf_renderer_set_progress(v->renderer, on_depth_progress, &b);
    int rc = NERF_OK;
    for (uint32_t i = 0; i < n && rc == NERF_OK; i++) {
        nerf_camera cam;
        rc = view_camera(v, i, &cam);
        w = cam.width;
        h = cam.height;
        if (rc == NERF_OK) {
            rc = nerf_renderer_render_depth(v->renderer, &cam, NULL, dist, z,
                                            op, largest);
        }
        uint64_t view = view_number(a, i);
        if (rc == NERF_OK) {
            rc = write_npy(a->out, view, "distance.npy", dist, w, h);
        }
        if (rc == NERF_OK) {
            rc = write_npy(a->out, view, "zdepth.npy", z, w, h);
        }
        if (rc == NERF_OK) {
            rc = write_npy(a->out, view, "opacity.npy", op, w, h);
        }
        if (rc == NERF_OK && a->png) {
            rc = write_previews(a, view, z, op, w, h, near, far, ndc);
        }
        b.before += (uint64_t)w * h;
    }
    free(buf);
    if (rc == NERF_OK) {
        char note[4200];
        snprintf(note, sizeof note, "%u view%s in %s", n, n == 1 ? "" : "s",
                 a->out);
        progress_end(&b.bar, note);
    }
    return rc;
}

int export_depth(int argc, char **argv)
{
    args a;
    memset(&a, 0, sizeof a);
    a.program = "nerf-export depth";
    a.split = NERF_SPLIT_TEST;
    a.skip = 1;
    a.downscale = 1;
    a.png = 1;
    if (parse(argc, argv, &a, 0) != 0) {
        return 2;
    }
    if (out_ready_folder(a.out, a.program) != 0) {
        return 1;
    }
    views v;
    int rc = open_views(&a, &v);
    if (rc == NERF_OK && check_depth_targets(&a, &v) != 0) {
        close_views(&v);
        return 2;
    }
    if (rc == NERF_OK) {
        interrupt_catch(1);
        rc = depth_views(&a, &v);
    }
    close_views(&v);
    return finish(&a, rc);
}

/* The folder of file, ready and writable before any rendering. */
static int ready_parent(const args *a)
{
    char dir[4200];
    snprintf(dir, sizeof dir, "%s", a->out);
    char *slash = strrchr(dir, '/');
    if (slash == NULL) {
        snprintf(dir, sizeof dir, ".");
    } else if (slash == dir) {
        dir[1] = '\0';
    } else {
        *slash = '\0';
    }
    return out_ready_folder(dir, a->program);
}

int export_points(int argc, char **argv)
{
    args a;
    memset(&a, 0, sizeof a);
    a.program = "nerf-export points";
    a.split = NERF_SPLIT_TRAIN;
    a.skip = 1;
    a.downscale = 1;
    a.max_points = NERF_POINTS_DEFAULT_MAX;
    a.stride = 1;
    a.opacity = NERF_POINTS_DEFAULT_OPACITY;
    if (parse(argc, argv, &a, 1) != 0) {
        return 2;
    }
    const out_input inputs[3] = {
        {"--model", a.model}, {"--data", a.data}, {"--poses", a.poses}};
    if (out_file_check(a.program, a.out, a.overwrite, NULL, inputs, 3) != 0) {
        return 2;
    }
    if (ready_parent(&a) != 0) {
        return 1;
    }
    views v;
    int rc = open_views(&a, &v);
    uint32_t n = rc == NERF_OK ? view_count(&v) : 0;
    nerf_camera *cams = n ? calloc(n, sizeof *cams) : NULL;
    if (rc == NERF_OK && cams == NULL) {
        fprintf(stderr, "%s: out of memory\n", a.program);
        rc = REPORTED;
    }
    uint64_t total = 0;
    for (uint32_t i = 0; i < n && rc == NERF_OK; i++) {
        rc = view_camera(&v, i, &cams[i]);
        uint64_t s = a.stride;
        total += ((cams[i].width + s - 1) / s) * ((cams[i].height + s - 1) / s);
    }
    nerf_points *pts = NULL;
    progress bar;
    if (rc == NERF_OK) {
        nerf_points_options po;
        NERF_POINTS_OPTIONS_INIT(&po);
        po.opacity_threshold = (float)a.opacity;
        po.max_points = a.max_points;
        po.stride = (uint32_t)a.stride;
        po.hooks = &v.hooks;
        po.progress = on_points_progress;
        po.progress_user = &bar;
        progress_begin(&bar, a.program, total);
        interrupt_catch(1);
        rc = nerf_points_from_views(&pts, v.renderer, cams, n, &po);
    }
    if (rc == NERF_OK) {
        rc = nerf_points_write(pts, a.out, a.ascii ? NERF_POINTS_PLY_ASCII
                                                   : NERF_POINTS_PLY_BINARY);
    }
    if (rc == NERF_OK) {
        char note[4300];
        snprintf(note, sizeof note, "%zu points from %u view%s in %s",
                 nerf_points_count(pts), n, n == 1 ? "" : "s", a.out);
        progress_end(&bar, note);
    }
    nerf_points_destroy(pts);
    free(cams);
    close_views(&v);
    return finish(&a, rc);
}
