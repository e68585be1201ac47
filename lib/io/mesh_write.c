#include "mesh_write.h"

#include <string.h>

#include "byte_buf.h"
#include "byteorder.h"

int nerf__mesh_write_ply(const nerf__env *env, const char *path,
                         const nerf__mesh_arrays *m, int ascii)
{
    nerf__buf b = {env, NULL, 0, 0, false};
    nerf__buf_printf(&b, "ply\nformat %s 1.0\ncomment %s\n",
                     ascii ? "ascii" : "binary_little_endian", m->comment);
    nerf__buf_printf(&b, "element vertex %zu\n", m->n_vertices);
    nerf__buf_printf(&b,
                     "property float x\nproperty float y\nproperty float z\n");
    if (m->normals) {
        nerf__buf_printf(
            &b, "property float nx\nproperty float ny\nproperty float nz\n");
    }
    if (m->colours) {
        nerf__buf_printf(&b, "property uchar red\nproperty uchar green\n"
                             "property uchar blue\n");
    }
    if (m->faces) {
        nerf__buf_printf(&b,
                         "element face %zu\nproperty list uchar uint "
                         "vertex_indices\n",
                         m->n_faces);
    }
    nerf__buf_printf(&b, "end_header\n");
    for (size_t i = 0; i < m->n_vertices; i++) {
        const float *v = m->vertices + 3 * i;
        const float *n = m->normals ? m->normals + 3 * i : NULL;
        const uint8_t *c = m->colours ? m->colours + 3 * i : NULL;
        if (ascii) {
            nerf__buf_printf(&b, "%.9g %.9g %.9g", (double)v[0], (double)v[1],
                             (double)v[2]);
            if (n) {
                nerf__buf_printf(&b, " %.9g %.9g %.9g", (double)n[0],
                                 (double)n[1], (double)n[2]);
            }
            if (c) {
                nerf__buf_printf(&b, " %u %u %u", c[0], c[1], c[2]);
            }
            nerf__buf_printf(&b, "\n");
            continue;
        }
        const size_t size = 12 + (n ? 12 : 0) + (c ? 3 : 0);
        unsigned char *p = nerf__buf_grow(&b, size);
        if (p == NULL) {
            break;
        }
        for (int k = 0; k < 3; k++) {
            nerf__store_lef32(p + 4 * k, v[k]);
        }
        if (n) {
            for (int k = 0; k < 3; k++) {
                nerf__store_lef32(p + 12 + 4 * k, n[k]);
            }
        }
        if (c) {
            memcpy(p + (n ? 24 : 12), c, 3);
        }
    }
    for (size_t f = 0; m->faces && f < m->n_faces; f++) {
        const uint32_t *t = m->faces + 3 * f;
        if (ascii) {
            nerf__buf_printf(&b, "3 %u %u %u\n", (unsigned)t[0], (unsigned)t[1],
                             (unsigned)t[2]);
            continue;
        }
        unsigned char *p = nerf__buf_grow(&b, 13);
        if (p == NULL) {
            break;
        }
        p[0] = 3;
        for (int k = 0; k < 3; k++) {
            nerf__store_le32(p + 1 + 4 * k, t[k]);
        }
    }
    return nerf__buf_save(&b, path);
}

int nerf__mesh_write_obj(const nerf__env *env, const char *path,
                         const nerf__mesh_arrays *m)
{
    nerf__buf b = {env, NULL, 0, 0, false};
    nerf__buf_printf(&b, "# libnerf mesh: %zu vertices, %zu faces\n",
                     m->n_vertices, m->n_faces);
    for (size_t i = 0; i < m->n_vertices && !b.failed; i++) {
        const float *v = m->vertices + 3 * i;
        nerf__buf_printf(&b, "v %.9g %.9g %.9g", (double)v[0], (double)v[1],
                         (double)v[2]);
        if (m->colours) {
            const uint8_t *c = m->colours + 3 * i;
            nerf__buf_printf(&b, " %.4g %.4g %.4g", c[0] / 255.0, c[1] / 255.0,
                             c[2] / 255.0);
        }
        nerf__buf_printf(&b, "\n");
    }
    for (size_t i = 0; m->normals && i < m->n_vertices && !b.failed; i++) {
        const float *n = m->normals + 3 * i;
        nerf__buf_printf(&b, "vn %.6g %.6g %.6g\n", (double)n[0], (double)n[1],
                         (double)n[2]);
    }
    for (size_t f = 0; f < m->n_faces && !b.failed; f++) {
        const uint32_t *t = m->faces + 3 * f;
        const unsigned long a = t[0] + 1ul, c = t[1] + 1ul, d = t[2] + 1ul;
        if (m->normals) {
            nerf__buf_printf(&b, "f %lu//%lu %lu//%lu %lu//%lu\n", a, a, c, c,
                             d, d);
        } else {
            nerf__buf_printf(&b, "f %lu %lu %lu\n", a, c, d);
        }
    }
    return nerf__buf_save(&b, path);
}
