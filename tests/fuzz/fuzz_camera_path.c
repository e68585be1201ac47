/*
 * libFuzzer target for camera-path files: nerf_camera_path_load on a
 * scratch file holding the input after its first byte.
 *
 * The first byte picks the file name and the options:
 *   bit 0     the name ends in ".npy" (read as NumPy whatever it holds)
 *             rather than ".json" (NumPy only with the NumPy magic);
 *   bits 1-2  0: defaults (everything from the file);
 *             1: 8x6 pixels, focal 5;
 *             2: 8x6 pixels, fov_x 60, the file's size where it has one;
 *             3: 8x6 pixels, focal 5, the file's size and intrinsics
 *                where it has them.
 * The JSON form opens no other file, so any bytes are safe to feed it.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#include "../data/data_fixtures.h"
#include "fuzz_camera.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char dir[512];
static char npy_path[1024];
static char json_path[1024];

static void remove_dir(void)
{
    fx_remove_tree(dir);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    snprintf(dir, sizeof dir, "%s", fx_make_temp_dir());
    atexit(remove_dir);
    fx_path(npy_path, sizeof npy_path, dir, "path.npy");
    fx_path(json_path, sizeof json_path, dir, "path.json");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) {
        return 0;
    }
    const char *path = (data[0] & 1) ? npy_path : json_path;
    fx_write_bytes(path, data + 1, size - 1);

    nerf_camera_path_options o;
    if (NERF_CAMERA_PATH_OPTIONS_INIT(&o) != NERF_OK) {
        abort();
    }
    int which = (data[0] >> 1) & 3;
    if (which != 0) {
        o.width = 8;
        o.height = 6;
    }
    if (which == 2) {
        o.fov_x = 60.0f;
        o.flags = NERF_CAMERA_PATH_FILE_SIZE;
    } else if (which != 0) {
        o.focal = 5.0f;
    }
    if (which == 3) {
        o.flags = NERF_CAMERA_PATH_FILE_SIZE |
                  NERF_CAMERA_PATH_FILE_INTRINSICS;
    }
    nerf_camera_path *cp = NULL;
    int rc = nerf_camera_path_load(&cp, path, &o);
    if ((rc == NERF_OK) != (cp != NULL)) {
        abort();
    }
    /* A path that loads has usable cameras: a renderer takes them as they
     * are. */
    for (uint32_t i = 0; i < nerf_camera_path_count(cp); i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        if (nerf_camera_path_camera(cp, i, &cam) != NERF_OK ||
            !fuzz_camera_usable(&cam)) {
            abort();
        }
    }
    nerf_camera_path_destroy(cp);
    return 0;
}
