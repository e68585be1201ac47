/* nerf-scene: write the built-in procedural scene as a dataset. */
#include <nerf.h>

#include <stdio.h>
#include <string.h>

#include "common/cli.h"
#include "common/out_folder.h"
#include "common/out_file.h"
#include "common/options.h"
#include "common/opt_table.h"
#include "common/shared_opts.h"

static const char about[] =
    "Write libnerf's built-in scene (a few coloured solids) to DIR, rendered\n"
    "exactly, as a dataset the other programs read: a scene to try them on\n"
    "without downloading one.\n";

static const char after[] =
    "Examples:\n"
    "  nerf-scene --out scene\n"
    "  nerf-scene --out fern-like --capture forward --width 160 --height 120\n"
    "  nerf-scene --out tiny --width 32 --height 32 --train 20 --val 0 \\\n"
    "      --test 4\n"
    "  nerf-scene --out walk --capture walk --texture --width 320 \\\n"
    "      --height 240 --train 60   (frames of a video for COLMAP)\n";

/* The most worker threads asked for; nerf_scene_write() runs at most its
 * own number. */
#define THREADS_MAX 100000

static const opt_choice captures[] = {
    {.name = "object", .id = NERF_SCENE_CAPTURE_OBJECT,
     .help = "the solids alone on a transparent background,\n"
             "from a hemisphere of views (the default)"},
    {.name = "forward", .id = NERF_SCENE_CAPTURE_FORWARD,
     .help = "forward-facing photos, as LLFF's: the solids on\n"
             "a ground before a far backdrop, from a small\n"
             "grid of cameras on one side"},
    {.name = "unbounded", .id = NERF_SCENE_CAPTURE_UNBOUNDED,
     .help = "all-round photos of the solids on a ground\n"
             "within a far backdrop (40 units away)"},
    {.name = "walk", .id = NERF_SCENE_CAPTURE_WALK,
     .help = "the same world seen as a video is shot: the\n"
             "train views, in order, walk once round the\n"
             "solids, each overlapping the next"},
    {.name = NULL},
};

static const opt_choice layouts[] = {
    {.name = "blender", .id = NERF_SCENE_LAYOUT_BLENDER,
     .help = "transforms_{train,val,test}.json and PNGs (the\n"
             "default for object and unbounded)"},
    {.name = "transforms", .id = NERF_SCENE_LAYOUT_TRANSFORMS,
     .help = "one instant-ngp transforms.json with every view\n"
             "(fl_x, fl_y, cx, cy, w, h, the lens, aabb_scale)"},
    {.name = "llff", .id = NERF_SCENE_LAYOUT_LLFF,
     .help = "poses_bounds.npy and images/ (the default for\n"
             "forward, and only for it): --train + --test\n"
             "views, every 8th held out by the loader"},
    {.name = "colmap-text", .id = NERF_SCENE_LAYOUT_COLMAP_TEXT,
     .help = "a COLMAP model: images/ and\n"
             "sparse/0/ cameras, images and points3D in\n"
             "COLMAP's text or binary files, all views"},
    {.name = "colmap-binary", .id = NERF_SCENE_LAYOUT_COLMAP_BINARY},
    {.name = NULL},
};

static const opt_choice formats[] = {
    {.name = "png", .id = NERF_IMAGE_FORMAT_PNG},
    {.name = "jpeg", .id = NERF_IMAGE_FORMAT_JPEG},
    {.name = "jpg", .id = NERF_IMAGE_FORMAT_JPEG, .alias = true},
    {.name = NULL},
};

/* --jpeg [QUALITY]: JPEG files, of that quality if given. */
static int read_jpeg(const char *program, const opt *o, const char *v)
{
    nerf_scene_options *so = o->to;
    uint64_t q = 0;
    so->image_format = NERF_IMAGE_FORMAT_JPEG;
    if (v == NULL) {
        return 0;
    }
    if (cli_int_option(program, o->name, v, o->min, o->max, &q) != 0) {
        return -1;
    }
    so->jpeg_quality = (uint32_t)q;
    return 0;
}

/* "k1,k2,p1,p2,k3", trailing coefficients optional; 0 or -1. */
static int parse_lens(const char *text, nerf_scene_options *o)
{
    float *dst[5] = {&o->k1, &o->k2, &o->p1, &o->p2, &o->k3};
    char buf[256];
    if (text == NULL || strlen(text) >= sizeof buf) {
        return -1;
    }
    strcpy(buf, text);
    char *rest = buf;
    for (int i = 0; i < 5; i++) {
        char *comma = strchr(rest, ',');
        if (comma) {
            *comma = '\0';
        }
        double v;
        if (cli_double(rest, &v) != 0) {
            return -1;
        }
        *dst[i] = (float)v;
        if (comma == NULL) {
            return 0;
        }
        rest = comma + 1;
    }
    return -1; /* more than five */
}

static int read_lens(const char *program, const opt *o, const char *v)
{
    if (parse_lens(v, o->to) != 0) {
        cli_usage_error(program, "%s needs 1 to 5 numbers separated by "
                        "commas: k1,k2,p1,p2,k3", o->name);
        return -1;
    }
    return 0;
}

typedef struct args {
    nerf_scene_options o;
    const char *out;
    int layout; /* -1: the capture's usual one */
    int val_given, overwrite;
} args;

/* 0: read; -1: a mistake, said. */
static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    NERF_SCENE_OPTIONS_INIT(&a->o);
    a->layout = -1;
    nerf_scene_options *o = &a->o;
    /* The counts' ranges are those nerf_scene_write() takes. */
    const opt opts[] = {
        {.name = "--out", OPT_TEXT_TO(&a->out), .flags = OPT_REQUIRED,
         .value = "DIR", .help = "the folder to write (required)"},
        {.name = "--width",
         OPT_INT_IN(&o->width, NERF_SCENE_MIN_SIDE, NERF_SCENE_MAX_SIDE),
         .value = "W",
         .help = "image width in pixels, {range} (default {default})"},
        {.name = "--height",
         OPT_INT_IN(&o->height, NERF_SCENE_MIN_SIDE, NERF_SCENE_MAX_SIDE),
         .value = "H",
         .help = "image height in pixels, {range} (default {default})"},
        {.name = "--train", OPT_INT_IN(&o->n_train, 1, NERF_SCENE_MAX_VIEWS),
         .value = "N",
         .help = "training views, {range} (default {default})"},
        {.name = "--val", OPT_INT_IN(&o->n_val, 0, NERF_SCENE_MAX_VIEWS),
         .given = &a->val_given, .value = "N",
         .help = "validation views, {range} (default {default};\n"
                 "none in --layout llff, which takes only 0)"},
        {.name = "--test", OPT_INT_IN(&o->n_test, 0, NERF_SCENE_MAX_VIEWS),
         .value = "N",
         .help = "test views, on a circle at 30 degrees,\n"
                 "{range} (default {default})"},
        {.name = "--threads", OPT_INT_IN(&o->threads, 0, THREADS_MAX),
         .value = "N",
         .help = "worker threads (default {default}: all cores)"},
        {.name = "--capture", OPT_CHOICE_OF(&o->capture, captures),
         .flags = OPT_SAY_NEEDS_ONE_OF},
        {.name = "--layout", OPT_CHOICE_OF(&a->layout, layouts),
         .flags = OPT_SAY_NEEDS_ONE_OF},
        {.name = "--format", OPT_CHOICE_OF(&o->image_format, formats),
         .help = "the views' files: PNG (default; RGBA for object)\n"
                 "or JPEG (RGB, on white for object)"},
        {.name = "--jpeg", OPT_CUSTOM_READ(o, read_jpeg), .min = 1,
         .max = 100, .flags = OPT_VALUE_OPTIONAL, .value = "QUALITY",
         .help = "JPEG files of quality {range} (default 95)"},
        {.name = "--distortion", OPT_CUSTOM_READ(o, read_lens),
         .value = "K1,K2,P1,P2,K3",
         .help = "photograph through that lens (OpenCV's model, as\n"
                 "nerf_camera's k1, k2, p1, p2, k3; trailing ones\n"
                 "may be left out; default none: a pinhole camera)"},
        {.name = "--appearance-changes",
         OPT_FLAG_SETS(&o->appearance, NERF_SCENE_APPEARANCE_VARIED),
         .help = "give each training photo its own exposure and\n"
                 "white balance, as a phone's automatic ones do\n"
                 "(blender layout; test views keep the scene's look)"},
        {.name = "--occluders", OPT_FLAG_SETS(&o->occluders, 1),
         .help = "paint a moving magenta disc into every other training\n"
                 "view, as a person walking through, and write its\n"
                 "masks (mask_path; masks/ for COLMAP; not llff)"},
        {.name = "--texture", OPT_FLAG_SETS(&o->texture, 1),
         .help = "blotches of light and dark on the solids and the\n"
                 "ground, for feature matchers such as COLMAP's\n"
                 "(default off: the plain scene)"},
        {OPT_OVERWRITE(&a->overwrite),
         .help = "write into DIR even if it holds files, replacing\n"
                 "those of the scene's names (default off: a DIR\n"
                 "that holds anything is refused)"},
        {.name = NULL},
    };
    const opt_program p = {.name = "nerf-scene", .opts = opts, .column = 23,
                           .about = about, .after = after};
    return opt_parse(&p, argc, argv);
}

int main(int argc, char **argv)
{
    args a;
    if (parse(argc, argv, &a) != 0) {
        return 2;
    }
    nerf_scene_options *o = &a.o;
    /* Each capture in its usual layout unless told otherwise. */
    o->layout = a.layout >= 0 ? (uint32_t)a.layout
                : o->capture == NERF_SCENE_CAPTURE_FORWARD
                    ? NERF_SCENE_LAYOUT_LLFF
                    : NERF_SCENE_LAYOUT_BLENDER;
    /* --val 0 asks for what the layout gives: none. */
    if (a.val_given && o->n_val > 0 && o->layout == NERF_SCENE_LAYOUT_LLFF) {
        cli_usage_error("nerf-scene", "--val: an LLFF layout has no "
                        "validation views (its loader holds out every 8th "
                        "view as the test split); give --train and --test "
                        "(or --val 0)");
        return 2;
    }
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = "nerf-scene";
    o->hooks = &hooks;
    if (out_folder_check("nerf-scene", a.out, a.overwrite, "--overwrite "
                         "writes the scene into it, replacing files of the "
                         "same names") != 0) {
        return 2;
    }
    /* Before the views are rendered, which a file in the way would
     * waste. */
    if (out_ready_folder(a.out, "nerf-scene") != 0) {
        return 1;
    }
    int rc = nerf_scene_write(a.out, o);
    if (rc != NERF_OK) {
        cli_report("nerf-scene", rc);
        return 1;
    }
    return 0;
}
