/*
 * libFuzzer target for the checkpoint parser (nerf__checkpoint_parse, the
 * part of nerf_model_load after the file is read).
 *
 * The first input byte picks what the rest is (its two low bits):
 *   0: a whole checkpoint file, header and zlib stream as stored;
 *   2: the same, but this target first writes the correct CRCs into the
 *      header (of the header, of the zlib stream and, when the stream
 *      inflates to the size the header gives, of the payload), so that
 *      mutated header fields and streams get past the CRC checks;
 *   1: the decompressed payload (the tagged sections), which this target
 *      compresses and wraps in a header with correct CRCs;
 *   3: the payload in a compact form that this target expands, then wraps
 *      as for 1: each section is u32 tag, u64 length, u16 count and count
 *      bytes, the rest of its length being the last 4 of them repeated
 *      (zeros when fewer are given); payloads are capped at 16 MB.
 * Without the last three forms nearly every mutation would die at a CRC
 * check and the section parser behind it would never be reached; the last
 * one lets a few bytes stand for the large sections (weights of a hash
 * grid, the 8 MB occupancy grid) and their contents.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include "env.h"
#include "model.h"

#define HEADER_SIZE 48
#define EXPAND_CAP ((size_t)16 << 20)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = (unsigned char)(v >> (8 * i));
    }
}

static void le64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) {
        p[i] = (unsigned char)(v >> (8 * i));
    }
}

/* A format-1 checkpoint holding payload, in a malloc'd buffer. */
static unsigned char *wrap(const uint8_t *payload, size_t n, size_t *out_size)
{
    uLongf packed = compressBound((uLong)n);
    unsigned char *file = malloc(HEADER_SIZE + packed);
    if (file == NULL) {
        return NULL;
    }
    /* Stored blocks: the parser inflates them all the same, and deflating
     * megabytes of expanded sections would dominate the run time. */
    if (compress2(file + HEADER_SIZE, &packed, payload, (uLong)n,
                  Z_NO_COMPRESSION) != Z_OK) {
        free(file);
        return NULL;
    }
    memcpy(file, "NERFCKPT", 8);
    le32(file + 8, 1);
    le32(file + 12, HEADER_SIZE);
    le64(file + 16, n);
    le64(file + 24, packed);
    le32(file + 32, (uint32_t)crc32_z(0L, file + HEADER_SIZE, packed));
    le32(file + 36, (uint32_t)crc32_z(0L, payload, n));
    le32(file + 40, 0);
    le32(file + 44, (uint32_t)crc32_z(0L, file, HEADER_SIZE - 4));
    *out_size = HEADER_SIZE + packed;
    return file;
}

static uint32_t get32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
           (uint32_t)p[3] << 24;
}

static uint64_t get64(const unsigned char *p)
{
    return get32(p) | (uint64_t)get32(p + 4) << 32;
}

/* Mode 2: the CRCs a writer would have stored, wherever they fit. */
static void fix_crcs(unsigned char *file, size_t n)
{
    if (n < 20) {
        return;
    }
    uint32_t hsize = get32(file + 12);
    if (hsize < 20 || hsize > 4096 || hsize % 4 != 0 || hsize > n) {
        return;
    }
    if (hsize >= HEADER_SIZE) {
        uint64_t plain = get64(file + 16), packed = get64(file + 24);
        if (packed <= n - HEADER_SIZE) {
            const unsigned char *z = file + HEADER_SIZE;
            le32(file + 32, (uint32_t)crc32_z(0L, z, (size_t)packed));
            /* The parser refuses more than this expansion anyway. */
            if (plain <= (uint64_t)1032 * packed && plain <= (64u << 20)) {
                unsigned char *out = malloc(plain ? (size_t)plain : 1);
                uLongf out_n = (uLongf)plain;
                uLong in_n = (uLong)packed;
                if (out && uncompress2(out, &out_n, z, &in_n) == Z_OK &&
                    out_n == plain) {
                    le32(file + 36, (uint32_t)crc32_z(0L, out, out_n));
                }
                free(out);
            }
        }
    }
    le32(file + hsize - 4, (uint32_t)crc32_z(0L, file, hsize - 4));
}

/* Mode 3: the payload the compact form in[0..n) stands for (malloc'd),
 * or NULL if it would pass EXPAND_CAP.  A cut-off tail is kept as is. */
static unsigned char *expand(const uint8_t *in, size_t n, size_t *out_n)
{
    size_t total = 0, at = 0;
    while (at + 14 <= n) {
        uint64_t len = get64(in + at + 4);
        size_t given = (size_t)in[at + 12] | (size_t)in[at + 13] << 8;
        if (given > n - at - 14 || total > EXPAND_CAP - 12 ||
            len > EXPAND_CAP - 12 - total) {
            break;
        }
        total += 12 + (size_t)len;
        at += 14 + given;
    }
    if (n - at > EXPAND_CAP - total) {
        return NULL;
    }
    unsigned char *out = malloc(total + (n - at) + 1);
    if (out == NULL) {
        return NULL;
    }
    size_t o = 0;
    at = 0;
    while (at + 14 <= n) {
        uint64_t len = get64(in + at + 4);
        size_t given = (size_t)in[at + 12] | (size_t)in[at + 13] << 8;
        if (given > n - at - 14 || o > EXPAND_CAP - 12 ||
            len > EXPAND_CAP - 12 - o) {
            break;
        }
        memcpy(out + o, in + at, 12);
        o += 12;
        size_t take = given < len ? given : (size_t)len;
        memcpy(out + o, in + at + 14, take);
        if (take < 4) {
            memset(out + o + take, 0, (size_t)len - take);
        } else {
            /* The last 4 bytes, then copies of all repeated so far. */
            size_t done = 4, rest = (size_t)len - take;
            while (done < rest + 4) {
                size_t k = done < rest + 4 - done ? done : rest + 4 - done;
                memcpy(out + o + take - 4 + done, out + o + take - 4, k);
                done += k;
            }
        }
        o += (size_t)len;
        at += 14 + given;
    }
    memcpy(out + o, in + at, n - at);
    *out_n = o + (n - at);
    return out;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) {
        return 0;
    }
    nerf__env env;
    nerf__env_default(&env);
    unsigned char *file = NULL;
    size_t n = size - 1;
    if ((data[0] & 3) == 3) {
        size_t plain_n = 0;
        unsigned char *plain = expand(data + 1, size - 1, &plain_n);
        if (plain != NULL) {
            file = wrap(plain, plain_n, &n);
            free(plain);
        }
    } else if (data[0] & 1) {
        file = wrap(data + 1, size - 1, &n);
    } else {
        /* An exact-size copy, so that ASan sees any read past the end. */
        file = malloc(n ? n : 1);
        if (file) {
            memcpy(file, data + 1, n);
            if (data[0] & 2) {
                fix_crcs(file, n);
            }
        }
    }
    if (file == NULL) {
        return 0;
    }
    nerf_model *m = NULL;
    if (nerf__checkpoint_parse(&env, "fuzz.ckpt", file, n, &m) == NERF_OK) {
        nerf_model_destroy(m);
    }
    free(file);
    return 0;
}
