/* nerf-scene: write the built-in procedural scene as a dataset. */
#include <nerf.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "common/cli.h"
#include "common/out_folder.h"
#include "common/out_file.h"
#include "common/options.h"

/* The library's limits, quoted by the help. */
#define SIDES CLI_STR(NERF_SCENE_MIN_SIDE) ".." CLI_STR(NERF_SCENE_MAX_SIDE)
#define MAX_VIEWS CLI_STR(NERF_SCENE_MAX_VIEWS)

static const char usage[] =
    "usage: nerf-scene --out DIR [--width W] [--height H] [--train N]\n"
    "                  [--val N] [--test N] [--threads N]\n"
    "                  [--capture object|forward|unbounded]\n"
    "                  [--layout blender|transforms|llff|colmap-text|\n"
    "                            colmap-binary]\n"
    "                  [--format png|jpeg] [--jpeg [QUALITY]]\n"
    "                  [--distortion K1,K2,P1,P2,K3] [--overwrite]\n"
    "Write libnerf's built-in scene (a few coloured solids) to DIR, rendered\n"
    "exactly, as a dataset the other programs read: a scene to try them on\n"
    "without downloading one.\n"
    "  --out DIR            the folder to write (required)\n"
    "  --width W            image width in pixels, " SIDES " (default 100)\n"
    "  --height H           image height in pixels, " SIDES " (default 100)\n"
    "  --train N            training views, 1.." MAX_VIEWS " (default 100)\n"
    "  --val N              validation views, 0.." MAX_VIEWS " (default 8;\n"
    "                       none in --layout llff, which takes only 0)\n"
    "  --test N             test views, on a circle at 30 degrees,\n"
    "                       0.." MAX_VIEWS " (default 16)\n"
    "  --threads N          worker threads (default 0: all cores)\n"
    "  --capture object     the solids alone on a transparent background,\n"
    "                       from a hemisphere of views (the default)\n"
    "  --capture forward    forward-facing photos, as LLFF's: the solids on\n"
    "                       a ground before a far backdrop, from a small\n"
    "                       grid of cameras on one side\n"
    "  --capture unbounded  all-round photos of the solids on a ground\n"
    "                       within a far backdrop (40 units away)\n"
    "  --layout blender     transforms_{train,val,test}.json and PNGs (the\n"
    "                       default for object and unbounded)\n"
    "  --layout transforms  one instant-ngp transforms.json with every view\n"
    "                       (fl_x, fl_y, cx, cy, w, h, the lens, aabb_scale)\n"
    "  --layout llff        poses_bounds.npy and images/ (the default for\n"
    "                       forward, and only for it): --train + --test\n"
    "                       views, every 8th held out by the loader\n"
    "  --layout colmap-text, colmap-binary  a COLMAP model: images/ and\n"
    "                       sparse/0/ cameras, images and points3D in\n"
    "                       COLMAP's text or binary files, all views\n"
    "  --format png|jpeg    the views' files: PNG (default; RGBA for object)\n"
    "                       or JPEG (RGB, on white for object)\n"
    "  --jpeg [QUALITY]     JPEG files of quality 1..100 (default 95)\n"
    "  --distortion K1,...  photograph through that lens (OpenCV's model, as\n"
    "                       nerf_camera's k1, k2, p1, p2, k3; trailing ones\n"
    "                       may be left out; default none: a pinhole camera)\n"
    "  --overwrite          write into DIR even if it holds files, replacing\n"
    "                       those of the scene's names (default off: a DIR\n"
    "                       that holds anything is refused)\n"
    "  --help               print this help and exit\n"
    "Examples:\n"
    "  nerf-scene --out scene\n"
    "  nerf-scene --out fern-like --capture forward --width 160 --height 120\n"
    "  nerf-scene --out tiny --width 32 --height 32 --train 20 --val 0 \\\n"
    "      --test 4\n";

/* The options main() knows, to suggest for a mistyped one. */
static const char *const options[] = {
    "--help", "-h", "--out", "--capture", "--layout", "--jpeg", "--format",
    "--distortion", "--width", "--height", "--train", "--val", "--test",
    "--threads", "--overwrite", NULL
};

/*
 * The numeric options: each a field of nerf_scene_options, in the range
 * nerf_scene_write() takes (the help quotes the same constants).
 */
typedef struct count {
    const char *option;
    size_t offset;
    uint32_t min, max;
} count;

/* The most worker threads asked for; nerf_scene_write() runs at most its
 * own number. */
#define THREADS_MAX 100000

static const count counts[] = {
    {"--width", offsetof(nerf_scene_options, width), NERF_SCENE_MIN_SIDE,
     NERF_SCENE_MAX_SIDE},
    {"--height", offsetof(nerf_scene_options, height), NERF_SCENE_MIN_SIDE,
     NERF_SCENE_MAX_SIDE},
    {"--train", offsetof(nerf_scene_options, n_train), 1,
     NERF_SCENE_MAX_VIEWS},
    {"--val", offsetof(nerf_scene_options, n_val), 0, NERF_SCENE_MAX_VIEWS},
    {"--test", offsetof(nerf_scene_options, n_test), 0, NERF_SCENE_MAX_VIEWS},
    {"--threads", offsetof(nerf_scene_options, threads), 0, THREADS_MAX},
};

static const count *find_count(const char *option)
{
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        if (strcmp(option, counts[k].option) == 0) {
            return &counts[k];
        }
    }
    return NULL;
}

/* A name of the list, by its index; -1 when it is not there. */
static int pick(const char *name, const char *const *names, int n)
{
    for (int k = 0; name && k < n; k++) {
        if (strcmp(name, names[k]) == 0) {
            return k;
        }
    }
    return -1;
}

/* --jpeg takes an optional quality: the next argument if it is a number. */
static int jpeg_flag(int argc, char **argv, int *i, nerf_scene_options *o)
{
    o->image_format = NERF_IMAGE_FORMAT_JPEG;
    uint64_t q = 0;
    if (*i + 1 < argc && argv[*i + 1][0] >= '0' && argv[*i + 1][0] <= '9') {
        if (cli_uint(argv[*i + 1], 1, 100, &q) != 0) {
            cli_usage_error("nerf-scene", "--jpeg quality must be "
                                "1..100, not '%s'", argv[*i + 1]);
            return -1;
        }
        o->jpeg_quality = (uint32_t)q;
        (*i)++;
    }
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

int main(int argc, char **argv)
{
    nerf_scene_options o;
    NERF_SCENE_OPTIONS_INIT(&o);
    const char *out = NULL;
    static const char *const captures[] = {"object", "forward", "unbounded"};
    static const char *const layouts[] = {"blender", "transforms", "llff",
                                          "colmap-text", "colmap-binary"};
    int layout = -1;
    bool val_given = false, overwrite = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        } else if (strcmp(a, "--overwrite") == 0) {
            overwrite = true;
            continue;
        } else if (strcmp(a, "--out") == 0) {
            out = cli_value(argc, argv, &i);
            if (out == NULL) {
                cli_bad_value("nerf-scene", a, NULL, "a folder");
                goto bad;
            }
            continue;
        } else if (strcmp(a, "--capture") == 0 ||
                   strcmp(a, "--layout") == 0) {
            const char *name = cli_value(argc, argv, &i);
            bool is_capture = strcmp(a, "--capture") == 0;
            int k = is_capture ? pick(name, captures, 3)
                               : pick(name, layouts, 5);
            if (k < 0) {
                cli_usage_error("nerf-scene", "%s needs one of %s%s%s%s", a,
                        is_capture ? "object, forward, unbounded"
                                   : "blender, transforms, llff, "
                                     "colmap-text, colmap-binary",
                        name ? ", not '" : "", name ? name : "",
                        name ? "'" : "");
                goto bad;
            }
            if (is_capture) {
                o.capture = (uint32_t)k;
            } else {
                layout = k;
            }
            continue;
        } else if (strcmp(a, "--jpeg") == 0) {
            if (jpeg_flag(argc, argv, &i, &o) != 0) {
                goto bad;
            }
            continue;
        } else if (strcmp(a, "--format") == 0) {
            const char *f = cli_value(argc, argv, &i);
            if (f != NULL && strcmp(f, "png") == 0) {
                o.image_format = NERF_IMAGE_FORMAT_PNG;
            } else if (f != NULL && (strcmp(f, "jpeg") == 0 ||
                                     strcmp(f, "jpg") == 0)) {
                o.image_format = NERF_IMAGE_FORMAT_JPEG;
            } else {
                cli_bad_value("nerf-scene", a, f, "png or jpeg");
                goto bad;
            }
            continue;
        } else if (strcmp(a, "--distortion") == 0) {
            if (parse_lens(cli_value(argc, argv, &i), &o) != 0) {
                cli_usage_error("nerf-scene", "--distortion needs 1 to 5 "
                                "numbers separated by commas: k1,k2,p1,p2,k3");
                goto bad;
            }
            continue;
        }
        const count *c = find_count(a);
        if (c == NULL) {
            cli_unknown("nerf-scene", a, options);
            goto bad;
        }
        const char *text = cli_value(argc, argv, &i);
        uint64_t v = 0;
        if (cli_int_option("nerf-scene", a, text, c->min, c->max, &v) != 0) {
            goto bad;
        }
        *(uint32_t *)((char *)&o + c->offset) = (uint32_t)v;
        if (strcmp(a, "--val") == 0) {
            val_given = v > 0;
        }
    }
    if (out == NULL) {
        cli_usage_error("nerf-scene", "--out is required");
        goto bad;
    }
    /* Each capture in its usual layout unless told otherwise. */
    o.layout = layout >= 0 ? (uint32_t)layout
               : o.capture == NERF_SCENE_CAPTURE_FORWARD
                   ? NERF_SCENE_LAYOUT_LLFF
                   : NERF_SCENE_LAYOUT_BLENDER;
    /* --val 0 asks for what the layout gives: none. */
    if (val_given && o.layout == NERF_SCENE_LAYOUT_LLFF) {
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
    o.hooks = &hooks;
    if (out_folder_check("nerf-scene", out, overwrite, "--overwrite writes "
                         "the scene into it, replacing files of the same "
                         "names") != 0) {
        return 2;
    }
    /* Before the views are rendered, which a file in the way would
     * waste. */
    if (out_ready_folder(out, "nerf-scene") != 0) {
        return 1;
    }
    int rc = nerf_scene_write(out, &o);
    if (rc != NERF_OK) {
        cli_report("nerf-scene", rc);
        return 1;
    }
    return 0;
bad:
    return 2;
}
