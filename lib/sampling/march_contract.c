/* Ray marching through a grid over contracted space (see march.h). */
#include <math.h>

#include "march_ray.h"
#include "space.h"

/* The warped distance along one ray (march.h), in world distance u:
 * s(u) = u up to uc, then smax - D^2 / (u + a) with smax = uc + D. */
typedef struct warp {
    float uc, a, D, smax;
} warp;

static float warp_s(const warp *w, float u)
{
    return u <= w->uc ? u : w->smax - w->D * w->D / (u + w->a);
}

static float warp_u(const warp *w, float s)
{
    if (s <= w->uc) {
        return s;
    }
    const float room = w->smax - s;
    return room > 0.0f ? w->D * w->D / room - w->a : INFINITY;
}


/* Where the ray leaves the cube [-half, half]^3, in t; false if it never
 * is inside it at t >= 0. */
static bool cube_exit(const float o[3], const float d[3], float half,
                      float *t_exit)
{
    float tn = 0.0f, tf = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (d[a] == 0.0f) {
            if (!(fabsf(o[a]) <= half)) {
                return false;
            }
            continue;
        }
        const float inv = 1.0f / d[a];
        float ta = (-half - o[a]) * inv, tb = (half - o[a]) * inv;
        tn = fmaxf(tn, fminf(ta, tb));
        tf = fminf(tf, fmaxf(ta, tb));
    }
    *t_exit = tf;
    return tn < tf;
}

/* The first lattice index whose t = base + k dt_t is not below t_end,
 * by the linear march's own arithmetic. */
static uint32_t first_at_or_past(float base, float dt_t, float t_end)
{
    float x = ceilf((t_end - base) / dt_t);
    uint32_t k = x > 0.0f ? (x < 16777216.0f ? (uint32_t)x : 16777216u) : 0;
    while (k > 0 && base + (float)(k - 1) * dt_t >= t_end) {
        k--;
    }
    while (k < 16777216u && base + (float)k * dt_t < t_end) {
        k++;
    }
    return k;
}

uint32_t nerf__march_ray_contract(const nerf__occupancy *g,
                                  const nerf__march_options *mo,
                                  const float o[3], const float d[3],
                                  float t0, float t1, float u, uint32_t k0,
                                  float *t_out, float *dt_out,
                                  uint32_t *resume)
{
    *resume = NERF__MARCH_DONE;
    const float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0.0f) || !isfinite(len) || k0 == NERF__MARCH_DONE ||
        !isfinite(o[0]) || !isfinite(o[1]) || !isfinite(o[2]) ||
        !(t0 < t1)) {
        return 0;
    }
    nerf__space space;
    nerf__space_contract(&space, mo->contract);
    const float inner = mo->contract, step = mo->step;
    const float a = nerf__space_norm(o);
    float tc = t0, t_exit;
    if (cube_exit(o, d, inner, &t_exit) && t_exit > t0) {
        tc = t_exit;
    }
    warp w = {.uc = tc * len, .a = a};
    w.D = fmaxf(w.uc + a, step);
    w.smax = w.uc + w.D;
    const float u0 = t0 * len;
    const float u1 = t1 * len, s1 = warp_s(&w, u1);
    const float base_s = u0 + u * step;
    if (!((s1 - base_s) / step < 16777216.0f)) {
        return 0; /* a step too small for the ray (see march.h) */
    }
    const uint32_t limit = mo->max_samples ? mo->max_samples : UINT32_MAX;
    uint32_t count = 0, k = k0;
    if (a <= inner && tc > t0) {
        /* From inside the cube to its exit nothing is contracted: the
         * linear march, with its skipping, on the same lattice. */
        const float dt_t = step / len, base_t = t0 + u * dt_t;
        const float t_end = fminf(t1, tc);
        const uint32_t k_end = first_at_or_past(base_t, dt_t, t_end);
        if (k < k_end) {
            count = nerf__march_ray_linear(g, mo, o, d, t0, t_end, u, k,
                                           t_out, dt_out, resume);
            if (*resume != NERF__MARCH_DONE || !(t1 > tc)) {
                return count;
            }
        }
        k = k > k_end ? k : k_end;
    }
    const bool skip = mo->skip_empty;
    for (;; k++) {
        const float s = base_s + (float)k * step;
        if (!(s < s1)) {
            break;
        }
        const float uw = warp_u(&w, s);
        const float t = uw / len;
        if (!(t < t1)) {
            break;
        }
        float p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        nerf__space_to_domain(&space, p, p);
        uint32_t ijk[3];
        size_t cell;
        if (!nerf__occupancy_cell(g, p, ijk, &cell) ||
            (skip && !nerf__occupancy_bit(g, cell))) {
            continue;
        }
        if (t_out) {
            /* As in the linear march, a sample stands for the stretch to
             * the next lattice point (so the lengths add up to the
             * distance covered), or to far. */
            const float u_next = fminf(warp_u(&w, s + step), u1);
            t_out[count] = t;
            dt_out[count] = u_next > uw ? u_next - uw : 0.0f;
        }
        if (++count == limit) {
            *resume = k + 1;
            break;
        }
    }
    return count;
}
