#include "encoding.h"

#include <math.h>

#include "nerf.h"

uint32_t nerf__encoding_width(const nerf__encoding *enc)
{
    return enc->dims * ((enc->include_input ? 1u : 0u) + 2u * enc->frequencies);
}

/*
 * The sines and cosines of the doubled frequencies come from the
 * double-angle recurrence, one sin/cos pair per coordinate instead of L.
 * It runs in double precision: each doubling at most doubles the rounding
 * error, so after L = 10..15 doublings the error stays near 1e-12, far
 * below float resolution, whereas a float recurrence would lose about
 * three digits.
 */
void nerf__encoding_forward(const nerf__encoding *enc, size_t n,
                            const float *in, size_t in_stride, float *out,
                            size_t out_stride)
{
    const uint32_t d = enc->dims;
    const uint32_t L = enc->frequencies;
    const double scale = enc->scale_pi ? 3.14159265358979323846 : 1.0;
    for (size_t i = 0; i < n; i++) {
        const float *x = in + i * in_stride;
        float *y = out + i * out_stride;
        if (enc->include_input) {
            for (uint32_t c = 0; c < d; c++) {
                y[c] = x[c];
            }
            y += d;
        }
        for (uint32_t c = 0; c < d; c++) {
            double s = 0.0, co = 1.0;
            if (L > 0) {
                double a = scale * (double)x[c];
                s = sin(a);
                co = cos(a);
            }
            for (uint32_t k = 0; k < L; k++) {
                y[2 * d * k + c] = (float)s;
                y[2 * d * k + d + c] = (float)co;
                double s2 = 2.0 * s * co;
                co = (co - s) * (co + s);
                s = s2;
            }
        }
    }
}
