#include "mesh_write.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "byteorder.h"
#include "error.h"
#include "file_io.h"

/* A growing text or byte buffer; `failed` sticks after an allocation
 * failure so that the writers check once at the end. */
typedef struct buf {
    const nerf__env *env;
    unsigned char *data;
    size_t size, cap;
    int failed;
} buf;

static unsigned char *reserve(buf *b, size_t more)
{
    if (b->failed) {
        return NULL;
    }
    if (b->size + more > b->cap) {
        size_t cap = b->cap ? b->cap : 65536;
        while (cap < b->size + more) {
            cap *= 2;
        }
        unsigned char *p = nerf__alloc(b->env, cap);
        if (p == NULL) {
            b->failed = 1;
            return NULL;
        }
        if (b->data) {
            memcpy(p, b->data, b->size);
            nerf__free(b->env, b->data);
        }
        b->data = p;
        b->cap = cap;
    }
    return b->data + b->size;
}

static void put(buf *b, const char *fmt, ...) NERF__PRINTF(2, 3);
static void put(buf *b, const char *fmt, ...)
{
    unsigned char *p = reserve(b, 256);
    if (p == NULL) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf((char *)p, 256, fmt, ap);
    va_end(ap);
    if (n > 0 && n < 256) {
        b->size += (size_t)n;
    }
}

static int finish(buf *b, const char *path)
{
    int rc = NERF_ENOMEM;
    if (!b->failed) {
        nerf__span part = {b->data, b->size};
        rc = nerf__file_write_atomic(b->env, path, &part, 1);
    }
    nerf__free(b->env, b->data);
    return rc;
}

int nerf__mesh_write_ply(const nerf__env *env, const char *path,
                         const nerf__mesh_arrays *m, int ascii)
{
    buf b = {env, NULL, 0, 0, 0};
    put(&b, "ply\nformat %s 1.0\ncomment %s\n",
        ascii ? "ascii" : "binary_little_endian", m->comment);
    put(&b, "element vertex %zu\n", m->n_vertices);
    put(&b, "property float x\nproperty float y\nproperty float z\n");
    if (m->normals) {
        put(&b, "property float nx\nproperty float ny\nproperty float nz\n");
    }
    if (m->colours) {
        put(&b, "property uchar red\nproperty uchar green\n"
            "property uchar blue\n");
    }
    if (m->faces) {
        put(&b, "element face %zu\nproperty list uchar uint "
            "vertex_indices\n", m->n_faces);
    }
    put(&b, "end_header\n");
    for (size_t i = 0; i < m->n_vertices; i++) {
        const float *v = m->vertices + 3 * i;
        const float *n = m->normals ? m->normals + 3 * i : NULL;
        const uint8_t *c = m->colours ? m->colours + 3 * i : NULL;
        if (ascii) {
            put(&b, "%.9g %.9g %.9g", (double)v[0], (double)v[1], (double)v[2]);
            if (n) {
                put(&b, " %.9g %.9g %.9g", (double)n[0], (double)n[1],
                    (double)n[2]);
            }
            if (c) {
                put(&b, " %u %u %u", c[0], c[1], c[2]);
            }
            put(&b, "\n");
            continue;
        }
        unsigned char *p = reserve(&b, 27);
        if (p == NULL) {
            break;
        }
        for (int k = 0; k < 3; k++) {
            nerf__store_lef32(p + 4 * k, v[k]);
        }
        size_t size = 12;
        if (n) {
            for (int k = 0; k < 3; k++) {
                nerf__store_lef32(p + size + 4 * k, n[k]);
            }
            size += 12;
        }
        if (c) {
            memcpy(p + size, c, 3);
            size += 3;
        }
        b.size += size;
    }
    for (size_t f = 0; m->faces && f < m->n_faces; f++) {
        const uint32_t *t = m->faces + 3 * f;
        if (ascii) {
            put(&b, "3 %u %u %u\n", (unsigned)t[0], (unsigned)t[1],
                (unsigned)t[2]);
            continue;
        }
        unsigned char *p = reserve(&b, 13);
        if (p == NULL) {
            break;
        }
        p[0] = 3;
        for (int k = 0; k < 3; k++) {
            nerf__store_le32(p + 1 + 4 * k, t[k]);
        }
        b.size += 13;
    }
    return finish(&b, path);
}

int nerf__mesh_write_obj(const nerf__env *env, const char *path,
                         const nerf__mesh_arrays *m)
{
    buf b = {env, NULL, 0, 0, 0};
    put(&b, "# libnerf mesh: %zu vertices, %zu faces\n", m->n_vertices,
        m->n_faces);
    for (size_t i = 0; i < m->n_vertices && !b.failed; i++) {
        const float *v = m->vertices + 3 * i;
        put(&b, "v %.9g %.9g %.9g", (double)v[0], (double)v[1], (double)v[2]);
        if (m->colours) {
            const uint8_t *c = m->colours + 3 * i;
            put(&b, " %.4g %.4g %.4g", c[0] / 255.0, c[1] / 255.0,
                c[2] / 255.0);
        }
        put(&b, "\n");
    }
    for (size_t i = 0; m->normals && i < m->n_vertices && !b.failed; i++) {
        const float *n = m->normals + 3 * i;
        put(&b, "vn %.6g %.6g %.6g\n", (double)n[0], (double)n[1],
            (double)n[2]);
    }
    for (size_t f = 0; f < m->n_faces && !b.failed; f++) {
        const uint32_t *t = m->faces + 3 * f;
        const unsigned long a = t[0] + 1ul, c = t[1] + 1ul, d = t[2] + 1ul;
        if (m->normals) {
            put(&b, "f %lu//%lu %lu//%lu %lu//%lu\n", a, a, c, c, d, d);
        } else {
            put(&b, "f %lu %lu %lu\n", a, c, d);
        }
    }
    return finish(&b, path);
}
