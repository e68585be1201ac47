/* PLY output of point clouds, written whole through a temporary file. */
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "byteorder.h"
#include "file_io.h"
#include "points.h"

/* Bytes of one binary vertex: six floats and three uchars. */
#define VERTEX_BYTES 27

static int header(char *buf, size_t size, const char *format, size_t count)
{
    return snprintf(buf, size,
                    "ply\n"
                    "format %s 1.0\n"
                    "comment libnerf point cloud: normal 0 0 0 means none\n"
                    "element vertex %zu\n"
                    "property float x\n"
                    "property float y\n"
                    "property float z\n"
                    "property float nx\n"
                    "property float ny\n"
                    "property float nz\n"
                    "property uchar red\n"
                    "property uchar green\n"
                    "property uchar blue\n"
                    "end_header\n",
                    format, count);
}

static unsigned char *binary_body(const nerf_points *p, size_t *size)
{
    unsigned char *b = nerf__alloc(&p->env, p->count * VERTEX_BYTES + 1);
    if (b == NULL) {
        return NULL;
    }
    for (size_t i = 0; i < p->count; i++) {
        unsigned char *v = b + i * VERTEX_BYTES;
        for (int c = 0; c < 3; c++) {
            nerf__store_lef32(v + 4 * c, p->positions[3 * i + c]);
            nerf__store_lef32(v + 12 + 4 * c, p->normals[3 * i + c]);
            v[24 + c] = p->colours[3 * i + c];
        }
    }
    *size = p->count * VERTEX_BYTES;
    return b;
}

/* %.9g round-trips a float; a line is at most about 6 x 16 + 12 chars. */
#define ASCII_LINE 128

static unsigned char *ascii_body(const nerf_points *p, size_t *size)
{
    char *b = nerf__alloc(&p->env, p->count * ASCII_LINE + 1);
    if (b == NULL) {
        return NULL;
    }
    size_t at = 0;
    for (size_t i = 0; i < p->count; i++) {
        const float *x = p->positions + 3 * i, *n = p->normals + 3 * i;
        const uint8_t *c = p->colours + 3 * i;
        int len = snprintf(b + at, ASCII_LINE,
                           "%.9g %.9g %.9g %.9g %.9g %.9g %u %u %u\n",
                           (double)x[0], (double)x[1], (double)x[2],
                           (double)n[0], (double)n[1], (double)n[2],
                           (unsigned)c[0], (unsigned)c[1], (unsigned)c[2]);
        at += len > 0 && len < ASCII_LINE ? (size_t)len : 0;
    }
    *size = at;
    return (unsigned char *)b;
}

NERF_API int nerf_points_write(const nerf_points *points, const char *path,
                               int format)
{
    static const char fn[] = "nerf_points_write";
    if (points == NULL || path == NULL) {
        return nerf__error(NERF_EINVAL, "%s: points and path must not be "
                           "NULL", fn);
    }
    if (format != NERF_POINTS_PLY_BINARY && format != NERF_POINTS_PLY_ASCII) {
        return nerf__error(NERF_EINVAL, "%s: %s: unknown format %d", fn,
                           path, format);
    }
    const bool ascii = format == NERF_POINTS_PLY_ASCII;
    char head[640];
    int len = header(head, sizeof head,
                     ascii ? "ascii" : "binary_little_endian",
                     points->count);
    if (len < 0 || (size_t)len >= sizeof head) {
        return nerf__error(NERF_EINVAL, "%s: %s: header too long", fn, path);
    }
    size_t size = 0;
    unsigned char *body = ascii ? ascii_body(points, &size)
                                : binary_body(points, &size);
    if (body == NULL) {
        return NERF_ENOMEM;
    }
    nerf__span parts[2] = {{head, (size_t)len}, {body, size}};
    int rc = nerf__file_write_atomic(&points->env, path, parts, 2);
    nerf__free(&points->env, body);
    return rc;
}
