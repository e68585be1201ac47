/*
 * Spherical-harmonics direction encoding: the 16 functions against the
 * textbook definition through associated Legendre functions, the sign
 * convention, orthonormality by quadrature, normalisation of the input.
 */
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "sh.h"

static double factorial(int k)
{
    double f = 1.0;
    for (int i = 2; i <= k; i++) {
        f *= i;
    }
    return f;
}

/* P_l^m(t), m >= 0, with the Condon-Shortley phase, by the standard
 * recurrence in l from P_m^m = (-1)^m (2m - 1)!! (1 - t^2)^(m/2). */
static double legendre(int l, int m, double t)
{
    double pmm = 1.0, s = sqrt((1.0 - t) * (1.0 + t));
    for (int i = 1; i <= m; i++) {
        pmm *= -(2.0 * i - 1.0) * s;
    }
    if (l == m) {
        return pmm;
    }
    double p1 = t * (2.0 * m + 1.0) * pmm;
    for (int ll = m + 2; ll <= l; ll++) {
        double p2 =
            ((2.0 * ll - 1.0) * t * p1 - (ll + m - 1.0) * pmm) / (ll - m);
        pmm = p1;
        p1 = p2;
    }
    return p1;
}

/* Real Y_l^m of the unit direction (x, y, z) from its definition. */
static double real_sh(int l, int m, double x, double y, double z)
{
    int am = m < 0 ? -m : m;
    double K = sqrt((2.0 * l + 1.0) / (4.0 * M_PI) * factorial(l - am) /
                    factorial(l + am));
    double phi = atan2(y, x);
    double P = legendre(l, am, z);
    if (m == 0) {
        return K * P;
    }
    return sqrt(2.0) * K * P * (m > 0 ? cos(am * phi) : sin(am * phi));
}

static const double dirs[][3] = {
    {0, 0, 1},          {0, 0, -1},     {1, 0, 0},        {0, 1, 0},
    {-1, 0, 0},         {0.6, -0.8, 0}, {1, 2, 3},        {-0.3, 0.2, -0.9},
    {0.5, 0.5, 0.7071}, {-2, -1, 0.5},  {0.01, -0.02, 1},
};

TEST(values_against_definition)
{
    const int nd = (int)(sizeof dirs / sizeof dirs[0]);
    for (int d = 0; d < nd; d++) {
        double r = sqrt(dirs[d][0] * dirs[d][0] + dirs[d][1] * dirs[d][1] +
                        dirs[d][2] * dirs[d][2]);
        double u[3] = {dirs[d][0] / r, dirs[d][1] / r, dirs[d][2] / r};
        /* Unnormalised on purpose: the encoder normalises. */
        float in[3] = {(float)(3.0 * dirs[d][0]), (float)(3.0 * dirs[d][1]),
                       (float)(3.0 * dirs[d][2])};
        float out[16];
        nerf__sh_forward(4, 1, in, 3, out, 16);
        for (int l = 0, j = 0; l < 4; l++) {
            for (int m = -l; m <= l; m++, j++) {
                double want = real_sh(l, m, u[0], u[1], u[2]);
                if (fabs(out[j] - want) > 2e-6) {
                    FAILF("direction %d, Y_%d^%d (element %d): %.9g vs %.9g", d,
                          l, m, j, out[j], want);
                }
            }
        }
    }
}

TEST(sign_convention_is_instant_ngp)
{
    /* Condon-Shortley phase kept: the l = 1 band is c (-y, z, -x). */
    const double c = sqrt(3.0 / (4.0 * M_PI));
    float out[16];
    const float x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1};
    nerf__sh_forward(4, 1, y, 3, out, 16);
    CHECK_NEAR(out[0], 0.5 / sqrt(M_PI), 1e-7);
    CHECK_NEAR(out[1], -c, 1e-7);
    CHECK_NEAR(out[2], 0.0, 1e-7);
    CHECK_NEAR(out[3], 0.0, 1e-7);
    nerf__sh_forward(4, 1, z, 3, out, 16);
    CHECK_NEAR(out[2], c, 1e-7);
    /* Y_2^0 at the pole: sqrt(5 / 4 pi); Y_3^0: sqrt(7 / 4 pi). */
    CHECK_NEAR(out[6], sqrt(5.0 / (4.0 * M_PI)), 1e-6);
    CHECK_NEAR(out[12], sqrt(7.0 / (4.0 * M_PI)), 1e-6);
    nerf__sh_forward(4, 1, x, 3, out, 16);
    CHECK_NEAR(out[3], -c, 1e-7);
    /* Y_2^2 at +x: sqrt(15 / 16 pi); Y_3^3 at +x: -sqrt(35 / 32 pi). */
    CHECK_NEAR(out[8], sqrt(15.0 / (16.0 * M_PI)), 1e-6);
    CHECK_NEAR(out[15], -sqrt(35.0 / (32.0 * M_PI)), 1e-6);
}

TEST(orthonormal_on_the_sphere)
{
    /* Midpoint rule in theta (weight sin theta) and phi: coarse, so the
     * tolerance is loose, but a wrong constant or a sign-flipped cross
     * term would be off by far more. */
    enum { nt = 64, np = 128 };
    double gram[16][16];
    memset(gram, 0, sizeof gram);
    for (int i = 0; i < nt; i++) {
        double th = (i + 0.5) * M_PI / nt;
        double w = sin(th) * (M_PI / nt) * (2.0 * M_PI / np);
        float in[np][3], out[np][16];
        for (int k = 0; k < np; k++) {
            double ph = (k + 0.5) * 2.0 * M_PI / np;
            in[k][0] = (float)(sin(th) * cos(ph));
            in[k][1] = (float)(sin(th) * sin(ph));
            in[k][2] = (float)cos(th);
        }
        nerf__sh_forward(4, np, &in[0][0], 3, &out[0][0], 16);
        for (int k = 0; k < np; k++) {
            for (int a = 0; a < 16; a++) {
                for (int b = 0; b < 16; b++) {
                    gram[a][b] += w * out[k][a] * out[k][b];
                }
            }
        }
    }
    double worst = 0.0;
    for (int a = 0; a < 16; a++) {
        for (int b = 0; b < 16; b++) {
            double err = fabs(gram[a][b] - (a == b ? 1.0 : 0.0));
            worst = err > worst ? err : worst;
        }
    }
    CHECK(worst < 5e-3);
    if (worst >= 5e-3) {
        printf("  worst Gram matrix error %g\n", worst);
    }
}

TEST(lower_degrees_are_prefixes)
{
    const float v[3] = {0.3f, -0.5f, 0.8f};
    float full[16];
    nerf__sh_forward(4, 1, v, 3, full, 16);
    for (uint32_t d = 1; d <= 4; d++) {
        CHECK_EQ_INT(nerf__sh_width(d), d * d);
        float out[2][20];
        memset(out, 0x7f, sizeof out);
        /* Two rows with a gap: stride wider than the width. */
        const float two[2][3] = {{v[0], v[1], v[2]}, {v[0], v[1], v[2]}};
        nerf__sh_forward(d, 2, &two[0][0], 3, &out[0][0], 20);
        for (int r = 0; r < 2; r++) {
            CHECK(memcmp(out[r], full, d * d * sizeof(float)) == 0);
            for (uint32_t j = d * d; j < 20; j++) {
                unsigned char b;
                memcpy(&b, (char *)&out[r][j], 1);
                CHECK_EQ_INT(b, 0x7f);
            }
        }
    }
    CHECK_EQ_INT(nerf__sh_width(0), 1);
    CHECK_EQ_INT(nerf__sh_width(9), 16);
}

TEST(zero_direction)
{
    const float zero[3] = {0, 0, 0};
    float out[16];
    nerf__sh_forward(4, 1, zero, 3, out, 16);
    for (int j = 0; j < 16; j++) {
        double want = j == 0   ? 0.5 / sqrt(M_PI)
                      : j == 6 ? -sqrt(5.0 / (16.0 * M_PI))
                               : 0.0;
        CHECK_NEAR(out[j], want, 1e-7);
    }
}

int main(void)
{
    RUN(values_against_definition);
    RUN(sign_convention_is_instant_ngp);
    RUN(orthonormal_on_the_sphere);
    RUN(lower_degrees_are_prefixes);
    RUN(zero_direction);
    HARNESS_EXIT();
}
