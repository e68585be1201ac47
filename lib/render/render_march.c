/*
 * The marching engine of a render batch (render_march.h).  See
 * render_batch.h for when each of its two forms runs.
 */
#include "render_march.h"

#include <math.h>
#include <string.h>

#include "headroom.h"
#include "parallel.h"
#include "render_batch.h"

/*
 * Rendering marches in pieces: each round marches every ray still going
 * by about PIECE_BUDGET / (rays going) more samples (within [PIECE_MIN,
 * PIECE_MAX]), evaluates and composites them.  Behind a hard surface a ray
 * is opaque after a few samples in occupied cells, and many rays have
 * none at all, so with 64-ray blocks the first rounds of 4 samples a ray
 * end most of them.  The samples of a piece past the point where its ray
 * turned opaque cost a density for nothing (not a colour: see
 * evaluate_used()), and each round costs a march and a network call.  On
 * a trained lego model larger pieces evaluate many samples past opacity
 * and smaller ones need more rounds; in bench_render_model pieces of 4 to
 * 8 rendered fastest, and with the colours of those samples spared,
 * larger pieces were still no faster (docs/perf-log/
 * 2026-11-26-rendering-a-trained-fast-model.md and
 * 2026-11-30-0.10.8-to-0.10.10-amd-epyc.md, "0.10.10").
 */
#define PIECE_BUDGET 256u
#define PIECE_MIN 4u
#define PIECE_MAX 8u

void nerf__march_state_init(nerf__march_state *st, const nerf__env *env)
{
    memset(st, 0, sizeof *st);
    nerf__march_samples_init(&st->samples, env);
}

void nerf__march_state_release(nerf__march_state *st, const nerf__env *env)
{
    nerf__march_samples_release(&st->samples);
    nerf__opacity_cut_release(&st->cut);
    nerf__free(env, st->packed_block);
    nerf__free(env, st->ray_block);
    nerf__march_state_init(st, env);
}

void nerf__march_state_bind(nerf__march_state *st,
                            const nerf__env *model_env)
{
    nerf__opacity_cut_release(&st->cut);
    nerf__opacity_cut_init(&st->cut, model_env);
}

void nerf__batch_set_march_test(nerf__batch *b, const nerf__march_test *t)
{
    static const nerf__march_test none = {0};
    b->marching.test = t ? *t : none;
}

/* The per-sample arrays for n samples (gradients too with keep). */
static int reserve_packed(nerf__batch *b, size_t n, bool keep)
{
    nerf__march_state *st = &b->marching;
    if (st->packed_block && n <= st->cap_packed &&
        (st->cap_packed_keep || !keep)) {
        return NERF_OK;
    }
    size_t cap = nerf__with_headroom(n);
    if (cap > ((size_t)1 << 26)) {
        return nerf__error(NERF_EINVAL, "render batch of %zu marched samples "
                           "is too large", n);
    }
    float **slots[] = {&st->points, &st->dirs, &st->rgb, &st->sigma,
                       &st->d_rgb, &st->d_sigma};
    const size_t f = sizeof(float);
    const size_t bytes[] = {3 * cap * f, 3 * cap * f, 3 * cap * f, cap * f,
                            keep ? 3 * cap * f : 0, keep ? cap * f : 0};
    int rc = nerf__carve_floats(&b->env, &st->packed_block, slots, bytes,
                                sizeof bytes / sizeof bytes[0]);
    if (rc != NERF_OK) {
        return rc;
    }
    st->cap_packed = cap;
    st->cap_packed_keep = keep;
    return NERF_OK;
}

/* The per-ray state of a render in pieces. */
static int reserve_rays(nerf__batch *b, size_t n)
{
    nerf__march_state *st = &b->marching;
    if (st->ray_block && n <= st->cap_rays) {
        return NERF_OK;
    }
    const size_t bytes[] = {
        n * sizeof(nerf__composite_state), n * sizeof(uint32_t),
        n * sizeof(uint32_t), n * sizeof(uint32_t), n * sizeof(uint32_t),
        3 * n * sizeof(float), 3 * n * sizeof(float), 3 * n * sizeof(float),
    };
    enum { N_ARRAYS = sizeof bytes / sizeof bytes[0] };
    unsigned char *p = nerf__alloc(&b->env, nerf__carve_size(bytes, N_ARRAYS));
    if (p == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(&b->env, st->ray_block);
    st->ray_block = p;
    void *at[N_ARRAYS];
    for (size_t i = 0; i < N_ARRAYS; i++) {
        at[i] = nerf__carve(&p, bytes[i]);
    }
    st->ray_state = at[0];
    st->ray_first = at[1];
    st->ray_count = at[2];
    st->active = at[3];
    st->active_first = at[4];
    st->active_o = at[5];
    st->active_d = at[6];
    st->active_view = at[7];
    st->cap_rays = n;
    return NERF_OK;
}

void nerf__render_march_options(const nerf__render_setup *s,
                                const nerf__occupancy *g,
                                nerf__march_options *mo)
{
    const nerf_sampler_options *so = &s->sampler->opts;
    nerf__march_defaults(mo, g);
    mo->step = nerf__march_step(g->lo, g->hi, so->march_steps);
    mo->max_samples = so->max_samples;
    /* Ray first_ray + k draws its offset from the stream (seed, ray), as
     * every other per-ray draw; the trainer's rays are numbered across
     * steps, so each step draws afresh. */
    mo->jitter = s->training && so->perturb;
    mo->seed = nerf__stream_seed(so->seed, NERF__STREAM_MARCH);
    mo->iteration = 0;
    const nerf__space *space = nerf__model_space(s->model);
    mo->contract = space->kind == NERF__SPACE_CONTRACT ? space->inner : 0.0f;
}

/* The marcher's settings for a batch of b: the setup's, and a test's. */
static void march_options(const nerf__batch *b, const nerf__render_setup *s,
                          const nerf__occupancy *g, nerf__march_options *mo)
{
    nerf__render_march_options(s, g, mo);
    mo->skip_empty = !b->marching.test.everywhere;
}

/* What the loops over rays and samples below read; each writes only the
 * rows of its own rays or samples. */
typedef struct march_job {
    nerf__batch *b;
    const nerf__march_rays *rays;
    const float *viewdir; /* [rays->n, 3] unit directions of those rays */
    uint32_t max_samples;
    const nerf__march_options *mo;
} march_job;

/* Unit view directions of the caller's rays, into b->viewdir. */
static void view_dirs(void *ctx, size_t begin, size_t end)
{
    const march_job *j = ctx;
    nerf__batch *b = j->b;
    const float *d = j->rays->dirs;
    for (size_t k = begin; k < end; k++) {
        const float *dk = d + 3 * k;
        float len = sqrtf(dk[0] * dk[0] + dk[1] * dk[1] + dk[2] * dk[2]);
        for (int c = 0; c < 3; c++) {
            b->viewdir[3 * k + c] = dk[c] / len;
        }
        b->dir_norm[k] = len;
    }
}

/* Each packed sample gets its ray's view direction.  viewdir is indexed
 * by the rays of j->rays. */
static void sample_dirs(void *ctx, size_t begin, size_t end)
{
    const march_job *j = ctx;
    nerf__march_state *st = &j->b->marching;
    const size_t *off = st->samples.offsets;
    for (size_t k = begin; k < end; k++) {
        const float *v = j->viewdir + 3 * k;
        for (size_t i = off[k]; i < off[k + 1]; i++) {
            memcpy(st->dirs + 3 * i, v, 3 * sizeof(float));
        }
    }
}

/* The network's workspace for n samples.  Workspaces grow with headroom,
 * so that sample counts that vary from batch to batch do not reallocate
 * every time (and a cut batch finds the room its density pass took). */
static int reserve_workspace(nerf__batch *b, const nerf_model *m, size_t n,
                             bool keep)
{
    nerf__workspace *ws = &b->ws[0];
    if (n > ws->cap || (keep && !ws->keep)) {
        return nerf__model_reserve(m, 0, ws, nerf__with_headroom(n), keep);
    }
    return NERF_OK;
}

/* The packed samples' points, and the room for the network on them. */
static int place_samples(nerf__batch *b, const nerf__render_setup *s,
                         const march_job *j, bool keep)
{
    nerf__march_state *st = &b->marching;
    const size_t total = st->samples.total;
    int rc = reserve_packed(b, total, keep);
    if (rc != NERF_OK || total == 0) {
        return rc;
    }
    nerf__march_points(j->mo, j->rays, st->samples.offsets, st->samples.t,
                       st->points);
    return reserve_workspace(b, s->model, total, keep);
}

/* The packed samples' view directions, or NULL if the model takes none. */
static const float *sample_directions(nerf__batch *b,
                                      const nerf__render_setup *s,
                                      const march_job *j)
{
    if (!nerf__model_uses_viewdirs(s->model)) {
        return NULL;
    }
    const size_t n = j->rays->n;
    nerf__parallel_for(n, 6 * (b->marching.samples.total / n + 1),
                       sample_dirs, (void *)j);
    return b->marching.dirs;
}

/* Training's forward over the batch's packed samples, activations kept. */
static int forward(nerf__batch *b, const nerf__render_setup *s,
                   const march_job *j)
{
    const nerf_model *m = s->model;
    nerf__march_state *st = &b->marching;
    const size_t total = st->samples.total;
    int rc = place_samples(b, s, j, true);
    if (rc != NERF_OK || total == 0) {
        return rc;
    }
    rc = nerf__model_forward(m, 0, &b->ws[0], total, st->points,
                             sample_directions(b, s, j), st->rgb, st->sigma);
    if (rc == NERF_OK && st->test.zero_empty) {
        nerf__occupancy_zero_empty(nerf__model_grid(m), total, st->points,
                                   st->sigma);
    }
    return rc;
}

static float disparity_of(float depth, float opacity)
{
    /* As composite.c: an empty ray's 0 / 0 gives 1e10. */
    return 1.0f / fmaxf(1e-10f, depth / opacity);
}

/* The fewest first rays whose samples reach `budget` (all if they never
 * do, at least one), and the marched batch cut to them. */
static size_t cut_to_budget(nerf__march_samples *ms, size_t budget)
{
    size_t n = 1;
    while (n < ms->n_rays && ms->offsets[n] < budget) {
        n++;
    }
    n = n < ms->n_rays ? n : ms->n_rays;
    ms->n_rays = n;
    ms->total = ms->offsets[n];
    return n;
}

/* Move `count` rows of `width` floats from row `from` to row `to`. */
static void move_rows(float *rows, size_t width, size_t to, size_t from,
                      size_t count)
{
    memmove(rows + to * width, rows + from * width,
            count * width * sizeof(float));
}

/*
 * Each ray's samples cut where compositing will stop.  Behind a surface a
 * ray turns opaque and its later samples get no gradient, yet the march
 * goes on through the occupied cells inside the object: on lego, after
 * the first steps, most of a step's samples (docs/perf-log/
 * 2026-11-27-0.9-to-0.10.2.md, "0.10.1").  A density pass in
 * rounds (opacity_cut.h) finds where each ray stops, evaluating few of
 * the samples behind, and the forward and backward that keep activations
 * run on the samples before alone.  The densities are the ones the full
 * forward computes, so the composite stops at the same sample.  The
 * pass's position encodings of the kept samples go to the forward's
 * workspace, so the forward does not compute them again.
 */
static int cut_where_opaque(nerf__batch *b, const nerf__render_setup *s,
                            const march_job *j)
{
    nerf__march_state *st = &b->marching;
    nerf__march_samples *ms = &st->samples;
    const size_t total = ms->total, n = j->rays->n;
    const nerf_model *m = s->model;
    nerf__workspace *ws = &b->ws[0];
    if (total == 0) {
        return NERF_OK;
    }
    int rc = reserve_packed(b, total, true);
    if (rc == NERF_OK) {
        rc = reserve_rays(b, n);
    }
    if (rc == NERF_OK) {
        rc = reserve_workspace(b, m, total, true);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__march_points(j->mo, j->rays, ms->offsets, ms->t, st->points);
    rc = nerf__opacity_cut_run(
        &st->cut, m, ms, st->points,
        st->test.zero_empty ? nerf__model_grid(m) : NULL,
        NERF__COMPOSITE_EPS_DEFAULT, st->ray_count, ws->enc_pos);
    if (rc != NERF_OK) {
        return rc;
    }
    b->n_evaluated += total;
    /* Each ray's kept samples are a prefix of its own, so moving them
     * down in ray order never overwrites one not yet moved. */
    const size_t E = m->nets[0].pos_width;
    size_t w = 0;
    for (size_t k = 0; k < n; k++) {
        const size_t at = ms->offsets[k], used = st->ray_count[k];
        if (at != w) {
            move_rows(ms->t, 1, w, at, used);
            move_rows(ms->dt, 1, w, at, used);
            move_rows(ws->enc_pos, E, w, at, used);
        }
        if (ws->pos) {
            memcpy(ws->pos + 3 * w, st->points + 3 * at,
                   3 * used * sizeof(float));
        }
        ms->offsets[k] = w;
        w += used;
    }
    ms->offsets[n] = w;
    ms->total = w;
    ws->encoded = w;
    return NERF_OK;
}

/* Training: every ray marched in full and cut where it turns opaque, one
 * forward, one composite. */
static int march_whole(nerf__batch *b, const nerf__render_setup *s,
                       const nerf__march_rays *all, const nerf__pass_out *out)
{
    nerf__march_state *st = &b->marching;
    nerf__march_samples *ms = &st->samples;
    const nerf__occupancy *g = nerf__model_grid(s->model);
    nerf__march_options mo;
    march_options(b, s, g, &mo);
    int rc = nerf__march_run(g, &mo, all, ms);
    /* The rays kept: a prefix, so their draws are the same as without a
     * budget. */
    nerf__march_rays kept = *all;
    const nerf__march_rays *rays = &kept;
    if (rc == NERF_OK && s->sample_budget > 0) {
        kept.n = cut_to_budget(ms, s->sample_budget);
        b->n_rays = kept.n;
    }
    march_job j = {.b = b, .rays = rays, .viewdir = b->viewdir, .mo = &mo};
    if (rc == NERF_OK) {
        rc = cut_where_opaque(b, s, &j);
    }
    if (rc == NERF_OK) {
        rc = forward(b, s, &j);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    st->packed = (nerf__packed_batch){
        .n_rays = rays->n, .offsets = ms->offsets, .t = ms->t, .dt = ms->dt,
        .rgb = st->rgb, .sigma = st->sigma,
        .bg = b->ray_bg ? b->ray_bg : b->white ? st->bg : NULL,
        .bg_stride = b->ray_bg ? 3 : 0,
        .eps = NERF__COMPOSITE_EPS_DEFAULT};
    nerf__packed_out po = {0};
    if (out) {
        po.rgb = out->rgb;
        po.depth = out->depth;
        po.opacity = out->opacity;
    }
    nerf__composite_packed(&st->packed, &po);
    if (out && out->disparity) {
        /* Rarely wanted; composite again for the depth and opacity the
         * caller may not have asked for. */
        for (size_t k = 0; k < rays->n; k++) {
            const size_t at = ms->offsets[k];
            nerf__composite_state cs;
            nerf__composite_state_init(&cs);
            nerf__composite_packed_ray(
                &cs, (uint32_t)(ms->offsets[k + 1] - at), ms->t + at,
                ms->dt + at, st->rgb + 3 * at, st->sigma + at,
                st->packed.eps, NULL);
            out->disparity[k] = disparity_of(cs.depth, cs.opacity);
        }
    }
    return NERF_OK;
}

/*
 * Each ray's samples of a round cut to those its compositing will use:
 * within its max_samples, and up to where it turns opaque, counted from
 * the densities in the composite's own arithmetic.  The kept samples move
 * down in ray order with their t, dt, density and head row; each ray's
 * kept samples are a prefix of its own, so no row is overwritten before
 * it has moved.
 */
static void keep_used(nerf__batch *b, const march_job *j, uint32_t head_width)
{
    nerf__march_state *st = &b->marching;
    nerf__march_samples *ms = &st->samples;
    float *head = b->ws[0].head;
    const size_t n_rays = j->rays->n;
    size_t w = 0;
    for (size_t i = 0; i < n_rays; i++) {
        const uint32_t k = st->active[i];
        const size_t at = ms->offsets[i];
        uint32_t n = (uint32_t)(ms->offsets[i + 1] - at);
        const uint32_t room = j->max_samples - st->ray_count[k];
        n = n < room ? n : room;
        float trans = st->ray_state[k].trans;
        const uint32_t used = nerf__composite_packed_ray_used(
            n, ms->dt + at, st->sigma + at, NERF__COMPOSITE_EPS_DEFAULT,
            &trans);
        if (at != w) {
            move_rows(ms->t, 1, w, at, used);
            move_rows(ms->dt, 1, w, at, used);
            move_rows(st->sigma, 1, w, at, used);
            move_rows(head, head_width, w, at, used);
        }
        ms->offsets[i] = w;
        w += used;
    }
    ms->offsets[n_rays] = w;
    ms->total = w;
}

/*
 * A round's network pass: the densities of every marched sample, then the
 * colour branch on the samples keep_used() keeps.  Behind the point where
 * a ray turns opaque a round's last samples are marched for nothing; they
 * cost a density here, not a colour too.  The colours are those of one
 * forward over every sample (network.h), so the image is too.
 * same_params: the model is unchanged since the last call on b.
 */
static int evaluate_used(nerf__batch *b, const nerf__render_setup *s,
                         const march_job *j, bool same_params)
{
    const nerf_model *m = s->model;
    nerf__march_state *st = &b->marching;
    const size_t total = st->samples.total;
    int rc = place_samples(b, s, j, false);
    if (rc != NERF_OK || total == 0) {
        return rc;
    }
    b->n_evaluated += total;
    nerf__workspace *ws = &b->ws[0];
    ws->params_unchanged = same_params;
    rc = nerf__model_head(m, 0, ws, total, st->points, st->sigma);
    if (rc == NERF_OK) {
        if (st->test.zero_empty) {
            nerf__occupancy_zero_empty(nerf__model_grid(m), total,
                                       st->points, st->sigma);
        }
        keep_used(b, j, nerf__network_head_width(&m->nets[0]));
        /* The weights the head's pass packed still hold. */
        ws->params_unchanged = true;
        rc = nerf__model_colour(m, 0, ws, st->samples.total,
                                sample_directions(b, s, j), st->rgb);
    }
    ws->params_unchanged = false;
    return rc;
}

/* One round's compositing: the new samples of each ray going, its count
 * and where its march resumes, and whether it is done. */
static void composite_round(void *ctx, size_t begin, size_t end)
{
    const march_job *j = ctx;
    nerf__march_state *st = &j->b->marching;
    const nerf__march_samples *ms = &st->samples;
    for (size_t i = begin; i < end; i++) {
        const uint32_t k = st->active[i];
        const size_t at = ms->offsets[i];
        /* keep_used() has cut them to the ray's room. */
        const uint32_t n = (uint32_t)(ms->offsets[i + 1] - at);
        nerf__composite_state *cs = &st->ray_state[k];
        nerf__composite_packed_ray(cs, n, ms->t + at, ms->dt + at,
                                   st->rgb + 3 * at, st->sigma + at,
                                   NERF__COMPOSITE_EPS_DEFAULT, NULL);
        st->ray_count[k] += n;
        const bool done = nerf__composite_state_done(
                              cs, NERF__COMPOSITE_EPS_DEFAULT) ||
                          ms->next_step[i] == NERF__MARCH_DONE ||
                          st->ray_count[k] >= j->max_samples;
        st->ray_first[k] = done ? NERF__MARCH_DONE : ms->next_step[i];
    }
}

/* Rendering: rounds of a few samples per ray, until every ray is opaque,
 * out of samples or out of the bound. */
static int march_pieces(nerf__batch *b, const nerf__render_setup *s,
                        const nerf__march_rays *all, const nerf__pass_out *out)
{
    nerf__march_state *st = &b->marching;
    const size_t n = all->n;
    const nerf__occupancy *g = nerf__model_grid(s->model);
    int rc = reserve_rays(b, n);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__march_options mo;
    march_options(b, s, g, &mo);
    march_job j = {.b = b, .viewdir = st->active_view,
                   .max_samples = mo.max_samples, .mo = &mo};
    size_t n_active = n;
    /* The model does not change between the rounds of a block. */
    bool first_round = true;
    for (size_t k = 0; k < n; k++) {
        nerf__composite_state_init(&st->ray_state[k]);
        st->ray_count[k] = 0;
        st->ray_first[k] = 0;
        st->active[k] = (uint32_t)k;
    }
    while (n_active > 0) {
        size_t piece = PIECE_BUDGET / n_active;
        piece = piece < PIECE_MIN ? PIECE_MIN
                                  : piece > PIECE_MAX ? PIECE_MAX : piece;
        mo.max_samples = (uint32_t)piece;
        /* The rays going, gathered, with where each resumes. */
        for (size_t i = 0; i < n_active; i++) {
            const uint32_t k = st->active[i];
            memcpy(st->active_o + 3 * i, all->origins + 3 * k,
                   3 * sizeof(float));
            memcpy(st->active_d + 3 * i, all->dirs + 3 * k,
                   3 * sizeof(float));
            memcpy(st->active_view + 3 * i, b->viewdir + 3 * k,
                   3 * sizeof(float));
            st->active_first[i] = st->ray_first[k];
        }
        nerf__march_rays rays = *all;
        rays.n = n_active;
        rays.origins = st->active_o;
        rays.dirs = st->active_d;
        rays.first_step = st->active_first;
        j.rays = &rays;
        rc = nerf__march_run(g, &mo, &rays, &st->samples);
        if (rc == NERF_OK) {
            rc = evaluate_used(b, s, &j, !first_round);
            first_round = false;
        }
        if (rc != NERF_OK) {
            return rc;
        }
        nerf__parallel_for(n_active, 30 * piece + 30, composite_round, &j);
        size_t going = 0;
        for (size_t i = 0; i < n_active; i++) {
            const uint32_t k = st->active[i];
            if (st->ray_first[k] != NERF__MARCH_DONE) {
                st->active[going++] = k;
            }
        }
        n_active = going;
    }
    if (out == NULL) {
        return NERF_OK;
    }
    for (size_t k = 0; k < n; k++) {
        const nerf__composite_state *cs = &st->ray_state[k];
        if (out->rgb) {
            const float *bg = b->ray_bg ? b->ray_bg + 3 * k
                              : b->white ? st->bg : NULL;
            nerf__composite_state_rgb(cs, bg, out->rgb + 3 * k);
        }
        if (out->depth) {
            out->depth[k] = cs->depth;
        }
        if (out->opacity) {
            out->opacity[k] = cs->opacity;
        }
        if (out->disparity) {
            out->disparity[k] = disparity_of(cs->depth, cs->opacity);
        }
    }
    return NERF_OK;
}

nerf__march_rays nerf__render_march_rays(const nerf__render_setup *s,
                                         size_t n_rays, const float *origins,
                                         const float *directions)
{
    const nerf_sampler_options *so = &s->sampler->opts;
    return (nerf__march_rays){
        .n = n_rays, .origins = origins, .dirs = directions,
        .near_all = so->t_near, .far_all = so->t_far,
        .first_ray = s->first_ray};
}

int nerf__render_march(nerf__batch *b, const nerf__render_setup *s,
                       size_t n_rays, const float *origins,
                       const float *directions,
                       const nerf__pass_out out[NERF__PASSES])
{
    if (nerf__model_grid(s->model) == NULL) {
        return nerf__error(NERF_EINVAL, "render: the sampler marches through "
                           "an occupancy grid, which this model has not");
    }
    int rc = nerf__batch_begin(b, s, n_rays);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__march_state *st = &b->marching;
    b->n_pass = 1;
    b->n_samples[0] = b->n_samples[1] = 0;
    b->net[0] = b->net[1] = 0;
    b->marched = true;
    st->bg[0] = st->bg[1] = st->bg[2] = 1.0f;
    st->samples.n_rays = st->samples.total = 0;
    if (n_rays == 0) {
        b->kept = s->keep;
        return NERF_OK;
    }
    nerf__march_rays rays =
        nerf__render_march_rays(s, n_rays, origins, directions);
    march_job j = {.b = b, .rays = &rays};
    /* View directions are the world rays' even in NDC, as the
     * reference's. */
    nerf__parallel_for(n_rays, 32, view_dirs, &j);
    if (s->sampler->opts.ndc) {
        /* March the warped rays: the model's grids lie over NDC space. */
        nerf__render_ndc_rays(s, n_rays, origins, directions, b->ray_o,
                              b->ray_d);
        rays.origins = b->ray_o;
        rays.dirs = b->ray_d;
    }
    const nerf__pass_out *o = out ? &out[0] : NULL;
    rc = s->keep ? march_whole(b, s, &rays, o)
                 : march_pieces(b, s, &rays, o);
    if (rc == NERF_OK) {
        b->kept = s->keep;
    }
    return rc;
}

int nerf__render_march_backward(nerf__batch *b, nerf_model *m,
                                const float *d_rgb, const float *d_depth,
                                const float *d_opacity)
{
    nerf__march_state *st = &b->marching;
    if (st->samples.total == 0 || (!d_rgb && !d_depth && !d_opacity)) {
        return NERF_OK;
    }
    nerf__composite_packed_backward(&st->packed, d_rgb, d_depth, d_opacity,
                                    st->d_rgb, st->d_sigma);
    return nerf__model_backward(m, 0, &b->ws[0], st->d_rgb, st->d_sigma);
}
