/* Lens distortion of cameras: the model, its inverse, and the rays. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "../harness.h"
#include "distortion.h"
#include "nerf.h"
#include "rng.h"

/* Coefficient sets: k1, k2, p1, p2, k3. */
typedef struct lens_case {
    const char *name;
    nerf__lens lens;
} lens_case;

static const lens_case cases[] = {
    /* A phone's main camera: mild, with a little of everything. */
    {"phone wide", {0.04, -0.09, 4e-4, -3e-4, 0.03}},
    /* A phone's ultra-wide module. */
    {"phone ultra-wide", {-0.12, 0.035, -6e-4, 2e-4, -0.004}},
    /* COLMAP SIMPLE_RADIAL (k1), RADIAL (k1, k2), OPENCV (k1 k2 p1 p2). */
    {"SIMPLE_RADIAL", {-0.06, 0.0, 0.0, 0.0, 0.0}},
    {"RADIAL", {-0.11, 0.025, 0.0, 0.0, 0.0}},
    {"OPENCV", {-0.28, 0.08, 1e-3, -5e-4, 0.0}},
    /* Pincushion. */
    {"pincushion", {0.2, 0.05, 0.0, 0.0, 0.0}},
    /* Strong barrel: the corners of the image below seen through it come
     * from 1.45 normalised units off-axis (110 degrees across). */
    {"strong barrel", {-0.5, 0.2, 2e-3, 1e-3, -0.02}},
};
#define N_CASES (sizeof cases / sizeof cases[0])

/* The test image: x_d in [-0.75, 0.75], 4:3. */
enum { W = 64, H = 48 };
#define FOCAL (0.5 * W / 0.75)

static void camera_with(nerf_camera *c, const nerf__lens *l)
{
    NERF_CAMERA_INIT(c);
    c->width = W;
    c->height = H;
    c->fx = c->fy = (float)FOCAL;
    c->cx = 0.5f * W;
    c->cy = 0.5f * H;
    c->k1 = (float)l->k1;
    c->k2 = (float)l->k2;
    c->p1 = (float)l->p1;
    c->p2 = (float)l->p2;
    c->k3 = (float)l->k3;
}

/*
 * Over every pixel of the image, undistortion converges and distorting
 * its result gives back the pixel's coordinates; and undistortion takes
 * distorted points back to where they came from.
 */
TEST(undistort_inverts_distort)
{
    for (size_t c = 0; c < N_CASES; c++) {
        const nerf__lens *l = &cases[c].lens;
        double worst = 0.0, worst_back = 0.0, r_max = 0.0;
        int failed = 0;
        for (int j = 0; j < H; j++) {
            for (int i = 0; i < W; i++) {
                double xd = (i + 0.5 - 0.5 * W) / FOCAL;
                double yd = (j + 0.5 - 0.5 * H) / FOCAL;
                double x, y, bx, by;
                failed += !nerf__undistort(l, xd, yd, &x, &y);
                nerf__distort(l, x, y, &bx, &by);
                double e = hypot(bx - xd, by - yd);
                worst = e > worst ? e : worst;
                r_max = hypot(x, y) > r_max ? hypot(x, y) : r_max;
            }
        }
        /* Points anywhere in the undistorted image come back. */
        nerf__rng g = nerf__rng_make(5, c);
        for (int k = 0; k < 2000; k++) {
            double a = 2.0 * M_PI * nerf__rng_uniform_d(&g);
            double r = r_max * sqrt(nerf__rng_uniform_d(&g));
            double x = r * cos(a), y = r * sin(a), xd, yd, ux, uy;
            nerf__distort(l, x, y, &xd, &yd);
            failed += !nerf__undistort(l, xd, yd, &ux, &uy);
            double e = hypot(ux - x, uy - y);
            worst_back = e > worst_back ? e : worst_back;
        }
        if (failed || !(worst <= 1e-9) || !(worst_back <= 1e-6)) {
            FAILF("%s: %d did not converge, residual %.3g, round trip %.3g",
                  cases[c].name, failed, worst, worst_back);
        }
    }
    /* The strong barrel case really is strong. */
    double x, y;
    nerf__undistort(&cases[N_CASES - 1].lens, 0.75, 0.5625, &x, &y);
    CHECK(hypot(x, y) > 1.4);
}

/*
 * Beyond the fold of a barrel lens (k1 = -0.4 alone: r_d peaks at 0.609
 * for r = 0.913) nothing distorts onto a point: the inverse says so and
 * keeps the closest iterate, which is finite and near the fold.
 */
TEST(undistort_beyond_the_fold)
{
    const nerf__lens l = {-0.4, 0.0, 0.0, 0.0, 0.0};
    double x, y, xd, yd;
    CHECK(!nerf__undistort(&l, 0.8, 0.0, &x, &y));
    CHECK(isfinite(x) && isfinite(y));
    CHECK_NEAR(hypot(x, y), 1.0 / sqrt(1.2), 0.05);
    nerf__distort(&l, x, y, &xd, &yd);
    CHECK_NEAR(xd, 0.8 - 0.191, 0.01);
    /* Inside the fold it converges. */
    CHECK(nerf__undistort(&l, 0.5, 0.1, &x, &y));
    /* A camera whose image reaches beyond the fold still gives finite
     * rays. */
    nerf_camera cam;
    camera_with(&cam, &l);
    cam.fx = cam.fy = 20.0f; /* x_d up to 1.6 */
    float o[W * H * 3], d[W * H * 3];
    CHECK_OK(nerf_camera_rays(&cam, 0, W * H, o, d));
    int bad = 0;
    for (int k = 0; k < W * H * 3; k++) {
        bad += !isfinite(d[k]);
    }
    CHECK_EQ_INT(bad, 0);
}

/* A random camera pose: a rotation (from a random unit quaternion) and a
 * position. */
static void random_pose(nerf__rng *g, float c2w[12])
{
    double q[4], n = 0.0;
    for (int k = 0; k < 4; k++) {
        q[k] = 2.0 * nerf__rng_uniform_d(g) - 1.0;
        n += q[k] * q[k];
    }
    n = sqrt(n);
    double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),
                   2 * (x * z + w * y), 2 * (x * y + w * z),
                   1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                   2 * (x * z - w * y), 2 * (y * z + w * x),
                   1 - 2 * (x * x + y * y)};
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            c2w[4 * i + j] = (float)r[3 * i + j];
        }
        c2w[4 * i + 3] = (float)(4.0 * nerf__rng_uniform_d(g) - 2.0);
    }
}

/* Distance from p to the ray o + t d, relative to p's distance from o. */
static double ray_miss(const float o[3], const float d[3], const double p[3])
{
    double v[3], dd = 0.0, vd = 0.0, vv = 0.0;
    for (int k = 0; k < 3; k++) {
        v[k] = p[k] - o[k];
        dd += (double)d[k] * d[k];
        vd += v[k] * d[k];
        vv += v[k] * v[k];
    }
    double perp = vv - vd * vd / dd;
    return sqrt(perp > 0.0 ? perp : 0.0) / sqrt(vv);
}

/*
 * World points seen through a lens (projected with the forward model) lie
 * on the ray of the pixel they land on.  The principal point is moved by
 * the fraction of a pixel that puts each point on a pixel's centre (or
 * corner with NERF_CAMERA_PIXEL_CORNER), which moves the projection by
 * the same amount.  The pinhole ray of that pixel misses the point.
 */
TEST(pixel_rays_pass_through_projected_points)
{
    nerf__rng g = nerf__rng_make(99, 0);
    double worst = 0.0, pinhole_least = 1.0;
    int tried = 0;
    for (size_t c = 0; c < N_CASES; c++) {
        double pinhole_most = 0.0;
        for (int k = 0; k < 200; k++) {
            nerf_camera cam;
            camera_with(&cam, &cases[c].lens);
            cam.flags = k % 2 ? NERF_CAMERA_PIXEL_CORNER : 0;
            random_pose(&g, cam.c2w);
            /* A point in front of the camera within the image: camera
             * space (x, -y, -1) z_depth, from a random pixel. */
            double xd = (W * nerf__rng_uniform_d(&g) - 0.5 * W) / FOCAL;
            double yd = (H * nerf__rng_uniform_d(&g) - 0.5 * H) / FOCAL;
            double x, y;
            nerf__undistort(&cases[c].lens, xd, yd, &x, &y);
            double depth = 0.5 + 5.0 * nerf__rng_uniform_d(&g);
            double q[3] = {x * depth, -y * depth, -depth}, p[3];
            for (int r = 0; r < 3; r++) {
                p[r] = cam.c2w[4 * r + 3];
                for (int s = 0; s < 3; s++) {
                    p[r] += cam.c2w[4 * r + s] * q[s];
                }
            }
            double u, v;
            if (!nerf__camera_project(&cam, p, &u, &v)) {
                FAILF("%s: a point in front of the camera is behind it",
                      cases[c].name);
                continue;
            }
            double off = cam.flags ? 0.0 : 0.5;
            double pi = floor(u - off), pj = floor(v - off);
            if (pi < 0 || pj < 0 || pi >= W || pj >= H) {
                continue;
            }
            cam.cx += (float)(pi + off - u);
            cam.cy += (float)(pj + off - v);
            float o[3], d[3];
            CHECK_OK(nerf_camera_rays(&cam, (size_t)pj * W + (size_t)pi, 1,
                                      o, d));
            double e = ray_miss(o, d, p);
            worst = e > worst ? e : worst;
            cam.k1 = cam.k2 = cam.p1 = cam.p2 = cam.k3 = 0.0f;
            CHECK_OK(nerf_camera_rays(&cam, (size_t)pj * W + (size_t)pi, 1,
                                      o, d));
            double miss = ray_miss(o, d, p);
            pinhole_most = miss > pinhole_most ? miss : pinhole_most;
            tried++;
        }
        pinhole_least = pinhole_most < pinhole_least ? pinhole_most
                                                     : pinhole_least;
    }
    CHECK(tried > 1000);
    /* Float rays: a few parts in 1e7 of the distance. */
    CHECK(worst < 2e-6);
    /* Every lens moves some points by a fair part of a pixel (the
     * mildest, the phone's, by a quarter of one in this small image),
     * 40000 times the miss above: ignoring the lens fails that check. */
    CHECK(pinhole_least > 0.2 / FOCAL);
    printf("  rays miss projected points by at most %.2g of their distance; "
           "pinhole rays, with the mildest lens, by up to %.2g\n", worst,
           pinhole_least);
}

/* The pinhole formula of nerf.h, in float, summed in the library's order. */
static void pinhole_ray(const nerf_camera *c, size_t p, float o[3],
                        float d[3])
{
    const float off = (c->flags & NERF_CAMERA_PIXEL_CORNER) ? 0.0f : 0.5f;
    float i = (float)(p % c->width) + off;
    float j = (float)(p / c->width) + off;
    float v[3] = {(i - c->cx) / c->fx, -(j - c->cy) / c->fy, -1.0f};
    for (int r = 0; r < 3; r++) {
        d[r] = v[0] * c->c2w[4 * r] + v[1] * c->c2w[4 * r + 1] +
               v[2] * c->c2w[4 * r + 2];
        o[r] = c->c2w[4 * r + 3];
    }
}

/*
 * All-zero coefficients, and a camera from a caller whose struct ends
 * before them, give the pinhole rays bit for bit.
 */
TEST(zero_distortion_is_pinhole_bitwise)
{
    nerf__rng g = nerf__rng_make(7, 0);
    static float o[W * H * 3], d[W * H * 3];
    int differ = 0;
    for (int k = 0; k < 8; k++) {
        nerf_camera cam;
        const nerf__lens zero = {0, 0, 0, 0, 0};
        camera_with(&cam, &zero);
        cam.fx = (float)(20.0 + 60.0 * nerf__rng_uniform_d(&g));
        cam.fy = (float)(20.0 + 60.0 * nerf__rng_uniform_d(&g));
        cam.cx = (float)(W * nerf__rng_uniform_d(&g));
        cam.cy = (float)(H * nerf__rng_uniform_d(&g));
        cam.flags = k % 2 ? NERF_CAMERA_PIXEL_CORNER : 0;
        random_pose(&g, cam.c2w);
        if (k >= 4) {
            /* What an older caller passes: the struct up to cy, with
             * whatever lies beyond it in memory. */
            unsigned char buf[sizeof cam + 32];
            memset(buf, 0xff, sizeof buf);
            cam.struct_size = offsetof(nerf_camera, k1);
            memcpy(buf, &cam, offsetof(nerf_camera, k1));
            CHECK_OK(nerf_camera_rays((const nerf_camera *)buf, 0, W * H, o,
                                      d));
        } else {
            CHECK_OK(nerf_camera_rays(&cam, 0, W * H, o, d));
        }
        for (size_t p = 0; p < (size_t)W * H; p++) {
            float po[3], pd[3];
            pinhole_ray(&cam, p, po, pd);
            differ += memcmp(po, o + 3 * p, sizeof po) != 0 ||
                      memcmp(pd, d + 3 * p, sizeof pd) != 0;
        }
    }
    CHECK_EQ_INT(differ, 0);
}

TEST(distortion_validation)
{
    nerf_camera cam;
    float o[3], d[3];
    const nerf__lens ok = {-0.3, 0.1, 0.001, 0.001, 0.01};
    camera_with(&cam, &ok);
    CHECK_OK(nerf_camera_rays(&cam, 0, 1, o, d));
    cam.k2 = NAN;
    CHECK_EQ_INT(nerf_camera_rays(&cam, 0, 1, o, d), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "distortion k2 is not finite") != NULL);
    cam.k2 = 0.1f;
    cam.p1 = INFINITY;
    CHECK_EQ_INT(nerf_camera_rays(&cam, 0, 1, o, d), NERF_EINVAL);
    cam.p1 = 0.0f;
    cam.k3 = 1e4f;
    CHECK_EQ_INT(nerf_camera_rays(&cam, 0, 1, o, d), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "distortion k3 10000 is beyond +-1000")
          != NULL);
    cam.k3 = -1000.0f; /* the bound itself is allowed */
    CHECK_OK(nerf_camera_rays(&cam, 0, 1, o, d));
    /* Defaults: a pinhole camera. */
    nerf_camera fresh;
    NERF_CAMERA_INIT(&fresh);
    CHECK(fresh.k1 == 0.0f && fresh.k2 == 0.0f && fresh.p1 == 0.0f &&
          fresh.p2 == 0.0f && fresh.k3 == 0.0f);
}

int main(void)
{
    RUN(undistort_inverts_distort);
    RUN(undistort_beyond_the_fold);
    RUN(pixel_rays_pass_through_projected_points);
    RUN(zero_distortion_is_pinhole_bitwise);
    RUN(distortion_validation);
    HARNESS_EXIT();
}
