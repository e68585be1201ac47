/*
 * The body of the COLMAP fuzz targets (fuzz_colmap_text.c and
 * fuzz_colmap_bin.c, which set COLMAP_BINARY): nerf_dataset_load on a
 * scratch COLMAP folder, the built-in scene's 3 views of 8x8 written at
 * start-up, one of whose model files is the input after its first byte.
 *
 * The first byte picks the file and the options:
 *   bits 0-1  the file the input replaces: 0 cameras, 1 images,
 *             2 points3D, 3 images with points3D removed (a model
 *             without points);
 *   bit 2     downscale 2 (no images_2/: the 8x8 photos are averaged);
 *   bit 3     the test split instead of the training one;
 *   bits 4-5  llff_holdout 0, 1, 2 or 8.
 * After each input the folder gets its original files back.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#include "../data/data_fixtures.h"
#include "fuzz_camera.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#if COLMAP_BINARY
#define EXT "bin"
#else
#define EXT "txt"
#endif

static char root[512];
static char scene[768];
static char files[3][1024];
static unsigned char *originals[3];
static size_t original_size[3];

static void remove_root(void)
{
    fx_remove_tree(root);
}

static void restore(int f)
{
    fx_write_bytes(files[f], originals[f], original_size[f]);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    static const char *const names[3] = {"cameras", "images", "points3D"};
    snprintf(root, sizeof root, "%s", fx_make_temp_dir());
    atexit(remove_root);
    fx_path(scene, sizeof scene, root, "scene");
    nerf_scene_options o;
    NERF_SCENE_OPTIONS_INIT(&o);
    o.width = 8;
    o.height = 8;
    o.n_train = 3;
    o.n_val = 0;
    o.n_test = 0;
    o.threads = 1;
    o.layout = COLMAP_BINARY ? NERF_SCENE_LAYOUT_COLMAP_BINARY
                             : NERF_SCENE_LAYOUT_COLMAP_TEXT;
    if (nerf_scene_write(scene, &o) != NERF_OK) {
        abort();
    }
    for (int f = 0; f < 3; f++) {
        char rel[64];
        snprintf(rel, sizeof rel, "sparse/0/%s.%s", names[f], EXT);
        fx_path(files[f], sizeof files[f], scene, rel);
        long n = fx_file_size(files[f]);
        originals[f] = malloc(n > 0 ? (size_t)n : 1);
        FILE *in = fopen(files[f], "rb");
        if (originals[f] == NULL || in == NULL ||
            fread(originals[f], 1, (size_t)n, in) != (size_t)n) {
            abort();
        }
        fclose(in);
        original_size[f] = (size_t)n;
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const uint32_t holdouts[4] = {0, 1, 2, 8};
    if (size == 0) {
        return 0;
    }
    int pick = data[0] & 3;
    int f = pick == 3 ? 1 : pick;
    fx_write_bytes(files[f], data + 1, size - 1);
    if (pick == 3) {
        unlink(files[2]);
    }

    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = (data[0] & 4) ? 2u : 1u;
    o.split = (data[0] & 8) ? NERF_SPLIT_TEST : NERF_SPLIT_TRAIN;
    o.llff_holdout = holdouts[(data[0] >> 4) & 3];
    nerf_dataset *ds = fuzz_load_dataset(scene, &o);
    if (ds != NULL) {
        /* The bounds: an interval in front of the cameras. */
        float near, far;
        if (nerf_dataset_bounds(ds, &near, &far) != NERF_OK ||
            !(near > 0.0f && far > near && isfinite(far))) {
            abort();
        }
    }
    nerf_dataset_destroy(ds);
    restore(f);
    if (pick == 3) {
        restore(2);
    }
    return 0;
}
