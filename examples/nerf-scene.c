/* nerf-scene: write the built-in procedural scene as a Blender dataset. */
#include <nerf.h>

#include <stdio.h>
#include <string.h>

#include "common/cli.h"

static const char usage[] =
    "usage: nerf-scene --out DIR [--width W] [--height H] [--train N]\n"
    "                  [--val N] [--test N] [--threads N]\n"
    "                  [--layout blender|colmap-text|colmap-binary]\n"
    "Write libnerf's built-in scene (a few coloured solids) to DIR as a\n"
    "Blender-format dataset: transforms_{train,val,test}.json and PNGs;\n"
    "or, with --layout colmap-*, as a COLMAP model: images/ and sparse/0/\n"
    "cameras, images and points3D in COLMAP's text or binary files.\n"
    "Defaults: 100x100 images, 100 train, 8 val and 16 test views.\n";

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
        } else if (strcmp(a, "--layout") == 0) {
            const char *name = cli_value(argc, argv, &i);
            if (name == NULL) {
                goto bad;
            } else if (strcmp(name, "blender") == 0) {
                o.layout = NERF_SCENE_LAYOUT_BLENDER;
            } else if (strcmp(name, "colmap-text") == 0) {
                o.layout = NERF_SCENE_LAYOUT_COLMAP_TEXT;
            } else if (strcmp(name, "colmap-binary") == 0) {
                o.layout = NERF_SCENE_LAYOUT_COLMAP_BINARY;
            } else {
                fprintf(stderr, "nerf-scene: unknown layout '%s'\n", name);
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
