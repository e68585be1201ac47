#include "mesh.h"

#include <math.h>
#include <string.h>

#include "error.h"

int nerf__mesh_create(const nerf__env *env, nerf_mesh **out)
{
    nerf_mesh *m = nerf__calloc(env, 1, sizeof *m);
    if (m == NULL) {
        return NERF_ENOMEM;
    }
    m->env = *env;
    *out = m;
    return NERF_OK;
}

/* Grow *array of *cap items of item_size bytes to hold `need` items. */
static int grow(const nerf__env *env, void **array, size_t *cap, size_t need,
                size_t item_size)
{
    if (need <= *cap) {
        return NERF_OK;
    }
    size_t cap2 = *cap ? *cap : 1024;
    while (cap2 < need) {
        cap2 *= 2;
    }
    void *p = nerf__alloc(env, cap2 * item_size);
    if (p == NULL) {
        return NERF_ENOMEM;
    }
    if (*array) {
        memcpy(p, *array, *cap * item_size);
        nerf__free(env, *array);
    }
    *array = p;
    *cap = cap2;
    return NERF_OK;
}

int nerf__mesh_add_vertex(nerf_mesh *m, const float p[3], uint32_t *index)
{
    if (m->n_vertices >= UINT32_MAX) {
        return nerf__error(NERF_EINVAL, "mesh: more than 2^32 - 1 vertices; "
                           "lower the resolution");
    }
    void *v = m->vertices;
    int rc = grow(&m->env, &v, &m->cap_vertices, m->n_vertices + 1,
                  3 * sizeof(float));
    m->vertices = v;
    if (rc != NERF_OK) {
        return rc;
    }
    memcpy(m->vertices + 3 * m->n_vertices, p, 3 * sizeof(float));
    *index = (uint32_t)m->n_vertices++;
    return NERF_OK;
}

int nerf__mesh_add_face(nerf_mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    void *f = m->faces;
    int rc = grow(&m->env, &f, &m->cap_faces, m->n_faces + 1,
                  3 * sizeof(uint32_t));
    m->faces = f;
    if (rc != NERF_OK) {
        return rc;
    }
    uint32_t *t = m->faces + 3 * m->n_faces++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    return NERF_OK;
}

int nerf__mesh_compute_normals(nerf_mesh *m)
{
    if (m->normals == NULL) {
        m->normals = nerf__alloc(&m->env,
                                 3 * m->n_vertices * sizeof(float) + 1);
        if (m->normals == NULL) {
            return NERF_ENOMEM;
        }
    }
    float *n = m->normals;
    memset(n, 0, 3 * m->n_vertices * sizeof(float));
    for (size_t f = 0; f < m->n_faces; f++) {
        const uint32_t *t = m->faces + 3 * f;
        const float *a = m->vertices + 3 * t[0];
        const float *b = m->vertices + 3 * t[1];
        const float *c = m->vertices + 3 * t[2];
        float u[3], v[3], w[3];
        for (int k = 0; k < 3; k++) {
            u[k] = b[k] - a[k];
            v[k] = c[k] - a[k];
        }
        /* |u x v| is twice the area: the weight comes for free. */
        w[0] = u[1] * v[2] - u[2] * v[1];
        w[1] = u[2] * v[0] - u[0] * v[2];
        w[2] = u[0] * v[1] - u[1] * v[0];
        for (int i = 0; i < 3; i++) {
            for (int k = 0; k < 3; k++) {
                n[3 * t[i] + k] += w[k];
            }
        }
    }
    for (size_t i = 0; i < m->n_vertices; i++) {
        float *p = n + 3 * i;
        const float len = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        const float s = len > 0.0f && isfinite(len) ? 1.0f / len : 0.0f;
        for (int k = 0; k < 3; k++) {
            p[k] *= s;
        }
    }
    return NERF_OK;
}

static uint32_t find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]]; /* path halving */
        x = parent[x];
    }
    return x;
}

/* Move the items of `array` (n x item_size) at the kept indices to the
 * front, in order: remap[i] is the new index of item i, or UINT32_MAX. */
static void compact(void *array, size_t item_size, size_t n,
                    const uint32_t *remap)
{
    if (array == NULL) {
        return;
    }
    unsigned char *a = array;
    for (size_t i = 0; i < n; i++) {
        if (remap[i] != UINT32_MAX && remap[i] != i) {
            memmove(a + remap[i] * item_size, a + i * item_size, item_size);
        }
    }
}

int nerf__mesh_filter_components(nerf_mesh *m, int keep_largest,
                                 size_t min_faces)
{
    if (!keep_largest && min_faces <= 1) {
        return NERF_OK;
    }
    const size_t nv = m->n_vertices;
    uint32_t *parent = nerf__alloc(&m->env, nv * sizeof(uint32_t) + 1);
    uint32_t *count = nerf__calloc(&m->env, nv + 1, sizeof(uint32_t));
    if (parent == NULL || count == NULL) {
        nerf__free(&m->env, parent);
        nerf__free(&m->env, count);
        return NERF_ENOMEM;
    }
    for (size_t i = 0; i < nv; i++) {
        parent[i] = (uint32_t)i;
    }
    for (size_t f = 0; f < m->n_faces; f++) {
        const uint32_t *t = m->faces + 3 * f;
        for (int k = 1; k < 3; k++) {
            uint32_t a = find(parent, t[0]), b = find(parent, t[k]);
            if (a != b) {
                parent[a < b ? b : a] = a < b ? a : b;
            }
        }
    }
    uint32_t largest = UINT32_MAX;
    for (size_t f = 0; f < m->n_faces; f++) {
        const uint32_t r = find(parent, m->faces[3 * f]);
        count[r]++;
    }
    for (size_t i = 0; i < nv; i++) {
        if (count[i] && (largest == UINT32_MAX || count[i] > count[largest])) {
            largest = (uint32_t)i;
        }
    }
    /* Faces first: count[] is reused as the vertex remap afterwards. */
    size_t kept = 0;
    for (size_t f = 0; f < m->n_faces; f++) {
        const uint32_t *t = m->faces + 3 * f;
        const uint32_t r = find(parent, t[0]);
        const int keep = count[r] >= min_faces &&
                         (!keep_largest || r == largest);
        if (keep) {
            memmove(m->faces + 3 * kept, t, 3 * sizeof(uint32_t));
            kept++;
        }
    }
    m->n_faces = kept;
    uint32_t *remap = count;
    for (size_t i = 0; i < nv; i++) {
        remap[i] = UINT32_MAX;
    }
    for (size_t f = 0; f < 3 * m->n_faces; f++) {
        remap[m->faces[f]] = 0;
    }
    uint32_t next = 0;
    for (size_t i = 0; i < nv; i++) {
        if (remap[i] == 0) {
            remap[i] = next++;
        }
    }
    compact(m->vertices, 3 * sizeof(float), nv, remap);
    compact(m->normals, 3 * sizeof(float), nv, remap);
    compact(m->colours, 3, nv, remap);
    for (size_t f = 0; f < 3 * m->n_faces; f++) {
        m->faces[f] = remap[m->faces[f]];
    }
    m->n_vertices = next;
    nerf__free(&m->env, parent);
    nerf__free(&m->env, count);
    return NERF_OK;
}
