#include "sh.h"

#include <math.h>
#include <string.h>

#include "encoding.h"
#include "nerf.h"

/*
 * Each constant is K_l^|m| (times sqrt 2 when m != 0) with
 * K_l^m = sqrt((2l + 1) / (4 pi) (l - m)! / (l + m)!), folded into the
 * Cartesian polynomial r^l P_l^m(cos theta) cos/sin(m phi); derived to
 * 30 digits and rounded.  The r^2 inside Y_6 and Y_11..Y_13 (3 z^2 - r^2,
 * 5 z^2 - r^2, 5 z^2 - 3 r^2) is written as 1, which is why inputs are
 * normalised first.
 */
#define SH_C0 0.282094791773878143f  /* 1 / (2 sqrt pi) */
#define SH_C1 0.488602511902919922f  /* sqrt(3 / 4pi) */
#define SH_C2A 1.09254843059207907f  /* sqrt(15 / 4pi) */
#define SH_C2B 0.946174695757560018f /* 3 sqrt(5 / 16pi) */
#define SH_C2C 0.315391565252520006f /* sqrt(5 / 16pi) */
#define SH_C2D 0.546274215296039535f /* sqrt(15 / 16pi) */
#define SH_C3A 0.590043589926643510f /* sqrt(35 / 32pi) */
#define SH_C3B 2.89061144264055406f  /* sqrt(105 / 4pi) */
#define SH_C3C 0.457045799464465736f /* sqrt(21 / 32pi) */
#define SH_C3D 0.373176332590115391f /* sqrt(7 / 16pi) */
#define SH_C3E 1.44530572132027703f  /* sqrt(105 / 16pi) */

static uint32_t clamp_degree(uint32_t degree)
{
    return degree < 1                     ? 1
           : degree > NERF__SH_MAX_DEGREE ? NERF__SH_MAX_DEGREE
                                          : degree;
}

uint32_t nerf__sh_width(uint32_t degree)
{
    uint32_t d = clamp_degree(degree);
    return d * d;
}

void nerf__sh_forward(uint32_t degree, size_t n, const float *in,
                      size_t in_stride, float *out, size_t out_stride)
{
    const uint32_t d = clamp_degree(degree);
    for (size_t i = 0; i < n; i++) {
        const float *v = in + i * in_stride;
        float *y = out + i * out_stride;
        float x = v[0], yy = v[1], z = v[2];
        float r2 = x * x + yy * yy + z * z;
        /* Normalised here, not trusted from the caller: the l >= 2 forms
         * below assume r = 1 and would be wrong for any other length. */
        float s = r2 > 0.0f ? 1.0f / sqrtf(r2) : 0.0f;
        x *= s;
        yy *= s;
        z *= s;
        y[0] = SH_C0;
        if (d < 2) {
            continue;
        }
        y[1] = -SH_C1 * yy;
        y[2] = SH_C1 * z;
        y[3] = -SH_C1 * x;
        if (d < 3) {
            continue;
        }
        float x2 = x * x, y2 = yy * yy, z2 = z * z;
        float xy = x * yy, yz = yy * z, xz = x * z;
        y[4] = SH_C2A * xy;
        y[5] = -SH_C2A * yz;
        y[6] = SH_C2B * z2 - SH_C2C;
        y[7] = -SH_C2A * xz;
        y[8] = SH_C2D * (x2 - y2);
        if (d < 4) {
            continue;
        }
        y[9] = SH_C3A * yy * (y2 - 3.0f * x2);
        y[10] = SH_C3B * xy * z;
        y[11] = SH_C3C * yy * (1.0f - 5.0f * z2);
        y[12] = SH_C3D * z * (5.0f * z2 - 3.0f);
        y[13] = SH_C3C * x * (1.0f - 5.0f * z2);
        y[14] = SH_C3E * z * (x2 - y2);
        y[15] = SH_C3A * x * (3.0f * y2 - x2);
    }
}

/* ---- as an encoding ----------------------------------------------------- */

static uint32_t width(const nerf__encoding *e)
{
    return nerf__sh_width(e->u.sh_degree);
}

static void encode_rows(const nerf__encoding *e, size_t n, const float *in,
                        float *out, size_t out_stride)
{
    nerf__sh_forward(e->u.sh_degree, n, in, 3, out, out_stride);
}

static void forward(const nerf__encoding *e, const float *params, size_t n,
                    const float *in, float *out, size_t out_stride)
{
    (void)params;
    nerf__encoding_by_rows(e, encode_rows, 40, n, in, out, out_stride);
}

static const nerf__encoding_ops sh_ops = {
    .width = width, .params = nerf__encoding_no_params, .forward = forward};

void nerf__encoding_sh(nerf__encoding *e, uint32_t degree)
{
    memset(e, 0, sizeof *e);
    e->kind = NERF_ENCODING_SPHERICAL_HARMONICS;
    e->ops = &sh_ops;
    e->u.sh_degree = degree;
}
