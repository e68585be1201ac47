/* Ray marching through the occupancy grid (see march.h). */
#include "march.h"
#include "march_ray.h"

#include <math.h>
#include <string.h>

#include "error.h"
#include "parallel.h"
#include "rng.h"
#include "space.h"

#define MARCH_STREAM UINT64_C(0x6d61726368726179)

/* Margin, in steps, kept before a cell's exit when skipping (march.h). */
#define SKIP_MARGIN (1.0f / 16.0f)

/* Rough operations per ray, for the thread pool's split. */
#define COST_PER_RAY 4000

void nerf__march_defaults(nerf__march_options *o, const nerf__occupancy *g)
{
    memset(o, 0, sizeof *o);
    o->step = nerf__march_step(g->lo, g->hi, NERF__MARCH_STEPS_DEFAULT);
    o->skip_empty = true;
}

static float ray_offset(const nerf__march_options *o, uint64_t ray)
{
    if (!o->jitter) {
        return 0.0f;
    }
    uint64_t key = nerf__mix64(o->seed ^ nerf__mix64(o->iteration ^ MARCH_STREAM));
    nerf__rng r = nerf__rng_make(key, ray);
    return nerf__rng_uniform(&r);
}

/*
 * A ray in lattice units: it crosses face f (a cell index) of axis a at
 * lattice index kc[a] + f kd[a].  Skipping walks cell to cell (block to
 * block through empty blocks) in these units.  That walk is a serial
 * chain, where the ray leaves a cell deciding where it looks next, so its
 * step is kept to a comparison and an addition: the next crossing of each
 * axis is carried along and advanced by |kd| per cell (8 |kd| per block),
 * and the occupancy bits read on the way only decide when to stop.  The
 * additions drift by far less than SKIP_MARGIN over a grid's width.
 */
typedef struct lattice_ray {
    float kc[3], kd[3];
    float step1[3], step8[3]; /* |kd|, 8 |kd|; 0 where d = 0 */
    uint32_t up[3];           /* 1 where d > 0 */
    float k_end;              /* lattice indices from here on are past
                               * far or the exit */
    const float *o, *d;
    float base, dt_t;
} lattice_ray;

/* The cell along axis a at lattice index k, by the grid's rule, kept
 * within [lo, hi] (the ray is known to be there; this only absorbs
 * rounding). */
static uint32_t cell_at(const nerf__occupancy *g, const lattice_ray *r,
                        int a, float k, uint32_t lo, uint32_t hi)
{
    const float t = r->base + k * r->dt_t;
    const float u = (r->o[a] + t * r->d[a] - g->lo[a]) * g->inv_cell[a];
    /* Clamped as a float first: the conversion of a value out of range
     * would be undefined. */
    if (!(u >= (float)lo)) {
        return lo;
    }
    return u < (float)hi ? (uint32_t)u : hi;
}

static inline int argmin3(const float v[3])
{
    int a = v[1] < v[0] ? 1 : 0;
    return v[2] < v[a] ? 2 : a;
}

static inline bool coarse_bit(const nerf__occupancy *g, const uint32_t b[3])
{
    const size_t rc = g->coarse_res;
    const size_t i = b[0] + rc * (b[1] + rc * b[2]);
    return (g->coarse[i >> 6] >> (i & 63)) & 1u;
}

static inline size_t cell_index(const nerf__occupancy *g, const uint32_t c[3])
{
    return c[0] + (size_t)g->res * (c[1] + (size_t)g->res * c[2]);
}

/*
 * From cell c, which is empty, walk along the ray until an occupied cell:
 * returns the lattice index where the ray enters it, or INFINITY when it
 * leaves the bound or passes far first.
 */
static float walk_empty(const nerf__occupancy *g, const lattice_ray *r,
                        uint32_t c[3])
{
    const uint32_t S = NERF__OCCUPANCY_BLOCK_SHIFT, R = g->res;
    const uint32_t rc = g->coarse_res;
    float ka[3];
    for (;;) {
        uint32_t b[3] = {c[0] >> S, c[1] >> S, c[2] >> S};
        if (!coarse_bit(g, b)) {
            /* Through empty blocks. */
            for (int a = 0; a < 3; a++) {
                ka[a] = r->kc[a] + (float)((b[a] + r->up[a]) << S) * r->kd[a];
            }
            int axis;
            float ke;
            do {
                axis = argmin3(ka);
                ke = ka[axis];
                if (!(ke - SKIP_MARGIN < r->k_end)) {
                    return INFINITY;
                }
                if (r->up[axis]) {
                    if (++b[axis] >= rc) {
                        return INFINITY;
                    }
                } else if (b[axis]-- == 0) {
                    return INFINITY;
                }
                ka[axis] += r->step8[axis];
            } while (!coarse_bit(g, b));
            /* Into an occupied block: the cell where the ray enters. */
            for (int a = 0; a < 3; a++) {
                const uint32_t lo = b[a] << S;
                const uint32_t hi = lo + (1u << S) - 1 < R ? lo + (1u << S) - 1
                                                           : R - 1;
                if (a == axis) {
                    c[a] = r->up[a] ? lo : hi;
                } else if (r->d[a] != 0.0f) {
                    c[a] = cell_at(g, r, a, ke, lo, hi);
                }
            }
            if (nerf__occupancy_bit(g, cell_index(g, c))) {
                return ke;
            }
        }
        /* Cell by cell through an occupied block, until an occupied cell
         * or an empty block. */
        for (int a = 0; a < 3; a++) {
            ka[a] = r->kc[a] + (float)(c[a] + r->up[a]) * r->kd[a];
        }
        for (;;) {
            const int axis = argmin3(ka);
            const float ke = ka[axis];
            if (!(ke - SKIP_MARGIN < r->k_end)) {
                return INFINITY;
            }
            bool new_block;
            if (r->up[axis]) {
                if (++c[axis] >= R) {
                    return INFINITY;
                }
                new_block = (c[axis] & ((1u << S) - 1)) == 0;
            } else {
                if (c[axis]-- == 0) {
                    return INFINITY;
                }
                new_block = (c[axis] & ((1u << S) - 1)) == (1u << S) - 1;
            }
            ka[axis] += r->step1[axis];
            if (new_block) {
                const uint32_t nb[3] = {c[0] >> S, c[1] >> S, c[2] >> S};
                if (!coarse_bit(g, nb)) {
                    break; /* back to walking blocks */
                }
            }
            if (nerf__occupancy_bit(g, cell_index(g, c))) {
                return ke;
            }
        }
    }
}

uint32_t nerf__march_ray_linear(const nerf__occupancy *g,
                                const nerf__march_options *mo,
                                const float o[3], const float d[3], float t0,
                                float t1, float u, uint32_t k0, float *t_out,
                                float *dt_out, uint32_t *resume)
{
    *resume = NERF__MARCH_DONE;
    const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0.0f) || !isfinite(len) || k0 == NERF__MARCH_DONE) {
        return 0;
    }
    float inv_d[3];
    for (int a = 0; a < 3; a++) {
        if (!isfinite(o[a])) {
            return 0;
        }
        if (d[a] == 0.0f) {
            /* Parallel to the slab: inside it for every t, or never. */
            if (o[a] < g->lo[a] || o[a] > g->hi[a]) {
                return 0;
            }
            inv_d[a] = 0.0f;
            continue;
        }
        inv_d[a] = 1.0f / d[a];
        float ta = (g->lo[a] - o[a]) * inv_d[a];
        float tb = (g->hi[a] - o[a]) * inv_d[a];
        float tn = ta < tb ? ta : tb, tf = ta < tb ? tb : ta;
        t0 = tn > t0 ? tn : t0;
        t1 = tf < t1 ? tf : t1;
    }
    if (!(t0 < t1)) {
        return 0;
    }
    const float dt_t = mo->step / len;
    const float base = t0 + u * dt_t;
    lattice_ray r = {.o = o, .d = d, .base = base, .dt_t = dt_t};
    r.k_end = (t1 - base) / dt_t;
    if (!(r.k_end < 16777216.0f)) {
        return 0; /* a step too small for the bound (see march.h) */
    }
    for (int a = 0; a < 3; a++) {
        r.up[a] = d[a] > 0.0f;
        if (d[a] == 0.0f) {
            r.kc[a] = INFINITY; /* never crossed */
            r.kd[a] = 0.0f;
        } else {
            r.kc[a] = ((g->lo[a] - o[a]) * inv_d[a] - base) / dt_t;
            r.kd[a] = g->cell_size[a] * inv_d[a] / dt_t;
        }
        r.step1[a] = fabsf(r.kd[a]);
        r.step8[a] = (float)(1u << NERF__OCCUPANCY_BLOCK_SHIFT) * r.step1[a];
    }
    const uint32_t limit = mo->max_samples ? mo->max_samples : UINT32_MAX;
    const bool skip = mo->skip_empty;
    uint32_t count = 0;
    uint32_t k = k0;
    /* Consecutive samples mostly share a cell: its bit is read once. */
    size_t last_cell = SIZE_MAX;
    bool last_bit = false;
    for (;;) {
        const float t = base + (float)k * dt_t;
        if (!(t < t1)) {
            break;
        }
        const float p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        uint32_t ijk[3];
        size_t cell;
        if (!nerf__occupancy_cell(g, p, ijk, &cell)) {
            /* Only at the faces, where the slab test and the cell rule
             * round differently. */
            k++;
            continue;
        }
        if (cell != last_cell) {
            last_cell = cell;
            last_bit = !skip || nerf__occupancy_bit(g, cell);
        }
        if (last_bit) {
            if (t_out) {
                t_out[count] = t;
                dt_out[count] = mo->step;
            }
            k++;
            if (++count == limit) {
                *resume = k;
                return count;
            }
            continue;
        }
        /* Resume at the first lattice point past the entry into the next
         * occupied cell, less the margin; that point's own cell is then
         * checked like any other. */
        const float x = walk_empty(g, &r, ijk) - SKIP_MARGIN;
        if (!(x < r.k_end)) {
            break;
        }
        uint32_t next = x > 0.0f ? (uint32_t)x + 1 : 0;
        k = next > k + 1 ? next : k + 1;
    }
    return count;
}

typedef struct march_job {
    const nerf__occupancy *g;
    const nerf__march_options *o;
    const nerf__march_rays *r;
    const size_t *offsets;
    size_t *counts;
    uint32_t *slot_count;
    const float *t;
    float *t_out, *dt_out, *xyz;
    uint32_t *next_step;
} march_job;

static uint32_t march_one(const march_job *j, size_t k, float *t_out,
                          float *dt_out, uint32_t *resume)
{
    const nerf__march_rays *r = j->r;
    float near = r->near ? r->near[k] : r->near_all;
    float far = r->far ? r->far[k] : r->far_all;
    uint32_t k0 = r->first_step ? r->first_step[k] : 0;
    if (k0 == NERF__MARCH_DONE) {
        /* Most rays of a continuation pass: no jitter to draw for them. */
        *resume = NERF__MARCH_DONE;
        return 0;
    }
    const float u = ray_offset(j->o, r->first_ray + k);
    if (j->o->contract > 0.0f) {
        return nerf__march_ray_contract(j->g, j->o, r->origins + 3 * k,
                                        r->dirs + 3 * k, near, far, u, k0,
                                        t_out, dt_out, resume);
    }
    return nerf__march_ray_linear(j->g, j->o, r->origins + 3 * k,
                                  r->dirs + 3 * k, near, far, u, k0, t_out,
                                  dt_out, resume);
}

static void count_range(void *ctx, size_t begin, size_t end)
{
    const march_job *j = ctx;
    uint32_t resume;
    for (size_t k = begin; k < end; k++) {
        j->counts[k + 1] = march_one(j, k, NULL, NULL, &resume);
    }
}

static void fill_range(void *ctx, size_t begin, size_t end)
{
    const march_job *j = ctx;
    uint32_t resume;
    for (size_t k = begin; k < end; k++) {
        size_t at = j->offsets[k];
        march_one(j, k, j->t_out + at, j->dt_out + at,
                  j->next_step ? j->next_step + k : &resume);
    }
}

size_t nerf__march_count(const nerf__occupancy *g,
                         const nerf__march_options *o,
                         const nerf__march_rays *rays, size_t *offsets)
{
    march_job j = {.g = g, .o = o, .r = rays, .counts = offsets};
    offsets[0] = 0;
    nerf__parallel_for(rays->n, COST_PER_RAY, count_range, &j);
    for (size_t k = 0; k < rays->n; k++) {
        offsets[k + 1] += offsets[k];
    }
    return offsets[rays->n];
}

void nerf__march_fill(const nerf__occupancy *g, const nerf__march_options *o,
                      const nerf__march_rays *rays, const size_t *offsets,
                      float *t, float *dt, uint32_t *next_step)
{
    march_job j = {.g = g, .o = o, .r = rays, .offsets = offsets,
                   .t_out = t, .dt_out = dt, .next_step = next_step};
    nerf__parallel_for(rays->n, COST_PER_RAY, fill_range, &j);
}

static void points_range(void *ctx, size_t begin, size_t end)
{
    const march_job *j = ctx;
    const bool contract = j->o->contract > 0.0f;
    nerf__space space;
    if (contract) {
        nerf__space_contract(&space, j->o->contract);
    }
    for (size_t k = begin; k < end; k++) {
        const float *o = j->r->origins + 3 * k, *d = j->r->dirs + 3 * k;
        for (size_t i = j->offsets[k]; i < j->offsets[k + 1]; i++) {
            const float t = j->t[i];
            float *p = j->xyz + 3 * i;
            for (int a = 0; a < 3; a++) {
                p[a] = o[a] + t * d[a];
            }
            if (contract) {
                nerf__space_to_domain(&space, p, p);
            }
        }
    }
}

void nerf__march_points(const nerf__march_options *o,
                        const nerf__march_rays *rays, const size_t *offsets,
                        const float *t, float *xyz)
{
    march_job j = {.o = o, .r = rays, .offsets = offsets, .t = t,
                   .xyz = xyz};
    size_t per_ray = rays->n ? offsets[rays->n] / rays->n : 0;
    nerf__parallel_for(rays->n, 8 * per_ray + 8, points_range, &j);
}

void nerf__march_samples_init(nerf__march_samples *s, const nerf__env *env)
{
    memset(s, 0, sizeof *s);
    s->env = *env;
}

void nerf__march_samples_release(nerf__march_samples *s)
{
    /* offsets heads the block of the per-ray arrays (reserve_rays). */
    nerf__free(&s->env, s->offsets);
    nerf__free(&s->env, s->t);
    nerf__free(&s->env, s->slot_t);
    nerf__env env = s->env;
    nerf__march_samples_init(s, &env);
}

/* Room for at least `total` samples in the pair (*t, *dt), one block;
 * what they held is lost. */
static int reserve_pair(const nerf__env *env, float **t, float **dt,
                        size_t *cap, size_t total)
{
    if (*t != NULL && total <= *cap) {
        return NERF_OK;
    }
    /* Some headroom: the next batch's count is rarely the same. */
    size_t want = total + total / 8 + 64, bytes;
    size_t half = (want + 15) & ~(size_t)15; /* dt stays 64-byte aligned */
    if (nerf__mul_size(2 * half, sizeof(float), &bytes) != 0) {
        return nerf__error(NERF_ENOMEM, "march: %zu samples overflow", total);
    }
    float *block = nerf__alloc(env, bytes);
    if (block == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(env, *t);
    *t = block;
    *dt = block + half;
    *cap = half;
    return NERF_OK;
}

/* The per-ray arrays for n rays, one block headed by offsets. */
static int reserve_rays(nerf__march_samples *s, size_t n)
{
    if (s->offsets != NULL && n <= s->cap_rays) {
        return NERF_OK;
    }
    size_t sizes, words, bytes;
    if (nerf__mul_size(n + 1, 2 * sizeof(size_t), &sizes) != 0 ||
        nerf__mul_size(n + 1, 2 * sizeof(uint32_t), &words) != 0 ||
        sizes > SIZE_MAX - words) {
        return nerf__error(NERF_ENOMEM, "march: %zu rays overflow", n);
    }
    bytes = sizes + words;
    size_t *block = nerf__alloc(&s->env, bytes);
    if (block == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(&s->env, s->offsets);
    s->offsets = block;
    s->more = block + (n + 1);
    s->next_step = (uint32_t *)(block + 2 * (n + 1));
    s->slot_count = s->next_step + (n + 1);
    s->cap_rays = n;
    return NERF_OK;
}

static void slot_range(void *ctx, size_t begin, size_t end)
{
    const march_job *j = ctx;
    const size_t room = j->o->max_samples;
    for (size_t k = begin; k < end; k++) {
        j->slot_count[k] = march_one(j, k, j->t_out + k * room,
                                     j->dt_out + k * room, j->next_step + k);
    }
}

/*
 * The one-walk march (march.h): every ray into its slot of `room`; the
 * rays a slot cut short of o->max_samples counted from where it stopped;
 * the layout; the slots copied into it and the rest filled behind them.
 */
static int march_slots(const nerf__occupancy *g, const nerf__march_options *o,
                       const nerf__march_rays *rays, nerf__march_samples *s,
                       uint32_t room)
{
    const size_t n = rays->n;
    int rc = reserve_pair(&s->env, &s->slot_t, &s->slot_dt, &s->cap_slots,
                          n * room);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__march_options in_slot = *o;
    in_slot.max_samples = room;
    march_job j = {.g = g, .o = &in_slot, .r = rays,
                   .slot_count = s->slot_count, .t_out = s->slot_t,
                   .dt_out = s->slot_dt, .next_step = s->next_step};
    size_t cost = 200 + 64 * (size_t)room;
    nerf__parallel_for(n, cost < COST_PER_RAY ? cost : COST_PER_RAY,
                       slot_range, &j);
    /* A ray cut by its slot, not by max_samples, goes on from its
     * next_step; the others' next_step is already final, and with a slot
     * of max_samples no ray goes on. */
    const bool go_on = o->max_samples == 0 || room < o->max_samples;
    nerf__march_options rest = *o;
    rest.max_samples = o->max_samples ? o->max_samples - room : 0;
    nerf__march_rays from_slot = *rays;
    from_slot.first_step = s->next_step;
    size_t more = 0;
    if (go_on) {
        more = nerf__march_count(g, &rest, &from_slot, s->more);
    }
    s->offsets[0] = 0;
    for (size_t k = 0; k < n; k++) {
        const size_t after = more ? s->more[k + 1] - s->more[k] : 0;
        s->offsets[k + 1] = s->offsets[k] + s->slot_count[k] + after;
    }
    rc = reserve_pair(&s->env, &s->t, &s->dt, &s->cap_samples, s->offsets[n]);
    if (rc != NERF_OK) {
        return rc;
    }
    for (size_t k = 0; k < n; k++) {
        const size_t at = s->offsets[k], c = s->slot_count[k];
        memcpy(s->t + at, s->slot_t + k * room, c * sizeof(float));
        memcpy(s->dt + at, s->slot_dt + k * room, c * sizeof(float));
        s->more[k] = at + c;
    }
    if (more) {
        /* Each ray reads its first_step before writing its next_step, the
         * same entry. */
        nerf__march_fill(g, &rest, &from_slot, s->more, s->t, s->dt,
                         s->next_step);
    }
    return NERF_OK;
}

int nerf__march_run(const nerf__occupancy *g, const nerf__march_options *o,
                    const nerf__march_rays *rays, nerf__march_samples *s)
{
    s->n_rays = 0;
    s->total = 0;
    int rc = reserve_rays(s, rays->n);
    if (rc != NERF_OK) {
        return rc;
    }
    const uint32_t limit = o->max_samples;
    uint32_t room = NERF__MARCH_SLOT_ROOM;
    if (limit > 0 && (limit < room ||
                      rays->n <= NERF__MARCH_ONE_PASS_ROOM / limit)) {
        room = limit;
    }
    if (rays->n <= NERF__MARCH_SLOT_CAP / room) {
        rc = march_slots(g, o, rays, s, room);
    } else {
        const size_t total = nerf__march_count(g, o, rays, s->offsets);
        rc = reserve_pair(&s->env, &s->t, &s->dt, &s->cap_samples, total);
        if (rc == NERF_OK) {
            nerf__march_fill(g, o, rays, s->offsets, s->t, s->dt,
                             s->next_step);
        }
    }
    if (rc != NERF_OK) {
        return rc;
    }
    s->n_rays = rays->n;
    s->total = s->offsets[rays->n];
    return NERF_OK;
}
