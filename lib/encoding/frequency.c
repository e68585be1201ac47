/* The frequency (positional) encoding of the paper. */
#include <math.h>
#include <string.h>

#include "encoding.h"
#include "nerf.h"

uint32_t nerf__frequency_width(const nerf__frequency *f)
{
    return f->dims * ((f->include_input ? 1u : 0u) + 2u * f->frequencies);
}

/*
 * The sines and cosines of the doubled frequencies come from the
 * double-angle recurrence, one sin/cos pair per coordinate instead of L.
 * It runs in double precision: each doubling at most doubles the rounding
 * error, so after L = 10..15 doublings the error stays near 1e-12, far
 * below float resolution, whereas a float recurrence would lose about
 * three digits.
 */
void nerf__frequency_encode(const nerf__frequency *enc, size_t n,
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

/* ---- as an encoding ----------------------------------------------------- */

static uint32_t width(const nerf__encoding *e)
{
    return nerf__frequency_width(&e->u.freq);
}

static void encode_rows(const nerf__encoding *e, size_t n, const float *in,
                        float *out, size_t out_stride)
{
    nerf__frequency_encode(&e->u.freq, n, in, 3, out, out_stride);
}

static void forward(const nerf__encoding *e, const float *params, size_t n,
                    const float *in, float *out, size_t out_stride)
{
    (void)params;
    nerf__encoding_by_rows(e, encode_rows, 4 * out_stride, n, in, out,
                           out_stride);
}

static const nerf__encoding_ops frequency_ops = {
    .width = width, .params = nerf__encoding_no_params, .forward = forward};

void nerf__encoding_frequency(nerf__encoding *e, uint32_t frequencies,
                              bool include_input, bool scale_pi)
{
    memset(e, 0, sizeof *e);
    e->kind = NERF_ENCODING_FREQUENCY;
    e->ops = &frequency_ops;
    e->u.freq = (nerf__frequency){3, frequencies, include_input, scale_pi};
}
