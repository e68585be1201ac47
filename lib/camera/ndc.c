/*
 * The NDC warp.  Constants are formed in double and rounded once, and the
 * float operations follow the reference's order, so that rays match it to
 * the last bit where the compilers agree.
 */
#include "ndc.h"

void nerf__ndc_rays(float focal, float width, float height, float near_plane,
                    size_t n, const float *o, const float *d, float *o_out,
                    float *d_out)
{
    const float sx = (float)(-1.0 / ((double)width / (2.0 * focal)));
    const float sy = (float)(-1.0 / ((double)height / (2.0 * focal)));
    const float two_near = (float)(2.0 * near_plane);
    const float neg_two_near = (float)(-2.0 * near_plane);
    for (size_t k = 0; k < n; k++) {
        const float *ok = o + 3 * k, *dk = d + 3 * k;
        float t = -(near_plane + ok[2]) / dk[2];
        float ox = ok[0] + t * dk[0];
        float oy = ok[1] + t * dk[1];
        float oz = ok[2] + t * dk[2];
        float dx = dk[0], dy = dk[1], dz = dk[2];
        o_out[3 * k] = sx * ox / oz;
        o_out[3 * k + 1] = sy * oy / oz;
        o_out[3 * k + 2] = 1.0f + two_near / oz;
        d_out[3 * k] = sx * (dx / dz - ox / oz);
        d_out[3 * k + 1] = sy * (dy / dz - oy / oz);
        d_out[3 * k + 2] = neg_two_near / oz;
    }
}
