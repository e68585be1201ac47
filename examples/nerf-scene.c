/* nerf-scene: write the built-in procedural scene as a dataset. */
#include <nerf.h>

#include <stdio.h>
#include <string.h>

#include "common/cli.h"

static const char usage[] =
    "usage: nerf-scene --out DIR [--width W] [--height H] [--train N]\n"
    "                  [--val N] [--test N] [--threads N]\n"
    "                  [--layout blender|transforms]\n"
    "                  [--distortion K1,K2,P1,P2,K3]\n"
    "Write libnerf's built-in scene (a few coloured solids) to DIR as a\n"
    "dataset.  Layouts: blender (default), transforms_{train,val,test}.json\n"
    "and PNGs; transforms, one instant-ngp transforms.json with every view.\n"
    "--distortion photographs the scene through that lens (OpenCV's model,\n"
    "as nerf_camera's k1, k2, p1, p2, k3; trailing ones may be left out).\n"
    "Defaults: 100x100 images, 100 train, 8 val and 16 test views.\n";

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
            if (name && strcmp(name, "blender") == 0) {
                o.layout = NERF_SCENE_LAYOUT_BLENDER;
            } else if (name && strcmp(name, "transforms") == 0) {
                o.layout = NERF_SCENE_LAYOUT_TRANSFORMS;
            } else {
                fprintf(stderr, "nerf-scene: --layout is blender or "
                        "transforms\n");
                goto bad;
            }
            continue;
        } else if (strcmp(a, "--distortion") == 0) {
            if (parse_lens(cli_value(argc, argv, &i), &o) != 0) {
                fprintf(stderr, "nerf-scene: --distortion needs 1 to 5 "
                        "numbers separated by commas: k1,k2,p1,p2,k3\n");
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
