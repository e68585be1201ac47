/*
 * libFuzzer target for the LLFF loader: nerf_dataset_load on a scratch
 * scene folder whose poses_bounds.npy is the input after its first byte.
 *
 * The first byte picks the scene and the options:
 *   bits 0-1  the number of images in the folder, 1..4;
 *   bit 2     the images: 0: images/ of 8x6 8-bit RGB and images_2/ of
 *             4x3 grey; 1: images/ of 6x4 16-bit RGBA with transparent
 *             pixels, beside a file the loader must ignore;
 *   bits 3-4  downscale 1..4 (2 and 4 find images_2/ where it exists);
 *   bits 5-6  llff_holdout 0, 1, 2 or 8;
 *   bit 7     the test split instead of the training one.
 * The eight folders are written once, at start-up; each input only
 * replaces the poses file of the one it picks.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#include "../data/data_fixtures.h"
#include "fuzz_camera.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char root[512];
static char scenes[8][768];

static void remove_root(void)
{
    fx_remove_tree(root);
}

static void write_images(const char *dir, const char *sub, int count,
                         uint32_t w, uint32_t h, int color_type, int depth,
                         int channels)
{
    fx_mkdir(dir, sub);
    uint16_t px[8 * 6 * 4];
    for (int k = 0; k < count; k++) {
        for (int i = 0; i < (int)(w * h) * channels; i++) {
            int v = (i * 37 + k * 11) % 256;
            px[i] = (uint16_t)(depth == 16 ? v * 257 : v);
        }
        if (channels == 4) {
            px[3] = 0; /* one transparent pixel: the coverage plane */
        }
        char name[64], p[1024];
        snprintf(name, sizeof name, "%s/IMG_%04d.png", sub, k);
        fx_path(p, sizeof p, dir, name);
        fx_write_png(p, w, h, color_type, depth, px, NULL, 0, NULL, 0);
    }
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    snprintf(root, sizeof root, "%s", fx_make_temp_dir());
    atexit(remove_root);
    for (int s = 0; s < 8; s++) {
        int count = 1 + (s & 3);
        char name[16];
        snprintf(name, sizeof name, "s%d", s);
        fx_mkdir(root, name);
        fx_path(scenes[s], sizeof scenes[s], root, name);
        if (s & 4) {
            write_images(scenes[s], "images", count, 6, 4, 6, 16, 4);
            fx_write_text(scenes[s], "images/notes.txt", "not an image");
        } else {
            write_images(scenes[s], "images", count, 8, 6, 2, 8, 3);
            write_images(scenes[s], "images_2", count, 4, 3, 0, 8, 1);
        }
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const uint32_t holdouts[4] = {0, 1, 2, 8};
    if (size == 0) {
        return 0;
    }
    const char *scene = scenes[data[0] & 7];
    char npy[1024];
    fx_path(npy, sizeof npy, scene, "poses_bounds.npy");
    fx_write_bytes(npy, data + 1, size - 1);

    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 1u + ((data[0] >> 3) & 3u);
    o.llff_holdout = holdouts[(data[0] >> 5) & 3];
    o.split = (data[0] & 0x80) ? NERF_SPLIT_TEST : NERF_SPLIT_TRAIN;
    nerf_dataset *ds = fuzz_load_dataset(scene, &o);
    if (ds != NULL) {
        /* Every camera of the spiral path must be usable too, as the
         * dataset's are (fuzz_load_dataset): renders of the scene use it. */
        for (uint32_t i = 0; i < 3; i++) {
            nerf_camera cam;
            NERF_CAMERA_INIT(&cam);
            if (nerf_dataset_spiral_camera(ds, i, 3, &cam) != NERF_OK ||
                !fuzz_camera_usable(&cam)) {
                abort();
            }
        }
    }
    nerf_dataset_destroy(ds);
    return 0;
}
