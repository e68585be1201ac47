/* How far each empty cell of a bake is from a brick (bake.h). */
#include "bake.h"
#include "error.h"

/*
 * Two raster passes of the 26-neighbour chamfer with unit weights, which
 * is exact for the Chebyshev distance: each cell takes one more than the
 * least of its neighbours already visited, forwards then backwards.
 */
static void pass(uint8_t *d, uint32_t r, int dir)
{
    const int64_t n = r;
    for (int64_t q = 0; q < n * n * n; q++) {
        const int64_t i = dir > 0 ? q : n * n * n - 1 - q;
        const int64_t x = i % n, y = i / n % n, z = i / n / n;
        unsigned best = d[i];
        if (best == 0) {
            continue;
        }
        for (int dz = -1; dz <= 1; dz++) {
            for (int dy = -1; dy <= 1; dy++) {
                for (int dx = -1; dx <= 1; dx++) {
                    const int64_t xx = x + dx, yy = y + dy, zz = z + dz;
                    if ((dx | dy | dz) == 0 || xx < 0 || yy < 0 || zz < 0 ||
                        xx >= n || yy >= n || zz >= n) {
                        continue;
                    }
                    const unsigned v = d[xx + n * (yy + n * zz)] + 1u;
                    best = v < best ? v : best;
                }
            }
        }
        d[i] = (uint8_t)best;
    }
}

/* Whether brick cell (x, y, z) touches a cell without a brick, or the
 * grid's side, across a face, an edge or a corner. */
static bool on_surface(const nerf_bake *b, int64_t x, int64_t y, int64_t z)
{
    const int64_t n = b->res;
    for (int dz = -1; dz <= 1; dz++) {
        for (int dy = -1; dy <= 1; dy++) {
            for (int dx = -1; dx <= 1; dx++) {
                const int64_t xx = x + dx, yy = y + dy, zz = z + dz;
                if (xx < 0 || yy < 0 || zz < 0 || xx >= n || yy >= n ||
                    zz >= n || b->brick_of[xx + n * (yy + n * zz)] < 0) {
                    return true;
                }
            }
        }
    }
    return false;
}

/* b->surface: where a ray from outside the bricks meets its first. */
static int surface_cells(nerf_bake *b)
{
    const size_t n = b->res, cells = n * n * n;
    for (int round = 0; round < 2; round++) {
        size_t count = 0;
        for (size_t c = 0; c < cells; c++) {
            if (b->brick_of[c] >= 0 &&
                on_surface(b, (int64_t)(c % n), (int64_t)(c / n % n),
                           (int64_t)(c / n / n))) {
                if (round == 1) {
                    b->surface[count] = (uint32_t)c;
                }
                count++;
            }
        }
        if (round == 0) {
            b->n_surface = count;
            b->surface = nerf__alloc(&b->env,
                                     (count ? count : 1) * sizeof(uint32_t));
            if (b->surface == NULL) {
                return nerf__error(NERF_ENOMEM,
                                   "nerf_bake_create: out of memory");
            }
        }
    }
    return NERF_OK;
}

int nerf__bake_empty_space(nerf_bake *b)
{
    const size_t cells = (size_t)b->res * b->res * b->res;
    b->empty = nerf__alloc(&b->env, cells);
    if (b->empty == NULL) {
        return nerf__error(NERF_ENOMEM, "nerf_bake_create: out of memory");
    }
    uint32_t first[3] = {b->res, b->res, b->res}, last[3] = {0, 0, 0};
    for (size_t c = 0; c < cells; c++) {
        b->empty[c] = b->brick_of[c] >= 0 ? 0 : 255;
        if (b->brick_of[c] >= 0) {
            const uint32_t v[3] = {(uint32_t)(c % b->res),
                                   (uint32_t)(c / b->res % b->res),
                                   (uint32_t)(c / b->res / b->res)};
            for (int a = 0; a < 3; a++) {
                first[a] = v[a] < first[a] ? v[a] : first[a];
                last[a] = v[a] > last[a] ? v[a] : last[a];
            }
        }
    }
    for (int a = 0; a < 3; a++) {
        /* No brick: an empty box, which every ray misses. */
        b->used_lo[a] = b->lo[a] + (float)first[a] * b->cell[a];
        b->used_hi[a] = first[a] > last[a]
                            ? b->used_lo[a]
                            : b->lo[a] + (float)(last[a] + 1) * b->cell[a];
    }
    pass(b->empty, b->res, 1);
    pass(b->empty, b->res, -1);
    return surface_cells(b);
}
