/*
 * Where a ray o + t d is inside an axis-aligned box: the slab test that
 * the marchers and the bake's renders start their rays with.
 */
#ifndef NERF_CAMERA_BOX_SPAN_H
#define NERF_CAMERA_BOX_SPAN_H

#include <math.h>
#include <stdbool.h>

/* t in [*t_in, *t_out) (t_in may be negative); false if the ray never is
 * inside [lo, hi] (NaN included).  An axis the ray runs along keeps it
 * inside only if o is within the box's slab on that axis. */
static inline bool nerf__box_span(const float o[3], const float d[3],
                                  const float lo[3], const float hi[3],
                                  float *t_in, float *t_out)
{
    float tn = -INFINITY, tf = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (d[a] == 0.0f) {
            if (!(o[a] >= lo[a] && o[a] <= hi[a])) {
                return false;
            }
            continue;
        }
        const float inv = 1.0f / d[a];
        const float ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
        tn = fmaxf(tn, fminf(ta, tb));
        tf = fminf(tf, fmaxf(ta, tb));
    }
    *t_in = tn;
    *t_out = tf;
    return tn < tf;
}

#endif
