#include "metrics.h"

#include <math.h>
#include <string.h>

#include "env.h"

#define WIN NERF__SSIM_WINDOW

/* The five local moments SSIM needs, stored as separate planes. */
enum { MU_A, MU_B, M_AA, M_BB, M_AB, N_MOMENTS };

void nerf__ssim_window(double taps[NERF__SSIM_WINDOW])
{
    double sum = 0.0;
    for (int k = 0; k < WIN; k++) {
        double d = (double)(k - WIN / 2) / NERF__SSIM_SIGMA;
        taps[k] = exp(-0.5 * d * d);
        sum += taps[k];
    }
    for (int k = 0; k < WIN; k++) {
        taps[k] /= sum;
    }
}

NERF_API int nerf_psnr(const float *a, const float *b, size_t count,
                       double *out)
{
    if (a == NULL || b == NULL || out == NULL || count == 0) {
        return nerf__error(NERF_EINVAL, "nerf_psnr: NULL argument or zero "
                           "count");
    }
    double sum = 0.0;
    for (size_t i = 0; i < count; i++) {
        double d = (double)a[i] - (double)b[i];
        sum += d * d;
    }
    if (!isfinite(sum)) {
        return nerf__error(NERF_EINVAL, "nerf_psnr: the images hold NaN or "
                           "infinite values");
    }
    *out = sum == 0.0 ? INFINITY : -10.0 * log10(sum / (double)count);
    return NERF_OK;
}

/*
 * Horizontal pass over one row of one channel: the Gaussian-weighted
 * moments at each 'valid' position, written as N_MOMENTS planes of out_w.
 */
static void filter_row(const float *a, const float *b, uint32_t stride,
                       uint32_t out_w, const double *g, double *dst)
{
    for (uint32_t x = 0; x < out_w; x++) {
        double ma = 0.0, mb = 0.0, aa = 0.0, bb = 0.0, ab = 0.0;
        for (int k = 0; k < WIN; k++) {
            double va = a[(size_t)(x + k) * stride];
            double vb = b[(size_t)(x + k) * stride];
            ma += g[k] * va;
            mb += g[k] * vb;
            aa += g[k] * va * va;
            bb += g[k] * vb * vb;
            ab += g[k] * va * vb;
        }
        dst[MU_A * out_w + x] = ma;
        dst[MU_B * out_w + x] = mb;
        dst[M_AA * out_w + x] = aa;
        dst[M_BB * out_w + x] = bb;
        dst[M_AB * out_w + x] = ab;
    }
}

/*
 * Vertical pass for one output row from the WIN horizontally filtered rows
 * held in the ring (row oy + k lives in slot (oy + k) % WIN); returns the
 * sum of the row's SSIM values.
 */
static double ssim_row(const double *ring, uint32_t oy, uint32_t out_w,
                       const double *g, const uint8_t *ok)
{
    const double c1 = (NERF__SSIM_K1 * NERF__SSIM_K1);
    const double c2 = (NERF__SSIM_K2 * NERF__SSIM_K2);
    size_t plane = (size_t)N_MOMENTS * out_w;
    double row_sum = 0.0;
    for (uint32_t x = 0; x < out_w; x++) {
        if (ok != NULL && !ok[x]) {
            continue;
        }
        double m[N_MOMENTS] = {0.0, 0.0, 0.0, 0.0, 0.0};
        for (int k = 0; k < WIN; k++) {
            const double *r = ring + ((oy + (uint32_t)k) % WIN) * plane;
            for (int j = 0; j < N_MOMENTS; j++) {
                m[j] += g[k] * r[(size_t)j * out_w + x];
            }
        }
        double var_a = m[M_AA] - m[MU_A] * m[MU_A];
        double var_b = m[M_BB] - m[MU_B] * m[MU_B];
        double cov = m[M_AB] - m[MU_A] * m[MU_B];
        double num = (2.0 * m[MU_A] * m[MU_B] + c1) * (2.0 * cov + c2);
        double den = (m[MU_A] * m[MU_A] + m[MU_B] * m[MU_B] + c1) *
                     (var_a + var_b + c2);
        row_sum += num / den;
    }
    return row_sum;
}

/*
 * Which windows of output row oy hold no left-out pixel, into ok[out_w],
 * from counts[width], the left-out pixels of each column within the
 * window's rows; returns how many.
 */
static size_t windows_clear(const uint32_t *counts, uint32_t out_w,
                            uint8_t *ok)
{
    uint32_t run = 0;
    for (int k = 0; k < WIN - 1; k++) {
        run += counts[k];
    }
    size_t n = 0;
    for (uint32_t x = 0; x < out_w; x++) {
        run += counts[x + WIN - 1];
        ok[x] = run == 0;
        n += ok[x];
        run -= counts[x];
    }
    return n;
}

/*
 * SSIM with a mask: the map is averaged over the windows that hold no
 * left-out pixel, so that a left-out pixel changes nothing (a window that
 * only reached into it would still compare its colour).  Column counts of
 * left-out pixels over the last WIN rows keep the memory O(width).
 */
static int ssim_core(const char *fn, const float *a, const float *b,
                     const uint8_t *mask, uint32_t width, uint32_t height,
                     uint32_t channels, double *out)
{
    if (a == NULL || b == NULL || out == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL argument", fn);
    }
    if (width < WIN || height < WIN) {
        return nerf__error(NERF_EINVAL, "%s: a %ux%u image is smaller "
                           "than the %dx%d window", fn, (unsigned)width,
                           (unsigned)height, WIN, WIN);
    }
    if (channels < 1 || channels > 4) {
        return nerf__error(NERF_EINVAL, "%s: %u channels (1..4)", fn,
                           (unsigned)channels);
    }
    size_t pixels, samples;
    if (nerf__mul_size(width, height, &pixels) != 0 ||
        nerf__mul_size(pixels, channels, &samples) != 0) {
        return nerf__error(NERF_EINVAL, "%s: %ux%ux%u is too large", fn,
                           (unsigned)width, (unsigned)height,
                           (unsigned)channels);
    }
    double g[WIN];
    nerf__ssim_window(g);
    uint32_t out_w = width - (WIN - 1);
    /* WIN filtered rows at a time: memory does not grow with height. */
    double *ring = nerf__calloc(NULL, (size_t)WIN * N_MOMENTS * out_w,
                                sizeof *ring);
    uint32_t *counts = NULL;
    uint8_t *ok = NULL;
    if (mask != NULL) {
        counts = nerf__calloc(NULL, width, sizeof *counts);
        ok = nerf__calloc(NULL, out_w, 1);
    }
    if (ring == NULL || (mask != NULL && (counts == NULL || ok == NULL))) {
        nerf__free(NULL, ring);
        nerf__free(NULL, counts);
        nerf__free(NULL, ok);
        return NERF_ENOMEM;
    }
    size_t plane = (size_t)N_MOMENTS * out_w;
    size_t row_len = (size_t)width * channels;
    double total = 0.0;
    size_t windows = 0;
    for (uint32_t c = 0; c < channels; c++) {
        if (counts != NULL) {
            memset(counts, 0, width * sizeof *counts);
        }
        for (uint32_t y = 0; y < height; y++) {
            filter_row(a + y * row_len + c, b + y * row_len + c, channels,
                       out_w, g, ring + (y % WIN) * plane);
            if (counts != NULL) {
                const uint8_t *in = mask + (size_t)y * width;
                const uint8_t *gone = y >= WIN
                    ? mask + (size_t)(y - WIN) * width : NULL;
                for (uint32_t x = 0; x < width; x++) {
                    counts[x] += in[x] == 0;
                    counts[x] -= gone != NULL && gone[x] == 0;
                }
            }
            if (y >= WIN - 1) {
                windows += ok != NULL ? windows_clear(counts, out_w, ok)
                                      : out_w;
                total += ssim_row(ring, y - (WIN - 1), out_w, g, ok);
            }
        }
    }
    nerf__free(NULL, ring);
    nerf__free(NULL, counts);
    nerf__free(NULL, ok);
    if (!isfinite(total)) {
        return nerf__error(NERF_EINVAL, "%s: the images hold NaN or "
                           "infinite values", fn);
    }
    if (windows == 0) {
        return nerf__error(NERF_EINVAL, "%s: the mask leaves no %dx%d "
                           "window whole", fn, WIN, WIN);
    }
    *out = total / (double)windows;
    return NERF_OK;
}

NERF_API int nerf_ssim(const float *a, const float *b, uint32_t width,
                       uint32_t height, uint32_t channels, double *out)
{
    return ssim_core("nerf_ssim", a, b, NULL, width, height, channels, out);
}

NERF_API int nerf_ssim_masked(const float *a, const float *b,
                              const uint8_t *mask, uint32_t width,
                              uint32_t height, uint32_t channels, double *out)
{
    if (mask == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_ssim_masked: NULL mask");
    }
    return ssim_core("nerf_ssim_masked", a, b, mask, width, height, channels,
                     out);
}

NERF_API int nerf_psnr_masked(const float *a, const float *b,
                              const uint8_t *mask, size_t pixels,
                              uint32_t channels, double *out)
{
    if (a == NULL || b == NULL || mask == NULL || out == NULL ||
        pixels == 0 || channels < 1 || channels > 4) {
        return nerf__error(NERF_EINVAL, "nerf_psnr_masked: NULL argument, "
                           "zero pixels or channels not 1..4");
    }
    double sum = 0.0;
    size_t kept = 0;
    for (size_t i = 0; i < pixels; i++) {
        if (mask[i] == 0) {
            continue;
        }
        kept++;
        for (uint32_t c = 0; c < channels; c++) {
            double d = (double)a[i * channels + c] -
                       (double)b[i * channels + c];
            sum += d * d;
        }
    }
    if (!isfinite(sum)) {
        return nerf__error(NERF_EINVAL, "nerf_psnr_masked: the images hold "
                           "NaN or infinite values");
    }
    if (kept == 0) {
        return nerf__error(NERF_EINVAL, "nerf_psnr_masked: the mask leaves "
                           "no pixel");
    }
    *out = sum == 0.0 ? INFINITY
                      : -10.0 * log10(sum / ((double)kept * channels));
    return NERF_OK;
}
