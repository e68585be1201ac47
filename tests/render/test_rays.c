/* Camera rays in the OpenGL convention, and the NDC warp. */
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "ndc.h"
#include "nerf.h"
#include "rng.h"

static void camera(nerf_camera *c, uint32_t w, uint32_t h, float f)
{
    NERF_CAMERA_INIT(c);
    c->width = w;
    c->height = h;
    c->fx = c->fy = f;
    c->cx = 0.5f * (float)w;
    c->cy = 0.5f * (float)h;
}

TEST(camera_conventions)
{
    nerf_camera c;
    camera(&c, 5, 3, 10.0f);
    float o[15 * 3], d[15 * 3];
    CHECK_OK(nerf_camera_rays(&c, 0, 15, o, d));
    /* The middle pixel's centre is the principal point: straight down -z. */
    const float *m = d + 3 * (1 * 5 + 2);
    CHECK(m[0] == 0.0f && m[1] == 0.0f && m[2] == -1.0f);
    /* Pixel (0, 0) is top left: x negative (left), y positive (up). */
    CHECK_NEAR(d[0], (0.5 - 2.5) / 10.0, 1e-7);
    CHECK_NEAR(d[1], -(0.5 - 1.5) / 10.0, 1e-7);
    CHECK(o[0] == 0.0f && o[1] == 0.0f && o[2] == 0.0f);
    /* The reference's convention drops the half pixel. */
    c.flags = NERF_CAMERA_PIXEL_CORNER;
    CHECK_OK(nerf_camera_rays(&c, 0, 1, o, d));
    CHECK_NEAR(d[0], -2.5 / 10.0, 1e-7);
    CHECK_NEAR(d[1], 1.5 / 10.0, 1e-7);

    /* A camera at (1, 2, 3) turned 90 degrees about world y: its -z axis
     * looks along world -x. */
    camera(&c, 5, 3, 10.0f);
    const float pose[12] = {0, 0, 1, 1, 0, 1, 0, 2, -1, 0, 0, 3};
    memcpy(c.c2w, pose, sizeof pose);
    CHECK_OK(nerf_camera_rays(&c, 7, 1, o, d));
    CHECK(d[0] == -1.0f && d[1] == 0.0f && d[2] == 0.0f);
    CHECK(o[0] == 1.0f && o[1] == 2.0f && o[2] == 3.0f);
}

TEST(camera_validation)
{
    nerf_camera c;
    float o[3], d[3];
    camera(&c, 4, 4, 5.0f);
    CHECK_EQ_INT(nerf_camera_rays(&c, 16, 1, o, d), NERF_EINVAL);
    CHECK_EQ_INT(nerf_camera_rays(&c, 15, 2, o, d), NERF_EINVAL);
    CHECK_OK(nerf_camera_rays(&c, 16, 0, NULL, NULL));
    c.fx = 0.0f;
    CHECK_EQ_INT(nerf_camera_rays(&c, 0, 1, o, d), NERF_EINVAL);
    c.fx = 5.0f;
    c.c2w[3] = NAN;
    CHECK_EQ_INT(nerf_camera_rays(&c, 0, 1, o, d), NERF_EINVAL);
    c.c2w[3] = 0.0f;
    c.width = 0;
    CHECK_EQ_INT(nerf_camera_rays(&c, 0, 1, o, d), NERF_EINVAL);
    c.width = 4;
    c.flags = 0x100;
    CHECK_EQ_INT(nerf_camera_rays(&c, 0, 1, o, d), NERF_EINVAL);
    c.flags = 0;
    c.struct_size = 2;
    CHECK_EQ_INT(nerf_camera_rays(&c, 0, 1, o, d), NERF_EINVAL);
    CHECK_EQ_INT(nerf_camera_rays(NULL, 0, 1, o, d), NERF_EINVAL);
    CHECK_EQ_INT(nerf_camera_init(NULL, sizeof c), NERF_EINVAL);
}

/* The NDC image of a world point: x and y projected, depth z'. */
static void ndc_point(double f, double w, double h, double near,
                      const double *p, double *q)
{
    q[0] = -f / (w / 2) * p[0] / p[2];
    q[1] = -f / (h / 2) * p[1] / p[2];
    q[2] = 1 + 2 * near / p[2];
}

TEST(ndc_near_plane_and_infinity)
{
    const float f = 400.0f, W = 504.0f, H = 378.0f, near = 1.0f;
    nerf__rng g = nerf__rng_make(17, 0);
    for (int k = 0; k < 200; k++) {
        float o[3], d[3], on[3], dn[3];
        for (int c = 0; c < 3; c++) {
            o[c] = 0.5f * (2.0f * nerf__rng_uniform(&g) - 1.0f);
        }
        d[0] = 0.3f * (2.0f * nerf__rng_uniform(&g) - 1.0f);
        d[1] = 0.3f * (2.0f * nerf__rng_uniform(&g) - 1.0f);
        d[2] = -(0.5f + nerf__rng_uniform(&g));
        nerf__ndc_rays(f, W, H, near, 1, o, d, on, dn);
        /* NDC depth t runs from the near plane (t = 0, z' = -1) ... */
        CHECK_NEAR(on[2], -1.0, 1e-5);
        /* ... to infinity (t = 1, z' = 1). */
        CHECK_NEAR(on[2] + dn[2], 1.0, 1e-5);
        /* Far along the ray the NDC point approaches t = 1. */
        double s = 1e6, p[3], q[3];
        for (int c = 0; c < 3; c++) {
            p[c] = o[c] + s * d[c];
        }
        ndc_point(f, W, H, near, p, q);
        CHECK_NEAR((q[2] - on[2]) / dn[2], 1.0, 1e-4);
        /* Every world point beyond the near plane lies on the NDC ray at
         * t = (z' + 1) / 2, in [0, 1]. */
        for (int j = 0; j < 5; j++) {
            double zw = -near - 50.0 * nerf__rng_uniform(&g); /* world z */
            double sp = (zw - o[2]) / d[2];
            for (int c = 0; c < 3; c++) {
                p[c] = o[c] + sp * d[c];
            }
            ndc_point(f, W, H, near, p, q);
            double t = (q[2] - on[2]) / dn[2];
            CHECK(t >= -1e-5 && t <= 1.0 + 1e-5);
            CHECK_NEAR(t, 0.5 * (q[2] + 1.0), 1e-5);
            CHECK_NEAR(on[0] + t * dn[0], q[0], 1e-4 * (1 + fabs(q[0])));
            CHECK_NEAR(on[1] + t * dn[1], q[1], 1e-4 * (1 + fabs(q[1])));
        }
    }
    /* A point on the near plane maps to depth 0 exactly. */
    float o[3] = {0.1f, -0.2f, 0.0f}, d[3] = {0.05f, 0.02f, -1.0f};
    float on[3], dn[3];
    nerf__ndc_rays(f, W, H, near, 1, o, d, on, dn);
    double p[3] = {0.1 + 0.05, -0.2 + 0.02, -1.0}, q[3];
    ndc_point(f, W, H, near, p, q);
    CHECK_NEAR(q[2], on[2], 1e-6);
    CHECK_NEAR(q[0], on[0], 1e-6);
    CHECK_NEAR(q[1], on[1], 1e-6);
}

TEST(ndc_formula)
{
    /* The reference's closed forms on random rays, in double. */
    const float f = 407.57f, W = 504.0f, H = 378.0f, near = 1.0f;
    nerf__rng g = nerf__rng_make(23, 0);
    for (int k = 0; k < 200; k++) {
        float o[3], d[3], on[3], dn[3];
        for (int c = 0; c < 3; c++) {
            o[c] = 2.0f * nerf__rng_uniform(&g) - 1.0f;
            d[c] = 2.0f * nerf__rng_uniform(&g) - 1.0f;
        }
        d[2] = -0.2f - nerf__rng_uniform(&g);
        nerf__ndc_rays(f, W, H, near, 1, o, d, on, dn);
        double t = -(near + (double)o[2]) / d[2];
        double ox = o[0] + t * d[0], oy = o[1] + t * d[1], oz = o[2] + t * d[2];
        double ax = -f / (W / 2.0), ay = -f / (H / 2.0);
        double e[6] = {ax * ox / oz, ay * oy / oz, 1 + 2 * near / oz,
                       ax * (d[0] / d[2] - ox / oz),
                       ay * (d[1] / d[2] - oy / oz), -2 * near / oz};
        for (int c = 0; c < 3; c++) {
            CHECK_NEAR(on[c], e[c], 1e-4 * (1 + fabs(e[c])));
            CHECK_NEAR(dn[c], e[3 + c], 1e-4 * (1 + fabs(e[3 + c])));
        }
    }
}

int main(void)
{
    RUN(camera_conventions);
    RUN(camera_validation);
    RUN(ndc_near_plane_and_infinity);
    RUN(ndc_formula);
    HARNESS_EXIT();
}
