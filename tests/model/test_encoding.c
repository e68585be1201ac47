/* Frequency encoding against its closed form, in both forms, through the
 * encoding interface the network uses. */
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "encoding.h"
#include "nerf.h"
#include "sh.h"

static const float inputs[4][3] = {
    {0.0f, 0.5f, -0.25f}, {1.5f, -1.5f, 0.75f}, {3.1f, -2.2f, 0.001f},
    {-4.0f, 6.0f, 2.5f}};

/* Closed form in double: element j of the encoding of x. */
static double closed_form(const nerf__frequency *e, const float *x,
                          uint32_t j)
{
    uint32_t d = e->dims;
    if (e->include_input) {
        if (j < d) {
            return x[j];
        }
        j -= d;
    }
    uint32_t k = j / (2 * d), r = j % (2 * d);
    double a = ldexp(e->scale_pi ? M_PI : 1.0, (int)k) * (double)x[r % d];
    return r < d ? sin(a) : cos(a);
}

static void check_form(bool include_input, bool scale_pi, uint32_t L)
{
    nerf__encoding e;
    nerf__encoding_frequency(&e, L, include_input, scale_pi);
    uint32_t w = nerf__encoding_width(&e);
    CHECK_EQ_INT(w, 3 * ((include_input ? 1 : 0) + 2 * L));
    CHECK_EQ_INT(nerf__encoding_params(&e), 0);
    float out[4 * 200];
    /* A stride wider than the width: the encoder must not touch the gap. */
    size_t stride = w + 5;
    memset(out, 0x7f, sizeof out);
    nerf__encoding_forward(&e, NULL, 4, &inputs[0][0], out, stride);
    for (int i = 0; i < 4; i++) {
        for (uint32_t j = 0; j < w; j++) {
            double want = closed_form(&e.u.freq, inputs[i], j);
            /* The argument is rounded to float precision relative to
             * 2^k |x|, so allow an error proportional to it. */
            double tol = 2e-6 + 4e-7 * ldexp(fabs(inputs[i][j % 3]) + 1.0, (int)(j / 6));
            if (fabs(out[i * stride + j] - want) > tol) {
                FAILF("L=%u input %d element %u: %.9g vs %.9g", L, i, j,
                      out[i * stride + j], want);
                return;
            }
        }
        for (size_t j = w; j < stride; j++) {
            unsigned char b;
            memcpy(&b, (char *)&out[i * stride + j], 1);
            CHECK_EQ_INT(b, 0x7f);
        }
    }
}

TEST(reference_form)
{
    check_form(true, false, 10);
    check_form(true, false, 4);
}

TEST(paper_form)
{
    check_form(false, true, 10);
    check_form(false, true, 15);
}

TEST(no_encoding_is_raw_input)
{
    nerf__encoding e;
    nerf__encoding_frequency(&e, 0, true, false);
    CHECK_EQ_INT(nerf__encoding_width(&e), 3);
    float out[12];
    nerf__encoding_forward(&e, NULL, 4, &inputs[0][0], out, 3);
    CHECK(memcmp(out, inputs, sizeof out) == 0);
}

TEST(forms_differ_as_they_should)
{
    nerf__encoding ref, paper;
    nerf__encoding_frequency(&ref, 10, true, false);
    nerf__encoding_frequency(&paper, 10, false, true);
    CHECK_EQ_INT(nerf__encoding_width(&ref), 63);
    CHECK_EQ_INT(nerf__encoding_width(&paper), 60);
    float a[63], b[60];
    const float x[3] = {0.3f, -0.2f, 0.1f};
    nerf__encoding_forward(&ref, NULL, 1, x, a, 63);
    nerf__encoding_forward(&paper, NULL, 1, x, b, 60);
    /* Reference k-th block is sin(2^k x); paper's is sin(2^k pi x). */
    CHECK_NEAR(a[3], sin(0.3), 1e-6);
    CHECK_NEAR(b[0], sin(M_PI * 0.3), 1e-6);
    CHECK(fabs(a[3] - b[0]) > 0.1);
}

/*
 * The hash grid behind the interface gives what its own functions give:
 * the same forward, and a backward that adds the per-level gradients.
 */
TEST(hashgrid_through_the_interface)
{
    const float lo[3] = {-1.5f, -1.5f, -1.5f}, hi[3] = {1.5f, 1.5f, 1.5f};
    nerf__hashgrid hg;
    CHECK_OK(nerf__hashgrid_defaults(&hg, lo, hi));
    hg.levels = 4;
    hg.log2_table = 10;
    hg.max_resolution = 64;
    CHECK_OK(nerf__hashgrid_layout(&hg));
    nerf__encoding e;
    nerf__encoding_hashgrid(&e, &hg);
    const uint32_t w = nerf__encoding_width(&e);
    const size_t np = nerf__encoding_params(&e);
    CHECK_EQ_INT(w, 8);
    CHECK(np == hg.count);
    float *table = calloc(np, sizeof(float));
    float *g1 = calloc(np, sizeof(float)), *g2 = calloc(np, sizeof(float));
    if (table == NULL || g1 == NULL || g2 == NULL) {
        FAILF("out of memory");
        free(table), free(g1), free(g2);
        return;
    }
    nerf__encoding_init(&e, table, 7, 100);
    float a[4 * 8], b[4 * 8], d[4 * 8];
    nerf__encoding_forward(&e, table, 4, &inputs[0][0], a, 8);
    nerf__hashgrid_forward_range(&hg, table, 0, 4, &inputs[0][0], 3, b, 8);
    CHECK(memcmp(a, b, sizeof a) == 0);
    for (int i = 0; i < 32; i++) {
        d[i] = 0.25f * (float)(i % 7) - 0.5f;
    }
    nerf__encoding_backward(&e, 4, &inputs[0][0], d, 8, g1);
    for (uint32_t l = 0; l < hg.levels; l++) {
        nerf__hashgrid_backward_level(&hg, l, 4, &inputs[0][0], 3, d, 8, g2);
    }
    CHECK(memcmp(g1, g2, np * sizeof(float)) == 0);
    size_t touched = 0;
    for (size_t k = 0; k < np; k++) {
        touched += g1[k] != 0.0f;
    }
    CHECK(touched > 0);
    free(table), free(g1), free(g2);
}

TEST(sh_through_the_interface)
{
    nerf__encoding e;
    nerf__encoding_sh(&e, 4);
    CHECK_EQ_INT(nerf__encoding_width(&e), 16);
    CHECK_EQ_INT(nerf__encoding_params(&e), 0);
    float a[4 * 16], b[4 * 16];
    nerf__encoding_forward(&e, NULL, 4, &inputs[0][0], a, 16);
    nerf__sh_forward(4, 4, &inputs[0][0], 3, b, 16);
    CHECK(memcmp(a, b, sizeof a) == 0);
}

int main(void)
{
    RUN(reference_form);
    RUN(paper_form);
    RUN(no_encoding_is_raw_input);
    RUN(forms_differ_as_they_should);
    RUN(hashgrid_through_the_interface);
    RUN(sh_through_the_interface);
    HARNESS_EXIT();
}
