/*
 * libFuzzer target for JPEG photos as the dataset loaders read them: the
 * input (after its first byte) becomes a scratch file that
 * nerf__dataset_load_image reads into a dataset of one image, which is
 * nerf__image_read_rgba's sniffing, then libjpeg-turbo's decode with its
 * error and warning jumps, the Exif orientation and the re-ordering of
 * the pixels, then compositing and box downscaling.
 *
 * The first byte picks the options and what the rest is:
 *   bit 0     white background;
 *   bits 1-2  downscale factor 1..4;
 *   bit 3     0: the rest is the file as stored;
 *             1: the rest is the body of an APP1 marker (an Exif block),
 *                which the target also hands to nerf__exif_orientation
 *                directly and puts right after the SOI of a small valid
 *                JPEG (16 x 8, written at start-up), so that mutations of
 *                the Exif block reach the orientation code instead of
 *                breaking the marker structure around it.
 *
 * Allocations through the library's allocator are capped at 16 MB, as
 * in fuzz_png: a few bytes may claim 16384 x 16384 pixels.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#include "dataset.h"
#include "fuzz_image.h"
#include "exif.h"
#include "file_io.h"
#include "jpeg_io.h"
#include "../data/data_fixtures.h"

#define APP1_MAX 65533u

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char scene[512];
static char jpeg_path[1024];
static unsigned char *base_jpeg;
static size_t base_size;

static void cleanup(void)
{
    fx_remove_tree(scene);
    free(base_jpeg);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    snprintf(scene, sizeof scene, "%s", fx_make_temp_dir());
    atexit(cleanup);
    fx_path(jpeg_path, sizeof jpeg_path, scene, "image.jpg");
    uint8_t px[16 * 8 * 3];
    for (size_t i = 0; i < sizeof px; i++) {
        px[i] = (uint8_t)(i * 37 + 11);
    }
    nerf__env env;
    nerf__env_default(&env);
    unsigned char *bytes = NULL;
    if (nerf__jpeg_write8(&env, jpeg_path, 16, 8, 3, px, 90) != NERF_OK ||
        nerf__file_read(&env, jpeg_path, 1 << 20, &bytes, &base_size) !=
            NERF_OK) {
        abort();
    }
    base_jpeg = malloc(base_size);
    if (base_jpeg == NULL) {
        abort();
    }
    memcpy(base_jpeg, bytes, base_size);
    nerf__free(&env, bytes);
    return 0;
}

/* SOI, APP1 holding body, then the base file after its SOI. */
static void write_with_app1(const uint8_t *body, size_t n)
{
    if (n > APP1_MAX) {
        n = APP1_MAX;
    }
    uint32_t orientation;
    char why[160];
    if (nerf__exif_orientation(body, n, &orientation, why, sizeof why) ==
            0 &&
        (orientation < 1 || orientation > 8)) {
        abort();
    }
    size_t total = 2 + 4 + n + base_size - 2;
    uint8_t *out = malloc(total);
    if (out == NULL) {
        return;
    }
    out[0] = 0xff;
    out[1] = 0xd8;
    out[2] = 0xff;
    out[3] = 0xe1;
    out[4] = (uint8_t)((n + 2) >> 8);
    out[5] = (uint8_t)(n + 2);
    memcpy(out + 6, body, n);
    memcpy(out + 6 + n, base_jpeg + 2, base_size - 2);
    fx_write_bytes(jpeg_path, out, total);
    free(out);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) {
        return 0;
    }
    uint32_t white = data[0] & 1u;
    uint32_t factor = 1u + ((data[0] >> 1) & 3u);
    if (data[0] & 8u) {
        write_with_app1(data + 1, size - 1);
    } else {
        fx_write_bytes(jpeg_path, data + 1, size - 1);
    }

    fuzz_load_image(jpeg_path, factor, white);
    return 0;
}
