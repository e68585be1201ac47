/* nerf-scene: write the built-in procedural scene as a Blender dataset. */
#include <nerf.h>

#include <stdio.h>
#include <string.h>

#include "common/cli.h"

static const char usage[] =
    "usage: nerf-scene --out DIR [--width W] [--height H] [--train N]\n"
    "                  [--val N] [--test N] [--threads N]\n"
    "                  [--format png|jpeg] [--jpeg [QUALITY]]\n"
    "Write libnerf's built-in scene (a few coloured solids) to DIR as a\n"
    "Blender-format dataset: transforms_{train,val,test}.json and PNGs\n"
    "(RGBA), or with --format jpeg / --jpeg JPEGs (RGB on white, quality\n"
    "QUALITY 1..100, default 95).\n"
    "Defaults: 100x100 images, 100 train, 8 val and 16 test views.\n";

/* --jpeg takes an optional quality: the next argument if it is a number. */
static int jpeg_flag(int argc, char **argv, int *i, nerf_scene_options *o)
{
    o->image_format = NERF_IMAGE_FORMAT_JPEG;
    uint64_t q = 0;
    if (*i + 1 < argc && argv[*i + 1][0] >= '0' && argv[*i + 1][0] <= '9') {
        if (cli_uint(argv[*i + 1], 1, 100, &q) != 0) {
            fprintf(stderr, "nerf-scene: --jpeg quality must be 1..100\n");
            return -1;
        }
        o->jpeg_quality = (uint32_t)q;
        (*i)++;
    }
    return 0;
}

int main(int argc, char **argv)
{
    nerf_scene_options o;
    NERF_SCENE_OPTIONS_INIT(&o);
    const char *out = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        uint64_t v = 0;
        uint32_t *field = NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(usage, stdout);
            return 0;
        } else if (strcmp(a, "--out") == 0) {
            out = cli_value(argc, argv, &i);
            if (out == NULL) {
                goto bad;
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
                fprintf(stderr, "nerf-scene: --format is png or jpeg\n");
                goto bad;
            }
            continue;
        } else if (strcmp(a, "--width") == 0) {
            field = &o.width;
        } else if (strcmp(a, "--height") == 0) {
            field = &o.height;
        } else if (strcmp(a, "--train") == 0) {
            field = &o.n_train;
        } else if (strcmp(a, "--val") == 0) {
            field = &o.n_val;
        } else if (strcmp(a, "--test") == 0) {
            field = &o.n_test;
        } else if (strcmp(a, "--threads") == 0) {
            field = &o.threads;
        } else {
            fprintf(stderr, "nerf-scene: unknown argument '%s'\n", a);
            goto bad;
        }
        if (cli_uint(cli_value(argc, argv, &i), 0, 100000, &v) != 0) {
            fprintf(stderr, "nerf-scene: %s needs a whole number\n", a);
            goto bad;
        }
        *field = (uint32_t)v;
    }
    if (out == NULL) {
        fprintf(stderr, "nerf-scene: --out is required\n");
        goto bad;
    }
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = "nerf-scene";
    o.hooks = &hooks;
    int rc = nerf_scene_write(out, &o);
    if (rc != NERF_OK) {
        cli_report("nerf-scene", rc);
        return 1;
    }
    return 0;
bad:
    fputs(usage, stderr);
    return 2;
}
