#include "exif.h"

#include <stdio.h>
#include <string.h>

#define EXIF_ID_SIZE 6u         /* "Exif\0\0" */
#define TAG_ORIENTATION 0x0112u
#define TYPE_SHORT 3u

typedef struct tiff {
    const uint8_t *p; /* the TIFF header: offsets count from here */
    size_t n;
    int big_endian;
} tiff;

static uint32_t get16(const tiff *t, size_t at)
{
    const uint8_t *b = t->p + at;
    return t->big_endian ? (uint32_t)b[0] << 8 | b[1]
                         : (uint32_t)b[1] << 8 | b[0];
}

static uint32_t get32(const tiff *t, size_t at)
{
    const uint8_t *b = t->p + at;
    return t->big_endian
               ? (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 |
                     (uint32_t)b[2] << 8 | b[3]
               : (uint32_t)b[3] << 24 | (uint32_t)b[2] << 16 |
                     (uint32_t)b[1] << 8 | b[0];
}

int nerf__exif_is_exif(const uint8_t *data, size_t n)
{
    return n >= EXIF_ID_SIZE && memcmp(data, "Exif\0\0", EXIF_ID_SIZE) == 0;
}

int nerf__exif_orientation(const uint8_t *data, size_t n,
                           uint32_t *orientation, char *why,
                           size_t why_size)
{
    *orientation = 1;
    if (!nerf__exif_is_exif(data, n)) {
        snprintf(why, why_size, "APP1 block is not Exif");
        return -1;
    }
    tiff t = {data + EXIF_ID_SIZE, n - EXIF_ID_SIZE, 0};
    if (t.n < 8 || !((t.p[0] == 'I' && t.p[1] == 'I') ||
                     (t.p[0] == 'M' && t.p[1] == 'M'))) {
        snprintf(why, why_size, "Exif block has no TIFF byte-order mark");
        return -1;
    }
    t.big_endian = t.p[0] == 'M';
    if (get16(&t, 2) != 42) {
        snprintf(why, why_size, "Exif block has a bad TIFF magic number");
        return -1;
    }
    uint32_t ifd = get32(&t, 4);
    if (ifd < 8 || ifd > t.n - 2) {
        snprintf(why, why_size, "Exif IFD0 offset %u is outside the %zu-byte "
                 "block", (unsigned)ifd, t.n);
        return -1;
    }
    uint32_t count = get16(&t, ifd);
    if (count > (t.n - ifd - 2) / 12) {
        snprintf(why, why_size, "Exif IFD0 claims %u entries; the block "
                 "holds at most %zu", (unsigned)count, (t.n - ifd - 2) / 12);
        return -1;
    }
    for (uint32_t i = 0; i < count; i++) {
        size_t e = (size_t)ifd + 2 + 12 * (size_t)i;
        if (get16(&t, e) != TAG_ORIENTATION) {
            continue;
        }
        uint32_t type = get16(&t, e + 2), n_values = get32(&t, e + 4);
        if (type != TYPE_SHORT || n_values != 1) {
            snprintf(why, why_size, "Exif Orientation has type %u and count "
                     "%u (expected one SHORT)", (unsigned)type,
                     (unsigned)n_values);
            return -1;
        }
        /* A single SHORT sits in the first two bytes of the value field. */
        uint32_t v = get16(&t, e + 8);
        if (v < 1 || v > 8) {
            snprintf(why, why_size, "Exif Orientation is %u; only 1 to 8 "
                     "are defined", (unsigned)v);
            return -1;
        }
        *orientation = v;
        return 0;
    }
    return 0;
}
