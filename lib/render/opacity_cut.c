/* The density pass of a training batch, in rounds (see opacity_cut.h). */
#include "opacity_cut.h"

#include <string.h>

#include "composite_packed.h"
#include "headroom.h"
#include "parallel.h"

/*
 * Round r takes up to FIRST_PIECE << r more samples of each ray still
 * going.  On lego a ray that meets the object turns opaque a few samples
 * behind its surface; the march goes on through the occupied cells
 * inside it, and most of a step's samples lie behind that point.
 * Small pieces evaluate few of those, but each round costs a network
 * call; doubling bounds the rounds of the long rays through thin matter
 * to a handful.
 */
#define FIRST_PIECE 8u
#define MAX_PIECE 256u

void nerf__opacity_cut_init(nerf__opacity_cut *c, const nerf__env *env)
{
    memset(c, 0, sizeof *c);
    c->env = *env;
}

void nerf__opacity_cut_release(nerf__opacity_cut *c)
{
    nerf__workspace_release(&c->env, &c->ws);
    nerf__free(&c->env, c->ray_block);
    nerf__free(&c->env, c->sample_block);
    nerf__env env = c->env;
    nerf__opacity_cut_init(c, &env);
}

static int reserve_rays(nerf__opacity_cut *c, size_t n)
{
    if (c->ray_block && n <= c->cap_rays) {
        return NERF_OK;
    }
    n = nerf__with_headroom(n);
    const size_t bytes[] = {n * sizeof(float), n * sizeof(uint32_t),
                            (n + 1) * sizeof(size_t)};
    unsigned char *p = nerf__alloc(&c->env, nerf__carve_size(bytes, 3));
    if (p == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(&c->env, c->ray_block);
    c->ray_block = p;
    c->trans = nerf__carve(&p, bytes[0]);
    c->active = nerf__carve(&p, bytes[1]);
    c->start = nerf__carve(&p, bytes[2]);
    c->cap_rays = n;
    return NERF_OK;
}

static int reserve_samples(nerf__opacity_cut *c, const nerf_model *m,
                           size_t n)
{
    if (c->sample_block == NULL || n > c->cap_samples) {
        const size_t cap = nerf__with_headroom(n);
        const size_t bytes[] = {3 * cap * sizeof(float), cap * sizeof(float)};
        float **const slots[] = {&c->pos, &c->sigma};
        int rc = nerf__carve_floats(&c->env, &c->sample_block, slots, bytes,
                                    2);
        if (rc != NERF_OK) {
            return rc;
        }
        c->cap_samples = cap;
    }
    /* The same headroom for the network's workspace, which
     * nerf__model_density() would otherwise size to each round. */
    if (n > c->ws.cap) {
        return nerf__workspace_reserve_density(&c->env, &c->ws, &m->nets[0],
                                               nerf__with_headroom(n));
    }
    return NERF_OK;
}

typedef struct round_job {
    nerf__opacity_cut *c;
    const nerf__march_samples *ms;
    const float *points;
    float eps;
    uint32_t *count;
    float *enc;
    size_t width;     /* floats of a position encoding */
} round_job;

static void gather_points(void *ctx, size_t begin, size_t end)
{
    const round_job *j = ctx;
    const nerf__opacity_cut *c = j->c;
    for (size_t i = begin; i < end; i++) {
        const uint32_t k = c->active[i];
        const size_t from = j->ms->offsets[k] + j->count[k];
        memcpy(c->pos + 3 * c->start[i], j->points + 3 * from,
               3 * (c->start[i + 1] - c->start[i]) * sizeof(float));
    }
}

/* Each going ray through its new samples: how many it uses, their
 * encodings to their rows, and the ray dropped from the next round once
 * opaque or out of samples (active[i] set to UINT32_MAX). */
static void count_round(void *ctx, size_t begin, size_t end)
{
    const round_job *j = ctx;
    nerf__opacity_cut *c = j->c;
    const nerf__march_samples *ms = j->ms;
    for (size_t i = begin; i < end; i++) {
        const uint32_t k = c->active[i];
        const size_t at = ms->offsets[k] + j->count[k];
        const size_t row = c->start[i];
        const uint32_t n = (uint32_t)(c->start[i + 1] - row);
        const uint32_t used = nerf__composite_packed_ray_used(
            n, ms->dt + at, c->sigma + row, j->eps, &c->trans[k]);
        if (j->enc) {
            memcpy(j->enc + at * j->width, c->ws.enc_pos + row * j->width,
                   used * j->width * sizeof(float));
        }
        j->count[k] += used;
        const size_t all = ms->offsets[k + 1] - ms->offsets[k];
        if (c->trans[k] < j->eps || j->count[k] == all) {
            c->active[i] = UINT32_MAX;
        }
    }
}

int nerf__opacity_cut_run(nerf__opacity_cut *c, const nerf_model *m,
                          const nerf__march_samples *ms, const float *points,
                          const nerf__occupancy *zero_in, float eps,
                          uint32_t *count, float *enc)
{
    const size_t n_rays = ms->n_rays;
    c->evaluated = 0;
    c->rounds = 0;
    int rc = reserve_rays(c, n_rays);
    if (rc != NERF_OK) {
        return rc;
    }
    round_job j = {.c = c, .ms = ms, .points = points, .eps = eps,
                   .count = count, .enc = enc, .width = m->nets[0].pos_width};
    size_t going = 0;
    for (size_t k = 0; k < n_rays; k++) {
        count[k] = 0;
        c->trans[k] = 1.0f;
        if (ms->offsets[k + 1] > ms->offsets[k]) {
            c->active[going++] = (uint32_t)k;
        }
    }
    for (size_t piece = FIRST_PIECE; going > 0;
         piece = piece < MAX_PIECE ? 2 * piece : piece) {
        size_t rows = 0;
        for (size_t i = 0; i < going; i++) {
            const uint32_t k = c->active[i];
            const size_t rest = ms->offsets[k + 1] - ms->offsets[k] - count[k];
            c->start[i] = rows;
            rows += rest < piece ? rest : piece;
        }
        c->start[going] = rows;
        rc = reserve_samples(c, m, rows);
        if (rc != NERF_OK) {
            return rc;
        }
        nerf__parallel_for(going, 3 * piece, gather_points, &j);
        /* The weights do not change between the rounds. */
        c->ws.params_unchanged = c->rounds > 0;
        rc = nerf__model_density(m, 0, &c->ws, rows, c->pos, c->sigma);
        c->ws.params_unchanged = false;
        if (rc != NERF_OK) {
            return rc;
        }
        if (zero_in) {
            nerf__occupancy_zero_empty(zero_in, rows, c->pos, c->sigma);
        }
        nerf__parallel_for(going, (4 + j.width / 4) * piece, count_round, &j);
        c->evaluated += rows;
        c->rounds++;
        size_t still = 0;
        for (size_t i = 0; i < going; i++) {
            if (c->active[i] != UINT32_MAX) {
                c->active[still++] = c->active[i];
            }
        }
        going = still;
    }
    return NERF_OK;
}
