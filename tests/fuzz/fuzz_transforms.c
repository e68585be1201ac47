/*
 * libFuzzer target for the Blender / instant-ngp transforms loader.  The
 * input becomes transforms_train.json in a scratch scene folder that holds
 * two tiny images, r_0.png (4x4 RGBA) and r_1.png (2x2 grey, a different
 * size on purpose), and nerf_dataset_load reads the folder twice: with the
 * default options and with skip_missing, downscale 2 and skip 2, which
 * take other paths through the frame list.  It also becomes the single
 * transforms.json of a second folder with the same images, loaded as the
 * test split with holdouts 2 and 0 and as the train split with holdout
 * 1 (always empty), which the split of one file for every split takes.
 * Every camera of a load must be usable (fuzz_camera.h), its lens too.
 * Both folders also hold masks, which frames name with mask_path or find
 * by instant-ngp's name: m_0.png (4x4 grey, half of it 0) and
 * dynamic_mask_r_0.png (4x4 grey, one pixel nonzero), so that the masks'
 * reads, size checks and refusals are fuzzed with the frames.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#include "../data/data_fixtures.h"
#include "fuzz_camera.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char scene[512], whole[512];
static char json_path[1024], whole_path[1024];

static void remove_scene(void)
{
    fx_remove_tree(scene);
    fx_remove_tree(whole);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    snprintf(scene, sizeof scene, "%s", fx_make_temp_dir());
    snprintf(whole, sizeof whole, "%s", fx_make_temp_dir());
    atexit(remove_scene);
    uint16_t px[4 * 4 * 4];
    for (int i = 0; i < 4 * 4 * 4; i++) {
        px[i] = (uint16_t)(i * 37 % 256);
    }
    char p[1024];
    const char *dirs[2] = {scene, whole};
    for (int d = 0; d < 2; d++) {
        fx_path(p, sizeof p, dirs[d], "r_0.png");
        fx_write_png(p, 4, 4, 6, 8, px, NULL, 0, NULL, 0);
        fx_path(p, sizeof p, dirs[d], "r_1.png");
        fx_write_png(p, 2, 2, 0, 8, px, NULL, 0, NULL, 0);
        uint16_t half[16] = {0, 0, 0, 0, 0, 0, 0, 0,
                             255, 255, 255, 255, 255, 255, 255, 255};
        fx_path(p, sizeof p, dirs[d], "m_0.png");
        fx_write_png(p, 4, 4, 0, 8, half, NULL, 0, NULL, 0);
        uint16_t one[16] = {0, 0, 0, 0, 0, 9};
        fx_path(p, sizeof p, dirs[d], "dynamic_mask_r_0.png");
        fx_write_png(p, 4, 4, 0, 8, one, NULL, 0, NULL, 0);
    }
    fx_path(json_path, sizeof json_path, scene, "transforms_train.json");
    fx_path(whole_path, sizeof whole_path, whole, "transforms.json");
    return 0;
}

static void load(const char *dir, uint32_t split, uint32_t holdout,
                 uint32_t skip_missing, uint32_t downscale, uint32_t skip)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = split;
    o.llff_holdout = holdout;
    o.skip_missing = skip_missing;
    o.downscale = downscale;
    o.skip = skip;
    nerf_dataset_destroy(fuzz_load_dataset(dir, &o));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* Paths are joined to the scene folder; "..", though, would let the
     * fuzzer open any file on the machine (a FIFO or /dev/stdin would
     * hang it), so keep it inside the folder.  "\u" escapes could spell
     * ".." too. */
    for (size_t i = 0; i + 1 < size; i++) {
        if ((data[i] == '.' && data[i + 1] == '.') ||
            (data[i] == '\\' && data[i + 1] == 'u')) {
            return 0;
        }
    }
    fx_write_bytes(json_path, data, size);
    load(scene, NERF_SPLIT_TRAIN, 8, 0, 1, 1);
    load(scene, NERF_SPLIT_TRAIN, 8, 1, 2, 2);
    fx_write_bytes(whole_path, data, size);
    load(whole, NERF_SPLIT_TEST, 2, 1, 1, 1);
    load(whole, NERF_SPLIT_TEST, 0, 1, 1, 2);
    load(whole, NERF_SPLIT_TRAIN, 1, 1, 1, 1);
    return 0;
}
