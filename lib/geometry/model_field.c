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
    if (f->ws == NULL || f->mapped == NULL) {
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
    f->ws = NULL;
    f->mapped = NULL;
}

typedef struct job {
    nerf__model_field *f;
    size_t n;
    const float *points, *dirs;
    float *out; /* density [n] or rgb [n x 3] */
    int colour;
    int status[1024]; /* per block; blocks <= the pool's threads */
} job;

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
    for (size_t at = begin; at < end && rc == NERF_OK; at += CHUNK) {
        const size_t k = end - at < CHUNK ? end - at : CHUNK;
        const float *pos = j->points + 3 * at;
        if (space->kind == NERF__SPACE_CONTRACT) {
            /* World points reach an unbounded model's networks
             * contracted (the identity inside its central cube). */
            for (size_t i = 0; i < k; i++) {
                nerf__space_to_domain(space, pos + 3 * i, mapped + 3 * i);
            }
            pos = mapped;
        }
        if (j->colour) {
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

int nerf__model_field_density(void *ctx, size_t n, const float *points,
                              float *out)
{
    job j;
    memset(&j, 0, sizeof j);
    j.f = ctx;
    j.n = n;
    j.points = points;
    j.out = out;
    return run(&j);
}

int nerf__model_field_colour(nerf__model_field *f, size_t n,
                             const float *points, const float *dirs,
                             float *rgb)
{
    job j;
    memset(&j, 0, sizeof j);
    j.f = f;
    j.n = n;
    j.points = points;
    j.dirs = dirs;
    j.out = rgb;
    j.colour = 1;
    return run(&j);
}
