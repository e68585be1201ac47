/* Filling a bake's bricks from the model's networks (bake.h). */
#include <math.h>

#include "bake.h"
#include "error.h"
#include "model.h"
#include "model_field.h"
#include "occupancy.h"
#include "progress.h"

/* Bricks evaluated together: their corners' densities in one call. */
#define CHUNK_BRICKS 128u
/* Points whose colours are evaluated together (times the directions). */
#define COLOUR_POINTS 1024u
/*
 * A point whose density gives one render step an opacity below this is
 * baked empty (density 0, no colour).  Its light is at most this fraction
 * of a pixel per step, and sparing its colour keeps it out of the
 * density-weighted colours of the samples around it (bake_render.c).
 */
#define MIN_ALPHA 1e-3
/* The cap of view directions a forward-facing bake fits, about -z. */
#define NDC_CAP_RADIANS (60.0 * 3.14159265358979323846 / 180.0)

typedef struct bake_work {
    nerf_bake *b;
    nerf__model_field field;
    uint32_t n_dirs;
    float *dirs, *proj;       /* the fit (nerf__bake_fit_init) */
    float *pts, *sigma;       /* [CHUNK_BRICKS corners] */
    float *cpts;              /* [COLOUR_POINTS]: the dense points */
    float *cdirs, *rgb;       /* [COLOUR_POINTS n_dirs] */
    uint32_t *dense;          /* [COLOUR_POINTS]: their chunk indices */
    uint16_t *out;            /* [CHUNK_BRICKS corners stride] */
    float sigma_min;
} bake_work;

static void work_release(bake_work *w)
{
    const nerf__env *env = &w->b->env;
    nerf__model_field_release(&w->field);
    void *p[] = {w->dirs, w->proj, w->pts, w->sigma, w->cpts, w->cdirs,
                 w->rgb, w->dense, w->out};
    for (size_t i = 0; i < sizeof p / sizeof p[0]; i++) {
        nerf__free(env, p[i]);
    }
}

static int work_init(bake_work *w, nerf_bake *b, const nerf_model *model,
                     const nerf_bake_options *o)
{
    memset(w, 0, sizeof *w);
    w->b = b;
    w->n_dirs = o->directions;
    const nerf__env *env = &b->env;
    int rc = nerf__model_field_init(&w->field, model, 0);
    if (rc == NERF_OK) {
        /* A forward-facing scene is seen only from in front (NDC takes
         * rays looking down -z): the networks' colours in directions no
         * photo saw are guesses, which would spoil the fit of those it
         * saw.  Its cap reaches past the field of view of a phone's
         * camera turned some way about. */
        const double angle = b->ndc ? NDC_CAP_RADIANS : 3.14159265358979323846;
        rc = nerf__bake_fit_init(env, b->degree, w->n_dirs, angle, &w->dirs,
                                 &w->proj);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    const size_t pts = (size_t)CHUNK_BRICKS * b->corners;
    const size_t rows = (size_t)COLOUR_POINTS * w->n_dirs;
    w->pts = nerf__alloc(env, pts * 3 * sizeof(float));
    w->sigma = nerf__alloc(env, pts * sizeof(float));
    w->cpts = nerf__alloc(env, (size_t)COLOUR_POINTS * 3 * sizeof(float));
    w->cdirs = nerf__alloc(env, rows * 3 * sizeof(float));
    w->rgb = nerf__alloc(env, rows * 3 * sizeof(float));
    w->dense = nerf__alloc(env, COLOUR_POINTS * sizeof(uint32_t));
    w->out = nerf__alloc(env, pts * b->stride * sizeof(uint16_t));
    if (!w->pts || !w->sigma || !w->cpts || !w->cdirs || !w->rgb ||
        !w->dense || !w->out) {
        return nerf__error(NERF_ENOMEM, "nerf_bake_create: out of memory");
    }
    w->sigma_min = (float)(-log(1.0 - MIN_ALPHA) / b->step);
    /* The directions repeat for every point of a colour call. */
    for (size_t r = 0; r < rows; r++) {
        memcpy(w->cdirs + 3 * r, w->dirs + 3 * (r % w->n_dirs),
               3 * sizeof(float));
    }
    return NERF_OK;
}

/* The corners of the bricks of cells[0 .. n) into w->pts. */
static void corner_points(const bake_work *w, const uint32_t *cells,
                          size_t n)
{
    const nerf_bake *b = w->b;
    const uint32_t k = b->k, e = k + 1, r = b->res;
    float *p = w->pts;
    for (size_t i = 0; i < n; i++) {
        const uint32_t c[3] = {cells[i] % r, cells[i] / r % r, cells[i] / r / r};
        for (uint32_t z = 0; z < e; z++) {
            for (uint32_t y = 0; y < e; y++) {
                for (uint32_t x = 0; x < e; x++) {
                    const uint32_t v[3] = {c[0] * k + x, c[1] * k + y,
                                           c[2] * k + z};
                    for (int a = 0; a < 3; a++) {
                        /* Voxel corners of the whole lattice, so that
                         * neighbouring bricks share their faces' points
                         * exactly. */
                        p[a] = b->lo[a] + (b->hi[a] - b->lo[a]) *
                                              ((float)v[a] / (float)(r * k));
                    }
                    p += 3;
                }
            }
        }
    }
}

/* Colours of the m dense points listed in w->dense, fitted, into w->out. */
static int fit_colours(bake_work *w, uint32_t m)
{
    nerf_bake *b = w->b;
    const uint32_t nd = w->n_dirs, nc = b->coefs;
    for (uint32_t i = 0; i < m; i++) {
        memcpy(w->cpts + 3 * (size_t)i, w->pts + 3 * (size_t)w->dense[i],
               3 * sizeof(float));
    }
    int rc = nerf__model_field_colour_views(&w->field, m, w->cpts, nd,
                                            w->cdirs, w->rgb);
    if (rc != NERF_OK) {
        return rc;
    }
    for (uint32_t i = 0; i < m; i++) {
        uint16_t *out = w->out + (size_t)w->dense[i] * b->stride;
        const float *rgb = w->rgb + (size_t)i * nd * 3;
        for (uint32_t c = 0; c < 3; c++) {
            for (uint32_t q = 0; q < nc; q++) {
                const float *row = w->proj + (size_t)q * nd;
                float s = 0.0f;
                for (uint32_t d = 0; d < nd; d++) {
                    s += row[d] * rgb[3 * d + c];
                }
                out[1 + c * nc + q] = nerf__bf16_from(s);
            }
        }
    }
    return NERF_OK;
}

/* Bake the n bricks of cells into w->out; kept[i] says whether brick i
 * has a point with density. */
static int bake_chunk(bake_work *w, const uint32_t *cells, size_t n,
                      bool *kept)
{
    nerf_bake *b = w->b;
    const size_t pts = n * b->corners;
    corner_points(w, cells, n);
    int rc = nerf__model_field_density(&w->field, pts, w->pts, w->sigma);
    if (rc != NERF_OK) {
        return rc;
    }
    memset(w->out, 0, pts * b->stride * sizeof(uint16_t));
    uint32_t m = 0;
    for (size_t i = 0; i < n; i++) {
        kept[i] = false;
    }
    for (size_t p = 0; p < pts && rc == NERF_OK; p++) {
        const float s = w->sigma[p];
        /* NaN counts as empty, as in the occupancy grid. */
        if (!(s > w->sigma_min)) {
            continue;
        }
        w->out[p * b->stride] = nerf__bf16_from(s);
        kept[p / b->corners] = true;
        w->dense[m++] = (uint32_t)p;
        b->points++;
        if (m == COLOUR_POINTS) {
            rc = fit_colours(w, m);
            m = 0;
        }
    }
    if (rc == NERF_OK && m > 0) {
        rc = fit_colours(w, m);
    }
    return rc;
}

static int report(const nerf_bake_options *o, uint64_t done, uint64_t total,
                  double start)
{
    if (nerf__progress_report(o->progress, o->progress_user,
                              NERF_PROGRESS_BAKE, done, total, start) != 0) {
        return nerf__error(NERF_ECANCELLED, "nerf_bake_create: cancelled");
    }
    return NERF_OK;
}

int nerf__bake_bricks(nerf_bake *b, const nerf_model *model,
                      const nerf_bake_options *o)
{
    const nerf__occupancy *g = nerf__model_grid(model);
    const nerf__env *env = &b->env;
    const size_t cells = g->cells;
    size_t occupied = 0;
    for (size_t w = 0; w < g->words; w++) {
        occupied += (size_t)__builtin_popcountll(g->bits[w]);
    }
    const size_t brick_bytes = (size_t)b->corners * b->stride * sizeof(uint16_t);
    const double need = (double)occupied * brick_bytes + 4.0 * cells;
    if (need > (double)o->max_bytes) {
        return nerf__error(NERF_ENOMEM, "nerf_bake_create: %zu occupied cells "
                           "at %u subdivisions would take up to %.0f MB, "
                           "above max_bytes (%.0f MB): lower subdivisions or "
                           "sh_degree, or raise max_bytes", occupied,
                           (unsigned)b->k, need / 1e6,
                           (double)o->max_bytes / 1e6);
    }
    b->brick_of = nerf__alloc(env, cells * sizeof(int32_t));
    uint32_t *list = nerf__alloc(env, (occupied ? occupied : 1) *
                                          sizeof(uint32_t));
    uint16_t *data = nerf__alloc(env, (occupied ? occupied : 1) * brick_bytes);
    if (b->brick_of == NULL || list == NULL || data == NULL) {
        nerf__free(env, list);
        nerf__free(env, data);
        return nerf__error(NERF_ENOMEM, "nerf_bake_create: out of memory "
                           "for %zu bricks", occupied);
    }
    size_t n_list = 0;
    for (size_t c = 0; c < cells; c++) {
        b->brick_of[c] = -1;
        if (g->bits[c / 64] >> (c % 64) & 1u) {
            list[n_list++] = (uint32_t)c;
        }
    }
    bake_work w;
    int rc = work_init(&w, b, model, o);
    const double start = nerf__seconds();
    bool kept[CHUNK_BRICKS];
    for (size_t at = 0; rc == NERF_OK && at < n_list; at += CHUNK_BRICKS) {
        const size_t n = n_list - at < CHUNK_BRICKS ? n_list - at
                                                    : CHUNK_BRICKS;
        rc = bake_chunk(&w, list + at, n, kept);
        for (size_t i = 0; rc == NERF_OK && i < n; i++) {
            if (kept[i]) {
                memcpy(data + b->bricks * (brick_bytes / sizeof(uint16_t)),
                       w.out + i * (brick_bytes / sizeof(uint16_t)),
                       brick_bytes);
                b->brick_of[list[at + i]] = (int32_t)b->bricks++;
            }
        }
        if (rc == NERF_OK) {
            rc = report(o, at + n, n_list, start);
        }
    }
    work_release(&w);
    nerf__free(env, list);
    if (rc == NERF_OK && b->bricks < occupied) {
        /* Keep only the bricks with density. */
        uint16_t *fit = nerf__alloc(env, (b->bricks ? b->bricks : 1) *
                                             brick_bytes);
        if (fit == NULL) {
            rc = nerf__error(NERF_ENOMEM, "nerf_bake_create: out of memory");
        } else {
            memcpy(fit, data, b->bricks * brick_bytes);
            nerf__free(env, data);
            data = fit;
        }
    }
    if (rc != NERF_OK) {
        nerf__free(env, data);
        return rc;
    }
    b->data = data;
    return NERF_OK;
}
