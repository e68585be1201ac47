/* Ray marching through a grid over contracted space (see march.h). */
#include <math.h>

#include "box_span.h"
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

/* One lattice point, at warped distance s and world distance uw =
 * warp_u(s), outside the linear march: its contracted cell tested, and the
 * sample written when occupied.  Returns whether it was kept. */
static bool plain_point(const nerf__occupancy *g, const nerf__space *space,
                        const warp *w, const float o[3], const float d[3],
                        float len, float s, float uw, float step, float u1,
                        bool skip, float *t_out, float *dt_out)
{
    const float t = uw / len;
    float p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
    nerf__space_to_domain(space, p, p);
    uint32_t ijk[3];
    size_t cell;
    if (!nerf__occupancy_cell(g, p, ijk, &cell) ||
        (skip && !nerf__occupancy_bit(g, cell))) {
        return false;
    }
    if (t_out) {
        /* As in the linear march, a sample stands for the stretch to the
         * next lattice point (so the lengths add up to the distance
         * covered), or to far. */
        const float u_next = fminf(warp_u(w, s + step), u1);
        *t_out = t;
        *dt_out = u_next > uw ? u_next - uw : 0.0f;
    }
    return true;
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
    float t_in = t0, tc = t0, t_out_cube;
    const float cube_lo[3] = {-inner, -inner, -inner};
    const float cube_hi[3] = {inner, inner, inner};
    const bool hit = nerf__box_span(o, d, cube_lo, cube_hi, &t_in,
                                    &t_out_cube) &&
                     t_out_cube > t0;
    if (hit) {
        tc = t_out_cube;
        t_in = fmaxf(t_in, t0);
    }
    warp w = {.uc = tc * len, .a = nerf__space_norm(o)};
    w.D = fmaxf(w.uc + w.a, step);
    w.smax = w.uc + w.D;
    const float u1 = t1 * len, s1 = warp_s(&w, u1);
    const float base_s = t0 * len + u * step;
    if (!((s1 - base_s) / step < 16777216.0f)) {
        return 0; /* a step too small for the ray (see march.h) */
    }
    /* Lattice points k_in .. k_end - 1 lie in the cube, where nothing is
     * contracted: the linear march takes them, with its skipping; the
     * others are tested one by one. */
    const float dt_t = step / len, base_t = t0 + u * dt_t;
    uint32_t k_in = 0, k_end = 0;
    if (hit) {
        k_in = first_at_or_past(base_t, dt_t, t_in);
        k_end = first_at_or_past(base_t, dt_t, fminf(t1, tc));
    }
    const uint32_t limit = mo->max_samples ? mo->max_samples : UINT32_MAX;
    const bool skip = mo->skip_empty;
    uint32_t count = 0;
    for (uint32_t k = k0;; k++) {
        if (k >= k_in && k < k_end) {
            /* The linear march from lattice point k_in, numbered from 0
             * there; it stops half a step before point k_end, so that
             * rounding cannot move the seam. */
            const float t_start = k_in ? t0 + (float)k_in * dt_t : t0;
            const float t_stop =
                fminf(t1, base_t + ((float)k_end - 0.5f) * dt_t);
            nerf__march_options lin = *mo;
            lin.max_samples = limit - count;
            uint32_t next;
            count += nerf__march_ray_linear(
                g, &lin, o, d, t_start, t_stop, u, k - k_in,
                t_out ? t_out + count : NULL, dt_out ? dt_out + count : NULL,
                &next);
            if (next != NERF__MARCH_DONE) {
                *resume = next + k_in;
                return count;
            }
            k = k_end;
        }
        const float s = base_s + (float)k * step;
        if (!(s < s1)) {
            break;
        }
        const float uw = warp_u(&w, s);
        if (!(uw / len < t1)) {
            break;
        }
        if (plain_point(g, &space, &w, o, d, len, s, uw, step, u1, skip,
                        t_out ? t_out + count : NULL,
                        dt_out ? dt_out + count : NULL) &&
            ++count == limit) {
            *resume = k + 1;
            break;
        }
    }
    return count;
}
