/*
 * libFuzzer target for the PNG decode path as the dataset loaders run it:
 * the input (after its first byte) is written to a scratch file, and
 * nerf__dataset_load_image reads it into a dataset of one image, which is
 * nerf__png_read_rgba through libpng's simplified API, then compositing,
 * box downscaling and the coverage plane.
 *
 * The first byte picks the options and what the rest is:
 *   bit 0     white background;
 *   bits 1-2  downscale factor 1..4;
 *   bits 3-4  0: the rest is the file as stored;
 *             1: the same, but every whole chunk gets its correct CRC;
 *             2, 3: also, the IDAT chunks hold raw (filtered, not
 *                compressed) scanlines, which this target deflates into
 *                one IDAT.
 * libpng rejects a critical chunk whose CRC is wrong, and a mutated zlib
 * stream rarely inflates, so without the last two forms hardly any
 * mutation would reach the row decoding.
 *
 * Allocations through the library's allocator are capped at 16 MB (a 1
 * megapixel image): a 50-byte file may claim 16384 x 16384 pixels, and the
 * loader allocates the pixels before it finds the data missing.  That is
 * by design (the side limit is the documented bound), but it would make
 * the fuzzer report out-of-memory instead of exploring.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include <nerf.h>

#include "dataset.h"
#include "fuzz_image.h"
#include "../data/data_fixtures.h"


int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char scene[512];
static char png_path[1024];

static void remove_scene(void)
{
    fx_remove_tree(scene);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    snprintf(scene, sizeof scene, "%s", fx_make_temp_dir());
    atexit(remove_scene);
    fx_path(png_path, sizeof png_path, scene, "image.png");
    return 0;
}

static uint32_t be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 |
           (uint32_t)p[2] << 8 | p[3];
}

static void put_be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

/* Append one chunk with its correct CRC to out at *at. */
static void put_chunk(uint8_t *out, size_t *at, const uint8_t *type,
                      const uint8_t *body, size_t n)
{
    put_be32(out + *at, (uint32_t)n);
    memcpy(out + *at + 4, type, 4);
    if (n > 0) {
        memcpy(out + *at + 8, body, n);
    }
    put_be32(out + *at + 8 + n,
             (uint32_t)crc32_z(0L, out + *at + 4, 4 + n));
    *at += 12 + n;
}

/*
 * The file that mode (1 or 2, see above) makes of in[0..n), in a malloc'd
 * buffer of *out_n bytes; NULL when out of memory.  Whatever follows the
 * last whole chunk is kept as it is.
 */
static uint8_t *rebuild(const uint8_t *in, size_t n, int mode,
                        size_t *out_n)
{
    size_t idat_n = 0;
    for (size_t at = 8; n >= 8 && at + 12 <= n;) {
        size_t len = be32(in + at);
        if (len > n - at - 12) {
            break;
        }
        if (memcmp(in + at + 4, "IDAT", 4) == 0) {
            idat_n += len;
        }
        at += 12 + len;
    }
    uLong packed_max = compressBound((uLong)idat_n);
    uint8_t *out = malloc(n + 12 + packed_max);
    uint8_t *raw = malloc(idat_n + 1);
    if (out == NULL || raw == NULL) {
        free(out);
        free(raw);
        return NULL;
    }
    size_t at = 0, o = 0, raw_n = 0;
    if (n >= 8) {
        memcpy(out, in, 8);
        at = o = 8;
    }
    const uint8_t *first_idat = NULL;
    size_t first_idat_at = 0;
    while (at + 12 <= n) {
        size_t len = be32(in + at);
        if (len > n - at - 12) {
            break;
        }
        const uint8_t *type = in + at + 4;
        if (mode == 2 && memcmp(type, "IDAT", 4) == 0) {
            if (first_idat == NULL) {
                /* Room for the compressed stream is kept here. */
                first_idat = type;
                first_idat_at = o;
                o += 12;
            }
            memcpy(raw + raw_n, in + at + 8, len);
            raw_n += len;
        } else {
            put_chunk(out, &o, type, in + at + 8, len);
        }
        at += 12 + len;
    }
    size_t tail_n = n - at;
    if (first_idat != NULL) {
        uLongf packed = packed_max;
        uint8_t *z = malloc(packed_max);
        if (z == NULL || compress2(z, &packed, raw, (uLong)raw_n, 1) != Z_OK) {
            free(z);
            free(raw);
            free(out);
            return NULL;
        }
        /* Shift what follows the first IDAT to make room for its body. */
        memmove(out + first_idat_at + 12 + packed, out + first_idat_at + 12,
                o - first_idat_at - 12);
        size_t w = first_idat_at;
        put_chunk(out, &w, (const uint8_t *)"IDAT", z, packed);
        o += packed;
        free(z);
    }
    memcpy(out + o, in + at, tail_n);
    free(raw);
    *out_n = o + tail_n;
    return out;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) {
        return 0;
    }
    uint32_t white = data[0] & 1u;
    uint32_t factor = 1u + ((data[0] >> 1) & 3u);
    int mode = (data[0] >> 3) & 3;
    if (mode == 0) {
        fx_write_bytes(png_path, data + 1, size - 1);
    } else {
        size_t n = 0;
        uint8_t *file = rebuild(data + 1, size - 1, mode > 2 ? 2 : mode, &n);
        if (file == NULL) {
            return 0;
        }
        fx_write_bytes(png_path, file, n);
        free(file);
    }

    fuzz_load_image(png_path, factor, white);
    return 0;
}
