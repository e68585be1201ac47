/*
 * Checks on triangle meshes shared by the geometry tests: whether a mesh
 * is closed and consistently wound, its connected components and its
 * Euler characteristic, and its signed volume.
 */
#ifndef NERF_TEST_MESH_CHECK_H
#define NERF_TEST_MESH_CHECK_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct mesh_stats {
    size_t n_edges;      /* distinct undirected edges */
    size_t bad_edges;    /* edges not in exactly two faces */
    size_t misoriented;  /* edges whose two faces run it the same way */
    size_t components;   /* connected components (faces sharing a vertex) */
    long euler;          /* V - E + F over the vertices faces use */
    double volume;       /* signed volume: > 0 for outward-facing normals */
} mesh_stats;

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static uint32_t uf_find(uint32_t *p, uint32_t x)
{
    while (p[x] != x) {
        p[x] = p[p[x]];
        x = p[x];
    }
    return x;
}

static void mesh_stats_compute(const float *v, size_t nv, const uint32_t *f,
                               size_t nf, mesh_stats *s)
{
    memset(s, 0, sizeof *s);
    /* Directed edges a -> b, keyed by (min, max) with the direction in
     * bit 0: a closed, consistently wound mesh has each key pair once
     * with each direction. */
    uint64_t *keys = malloc((3 * nf + 1) * sizeof *keys);
    for (size_t i = 0; i < nf; i++) {
        for (int k = 0; k < 3; k++) {
            uint64_t a = f[3 * i + k], b = f[3 * i + (k + 1) % 3];
            uint64_t lo = a < b ? a : b, hi = a < b ? b : a;
            keys[3 * i + k] = (lo << 33) | (hi << 1) | (a < b ? 0u : 1u);
        }
    }
    qsort(keys, 3 * nf, sizeof *keys, cmp_u64);
    for (size_t i = 0; i < 3 * nf;) {
        size_t j = i;
        while (j < 3 * nf && keys[j] >> 1 == keys[i] >> 1) {
            j++;
        }
        s->n_edges++;
        if (j - i != 2) {
            s->bad_edges++;
        } else if ((keys[i] & 1) == (keys[i + 1] & 1)) {
            s->misoriented++;
        }
        i = j;
    }
    free(keys);
    uint32_t *p = malloc((nv + 1) * sizeof *p);
    char *used = calloc(nv + 1, 1);
    for (size_t i = 0; i < nv; i++) {
        p[i] = (uint32_t)i;
    }
    for (size_t i = 0; i < 3 * nf; i++) {
        used[f[i]] = 1;
        uint32_t a = uf_find(p, f[i - i % 3]), b = uf_find(p, f[i]);
        p[a] = b;
    }
    size_t used_count = 0;
    for (size_t i = 0; i < nv; i++) {
        if (used[i]) {
            used_count++;
            s->components += uf_find(p, (uint32_t)i) == i;
        }
    }
    s->euler = (long)used_count - (long)s->n_edges + (long)nf;
    for (size_t i = 0; i < nf; i++) {
        const float *a = v + 3 * f[3 * i], *b = v + 3 * f[3 * i + 1],
                    *c = v + 3 * f[3 * i + 2];
        s->volume += ((double)a[0] * (b[1] * c[2] - b[2] * c[1]) -
                      (double)a[1] * (b[0] * c[2] - b[2] * c[0]) +
                      (double)a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
    free(p);
    free(used);
}

#endif
