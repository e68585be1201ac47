/*
 * Fixture writers for the data tests: temporary folders, text files, a
 * minimal PNG encoder (any colour type, 8 or 16 bits, built on zlib so
 * that the tests can produce formats the library never writes) and a .npy
 * writer with a hand-made header.
 */
#ifndef NERF_TEST_DATA_FIXTURES_H
#define NERF_TEST_DATA_FIXTURES_H

#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

/* A fresh folder under $TMPDIR (or /tmp); the caller removes it. */
/* The whole file at path, malloc'd (free it), its length in *size; NULL
 * if it cannot be opened. */
static inline unsigned char *fx_slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(n > 0 ? (size_t)n : 1);
    *size = b ? fread(b, 1, (size_t)n, f) : 0;
    fclose(f);
    return b;
}

static inline char *fx_make_temp_dir(void)
{
    const char *base = getenv("TMPDIR");
    static char path[512];
    snprintf(path, sizeof path, "%s/nerf-data-XXXXXX",
             base && base[0] ? base : "/tmp");
    if (mkdtemp(path) == NULL) {
        perror("mkdtemp");
        exit(1);
    }
    return path;
}

/* Remove a folder and everything under it (fixtures hold no links). */
static inline void fx_remove_tree(const char *path)
{
    DIR *d = opendir(path);
    if (d == NULL) {
        unlink(path);
        return;
    }
    for (struct dirent *e = readdir(d); e; e = readdir(d)) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) {
            continue;
        }
        char child[1024];
        int n = snprintf(child, sizeof child, "%s/%s", path, e->d_name);
        if (n < 0 || (size_t)n >= sizeof child) {
            continue;
        }
        struct stat st;
        if (lstat(child, &st) == 0 && S_ISDIR(st.st_mode)) {
            fx_remove_tree(child);
        } else {
            unlink(child);
        }
    }
    closedir(d);
    rmdir(path);
}

static inline void fx_path(char *buf, size_t size, const char *dir,
                           const char *name)
{
    int n = snprintf(buf, size, "%s/%s", dir, name);
    if (n < 0 || (size_t)n >= size) {
        fprintf(stderr, "fixture path too long: %s/%s\n", dir, name);
        exit(1);
    }
}

static inline void fx_mkdir(const char *dir, const char *name)
{
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    mkdir(p, 0777);
}

static inline void fx_write_bytes(const char *path, const void *data,
                                  size_t n)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL || fwrite(data, 1, n, f) != n || fclose(f) != 0) {
        perror(path);
        exit(1);
    }
}

static inline void fx_write_text(const char *dir, const char *name,
                                 const char *text)
{
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    fx_write_bytes(p, text, strlen(text));
}

/* Keep only the first keep bytes of a file. */
static inline void fx_truncate(const char *path, long keep)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        perror(path);
        exit(1);
    }
    unsigned char *buf = malloc((size_t)keep);
    size_t got = fread(buf, 1, (size_t)keep, f);
    fclose(f);
    fx_write_bytes(path, buf, got);
    free(buf);
}

static inline long fx_file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static inline void fx_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

static inline void fx_chunk(FILE *f, const char *type,
                            const unsigned char *data, uint32_t n)
{
    unsigned char head[8], tail[4];
    fx_be32(head, n);
    memcpy(head + 4, type, 4);
    uLong crc = crc32(0L, (const Bytef *)type, 4);
    if (n > 0) {
        crc = crc32(crc, data, n);
    }
    fx_be32(tail, (uint32_t)crc);
    fwrite(head, 1, 8, f);
    if (n > 0) {
        fwrite(data, 1, n, f);
    }
    fwrite(tail, 1, 4, f);
}

/*
 * Write a PNG.  color_type: 0 gray, 2 RGB, 3 palette, 4 gray+alpha, 6 RGBA;
 * depth 8 or 16 (8 for palette).  samples: w x h x channels values, one per
 * sample whatever the depth.  plte/trns: palette entries (RGB triples) and
 * their alphas, for color type 3.
 */
static inline void fx_write_png(const char *path, uint32_t w, uint32_t h,
                                int color_type, int depth,
                                const uint16_t *samples,
                                const unsigned char *plte, int n_plte,
                                const unsigned char *trns, int n_trns)
{
    static const int channels_of[7] = {1, 0, 3, 1, 2, 0, 4};
    int ch = channels_of[color_type];
    int bytes = depth / 8;
    size_t row = 1 + (size_t)w * ch * bytes;
    size_t raw_n = row * h;
    unsigned char *raw = calloc(raw_n, 1);
    for (uint32_t y = 0; y < h; y++) {
        unsigned char *p = raw + y * row + 1; /* filter byte 0: none */
        for (size_t i = 0; i < (size_t)w * ch; i++) {
            uint16_t v = samples[(size_t)y * w * ch + i];
            if (bytes == 2) {
                *p++ = (unsigned char)(v >> 8);
            }
            *p++ = (unsigned char)v;
        }
    }
    uLongf zn = compressBound(raw_n);
    unsigned char *z = malloc(zn);
    compress2(z, &zn, raw, raw_n, 6);
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        perror(path);
        exit(1);
    }
    fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
    unsigned char ihdr[13];
    fx_be32(ihdr, w);
    fx_be32(ihdr + 4, h);
    ihdr[8] = (unsigned char)depth;
    ihdr[9] = (unsigned char)color_type;
    ihdr[10] = ihdr[11] = ihdr[12] = 0;
    fx_chunk(f, "IHDR", ihdr, 13);
    if (plte) {
        fx_chunk(f, "PLTE", plte, (uint32_t)(3 * n_plte));
    }
    if (trns) {
        fx_chunk(f, "tRNS", trns, (uint32_t)n_trns);
    }
    fx_chunk(f, "IDAT", z, (uint32_t)zn);
    fx_chunk(f, "IEND", NULL, 0);
    fclose(f);
    free(z);
    free(raw);
}

/* An 8-bit RGBA PNG from floats in [0, 1] (rounded). */
static inline void fx_write_rgba8(const char *path, uint32_t w, uint32_t h,
                                  const float *rgba)
{
    size_t n = (size_t)w * h * 4;
    uint16_t *s = malloc(n * sizeof *s);
    for (size_t i = 0; i < n; i++) {
        s[i] = (uint16_t)(rgba[i] * 255.0f + 0.5f);
    }
    fx_write_png(path, w, h, 6, 8, s, NULL, 0, NULL, 0);
    free(s);
}

/*
 * A .npy file: descr such as "<f8", fortran "False"/"True", shape text such
 * as "(9, 17)", then the raw data.  The header is padded with spaces so
 * that the data starts at a multiple of 64, as NumPy does.
 */
static inline void fx_write_npy(const char *path, const char *descr,
                                const char *fortran, const char *shape,
                                const void *data, size_t n)
{
    char dict[256];
    int len = snprintf(dict, sizeof dict,
                       "{'descr': '%s', 'fortran_order': %s, 'shape': %s, }",
                       descr, fortran, shape);
    size_t total = 10 + (size_t)len + 1;
    size_t padded = (total + 63) / 64 * 64;
    size_t hlen = padded - 10;
    unsigned char *buf = calloc(padded + n, 1);
    memcpy(buf, "\x93NUMPY\x01\x00", 8);
    buf[8] = (unsigned char)(hlen & 0xff);
    buf[9] = (unsigned char)(hlen >> 8);
    memset(buf + 10, ' ', hlen);
    memcpy(buf + 10, dict, (size_t)len);
    buf[padded - 1] = '\n';
    if (n > 0) {
        memcpy(buf + padded, data, n);
    }
    fx_write_bytes(path, buf, padded + n);
    free(buf);
}

/* Does haystack contain needle?  For checking error messages. */
static inline int fx_has(const char *haystack, const char *needle)
{
    return haystack && strstr(haystack, needle) != NULL;
}

#endif
