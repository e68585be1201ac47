/* PSNR and SSIM against closed forms and a direct 2-D implementation. */
#include <nerf.h>

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../harness.h"

/* A small deterministic generator (xorshift64*), independent of libnerf. */
static uint64_t rng_state = 88172645463325252ull;

static double uniform(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ull) >> 11) /
           9007199254740992.0;
}

static double gaussian(void)
{
    double u1 = 1.0 - uniform(), u2 = uniform();
    return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
}

static float *random_image(size_t n)
{
    float *p = malloc(n * sizeof *p);
    for (size_t i = 0; i < n; i++) {
        p[i] = (float)uniform();
    }
    return p;
}

/*
 * SSIM written straight from its definition: for every valid 11 x 11
 * window, weighted means, variances and covariance with the 2-D Gaussian
 * weight g(dx) g(dy), all in double.  No separability, no ring buffer.
 */
static double reference_ssim_masked(const float *a, const float *b,
                                    const uint8_t *mask, int w, int h,
                                    int ch);

static double reference_ssim(const float *a, const float *b, int w, int h,
                             int ch)
{
    return reference_ssim_masked(a, b, NULL, w, h, ch);
}

/* Whether the window at (x, y) holds no pixel mask leaves out. */
static int window_whole(const uint8_t *mask, int w, int x, int y)
{
    for (int dy = 0; mask != NULL && dy < 11; dy++) {
        for (int dx = 0; dx < 11; dx++) {
            if (mask[(size_t)(y + dy) * w + x + dx] == 0) {
                return 0;
            }
        }
    }
    return 1;
}

static double reference_ssim_masked(const float *a, const float *b,
                                    const uint8_t *mask, int w, int h,
                                    int ch)
{
    double g[11], sum = 0.0;
    for (int k = 0; k < 11; k++) {
        g[k] = exp(-0.5 * ((k - 5) / 1.5) * ((k - 5) / 1.5));
        sum += g[k];
    }
    for (int k = 0; k < 11; k++) {
        g[k] /= sum;
    }
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double total = 0.0, windows = 0.0;
    for (int c = 0; c < ch; c++) {
        for (int y = 0; y + 11 <= h; y++) {
            for (int x = 0; x + 11 <= w; x++) {
                if (!window_whole(mask, w, x, y)) {
                    continue;
                }
                windows += 1.0;
                double ma = 0, mb = 0, aa = 0, bb = 0, ab = 0;
                for (int dy = 0; dy < 11; dy++) {
                    for (int dx = 0; dx < 11; dx++) {
                        double wgt = g[dy] * g[dx];
                        size_t i = ((size_t)(y + dy) * w + (x + dx)) * ch + c;
                        ma += wgt * a[i];
                        mb += wgt * b[i];
                        aa += wgt * a[i] * a[i];
                        bb += wgt * b[i] * b[i];
                        ab += wgt * a[i] * b[i];
                    }
                }
                double va = aa - ma * ma, vb = bb - mb * mb, cov = ab - ma * mb;
                total += ((2 * ma * mb + c1) * (2 * cov + c2)) /
                         ((ma * ma + mb * mb + c1) * (va + vb + c2));
            }
        }
    }
    return total / windows;
}

TEST(identical_images)
{
    float *a = random_image(32 * 20 * 3);
    double psnr = 0.0, ssim = 0.0;
    CHECK_OK(nerf_psnr(a, a, 32 * 20 * 3, &psnr));
    CHECK(isinf(psnr) && psnr > 0);
    CHECK_OK(nerf_ssim(a, a, 32, 20, 3, &ssim));
    CHECK_NEAR(ssim, 1.0, 1e-12);
    free(a);
}

TEST(psnr_closed_forms)
{
    enum { N = 128 * 128 * 3 };
    float *a = random_image(N), *b = malloc(N * sizeof *b);
    /* A constant offset d: MSE d^2, PSNR -20 log10(d). */
    for (int i = 0; i < N; i++) {
        b[i] = a[i] + 0.1f;
    }
    double psnr;
    CHECK_OK(nerf_psnr(a, b, N, &psnr));
    CHECK_NEAR(psnr, 20.0, 1e-4);
    /* Gaussian noise of variance v: PSNR close to 10 log10(1 / v). */
    double sigma = 0.05;
    for (int i = 0; i < N; i++) {
        b[i] = a[i] + (float)(sigma * gaussian());
    }
    CHECK_OK(nerf_psnr(a, b, N, &psnr));
    CHECK_NEAR(psnr, 10.0 * log10(1.0 / (sigma * sigma)), 0.05);
    free(a);
    free(b);
}

TEST(ssim_constant_images)
{
    /* Flat images have no variance: SSIM = (2 a b + C1) / (a^2 + b^2 + C1). */
    enum { W = 16, H = 13 };
    float a[W * H], b[W * H];
    for (int i = 0; i < W * H; i++) {
        a[i] = 0.3f;
        b[i] = 0.7f;
    }
    double ssim;
    CHECK_OK(nerf_ssim(a, b, W, H, 1, &ssim));
    double x = 0.3f, y = 0.7f, c1 = 1e-4;
    CHECK_NEAR(ssim, (2 * x * y + c1) / (x * x + y * y + c1), 1e-9);
}

TEST(ssim_matches_direct_definition)
{
    static const int sizes[][3] = {{11, 11, 1}, {23, 17, 3}, {40, 12, 3},
                                   {14, 29, 2}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        int w = sizes[s][0], h = sizes[s][1], ch = sizes[s][2];
        size_t n = (size_t)w * h * ch;
        float *a = random_image(n), *b = random_image(n);
        /* Correlate b with a so that SSIM is far from 0 as well. */
        for (size_t i = 0; i < n; i++) {
            b[i] = 0.7f * a[i] + 0.3f * b[i];
        }
        double got, want = reference_ssim(a, b, w, h, ch);
        CHECK_OK(nerf_ssim(a, b, (uint32_t)w, (uint32_t)h, (uint32_t)ch,
                           &got));
        CHECK_NEAR(got, want, 1e-10);
        double back;
        CHECK_OK(nerf_ssim(b, a, (uint32_t)w, (uint32_t)h, (uint32_t)ch,
                           &back));
        CHECK_NEAR(back, got, 1e-14);
        free(a);
        free(b);
    }
}

/*
 * The masked scores against their definitions: PSNR over the kept pixels'
 * channels, SSIM over the windows that hold no left-out pixel; a mask of
 * ones gives the unmasked scores, and what lies under a left-out pixel
 * changes nothing.
 */
TEST(masked_scores_leave_the_masked_pixels_out)
{
    static const int sizes[][3] = {{23, 17, 3}, {40, 30, 3}, {14, 29, 1}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        int w = sizes[s][0], h = sizes[s][1], ch = sizes[s][2];
        size_t px = (size_t)w * h, n = px * ch;
        float *a = random_image(n), *b = random_image(n);
        uint8_t *mask = malloc(px), *ones = malloc(px);
        memset(ones, 1, px);
        size_t kept = 0;
        for (size_t i = 0; i < px; i++) {
            /* A block in a corner and a few scattered pixels. */
            int x = (int)(i % w), y = (int)(i / w);
            mask[i] = !((x < 5 && y < 6) || uniform() < 0.01);
            kept += mask[i];
        }
        for (size_t i = 0; i < n; i++) {
            b[i] = 0.7f * a[i] + 0.3f * b[i];
        }
        double sum = 0.0;
        for (size_t i = 0; i < px; i++) {
            for (int c = 0; c < ch && mask[i]; c++) {
                double d = (double)a[i * ch + c] - b[i * ch + c];
                sum += d * d;
            }
        }
        double psnr, ssim, all_psnr, all_ssim, psnr1, ssim1;
        CHECK_OK(nerf_psnr_masked(a, b, mask, px, (uint32_t)ch, &psnr));
        CHECK_NEAR(psnr, -10.0 * log10(sum / ((double)kept * ch)), 1e-9);
        CHECK_OK(nerf_ssim_masked(a, b, mask, (uint32_t)w, (uint32_t)h,
                                  (uint32_t)ch, &ssim));
        CHECK_NEAR(ssim, reference_ssim_masked(a, b, mask, w, h, ch),
                   1e-10);
        CHECK_OK(nerf_psnr(a, b, n, &all_psnr));
        CHECK_OK(nerf_ssim(a, b, (uint32_t)w, (uint32_t)h, (uint32_t)ch,
                           &all_ssim));
        CHECK_OK(nerf_psnr_masked(a, b, ones, px, (uint32_t)ch, &psnr1));
        CHECK_OK(nerf_ssim_masked(a, b, ones, (uint32_t)w, (uint32_t)h,
                                  (uint32_t)ch, &ssim1));
        CHECK(psnr1 == all_psnr);
        CHECK(ssim1 == all_ssim);
        CHECK(ssim != all_ssim);
        for (size_t i = 0; i < px; i++) {
            for (int c = 0; c < ch && !mask[i]; c++) {
                b[i * ch + c] = 1.0f - b[i * ch + c];
            }
        }
        double psnr2, ssim2;
        CHECK_OK(nerf_psnr_masked(a, b, mask, px, (uint32_t)ch, &psnr2));
        CHECK_OK(nerf_ssim_masked(a, b, mask, (uint32_t)w, (uint32_t)h,
                                  (uint32_t)ch, &ssim2));
        CHECK(psnr2 == psnr);
        CHECK(ssim2 == ssim);
        free(a);
        free(b);
        free(mask);
        free(ones);
    }
    float a[12 * 12] = {0}, b[12 * 12] = {0};
    uint8_t none[12 * 12] = {0};
    double out;
    CHECK_EQ_INT(nerf_psnr_masked(a, b, none, 144, 1, &out), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "leaves no pixel") != NULL);
    none[0] = 1;
    CHECK_EQ_INT(nerf_ssim_masked(a, b, none, 12, 12, 1, &out), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "window whole") != NULL);
    CHECK_EQ_INT(nerf_ssim_masked(a, b, NULL, 12, 12, 1, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_psnr_masked(a, b, NULL, 144, 1, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_psnr_masked(a, b, none, 144, 5, &out), NERF_EINVAL);
}

TEST(more_noise_lower_scores)
{
    enum { W = 48, H = 40, N = W * H * 3 };
    float *a = random_image(N), *b = malloc(N * sizeof *b);
    /* Smooth the base image so that structure exists to lose. */
    for (int i = 0; i < N; i++) {
        a[i] = 0.5f + 0.4f * (float)sin(0.2 * (i / 3 % W)) *
               (float)cos(0.15 * (i / 3 / W));
    }
    double last_ssim = 2.0, last_psnr = INFINITY;
    for (int level = 1; level <= 4; level++) {
        for (int i = 0; i < N; i++) {
            b[i] = a[i] + (float)(0.03 * level * gaussian());
        }
        double ssim, psnr;
        CHECK_OK(nerf_ssim(a, b, W, H, 3, &ssim));
        CHECK_OK(nerf_psnr(a, b, N, &psnr));
        CHECK(ssim < last_ssim);
        CHECK(psnr < last_psnr);
        CHECK(ssim > 0.0 && ssim < 1.0);
        last_ssim = ssim;
        last_psnr = psnr;
    }
    free(a);
    free(b);
}

TEST(bad_arguments)
{
    float a[20 * 20 * 3] = {0}, b[20 * 20 * 3] = {0};
    double out;
    CHECK_EQ_INT(nerf_psnr(NULL, b, 3, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_psnr(a, b, 0, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_psnr(a, b, 3, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_ssim(a, b, 10, 20, 3, &out), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "smaller than") != NULL);
    CHECK_EQ_INT(nerf_ssim(a, b, 20, 10, 3, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_ssim(a, b, 20, 20, 0, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_ssim(a, b, 20, 20, 5, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_ssim(a, NULL, 20, 20, 3, &out), NERF_EINVAL);
    a[7] = NAN;
    CHECK_EQ_INT(nerf_psnr(a, b, 20 * 20 * 3, &out), NERF_EINVAL);
    CHECK_EQ_INT(nerf_ssim(a, b, 20, 20, 3, &out), NERF_EINVAL);
}

int main(void)
{
    RUN(identical_images);
    RUN(psnr_closed_forms);
    RUN(ssim_constant_images);
    RUN(ssim_matches_direct_definition);
    RUN(masked_scores_leave_the_masked_pixels_out);
    RUN(more_noise_lower_scores);
    RUN(bad_arguments);
    HARNESS_EXIT();
}
