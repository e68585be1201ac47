#include "space.h"

#include <string.h>

void nerf__space_world(nerf__space *s)
{
    memset(s, 0, sizeof *s);
    s->kind = NERF__SPACE_WORLD;
}

static void box(nerf__space *s, uint32_t kind, float hx, float hz)
{
    memset(s, 0, sizeof *s);
    s->kind = kind;
    for (int a = 0; a < 3; a++) {
        s->lo[a] = a == 2 ? -hz : -hx;
        s->hi[a] = a == 2 ? hz : hx;
    }
}

void nerf__space_cube(nerf__space *s, float half)
{
    box(s, NERF__SPACE_BOX, half, half);
}

void nerf__space_ndc(nerf__space *s, float half)
{
    box(s, NERF__SPACE_NDC, half, 1.0f);
}

void nerf__space_contract(nerf__space *s, float inner)
{
    box(s, NERF__SPACE_CONTRACT, 2.0f * inner, 2.0f * inner);
    s->inner = inner;
}

void nerf__space_from_domain(const nerf__space *s, const float *q, float *p)
{
    float f = 1.0f;
    if (s->kind == NERF__SPACE_CONTRACT) {
        /* |c(x)| = (2 - inner / r) inner, so r = inner / (2 - |q| / inner)
         * and x = q r / |q|. */
        const float rq = nerf__space_norm(q);
        if (rq > s->inner) {
            f = s->inner / ((2.0f - rq / s->inner) * rq);
        }
    }
    p[0] = q[0] * f;
    p[1] = q[1] * f;
    p[2] = q[2] * f;
}
