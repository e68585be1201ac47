/*
 * The .npy parser and the zip reader on their own: accepted and refused
 * headers, every truncation, and byte damage everywhere (run under ASan,
 * the sweeps prove that no input reads out of bounds).
 */
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "../harness.h"
#include "env.h"
#include "npy.h"
#include "npz_writer.h"
#include "zip_read.h"

/* ---- the .npy parser ---------------------------------------------------- */

static int parse_npy(int major, int minor, const char *text, size_t data,
                     nerf__npy *a)
{
    bytes b = {0};
    unsigned char version[2] = {(unsigned char)major, (unsigned char)minor};
    put(&b, "\x93NUMPY", 6);
    put(&b, version, 2);
    put_le(&b, strlen(text), major == 1 ? 2 : 4);
    put(&b, text, strlen(text));
    for (size_t i = 0; i < data; i++) {
        put(&b, "", 1);
    }
    int rc = nerf__npy_parse(b.p, b.n, a);
    a->data = NULL; /* points into b */
    free(b.p);
    return rc;
}

TEST(npy_headers_accepted)
{
    nerf__npy a;
    CHECK_OK(parse_npy(1, 0, "{'descr': '<f4', 'fortran_order': False, "
                       "'shape': (2, 3), }          \n", 24, &a));
    CHECK(a.dtype == NERF__NPY_F4 && a.ndim == 2 && a.count == 6 &&
          !a.fortran_order && a.shape[0] == 2 && a.shape[1] == 3);
    CHECK_OK(parse_npy(2, 0, "{\"shape\": (3,), \"fortran_order\": True, "
                       "\"descr\": \"<f8\"}\n", 24, &a));
    CHECK(a.dtype == NERF__NPY_F8 && a.ndim == 1 && a.fortran_order &&
          a.elem_size == 8);
    CHECK_OK(parse_npy(1, 0, "{'descr':'<f8','fortran_order':False,"
                       "'shape':()}\n", 8, &a));
    CHECK(a.ndim == 0 && a.count == 1);
    CHECK_OK(parse_npy(1, 0, "{'descr': '<f4', 'fortran_order': False, "
                       "'shape': (0, 5), }\n", 0, &a));
    CHECK(a.count == 0 && a.data_size == 0);
    CHECK_OK(parse_npy(1, 0, "{'descr': '<f4', 'fortran_order': False, "
                       "'shape': (2L, 1L, 1L, 2L), }\n", 16, &a));
    CHECK(a.ndim == 4 && a.count == 4);
    char s[64];
    size_t dims[2] = {64, 63};
    nerf__npy_format_shape(dims, 2, s, sizeof s);
    CHECK(strcmp(s, "(64, 63)") == 0);
    nerf__npy_format_shape(dims, 1, s, sizeof s);
    CHECK(strcmp(s, "(64,)") == 0);
    nerf__npy_format_shape(dims, 0, s, sizeof s);
    CHECK(strcmp(s, "()") == 0);
}

TEST(npy_headers_refused)
{
    static const struct {
        int major, minor;
        const char *text;
        size_t data;
        const char *needle;
    } cases[] = {
        {3, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (1,), }\n",
         4, "version 3.0"},
        {1, 1, "{'descr': '<f4', 'fortran_order': False, 'shape': (1,), }\n",
         4, "version 1.1"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False}\n", 4, "'shape'"},
        {1, 0, "{'descr': '<f4', 'shape': (1,)}\n", 4, "'fortran_order'"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (1,), "
               "'extra': 1}\n", 4, "'extra'"},
        {1, 0, "{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, "
               "'shape': (1,)}\n", 4, "duplicate"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (3)}\n",
         12, "(n,)"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, "
               "'shape': (1, 1, 1, 1, 1)}\n", 4, "dimensions"},
        {1, 0, "{'descr': '>f4', 'fortran_order': False, 'shape': (1,)}\n",
         4, "big-endian dtype '>f4'"},
        {1, 0, "{'descr': '<i4', 'fortran_order': False, 'shape': (1,)}\n",
         4, "'<i4'"},
        {1, 0, "{'descr': '|b1', 'fortran_order': False, 'shape': (1,)}\n",
         1, "'|b1'"},
        {1, 0, "{'descr': [('a', '<f4')], 'fortran_order': False, "
               "'shape': (1,)}\n", 4, "structured"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (1,)}",
         4, "newline"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (2,)}\n",
         4, "truncated"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (1,)}\n",
         8, "trailing"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, "
               "'shape': (99999999999999999999999,)}\n", 4, "too large"},
        {1, 0, "{'descr': '<f8', 'fortran_order': False, "
               "'shape': (4294967296, 4294967296)}\n", 4, "too large"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (-1,)}\n",
         4, "dimension"},
        {1, 0, "{'descr': '<f4, 'fortran_order': False, 'shape': (1,)}\n",
         4, "expected"},
        {1, 0, "{'descr': '<f4', 'fortran_order': false, 'shape': (1,)}\n",
         4, "True or False"},
        {1, 0, "{'descr': '<f4', 'fortran_order': False, 'shape': (1,)} x\n",
         4, "newline"},
        {1, 0, "", 0, "'{'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        nerf__npy a;
        memset(&a, 0x5a, sizeof a);
        int rc = parse_npy(cases[i].major, cases[i].minor, cases[i].text,
                           cases[i].data, &a);
        if (rc != NERF_EFORMAT ||
            strstr(nerf_last_error(), cases[i].needle) == NULL) {
            FAILF("case %zu: status %d, message '%s' (want '%s')", i, rc,
                  nerf_last_error(), cases[i].needle);
        }
        CHECK(a.count == 0 && a.ndim == 0);
    }
}

TEST(npy_truncated_and_damaged)
{
    bytes b = {0};
    size_t shape[2] = {3, 5};
    double v[15] = {0};
    npy_write(&b, "<f8", false, shape, 2, v);
    nerf__npy a;
    CHECK_OK(nerf__npy_parse(b.p, b.n, &a));
    for (size_t len = 0; len < b.n; len++) {
        /* An exact copy, so that ASan sees reads past the cut. */
        unsigned char *cut = malloc(len ? len : 1);
        memcpy(cut, b.p, len);
        CHECK_EQ_INT(nerf__npy_parse(cut, len, &a), NERF_EFORMAT);
        free(cut);
    }
    for (size_t at = 0; at < 128; at++) {
        for (int bit = 0; bit < 8; bit++) {
            b.p[at] ^= (unsigned char)(1 << bit);
            int rc = nerf__npy_parse(b.p, b.n, &a);
            CHECK(rc == NERF_OK || rc == NERF_EFORMAT);
            b.p[at] ^= (unsigned char)(1 << bit);
        }
    }
    free(b.p);
}

/* ---- the zip reader ----------------------------------------------------- */

static void small_archive(bytes *z)
{
    static archive a;
    const char *texts[3] = {"stored text", "deflated text deflated text",
                            "zip64-style local header"};
    for (int i = 0; i < 3; i++) {
        char name[16];
        snprintf(name, sizeof name, "m%d", i);
        member *m = add_member(&a, name);
        put(&m->data, texts[i], strlen(texts[i]));
        m->method = i == 1 ? 8 : 0;
        m->zip64_local = i == 2;
    }
    zip_write(&a, z);
    free_archive(&a);
}

/* Open and extract everything; returns the first failure. */
static int read_everything(const unsigned char *p, size_t n, size_t max_size)
{
    nerf__env env;
    nerf__env_default(&env);
    nerf__zip zip;
    int rc = nerf__zip_open(&zip, &env, p, n);
    for (size_t i = 0; rc == NERF_OK && i < zip.count; i++) {
        unsigned char *data = NULL;
        rc = nerf__zip_extract(&zip, &env, &zip.entries[i], max_size, &data);
        nerf__free(&env, data);
    }
    nerf__zip_close(&zip, &env);
    return rc;
}

TEST(zip_members)
{
    bytes z = {0};
    small_archive(&z);
    nerf__env env;
    nerf__env_default(&env);
    nerf__zip zip;
    CHECK_OK(nerf__zip_open(&zip, &env, z.p, z.n));
    CHECK_EQ_INT(zip.count, 3);
    const nerf__zip_entry *e = nerf__zip_find(&zip, "m1");
    CHECK(e != NULL && nerf__zip_find(&zip, "m") == NULL);
    unsigned char *data = NULL;
    if (e) {
        CHECK_EQ_INT(e->method, 8);
        CHECK_OK(nerf__zip_extract(&zip, &env, e, 1000, &data));
        CHECK(data && memcmp(data, "deflated text deflated text", 27) == 0);
        nerf__free(&env, data);
        CHECK_EQ_INT(nerf__zip_extract(&zip, &env, e, 26, &data), NERF_EFORMAT);
        CHECK(data == NULL);
    }
    nerf__zip_close(&zip, &env);
    CHECK_OK(read_everything(z.p, z.n, 100));

    bytes empty = {0};
    archive none = {.n = 0};
    zip_write(&none, &empty);
    CHECK_OK(nerf__zip_open(&zip, &env, empty.p, empty.n));
    CHECK(zip.count == 0 && nerf__zip_find(&zip, "m0") == NULL);
    nerf__zip_close(&zip, &env);
    free(empty.p);
    free(z.p);
}

TEST(zip_refusals)
{
    bytes z = {0};
    small_archive(&z);
    size_t eocd = z.n - 22;
    size_t cd = (size_t)z.p[eocd + 16] | (size_t)z.p[eocd + 17] << 8;
    static const struct {
        size_t offset; /* from the central directory's start, or EOCD */
        bool in_eocd;
        unsigned char value;
        size_t width; /* bytes set to value */
        const char *needle;
    } cases[] = {
        {10, true, 0xFF, 2, "zip64"},         /* total entries 0xFFFF */
        {16, true, 0xFF, 4, "zip64"},         /* directory offset */
        {4, true, 1, 1, "multi-disk"},
        {8, false, 1, 1, "encrypted"},        /* general purpose flags */
        {10, false, 12, 1, "method 12"},      /* compression method */
        {16, false, 0x77, 1, "CRC-32"},
        {20, false, 0x7F, 1, "stored"},       /* compressed size */
        {24, false, 0xFF, 4, "zip64"},        /* uncompressed size */
        {42, false, 0x03, 1, "local header"}, /* local header offset */
        {0, false, 0x51, 1, "signature"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        size_t at = (cases[i].in_eocd ? eocd : cd) + cases[i].offset;
        unsigned char keep[4];
        memcpy(keep, z.p + at, cases[i].width);
        memset(z.p + at, cases[i].value, cases[i].width);
        int rc = read_everything(z.p, z.n, 1000);
        if (rc != NERF_EFORMAT ||
            strstr(nerf_last_error(), cases[i].needle) == NULL) {
            FAILF("case %zu: status %d, message '%s' (want '%s')", i, rc,
                  nerf_last_error(), cases[i].needle);
        }
        memcpy(z.p + at, keep, cases[i].width);
    }
    CHECK_OK(read_everything(z.p, z.n, 1000));
    free(z.p);
}

TEST(zip_truncated_and_damaged)
{
    bytes z = {0};
    small_archive(&z);
    for (size_t len = 0; len < z.n; len++) {
        unsigned char *cut = malloc(len ? len : 1);
        memcpy(cut, z.p, len);
        CHECK_EQ_INT(read_everything(cut, len, 1000), NERF_EFORMAT);
        free(cut);
    }
    for (size_t at = 0; at < z.n; at++) {
        for (int k = 0; k < 3; k++) {
            static const unsigned char flips[3] = {0x01, 0x80, 0xFF};
            z.p[at] ^= flips[k];
            int rc = read_everything(z.p, z.n, 1000);
            CHECK(rc == NERF_OK || rc == NERF_EFORMAT);
            z.p[at] ^= flips[k];
        }
    }
    free(z.p);
}

int main(void)
{
    RUN(npy_headers_accepted);
    RUN(npy_headers_refused);
    RUN(npy_truncated_and_damaged);
    RUN(zip_members);
    RUN(zip_refusals);
    RUN(zip_truncated_and_damaged);
    HARNESS_EXIT();
}
