#include "model_field.h"

#include <string.h>

#include "error.h"
#include "gemm.h"
#include "parallel.h"
#include "space.h"

#define CHUNK NERF__FIELD_CHUNK

int nerf__model_field_init(nerf__model_field *f, const nerf_model *model,
                           unsigned threads)
{
    memset(f, 0, sizeof *f);
    f->model = model;
    f->net = model->n_nets > 1 ? 1 : 0;
    const unsigned pool = nerf__parallel_threads();
    /* Each block's products run on the BLAS's threads: over a threaded
     * OpenBLAS, as many blocks as cores would oversubscribe them (the
     * renderer's rule, render/renderer.c). */
    const int blas = nerf__blas_threads();
    unsigned fit = blas > 1 ? pool / (unsigned)blas : pool;
    fit = fit ? fit : 1;
    f->blocks = threads == 0 ? fit : threads > pool ? pool : threads;
    const nerf__env *env = nerf__model_env(model);
    f->ws = nerf__calloc(env, f->blocks, sizeof *f->ws);
    f->mapped = nerf__alloc(env, (size_t)f->blocks * CHUNK * 3 * sizeof(float));
    f->sigma = nerf__alloc(env, (size_t)f->blocks * CHUNK * sizeof(float));
    if (f->ws == NULL || f->mapped == NULL || f->sigma == NULL) {
        nerf__model_field_release(f);
        return NERF_ENOMEM;
    }
    return NERF_OK;
}

void nerf__model_field_release(nerf__model_field *f)
{
    const nerf__env *env = nerf__model_env(f->model);
    if (f->ws) {
        for (unsigned b = 0; b < f->blocks; b++) {
            nerf__workspace_release(env, &f->ws[b]);
        }
    }
    nerf__free(env, f->ws);
    nerf__free(env, f->mapped);
    nerf__free(env, f->sigma);
    f->ws = NULL;
    f->mapped = NULL;
    f->sigma = NULL;
}

typedef struct job {
    nerf__model_field *f;
    size_t n;
    const float *points, *dirs;
    float *out; /* density [n] or rgb [n x 3] (n x views x 3) */
    int colour;
    uint32_t views; /* > 0: colour_views() */
    int status[1024]; /* per block; blocks <= the pool's threads */
} job;

/* Colours of k points (pos) in j->views directions each: the head once a
 * point, its row repeated for each view, then the colour branch. */
static int colour_views(const job *j, nerf__workspace *ws, size_t k,
                        const float *pos, const float *dirs, float *rgb,
                        float *sigma)
{
    const nerf_model *m = j->f->model;
    const size_t rows = k * j->views;
    int rc = nerf__model_reserve(m, j->f->net, ws, rows, false);
    if (rc == NERF_OK) {
        rc = nerf__model_head(m, j->f->net, ws, k, pos, sigma);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    const size_t hw = nerf__network_head_width(&m->nets[j->f->net]);
    /* Backwards, so that no row is overwritten before it is copied. */
    for (size_t p = k; p-- > 0;) {
        for (uint32_t d = j->views; d-- > 0;) {
            const size_t to = p * j->views + d;
            if (to != p) {
                memcpy(ws->head + to * hw, ws->head + p * hw,
                       hw * sizeof(float));
            }
        }
    }
    return nerf__model_colour(m, j->f->net, ws, rows, dirs, rgb);
}

static void run_block(void *ctx, size_t block)
{
    job *j = ctx;
    nerf__model_field *f = j->f;
    const nerf_model *m = f->model;
    const nerf__space *space = nerf__model_space(m);
    const size_t begin = j->n * block / f->blocks;
    const size_t end = j->n * (block + 1) / f->blocks;
    float *mapped = f->mapped + block * CHUNK * 3;
    int rc = NERF_OK;
    /* Points a network call takes: CHUNK rows. */
    const size_t step = j->views ? (CHUNK / j->views ? CHUNK / j->views : 1)
                                 : CHUNK;
    for (size_t at = begin; at < end && rc == NERF_OK; at += step) {
        const size_t k = end - at < step ? end - at : step;
        const float *pos = j->points + 3 * at;
        if (space->kind == NERF__SPACE_CONTRACT) {
            /* World points reach an unbounded model's networks
             * contracted (the identity inside its central cube). */
            for (size_t i = 0; i < k; i++) {
                nerf__space_to_domain(space, pos + 3 * i, mapped + 3 * i);
            }
            pos = mapped;
        }
        if (j->views) {
            rc = colour_views(j, &f->ws[block], k, pos,
                              j->dirs + 3 * at * j->views,
                              j->out + 3 * at * j->views,
                              f->sigma + block * CHUNK);
        } else if (j->colour) {
            rc = nerf__model_evaluate(m, f->net, &f->ws[block], k, pos,
                                      j->dirs + 3 * at, j->out + 3 * at, NULL);
        } else {
            float *sigma = j->out + at;
            rc = nerf__model_density(m, f->net, &f->ws[block], k, pos, sigma);
            if (m->opts.density_activation != NERF_DENSITY_EXP) {
                /* The ReLU that compositing applies to raw density. */
                for (size_t i = 0; i < k; i++) {
                    sigma[i] = sigma[i] > 0.0f ? sigma[i] : 0.0f;
                }
            }
        }
    }
    j->status[block] = rc;
}

static int run(job *j)
{
    nerf__model_field *f = j->f;
    if (f->blocks > sizeof j->status / sizeof j->status[0]) {
        f->blocks = sizeof j->status / sizeof j->status[0];
    }
    /* Small jobs (a few vertices) run on this thread alone. */
    const size_t blocks = j->n < 2 * CHUNK ? 1 : f->blocks;
    const unsigned saved = f->blocks;
    f->blocks = (unsigned)blocks;
    nerf__parallel_blocks(blocks, (size_t)1 << 30, run_block, j);
    f->blocks = saved;
    for (size_t b = 0; b < blocks; b++) {
        if (j->status[b] != NERF_OK) {
            return j->status[b];
        }
    }
    return NERF_OK;
}

/* A job over n points: densities (colour 0, views 0), colours (colour 1)
 * or colours in several views each (views > 0). */
static int run_job(nerf__model_field *f, size_t n, const float *points,
                   const float *dirs, float *out, int colour, uint32_t views)
{
    job j;
    memset(&j, 0, sizeof j);
    j.f = f;
    j.n = n;
    j.points = points;
    j.dirs = dirs;
    j.out = out;
    j.colour = colour;
    j.views = views;
    return run(&j);
}

int nerf__model_field_density(void *ctx, size_t n, const float *points,
                              float *out)
{
    return run_job(ctx, n, points, NULL, out, 0, 0);
}

int nerf__model_field_colour(nerf__model_field *f, size_t n,
                             const float *points, const float *dirs,
                             float *rgb)
{
    return run_job(f, n, points, dirs, rgb, 1, 0);
}

int nerf__model_field_colour_views(nerf__model_field *f, size_t n,
                                   const float *points, uint32_t views,
                                   const float *dirs, float *rgb)
{
    return run_job(f, n, points, dirs, rgb, 1, views);
}
