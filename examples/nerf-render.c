/* nerf-render: render views of a trained model to PNG files. */
#include <nerf.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/cli.h"
#include "common/dist.h"
#include "common/interrupt.h"
#include "common/out_folder.h"
#include "common/out_file.h"
#include "common/options.h"
#include "common/opt_table.h"
#include "common/orbit.h"
#include "common/progress.h"
#include "common/scene_setup.h"
#include "common/shared_opts.h"
#include "common/video.h"

/* nerf-render-mpi is this program built with common/dist_mpi.c. */
#ifndef PROG
#define PROG "nerf-render"
#endif

static const char about[] =
    "Render views of MODEL and write them to DIR (created if missing) as\n"
    "r_NNN.png, NNN counting from 000 in the order of the views.\n";

static const char after[] =
    "Ctrl-C (SIGINT) stops at once (the view being rendered is not\n"
    "written), says which views are written and exits with status 130\n"
    "(SIGTERM: 143).\n"
    "Examples:\n"
    "  nerf-render --model lego.nerf --out lego-orbit --path orbit \\\n"
    "      --frames 40 --width 200 --height 200 --video lego-orbit.mp4\n"
    "  nerf-render --model fern.nerf --data fern --downscale 8 \\\n"
    "      --path spiral --frames 60 --depth --out fern-spiral\n"
    "  nerf-render --model lego.nerf --data lego --split test --width 200 \\\n"
    "      --out lego-test\n"
    "nerf-render-mpi (built with Open MPI) takes the same flags under\n"
    "mpirun -np N: rank r renders views r, r + N, r + 2N ... (not --video).\n";

/* --path's: none, or a path of --frames views. */
enum { PATH_NONE, PATH_ORBIT, PATH_SPIRAL };

typedef struct args {
    const char *model, *out, *data, *poses;
    int path;
    uint64_t split, downscale, frames, width, height;
    double near, far, focal, fov;
    int depth, size_given, skip_existing, overwrite;
    int bounds_given; /* 1: --near, 2: --far */
    int split_given, downscale_given, frames_given;
    const char *video; /* NULL: PNG frames only */
    uint64_t fps;
    int fps_given;
    int64_t march; /* -1: the model's */
    uint32_t appearance;
} args;

/* The most views of a --path (nerf_camera_path_load()'s most poses), and
 * of frames a second of a video. */
#define FRAMES_MAX 100000
#define FPS_MAX 1000

/* --path orbit's frames without --width or --height are the size of the
 * scene's images with --data (after --downscale), else this square; so
 * are the frames of a --poses file that gives no size. */
#define ORBIT_SIDE 100

static const opt_choice paths[] = {
    {.name = "orbit", .id = PATH_ORBIT,
     .help = "a circle of --frames views around the origin at 30\n"
             "degrees elevation, as for Blender scenes, framed to\n"
             "keep the sphere of radius 1.5 (the box Blender scenes\n"
             "lie in) whole at any aspect ratio: 39.6 degrees\n"
             "across the frame's smaller side, from distance 4.43"},
    {.name = "spiral", .id = PATH_SPIRAL,
     .help = "the reference's spiral path of a forward-facing (LLFF)\n"
             "scene, two turns around its average pose (needs --data)"},
    {.name = NULL},
};

static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    a->split = NERF_SPLIT_TEST;
    a->downscale = 1;
    a->frames = 40;
    a->width = a->height = ORBIT_SIDE;
    a->fps = 30;
    a->march = -1;
    const opt opts[] = {
        {OPT_MODEL(&a->model)},
        {.name = "--out", OPT_TEXT_TO(&a->out), .flags = OPT_REQUIRED,
         .value = "DIR", .help = "the folder of the images (required)"},
        {.name = "--data", OPT_TEXT_TO(&a->data), .flags = OPT_ONE_OF,
         .value = "DIR",
         .help = "the scene MODEL was trained on.  Alone: render each\n"
                 "view of its --split with the scene's own cameras.  With\n"
                 "--path or --poses it only gives the bounds, the\n"
                 "background and the placement (NDC for LLFF); without\n"
                 "it, those MODEL recorded in training (nerf-info shows\n"
                 "them; guessed from its shape for older files)."},
        {OPT_SPLIT(&a->split), .given = &a->split_given,
         .help = "with --data alone: train, val or test (default "
                 "{default})"},
        {OPT_DOWNSCALE(&a->downscale), .given = &a->downscale_given,
         .help = "with --data: read the scene's images and cameras K\n"
                 "times smaller (an LLFF or COLMAP scene's images_K/;\n"
                 "default {default}), which sets the size of the views of\n"
                 "--data and of --path unless --width/--height do;\n"
                 "a --path without it takes the first of images/,\n"
                 "images_2/ ... images_16/ the scene has"},
        {.name = "--path", OPT_CHOICE_OF(&a->path, paths),
         .flags = OPT_ONE_OF},
        {.name = "--frames", OPT_INT_IN(&a->frames, 1, FRAMES_MAX),
         .given = &a->frames_given, .value = "N",
         .help = "views along --path (default {default})"},
        {.name = "--poses", OPT_TEXT_TO(&a->poses), .flags = OPT_ONE_OF,
         .value = "FILE",
         .help = "a camera path: a .npy of N camera-to-world matrices,\n"
                 "shape (N,3,4), (N,4,4), (N,12) or (N,16), float32 or\n"
                 "float64, OpenGL axes; or a transforms.json-style file\n"
                 "(camera_angle_x or fl_x, optional w and h,\n"
                 "frames[].transform_matrix)"},
        {.name = "--focal",
         OPT_REAL_IN(&a->focal, 0.0, HUGE_VAL, CLI_ABOVE_MIN), .value = "F",
         .help = "with --poses: focal length in pixels (default: the\n"
                 "file's, else --fov 39.6)"},
        {.name = "--fov",
         OPT_REAL_IN(&a->fov, 0.0, 180.0, CLI_ABOVE_MIN | CLI_BELOW_MAX),
         .value = "DEG",
         .help = "with --poses: horizontal field of view in degrees\n"
                 "(default: the file's, else 39.6, as --path orbit)"},
        {OPT_IMAGE_SIDE("--width", &a->width, "W"), .given = &a->size_given,
         .bit = 1,
         .help = "image width in pixels.  Default: with --data, the\n"
                 "size of its images (after --downscale) for its views\n"
                 "and either --path (the scene's views and the spiral\n"
                 "scale their focal length and centre with the size:\n"
                 "the same view, sharper or coarser); 100 for --path\n"
                 "orbit without --data; for --poses the file's w,\n"
                 "else 100.  Given alone, the height keeps the aspect\n"
                 "ratio (except with --poses, which needs both)."},
        {OPT_IMAGE_SIDE("--height", &a->height, "H"),
         .given = &a->size_given, .bit = 2,
         .help = "image height in pixels; defaults as --width"},
        {.name = "--depth", OPT_FLAG_SETS(&a->depth, 1),
         .help = "also write depth_NNN.png and opacity_NNN.png (default\n"
                 "off).  depth_NNN.png is 8-bit grey: the expected depth\n"
                 "of each pixel's visible content (the sum of w t over\n"
                 "the ray divided by its opacity) mapped linearly from\n"
                 "--near (white, 255) to --far (black, 0); pixels of\n"
                 "opacity below 0.001 are black.  Grey level v is depth\n"
                 "near + (1 - v / 255) (far - near), in units of t along\n"
                 "the ray (NDC depth, 0..1, for an LLFF scene).\n"
                 "opacity_NNN.png: 255 where the ray is fully absorbed,\n"
                 "0 where it sees only the background."},
        /* Their own checks follow, after both are read. */
        {.name = "--near", OPT_REAL_IN(&a->near, -HUGE_VAL, HUGE_VAL, 0),
         .given = &a->bounds_given, .bit = 1, .value = "T",
         .head = "--near T --far T",
         .help = "the range of depths sampled along each ray (and the\n"
                 "depth map's scale), given together, 0 <= T_near <\n"
                 "T_far (NDC depths within [0, 1] for an LLFF scene);\n"
                 "default the scene's bounds with --data, else 2 and 6"},
        {.name = "--far", OPT_REAL_IN(&a->far, -HUGE_VAL, HUGE_VAL, 0),
         .given = &a->bounds_given, .bit = 2, .value = "T"},
        {OPT_MARCH_STEPS("--march-steps", &a->march),
         .help = "march a marching model (the fast preset) in steps of\n"
                 "its grid's diagonal / N, {range} (default: the N\n"
                 "MODEL records, 1280 for fast since 0.10.9); finer\n"
                 "is slower and sharper, as nerf-eval --help says"},
        {.name = "--video", OPT_TEXT_TO(&a->video), .value = "FILE",
         .help = "also write the views, in order, as an MP4 video\n"
                 "(H.264, or MPEG-4 part 2 if FFmpeg lacks libx264);\n"
                 "all views must share one even width and height.  A\n"
                 "build without FFmpeg's libraries says so and writes\n"
                 "the PNGs only (default none: PNGs only)"},
        {.name = "--fps", OPT_INT_IN(&a->fps, 1, FPS_MAX),
         .given = &a->fps_given, .value = "N",
         .help = "frames a second of the video (default {default})"},
        {OPT_APPEARANCE(&a->appearance),
         .help = "a model with appearance codes renders with: neutral\n"
                 "(the mean of its codes, the default) or training\n"
                 "image A's code, that photo's exposure and colour"},
        {.name = "--skip-existing", OPT_FLAG_SETS(&a->skip_existing, 1),
         .help = "render only the views whose files are not in DIR\n"
                 "yet: the same command again finishes a render that\n"
                 "was stopped (default off: render every view)"},
        {OPT_OVERWRITE(&a->overwrite),
         .help = "replace the files of views DIR holds already, and an\n"
                 "existing --video FILE (default off: any file this run\n"
                 "would write over is refused before rendering; an\n"
                 "input never is replaced)"},
        {.name = NULL},
    };
    const opt_program p = {.name = PROG, .opts = opts, .column = 17,
                           .about = about, .after = after};
    if (opt_parse(&p, argc, argv) != 0) {
        return -1;
    }
    if (a->path && a->poses) {
        cli_usage_error(PROG, "--path and --poses exclude each "
                        "other");
        return -1;
    }
    if ((a->focal > 0.0 || a->fov > 0.0) && a->poses == NULL) {
        cli_usage_error(PROG, "--focal and --fov go with --poses");
        return -1;
    }
    if (a->focal > 0.0 && a->fov > 0.0) {
        cli_usage_error(PROG, "give --focal or --fov, not both");
        return -1;
    }
    /* A file's w and h keep their aspect ratio only as a pair. */
    if (a->poses && a->size_given && a->size_given != 3) {
        cli_usage_error(PROG, "with --poses, give --width and "
                        "--height together");
        return -1;
    }
    /* One bound alone would leave the other to a default that may not fit
     * it; a wrong pair would be sampled backwards. */
    if (a->bounds_given && a->bounds_given != 3) {
        cli_usage_error(PROG, "give --near and --far together");
        return -1;
    }
    if (a->bounds_given && !(a->near >= 0.0)) {
        cli_usage_error(PROG, "--near must be at least 0 (got %g)",
                a->near);
        return -1;
    }
    if (a->bounds_given && !(a->near < a->far)) {
        cli_usage_error(PROG, "--near must be less than --far (got "
                        "--near %g --far %g)", a->near, a->far);
        return -1;
    }
    if (a->fps_given && a->video == NULL) {
        cli_usage_error(PROG, "--fps goes with --video");
        return -1;
    }
    if (a->video != NULL && a->skip_existing) {
        /* The video is encoded from the views this run renders. */
        cli_usage_error(PROG, "--video needs every view rendered: "
                        "drop --skip-existing");
        return -1;
    }
    if (a->path == PATH_SPIRAL && a->data == NULL) {
        cli_usage_error(PROG, "--path spiral needs --data");
        return -1;
    }
    /* Options that would change nothing are refused rather than ignored:
     * the user meant something by them. */
    if (a->frames_given && a->path == PATH_NONE) {
        cli_usage_error(PROG, "--frames goes with --path (--data "
                        "renders each view of its split, --poses each "
                        "camera of the file)");
        return -1;
    }
    int views_of_data = a->path == PATH_NONE && a->poses == NULL;
    if (a->split_given && !views_of_data) {
        cli_usage_error(PROG, "--split chooses the views of --data "
                        "to render; with --%s it would change nothing",
                        a->path ? "path" : "poses");
        return -1;
    }
    /* --downscale chooses which of the scene's photos are read (LLFF and
     * COLMAP scenes may ship only images_K/); a path or a file of poses
     * reads the scene's cameras and bounds through them too, and takes
     * its frame size from --width/--height when given. */
    if (a->downscale_given && a->data == NULL) {
        cli_usage_error(PROG, "--downscale chooses which photos of --data "
                        "are read; without --data it would change nothing "
                        "(give --width and --height for the frames' size)");
        return -1;
    }
    return 0;
}

/*
 * The --poses file's cameras.  Options given on the command line win over
 * the file; where neither gives a size or intrinsics, --path orbit's
 * defaults serve.
 */
static int load_poses(const args *a, const nerf_hooks *hooks,
                      nerf_camera_path **out)
{
    nerf_camera_path_options o;
    NERF_CAMERA_PATH_OPTIONS_INIT(&o);
    o.width = (uint32_t)a->width;
    o.height = (uint32_t)a->height;
    if (!a->size_given) {
        o.flags |= NERF_CAMERA_PATH_FILE_SIZE;
    }
    o.focal = (float)a->focal;
    o.fov_x = (float)a->fov;
    if (a->focal <= 0.0 && a->fov <= 0.0) {
        o.fov_x = (float)(ORBIT_FOV * 180.0 / 3.14159265358979);
        o.flags |= NERF_CAMERA_PATH_FILE_INTRINSICS;
    }
    o.hooks = hooks;
    return nerf_camera_path_load(out, a->poses, &o);
}

/*
 * The frame size asked for, from a base size (the scene's images, or
 * --path orbit's default): --width and --height as given, one side alone
 * keeping the base's aspect ratio, neither the base itself.
 */
static void frame_size(const args *a, double w, double h, double *nw,
                       double *nh)
{
    *nw = (a->size_given & 1) ? (double)a->width
          : (a->size_given & 2) ? floor(a->height * w / h + 0.5)
                                : w;
    *nh = (a->size_given & 2) ? (double)a->height
          : (a->size_given & 1) ? floor(a->width * h / w + 0.5)
                                : h;
    *nw = *nw < 1.0 ? 1.0 : *nw > NERF_IMAGE_MAX_SIDE ? NERF_IMAGE_MAX_SIDE
                                                      : *nw;
    *nh = *nh < 1.0 ? 1.0 : *nh > NERF_IMAGE_MAX_SIDE ? NERF_IMAGE_MAX_SIDE
                                                      : *nh;
}

/*
 * A camera of the scene at the size asked for: the intrinsics scale with
 * the image, so that the view is the same, only sharper or coarser.
 */
static void resize_camera(const args *a, nerf_camera *cam)
{
    double w = (double)cam->width, h = (double)cam->height, nw, nh;
    frame_size(a, w, h, &nw, &nh);
    cam->fx = (float)(cam->fx * nw / w);
    cam->cx = (float)(cam->cx * nw / w);
    cam->fy = (float)(cam->fy * nh / h);
    cam->cy = (float)(cam->cy * nh / h);
    cam->width = (uint32_t)nw;
    cam->height = (uint32_t)nh;
}

static int orbit_view(const args *a, const nerf_dataset *ds, uint32_t i,
                      uint32_t n, nerf_camera *cam)
{
    uint32_t bw = ORBIT_SIDE, bh = ORBIT_SIDE;
    if (ds != NULL) {
        nerf_dataset_image_size(ds, &bw, &bh);
    }
    double w, h;
    frame_size(a, bw, bh, &w, &h);
    return orbit_camera(i, n, (uint32_t)w, (uint32_t)h, cam);
}

/* Camera `i` of the requested views. */
static int view_camera(const args *a, const nerf_dataset *ds,
                       const nerf_camera_path *cp, uint32_t i, uint32_t n,
                       nerf_camera *cam)
{
    NERF_CAMERA_INIT(cam);
    if (cp != NULL) {
        return nerf_camera_path_camera(cp, i, cam);
    }
    if (a->path != PATH_ORBIT) {
        int rc = a->path == PATH_NONE ? nerf_dataset_camera(ds, i, cam)
                                 : nerf_dataset_spiral_camera(ds, i, n, cam);
        if (rc == NERF_OK && a->size_given) {
            resize_camera(a, cam);
        }
        return rc;
    }
    return orbit_view(a, ds, i, n, cam);
}

/* Depth as a grey image: near white, far black, scaled to [near, far]. */
static void depth_to_grey(float *depth, const float *opacity, size_t n,
                          float near, float far)
{
    for (size_t k = 0; k < n; k++) {
        float d = opacity[k] > 1e-3f ? depth[k] / opacity[k] : far;
        depth[k] = 1.0f - (d - near) / (far - near);
    }
}

/* The processes of the render: this one alone, or MPI's ranks, each of
 * which renders every size-th view from its rank on. */
static dist D;

static int mine(uint32_t i)
{
    return (int)(i % (uint32_t)D.size) == D.rank;
}

/* A failure already described on stderr (not a libnerf status). */
#define REPORTED 1
/* Stopped by a signal, and said so. */
#define INTERRUPTED 2
/* An output refused before anything was rendered (it exists, or is an
 * input), and said so. */
#define REFUSED 3

/*
 * The scene of --data.  A path needs the scene's cameras and bounds, not
 * its photos: without --downscale it takes the photos of the first of
 * images/, images_2/, images_4/ ... the scene has (fern ships images_8/
 * alone), and says which; with --downscale, or without --path, exactly
 * what was asked.
 */
static int load_scene(args *a, const nerf_model *m, const nerf_hooks *hooks,
                      nerf_dataset **out)
{
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    dopt.split = (uint32_t)a->split;
    dopt.downscale = (uint32_t)a->downscale;
    dopt.forward_facing = setup_forward_facing(m, -1);
    dopt.hooks = hooks;
    int rc = nerf_dataset_load(out, a->data, &dopt);
    if (rc != NERF_ENOENT || a->path == PATH_NONE || a->downscale_given) {
        return rc;
    }
    char first[1024];
    snprintf(first, sizeof first, "%s", nerf_last_error());
    for (uint32_t k = 2; k <= 16; k *= 2) {
        dopt.downscale = k;
        if (nerf_dataset_load(out, a->data, &dopt) == NERF_OK) {
            fprintf(stderr, "%s: %s has no photos at full size; the path "
                    "takes its cameras from its photos reduced %u times "
                    "(as --downscale %u)\n", PROG, a->data, k, k);
            a->downscale = k;
            return NERF_OK;
        }
    }
    fprintf(stderr, "%s: %s: %s\n", PROG, nerf_status_string(NERF_ENOENT),
            first);
    return REPORTED;
}

/* The renderer's reports, within an image, onto the bar of all views. */
typedef struct render_progress {
    progress bar;
    uint64_t before; /* pixels of the views already rendered */
} render_progress;

static int on_render_progress(const nerf_progress *p, void *user)
{
    render_progress *rp = user;
    if (D.rank == 0) {
        progress_update(&rp->bar, rp->before + p->done, "pixels");
    }
    return interrupted ? 1 : 0;
}

/*
 * The output buffers, sized for the largest view and allocated before
 * anything is rendered, so that an image that cannot be held is refused
 * at once, with its size, rather than after the views before it.
 */
typedef struct outputs {
    float *rgb, *depth, *opacity;
    size_t capacity; /* pixels */
} outputs;

static int alloc_outputs(outputs *o, size_t pixels, uint32_t w, uint32_t h,
                         int depth)
{
    memset(o, 0, sizeof *o);
    size_t floats = depth ? 5 : 3; /* rgb, and depth and opacity */
    if (pixels > SIZE_MAX / floats / sizeof(float)) {
        fprintf(stderr, PROG ": a %ux%u image is more than this "
                        "machine can address\n", (unsigned)w, (unsigned)h);
        return -1;
    }
    o->capacity = pixels;
    o->rgb = malloc(pixels * 3 * sizeof(float));
    if (depth) {
        o->depth = malloc(pixels * sizeof(float));
        o->opacity = malloc(pixels * sizeof(float));
    }
    if (o->rgb == NULL || (depth && (o->depth == NULL || o->opacity == NULL))) {
        size_t bytes = pixels * floats * sizeof(float);
        fprintf(stderr, PROG ": cannot allocate %zu bytes (%.1f GiB) "
                        "for the output of a %ux%u image\n", bytes,
                (double)bytes / (1u << 30), (unsigned)w, (unsigned)h);
        return -1;
    }
    return 0;
}

static void free_outputs(outputs *o)
{
    free(o->rgb);
    free(o->depth);
    free(o->opacity);
}

/* The files of a view in the output folder: the image, and with --depth
 * the opacity and the depth. */
static const char *const view_kinds[3] = {"r", "opacity", "depth"};

static int view_files(const args *a)
{
    return a->depth ? 3 : 1;
}

static void view_path(char *path, size_t size, const args *a, int kind,
                      uint32_t i)
{
    snprintf(path, size, "%s/%s_%03u.png", a->out, view_kinds[kind], i);
}

static int write_view(const args *a, const nerf_camera *cam, uint32_t i,
                      const outputs *o, float near, float far)
{
    char path[4200];
    view_path(path, sizeof path, a, 0, i);
    int rc = nerf_image_write_png(path, cam->width, cam->height, 3, o->rgb);
    if (rc == NERF_OK && a->depth) {
        view_path(path, sizeof path, a, 1, i);
        rc = nerf_image_write_png(path, cam->width, cam->height, 1,
                                  o->opacity);
        depth_to_grey(o->depth, o->opacity,
                      (size_t)cam->width * cam->height, near, far);
        view_path(path, sizeof path, a, 2, i);
        if (rc == NERF_OK) {
            rc = nerf_image_write_png(path, cam->width, cam->height, 1,
                                      o->depth);
        }
    }
    return rc;
}

/*
 * A video holds frames of one size, even in both directions; checked on
 * every view before anything is rendered.  lw x lh is the size of the
 * views before view i (0 x 0 for the first).
 */
static int video_mismatch(const args *a, const nerf_camera *cam, uint32_t i,
                          uint32_t lw, uint32_t lh)
{
    if (a->video == NULL) {
        return 0;
    }
    if (i > 0 && (cam->width != lw || cam->height != lh)) {
        fprintf(stderr, PROG ": --video needs views of one size, but "
                        "view %u is %ux%u and the ones before %ux%u\n",
                (unsigned)i, (unsigned)cam->width, (unsigned)cam->height,
                (unsigned)lw, (unsigned)lh);
        return 1;
    }
    if (cam->width % 2 != 0 || cam->height % 2 != 0) {
        fprintf(stderr, PROG ": --video needs an even width and "
                        "height (the codecs keep colour at half "
                        "resolution), but the views are %ux%u\n",
                (unsigned)cam->width, (unsigned)cam->height);
        return 1;
    }
    return 0;
}

/* Whether view i's files are all in the output folder: write_view()
 * writes each through a temporary file, so one that is there is whole. */
static int view_written(const args *a, uint32_t i)
{
    for (int k = 0; k < view_files(a); k++) {
        char path[4200];
        view_path(path, sizeof path, a, k, i);
        if (access(path, F_OK) != 0) {
            return 0;
        }
    }
    return 1;
}

/* The inputs of the run, which no output may be. */
static int check_target(const args *a, const char *path, const char *how)
{
    const out_input inputs[3] = {
        {"--model", a->model}, {"--data", a->data}, {"--poses", a->poses}};
    return out_file_check(PROG, path, a->overwrite, how, inputs, 3);
}

/* View i's files, which this run is about to write: new, or replaced as
 * told. */
static int check_view_targets(const args *a, uint32_t i)
{
    for (int k = 0; k < view_files(a); k++) {
        char path[4200];
        view_path(path, sizeof path, a, k, i);
        const char *how = a->skip_existing
                              ? "the view lacks some of its files, so it is "
                                "rendered again: --overwrite replaces them"
                              : "--overwrite replaces the views there, "
                                "--skip-existing renders only the missing "
                                "ones";
        if (check_target(a, path, how) != 0) {
            return -1;
        }
    }
    return 0;
}

/* What a run has written, for the line that ends an interrupted one. */
typedef struct written {
    uint32_t before;      /* views skipped: already in the folder */
    uint32_t now;         /* views written by this run */
    uint32_t first, last; /* this run's first and last view written */
} written;

static void say_interrupted(const args *a, const written *w, uint32_t n,
                            int tty)
{
    if (tty) {
        fputc('\n', stderr); /* end the bar's line */
    }
    uint32_t have = w->before + w->now;
    char now[96];
    if (w->now == 0) {
        snprintf(now, sizeof now, "none");
    } else if (w->now == 1) {
        snprintf(now, sizeof now, "1, r_%03u.png", w->first);
    } else {
        snprintf(now, sizeof now, "%u, r_%03u.png to r_%03u.png", w->now,
                 w->first, w->last);
    }
    fprintf(stderr, PROG ": interrupted: %s holds %u of the %u views "
            "(this run wrote %s); the same command with --skip-existing "
            "renders the other %u\n", a->out, have, n, now, n - have);
}

static int render_all(const args *a, nerf_renderer *r, const nerf_dataset *ds,
                      const nerf_camera_path *cp, float near, float far)
{
    uint32_t n = cp        ? nerf_camera_path_count(cp)
                 : a->path ? (uint32_t)a->frames
                           : nerf_dataset_count(ds);
    written w;
    memset(&w, 0, sizeof w);
    /* Every view's size first: the bar counts pixels, and the buffers
     * hold the largest view. */
    uint64_t total = 0;
    size_t largest = 0;
    uint32_t lw = 0, lh = 0;
    for (uint32_t i = 0; i < n; i++) {
        nerf_camera cam;
        int rc = view_camera(a, ds, cp, i, n, &cam);
        if (rc != NERF_OK) {
            return rc;
        }
        if (video_mismatch(a, &cam, i, lw, lh)) {
            return REPORTED;
        }
        size_t pixels = (size_t)cam.width * cam.height;
        if (a->skip_existing && view_written(a, i)) {
            w.before++;
            continue;
        }
        if (check_view_targets(a, i) != 0) {
            return REFUSED;
        }
        if (!mine(i)) {
            continue;
        }
        total += pixels;
        if (pixels > largest) {
            largest = pixels;
            lw = cam.width;
            lh = cam.height;
        }
    }
    if (w.before == n) {
        if (D.rank != 0) {
            return NERF_OK;
        }
        fprintf(stderr, PROG ": all %u views are in %s already: "
                "nothing to render\n", n, a->out);
        return NERF_OK;
    }
    if (w.before > 0 && D.rank == 0) {
        fprintf(stderr, PROG ": %u of the %u views are in %s already; "
                "rendering the other %u\n", w.before, n, a->out,
                n - w.before);
    }
    outputs o;
    if (alloc_outputs(&o, largest, lw, lh, a->depth) != 0) {
        free_outputs(&o);
        return REPORTED;
    }
    /* Opened before the first view, so that a file that cannot be made
     * costs no rendering. */
    video *vid = NULL;
    if (a->video != NULL) {
        vid = video_open(PROG, a->video, lw, lh, (unsigned)a->fps);
        if (vid == NULL) {
            free_outputs(&o);
            return REPORTED;
        }
    }
    render_progress rp;
    rp.before = 0;
    progress_begin(&rp.bar, PROG, total);
    nerf_renderer_set_progress(r, on_render_progress, &rp);
    int rc = NERF_OK;
    for (uint32_t i = 0; i < n && rc == NERF_OK; i++) {
        if (!mine(i) || (a->skip_existing && view_written(a, i))) {
            continue;
        }
        nerf_camera cam;
        rc = view_camera(a, ds, cp, i, n, &cam);
        if (rc == NERF_OK) {
            rc = nerf_renderer_render_image(r, &cam, o.rgb, o.depth,
                                            o.opacity, o.capacity);
        }
        if (rc == NERF_OK) {
            rc = write_view(a, &cam, i, &o, near, far);
        }
        if (rc == NERF_OK && vid != NULL && video_write(vid, o.rgb) != 0) {
            rc = REPORTED;
        }
        if (rc == NERF_OK) {
            w.first = w.now == 0 ? i : w.first;
            w.last = i;
            w.now++;
        }
        rp.before += (uint64_t)cam.width * cam.height;
    }
    free_outputs(&o);
    char codec[64] = "";
    if (vid != NULL) {
        snprintf(codec, sizeof codec, "%s", video_codec(vid));
        if (rc != NERF_OK) {
            video_discard(vid);
        } else if (video_finish(vid) != 0) {
            rc = REPORTED;
        }
    }
    if (rc == NERF_OK || rc == NERF_ECANCELLED) {
        /* Rank 0 reports once every process has written its views; a
         * process that failed ends the job instead (main). */
        dist_barrier(&D);
    }
    if (rc == NERF_ECANCELLED && interrupted) {
        if (D.size == 1) {
            say_interrupted(a, &w, n, rp.bar.tty);
        } else if (D.rank == 0) {
            fprintf(stderr, PROG ": interrupted: the same command with "
                    "--skip-existing renders the views missing from %s\n",
                    a->out);
        }
        return INTERRUPTED;
    }
    if (rc == NERF_OK && D.rank == 0) {
        char note[4200];
        snprintf(note, sizeof note, "%u view%s in %s", (unsigned)n,
                 n == 1 ? "" : "s", a->out);
        progress_end(&rp.bar, note);
        if (a->video != NULL) {
            fprintf(stderr, PROG ": wrote %s: %u frames of %ux%u at "
                            "%u fps, %s\n", a->video, (unsigned)n,
                    (unsigned)lw, (unsigned)lh, (unsigned)a->fps, codec);
        }
    }
    return rc;
}

static int run(int argc, char **argv)
{
    cli_blas_single_thread();
    args a;
    if (parse(argc, argv, &a) != 0) {
        return 2;
    }
    if (a.video != NULL &&
        check_target(&a, a.video, OUT_OVERWRITE_HOW) != 0) {
        return 2;
    }
    if (a.video != NULL && D.size > 1) {
        cli_usage_error(PROG, "--video needs the views in order in one "
                        "process: render the frames with several, then "
                        "encode them with one (nerf-render --skip-existing "
                        "--video)");
        return 2;
    }
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = PROG;
    if (a.video != NULL && !video_supported()) {
        fprintf(stderr, PROG ": this build has no video output "
                        "(FFmpeg's libraries were not found at build time); "
                        "the frames are written as PNG in %s\n", a.out);
        a.video = NULL;
    }
    nerf_model *m = NULL;
    nerf_dataset *ds = NULL;
    nerf_sampler *s = NULL;
    nerf_renderer *r = NULL;
    nerf_camera_path *cp = NULL;
    int rc = nerf_model_load(&m, a.model, &hooks);
    if (rc == NERF_OK && a.poses) {
        rc = load_poses(&a, &hooks, &cp);
    }
    if (rc == NERF_OK && a.data) {
        rc = load_scene(&a, m, &hooks, &ds);
    }
    if (rc == NERF_OK) {
        sampler_choice c = SAMPLER_AS_RECORDED;
        c.near = (float)a.near;
        c.far = (float)a.far;
        c.march_steps = a.march;
        rc = setup_sampler(&s, m, ds, &c);
    }
    float near = 2.0f, far = 6.0f;
    if (rc == NERF_OK && ds) {
        nerf_dataset_bounds(ds, &near, &far);
    } else if (rc == NERF_OK) {
        /* An NDC model's depths are NDC depths, in the range its sampler
         * samples; the others keep the Blender range. */
        nerf_sampler_options so;
        NERF_SAMPLER_OPTIONS_INIT(&so);
        if (nerf_model_render_settings(m, &so, NULL) == NERF_OK && so.ndc) {
            near = so.t_near;
            far = so.t_far;
        }
    }
    if (a.far > a.near) {
        near = (float)a.near;
        far = (float)a.far;
    }
    if (rc == NERF_OK) {
        nerf_renderer_options ro;
        NERF_RENDERER_OPTIONS_INIT(&ro);
        ro.white_background = (uint32_t)setup_background(m, ds);
        ro.appearance = a.appearance;
        ro.hooks = &hooks;
        rc = nerf_renderer_create(&r, m, s, &ro);
    }
    if (rc == NERF_OK && D.rank == 0) {
        rc = out_ready_folder(a.out, PROG) == 0 ? NERF_OK : REPORTED;
    }
    /* The others write into the folder rank 0 has made (or, if it could
     * not, are ended by it). */
    dist_barrier(&D);
    if (rc == NERF_OK) {
        interrupt_catch(D.size == 1);
        rc = render_all(&a, r, ds, cp, near, far);
    }
    if (rc != NERF_OK && rc != REPORTED && rc != INTERRUPTED &&
        rc != REFUSED) {
        cli_report(PROG, rc);
    }
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_dataset_destroy(ds);
    nerf_camera_path_destroy(cp);
    nerf_model_destroy(m);
    /* As a shell reports a program killed by the signal: 130 for
     * SIGINT. */
    return rc == INTERRUPTED ? 128 + interrupted
           : rc == REFUSED   ? 2
           : rc == NERF_OK   ? 0
                             : 1;
}


int main(int argc, char **argv)
{
    if (dist_init(&D, &argc, &argv, PROG) != 0) {
        return 1;
    }
    int status = run(argc, argv);
    if (status != 0 && status < 128) {
        dist_fail(&D, status); /* the others may wait at a barrier */
    }
    dist_finish(&D);
    return status;
}
