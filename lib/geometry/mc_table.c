#include "mc_table.h"

#include <pthread.h>
#include <stdbool.h>
#include <string.h>

static nerf__mc_case table[256];
static pthread_once_t table_once = PTHREAD_ONCE_INIT;
static int fans; /* loops that had to be fanned */

void nerf__mc_edge_corners(int e, int *a, int *b)
{
    /* Edges of axis `axis` start at the corners whose bit `axis` is 0, in
     * increasing order; the edge's other end sets that bit. */
    const int axis = e / 4, k = e % 4;
    const int lo_mask = (1 << axis) - 1;
    const int start = (k & lo_mask) | ((k & ~lo_mask) << 1);
    *a = start;
    *b = start | (1 << axis);
}

static int edge_between(int a, int b)
{
    const int lo = a < b ? a : b;
    const int axis = (a ^ b) == 1 ? 0 : (a ^ b) == 2 ? 1 : 2;
    const int lo_mask = (1 << axis) - 1;
    const int k = (lo & lo_mask) | ((lo >> 1) & ~lo_mask);
    return axis * 4 + k;
}

/*
 * The corners of the face of `axis` at side `side`, in counter-clockwise
 * order seen from outside the cube.  With u, v the next axes (u x v = the
 * face's axis), (0,0) (1,0) (1,1) (0,1) turns counter-clockwise seen from
 * the + side; the face at side 0 is seen from the - side, so reversed.
 */
static void face_corners(int axis, int side, int out[4])
{
    static const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int i = 0; i < 4; i++) {
        const int *p = uv[side ? i : 3 - i];
        out[i] = (side << axis) | (p[0] << u) | (p[1] << v);
    }
}

/*
 * next[e]: the crossing point the surface's boundary on the cube goes to
 * from crossing edge e.  Along each face, counter-clockwise seen from
 * outside, an edge leaving an inside corner is an exit and one entering
 * an inside corner an entry; the boundary of the inside region, walked
 * with the inside on its left, runs from an exit to an entry.  Walking
 * back from an exit to the first entry keeps diagonal inside corners
 * apart.  Each crossing edge is an exit on one of its faces and an entry
 * on the other (the faces run it in opposite directions), so next[] is a
 * permutation of the crossing edges: its cycles are the loops.
 */
static void face_links(unsigned pattern, int next[12])
{
    for (int axis = 0; axis < 3; axis++) {
        for (int side = 0; side < 2; side++) {
            int c[4];
            face_corners(axis, side, c);
            bool in[4];
            for (int i = 0; i < 4; i++) {
                in[i] = (pattern >> c[i]) & 1u;
            }
            for (int i = 0; i < 4; i++) {
                if (!(in[i] && !in[(i + 1) % 4])) {
                    continue; /* not an exit */
                }
                for (int back = 1; back <= 3; back++) {
                    const int j = (i + 4 - back) % 4;
                    if (!in[j] && in[(j + 1) % 4]) {
                        next[edge_between(c[i], c[(i + 1) % 4])] =
                            edge_between(c[j], c[(j + 1) % 4]);
                        break;
                    }
                }
            }
        }
    }
}

/* Whether cube edges e and f lie on a common face of the cube. */
static bool share_face(int e, int f)
{
    int a, b, c, d;
    nerf__mc_edge_corners(e, &a, &b);
    nerf__mc_edge_corners(f, &c, &d);
    for (int axis = 0; axis < 3; axis++) {
        const int bit = 1 << axis;
        /* Both ends of each edge on the same side of this axis. */
        if ((a & bit) == (b & bit) && (c & bit) == (d & bit) &&
            (a & bit) == (c & bit)) {
            return true;
        }
    }
    return false;
}

/*
 * Whether loop[i..j] (with the chord i-j as its base) can be cut into
 * triangles whose chords join no two points on a common face of the
 * cube.  Such a chord would lie in that face, where the neighbouring
 * cube may draw the same chord: the edge would then have four triangles.
 * ok[i][j] memoises: 0 unknown, 1 possible (via[i][j] the apex), 2 not.
 */
typedef struct poly {
    const int *loop;
    int n;
    uint8_t ok[12][12], via[12][12];
} poly;

static bool chord_allowed(const poly *p, int i, int j)
{
    return j - i == 1 || (i == 0 && j == p->n - 1) ||
           !share_face(p->loop[i], p->loop[j]);
}

static bool can_cut(poly *p, int i, int j)
{
    if (j - i < 2) {
        return true;
    }
    if (p->ok[i][j]) {
        return p->ok[i][j] == 1;
    }
    p->ok[i][j] = 2;
    for (int k = i + 1; k < j; k++) {
        if (chord_allowed(p, i, k) && chord_allowed(p, k, j) &&
            can_cut(p, i, k) && can_cut(p, k, j)) {
            p->ok[i][j] = 1;
            p->via[i][j] = (uint8_t)k;
            break;
        }
    }
    return p->ok[i][j] == 1;
}

/* The loop turns counter-clockwise about the inside (its left side seen
 * from outside the cube), so each triangle is emitted reversed, to wind
 * counter-clockwise seen from the empty side. */
static void emit(const poly *p, int i, int j, nerf__mc_case *out)
{
    if (j - i < 2) {
        return;
    }
    const int k = p->via[i][j];
    uint8_t *t = out->edges[out->n_triangles++];
    t[0] = (uint8_t)p->loop[i];
    t[1] = (uint8_t)p->loop[j];
    t[2] = (uint8_t)p->loop[k];
    emit(p, i, k, out);
    emit(p, k, j, out);
}

static void triangulate(const int *loop, int n, nerf__mc_case *out)
{
    poly p;
    memset(&p, 0, sizeof p);
    p.loop = loop;
    p.n = n;
    if (!can_cut(&p, 0, n - 1)) {
        /* Never happens for the 256 patterns (the tests check it): a
         * fan keeps the table whole regardless. */
        fans++;
        for (int k = 1; k + 1 < n; k++) {
            uint8_t *t = out->edges[out->n_triangles++];
            t[0] = (uint8_t)loop[0];
            t[1] = (uint8_t)loop[k + 1];
            t[2] = (uint8_t)loop[k];
        }
        return;
    }
    emit(&p, 0, n - 1, out);
}

static void build_case(unsigned pattern, nerf__mc_case *out)
{
    int next[12];
    bool crossing[12], seen[12] = {false};
    for (int e = 0; e < 12; e++) {
        int a, b;
        nerf__mc_edge_corners(e, &a, &b);
        crossing[e] = ((pattern >> a) & 1u) != ((pattern >> b) & 1u);
        next[e] = -1;
    }
    face_links(pattern, next);
    memset(out, 0, sizeof *out);
    for (int start = 0; start < 12; start++) {
        if (!crossing[start] || seen[start]) {
            continue;
        }
        int loop[12], n = 0;
        for (int e = start; e >= 0 && !seen[e]; e = next[e]) {
            seen[e] = true;
            loop[n++] = e;
        }
        triangulate(loop, n, out);
    }
}
static void build_table(void)
{
    for (unsigned p = 0; p < 256; p++) {
        build_case(p, &table[p]);
    }
}

const nerf__mc_case *nerf__mc_table(void)
{
    pthread_once(&table_once, build_table);
    return table;
}

int nerf__mc_table_fans(void)
{
    nerf__mc_table();
    return fans;
}
