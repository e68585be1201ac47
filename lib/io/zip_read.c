#include "zip_read.h"

#include <stdio.h>
#include <string.h>

#define ZLIB_CONST
#include <zlib.h>

#include "byteorder.h"
#include "deflate_bound.h"

#define SIG_LOCAL 0x04034b50u
#define SIG_CENTRAL 0x02014b50u
#define SIG_EOCD 0x06054b50u
#define SIG_ZIP64_LOCATOR 0x07064b50u
#define EOCD_SIZE 22
#define CENTRAL_SIZE 46
#define LOCAL_SIZE 30
#define MAX_COMMENT 65535
#define FLAG_ENCRYPTED 0x0001u
#define FLAG_STRONG_ENCRYPTION 0x0040u

/* The central directory's bounds, from the end record. */
typedef struct directory {
    size_t count, offset, size;
} directory;

/* Members are named in messages with at most this many bytes. */
#define NAME_FMT "'%.*s'"
#define NAME_ARG(e) (int)((e)->name_len > 200 ? 200 : (e)->name_len), (e)->name

static int find_end_record(const unsigned char *b, size_t size, size_t *pos)
{
    if (size < EOCD_SIZE) {
        return nerf__error(NERF_EFORMAT, "not a zip archive (%zu bytes is "
                           "too short)", size);
    }
    /* The record is followed only by its comment, whose length it holds;
     * scan backwards over the longest comment possible. */
    size_t last = size - EOCD_SIZE;
    size_t first = last > MAX_COMMENT ? last - MAX_COMMENT : 0;
    for (size_t p = last + 1; p-- > first;) {
        if (nerf__load_le32(b + p) == SIG_EOCD &&
            nerf__load_le16(b + p + 20) == last - p) {
            *pos = p;
            return NERF_OK;
        }
    }
    return nerf__error(NERF_EFORMAT, "not a zip archive (no end of central "
                       "directory record)");
}

static int read_end_record(const unsigned char *b, size_t size, directory *d)
{
    size_t p = 0;
    int rc = find_end_record(b, size, &p);
    if (rc != NERF_OK) {
        return rc;
    }
    const unsigned char *r = b + p;
    unsigned disk = nerf__load_le16(r + 4), cd_disk = nerf__load_le16(r + 6);
    unsigned here = nerf__load_le16(r + 8), total = nerf__load_le16(r + 10);
    uint32_t cd_size = nerf__load_le32(r + 12);
    uint32_t cd_off = nerf__load_le32(r + 16);
    if (total == 0xFFFFu || cd_size == 0xFFFFFFFFu || cd_off == 0xFFFFFFFFu ||
        (p >= 20 && nerf__load_le32(r - 20) == SIG_ZIP64_LOCATOR)) {
        return nerf__error(NERF_EFORMAT, "zip64 archives are not supported");
    }
    if (disk != 0 || cd_disk != 0 || here != total) {
        return nerf__error(NERF_EFORMAT, "multi-disk zip archives are not "
                           "supported");
    }
    if (cd_off > p || cd_size > p - cd_off) {
        return nerf__error(NERF_EFORMAT, "zip central directory (offset %lu, "
                           "%lu bytes) lies outside the archive",
                           (unsigned long)cd_off, (unsigned long)cd_size);
    }
    if ((size_t)total * CENTRAL_SIZE > cd_size) {
        return nerf__error(NERF_EFORMAT, "zip central directory of %lu bytes "
                           "cannot hold %u entries", (unsigned long)cd_size,
                           total);
    }
    *d = (directory){total, cd_off, cd_size};
    return NERF_OK;
}

/* Check the member's local header and find where its data starts. */
static int check_local(const unsigned char *b, const directory *d,
                       nerf__zip_entry *e, size_t offset)
{
    if (offset > d->offset || d->offset - offset < LOCAL_SIZE ||
        nerf__load_le32(b + offset) != SIG_LOCAL) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": no local "
                           "header at offset %zu", NAME_ARG(e), offset);
    }
    size_t name_len = nerf__load_le16(b + offset + 26);
    size_t extra_len = nerf__load_le16(b + offset + 28);
    size_t room = d->offset - offset - LOCAL_SIZE;
    if (name_len + extra_len > room || name_len != e->name_len ||
        memcmp(b + offset + LOCAL_SIZE, e->name, name_len) != 0) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": local "
                           "header does not match the central directory",
                           NAME_ARG(e));
    }
    e->data_offset = offset + LOCAL_SIZE + name_len + extra_len;
    if (d->offset - e->data_offset < e->comp_size) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": %zu bytes "
                           "of data run past the central directory",
                           NAME_ARG(e), e->comp_size);
    }
    return NERF_OK;
}

/* Parse the central directory entry at *at and advance past it. */
static int read_entry(const unsigned char *b, const directory *d, size_t i,
                      size_t *at, nerf__zip_entry *e)
{
    size_t end = d->offset + d->size;
    const unsigned char *q = b + *at;
    if (end - *at < CENTRAL_SIZE || nerf__load_le32(q) != SIG_CENTRAL) {
        return nerf__error(NERF_EFORMAT, "zip central directory entry %zu "
                           "is truncated or has a bad signature", i);
    }
    unsigned flags = nerf__load_le16(q + 8);
    size_t var_len = (size_t)nerf__load_le16(q + 28) + nerf__load_le16(q + 30) +
                     nerf__load_le16(q + 32);
    if (end - *at - CENTRAL_SIZE < var_len) {
        return nerf__error(NERF_EFORMAT, "zip central directory entry %zu "
                           "is truncated", i);
    }
    e->name = (const char *)q + CENTRAL_SIZE;
    e->name_len = nerf__load_le16(q + 28);
    e->method = nerf__load_le16(q + 10);
    e->crc = nerf__load_le32(q + 16);
    uint32_t comp = nerf__load_le32(q + 20), size = nerf__load_le32(q + 24);
    uint32_t offset = nerf__load_le32(q + 42);
    unsigned disk = nerf__load_le16(q + 34);
    if (comp == 0xFFFFFFFFu || size == 0xFFFFFFFFu || offset == 0xFFFFFFFFu ||
        disk == 0xFFFFu) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": needs "
                           "zip64, which is not supported", NAME_ARG(e));
    }
    if (flags & (FLAG_ENCRYPTED | FLAG_STRONG_ENCRYPTION) || disk != 0) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": %s",
                           NAME_ARG(e), disk ? "on another disk"
                                             : "encrypted members are not "
                                               "supported");
    }
    e->comp_size = comp;
    e->size = size;
    *at += CENTRAL_SIZE + var_len;
    return check_local(b, d, e, offset);
}

int nerf__zip_open(nerf__zip *zip, const nerf__env *env, const void *buf,
                   size_t size)
{
    memset(zip, 0, sizeof *zip);
    const unsigned char *b = buf;
    directory d = {0, 0, 0};
    int rc = read_end_record(b, size, &d);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__zip_entry *entries = nerf__calloc(env, d.count ? d.count : 1,
                                            sizeof *entries);
    if (entries == NULL) {
        return NERF_ENOMEM;
    }
    size_t at = d.offset;
    for (size_t i = 0; i < d.count && rc == NERF_OK; i++) {
        rc = read_entry(b, &d, i, &at, &entries[i]);
    }
    if (rc != NERF_OK) {
        nerf__free(env, entries);
        return rc;
    }
    *zip = (nerf__zip){b, size, d.count, entries};
    return NERF_OK;
}

void nerf__zip_close(nerf__zip *zip, const nerf__env *env)
{
    nerf__free(env, zip->entries);
    memset(zip, 0, sizeof *zip);
}

const nerf__zip_entry *nerf__zip_find(const nerf__zip *zip, const char *name)
{
    size_t len = strlen(name);
    for (size_t i = 0; i < zip->count; i++) {
        const nerf__zip_entry *e = &zip->entries[i];
        if (e->name_len == len && memcmp(e->name, name, len) == 0) {
            return e;
        }
    }
    return NULL;
}

static int inflate_error(const nerf__zip_entry *e, int zr, const z_stream *s)
{
    if (zr == Z_MEM_ERROR) {
        return nerf__error(NERF_ENOMEM, "zlib: out of memory inflating zip "
                           "member " NAME_FMT, NAME_ARG(e));
    }
    char what[96] = "deflate data is truncated";
    if (zr == Z_DATA_ERROR) {
        snprintf(what, sizeof what, "corrupt deflate data (%s)",
                 s->msg ? s->msg : "no detail");
    } else if (zr == Z_STREAM_END && s->avail_out != 0) {
        snprintf(what, sizeof what, "inflates to fewer than the %zu bytes "
                 "declared", e->size);
    } else if (zr == Z_STREAM_END) {
        snprintf(what, sizeof what, "has bytes after its deflate data");
    } else if (s->avail_out == 0) {
        snprintf(what, sizeof what, "inflates to more than the %zu bytes "
                 "declared", e->size);
    }
    return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": %s",
                       NAME_ARG(e), what);
}

static int inflate_member(const nerf__zip *zip, const nerf__zip_entry *e,
                          unsigned char *out)
{
    z_stream s;
    memset(&s, 0, sizeof s);
    if (inflateInit2(&s, -MAX_WBITS) != Z_OK) {
        return nerf__error(NERF_ENOMEM, "zlib: cannot start inflating zip "
                           "member " NAME_FMT, NAME_ARG(e));
    }
    /* Sizes come from 32-bit fields, so they fit zlib's uInt counters. */
    s.next_in = zip->buf + e->data_offset;
    s.avail_in = (uInt)e->comp_size;
    s.next_out = out;
    s.avail_out = (uInt)e->size;
    int zr = inflate(&s, Z_FINISH);
    int rc = NERF_OK;
    if (zr != Z_STREAM_END || s.avail_in != 0 || s.avail_out != 0) {
        rc = inflate_error(e, zr, &s);
    }
    inflateEnd(&s);
    return rc;
}

static int check_member(const nerf__zip_entry *e, size_t max_size)
{
    if (e->size > max_size) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": %zu bytes "
                           "is more than the %zu expected", NAME_ARG(e),
                           e->size, max_size);
    }
    if (e->method == 0 && e->comp_size != e->size) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": stored "
                           "with %zu bytes but declares %zu", NAME_ARG(e),
                           e->comp_size, e->size);
    }
    if (e->method == 8 && e->size / NERF__DEFLATE_MAX_RATIO > e->comp_size) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": %zu "
                           "compressed bytes cannot inflate to %zu",
                           NAME_ARG(e), e->comp_size, e->size);
    }
    if (e->method != 0 && e->method != 8) {
        return nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": "
                           "compression method %u is not supported (only "
                           "stored and deflate are)", NAME_ARG(e),
                           (unsigned)e->method);
    }
    return NERF_OK;
}

int nerf__zip_extract(const nerf__zip *zip, const nerf__env *env,
                      const nerf__zip_entry *e, size_t max_size,
                      unsigned char **data_out)
{
    *data_out = NULL;
    int rc = check_member(e, max_size);
    if (rc != NERF_OK) {
        return rc;
    }
    unsigned char *out = nerf__alloc(env, e->size ? e->size : 1);
    if (out == NULL) {
        return NERF_ENOMEM;
    }
    if (e->method == 0) {
        memcpy(out, zip->buf + e->data_offset, e->size);
    } else {
        rc = inflate_member(zip, e, out);
    }
    if (rc == NERF_OK) {
        uint32_t crc = (uint32_t)crc32_z(0L, out, e->size);
        if (crc != e->crc) {
            rc = nerf__error(NERF_EFORMAT, "zip member " NAME_FMT ": CRC-32 "
                             "mismatch (recorded %08lx, computed %08lx)",
                             NAME_ARG(e), (unsigned long)e->crc,
                             (unsigned long)crc);
        }
    }
    if (rc != NERF_OK) {
        nerf__free(env, out);
        return rc;
    }
    *data_out = out;
    return NERF_OK;
}
