/*
 * Writers of .npy arrays and zip archives for the npz tests, built from the
 * format descriptions rather than from NumPy, so that the tests control
 * every byte: stored or deflated members, NumPy's zip64-style local
 * headers, wrong CRCs.  Include after harness.h.
 */
#ifndef NERF_TEST_NPZ_WRITER_H
#define NERF_TEST_NPZ_WRITER_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

/* ---- byte buffers ------------------------------------------------------- */

typedef struct bytes {
    unsigned char *p;
    size_t n, cap;
} bytes;

static inline void put(bytes *b, const void *data, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2 + 64;
        b->p = realloc(b->p, b->cap);
    }
    if (n > 0) {
        memcpy(b->p + b->n, data, n);
    }
    b->n += n;
}

static inline void put_le(bytes *b, uint64_t v, int width)
{
    unsigned char t[8];
    for (int i = 0; i < width; i++) {
        t[i] = (unsigned char)(v >> (8 * i));
    }
    put(b, t, (size_t)width);
}

/* ---- .npy writer -------------------------------------------------------- */

static inline void put_element(bytes *b, const char *descr, double v)
{
    if (strcmp(descr, "<f8") == 0) {
        uint64_t bits;
        memcpy(&bits, &v, sizeof bits);
        put_le(b, bits, 8);
    } else if (strcmp(descr, "<i4") == 0) {
        put_le(b, (uint32_t)(int32_t)v, 4);
    } else {
        float f = (float)v;
        uint32_t bits;
        memcpy(&bits, &f, sizeof bits);
        put_le(b, bits, 4);
    }
}

/* An .npy image as numpy.save writes it (version 1.0, 64-byte aligned). */
static inline void npy_write(bytes *out, const char *descr, bool fortran,
                      const size_t *shape, int ndim, const double *v)
{
    char dims[96] = "(";
    size_t count = 1;
    for (int i = 0; i < ndim; i++) {
        size_t at = strlen(dims);
        snprintf(dims + at, sizeof dims - at, i ? ", %zu" : "%zu", shape[i]);
        count *= shape[i];
    }
    strcat(dims, ndim == 1 ? ",)" : ")");
    char text[256];
    int len = snprintf(text, sizeof text, "{'descr': '%s', 'fortran_order': "
                       "%s, 'shape': %s, }", descr, fortran ? "True" : "False",
                       dims);
    while ((10 + len + 1) % 64 != 0) {
        text[len++] = ' ';
    }
    text[len++] = '\n';
    put(out, "\x93NUMPY\1\0", 8);
    put_le(out, (uint64_t)len, 2);
    put(out, text, (size_t)len);
    for (size_t i = 0; i < count; i++) {
        put_element(out, descr, v[i]);
    }
}

/* ---- zip writer --------------------------------------------------------- */

typedef struct member {
    char name[128];
    bytes data;
    int method;        /* 0 stored, 8 deflated */
    bool zip64_local;  /* numpy.savez's local headers */
    bool bad_crc;
} member;

typedef struct archive {
    member m[64];
    int n;
} archive;

static inline member *add_member(archive *a, const char *name)
{
    member *m = &a->m[a->n++];
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%s", name);
    return m;
}

static inline void free_archive(archive *a)
{
    for (int i = 0; i < a->n; i++) {
        free(a->m[i].data.p);
    }
    a->n = 0;
}

static inline void deflate_raw(const bytes *in, bytes *out)
{
    z_stream s;
    memset(&s, 0, sizeof s);
    deflateInit2(&s, 6, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY);
    out->cap = deflateBound(&s, in->n) + 16;
    out->p = malloc(out->cap);
    s.next_in = in->p;
    s.avail_in = (uInt)in->n;
    s.next_out = out->p;
    s.avail_out = (uInt)out->cap;
    CHECK(deflate(&s, Z_FINISH) == Z_STREAM_END);
    out->n = s.total_out;
    deflateEnd(&s);
}

static inline void local_header(bytes *z, const member *m, uint32_t crc,
                         const bytes *packed)
{
    size_t name_len = strlen(m->name);
    put_le(z, 0x04034b50u, 4);
    put_le(z, m->zip64_local ? 45 : 20, 2);
    put_le(z, 0, 2);
    put_le(z, (uint64_t)m->method, 2);
    put_le(z, 0, 2);
    put_le(z, 0x21, 2);
    put_le(z, crc, 4);
    put_le(z, m->zip64_local ? 0xFFFFFFFFu : packed->n, 4);
    put_le(z, m->zip64_local ? 0xFFFFFFFFu : m->data.n, 4);
    put_le(z, name_len, 2);
    put_le(z, m->zip64_local ? 20 : 0, 2);
    put(z, m->name, name_len);
    if (m->zip64_local) {
        put_le(z, 1, 2);
        put_le(z, 16, 2);
        put_le(z, m->data.n, 8);
        put_le(z, packed->n, 8);
    }
}

static inline void central_entry(bytes *z, const member *m, uint32_t crc,
                          size_t packed_size, size_t offset)
{
    size_t name_len = strlen(m->name);
    put_le(z, 0x02014b50u, 4);
    put_le(z, 0x031e, 2);
    put_le(z, m->zip64_local ? 45 : 20, 2);
    put_le(z, 0, 2);
    put_le(z, (uint64_t)m->method, 2);
    put_le(z, 0, 2);
    put_le(z, 0x21, 2);
    put_le(z, m->bad_crc ? crc ^ 0x10u : crc, 4);
    put_le(z, packed_size, 4);
    put_le(z, m->data.n, 4);
    put_le(z, name_len, 2);
    put_le(z, 0, 2 + 2 + 2 + 2);
    put_le(z, 0x81a40000u, 4);
    put_le(z, offset, 4);
    put(z, m->name, name_len);
}

static inline void zip_write(const archive *a, bytes *z)
{
    uint32_t crc[64];
    size_t packed_size[64], offset[64];
    for (int i = 0; i < a->n; i++) {
        const member *m = &a->m[i];
        bytes packed = {0};
        if (m->method == 8) {
            deflate_raw(&m->data, &packed);
        } else {
            put(&packed, m->data.p, m->data.n);
        }
        crc[i] = (uint32_t)crc32(0L, m->data.p, (uInt)m->data.n);
        offset[i] = z->n;
        packed_size[i] = packed.n;
        local_header(z, m, crc[i], &packed);
        put(z, packed.p, packed.n);
        free(packed.p);
    }
    size_t cd_at = z->n;
    for (int i = 0; i < a->n; i++) {
        central_entry(z, &a->m[i], crc[i], packed_size[i], offset[i]);
    }
    size_t cd_size = z->n - cd_at;
    put_le(z, 0x06054b50u, 4);
    put_le(z, 0, 4);
    put_le(z, (uint64_t)a->n, 2);
    put_le(z, (uint64_t)a->n, 2);
    put_le(z, cd_size, 4);
    put_le(z, cd_at, 4);
    put_le(z, 0, 2);
}

#endif
