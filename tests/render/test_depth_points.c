/*
 * Depth in world units and point clouds: the depths agree with the raw
 * render and with the rays' geometry (also through NDC), a model of
 * constant density gives a plane of constant depth whose points' normals
 * face the camera, the point filters and the cap do what the header says,
 * the PLY file reads back, and bad arguments are refused.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "model.h"
#include "nerf.h"

/* Few pixels: in CI's aarch64 stage, under qemu, a tiny-model render of
 * 24x16 took about 20 s, and these tests render dozens. */
#define W 16
#define H 12
#define NPIX (W * H)

static nerf_model *tiny_model(void)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    mo.seed = 3;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &mo));
    return m;
}

/* Every network's density is the constant sigma: its row of the head has
 * zero weights and bias sigma. */
static void constant_density(nerf_model *m, float sigma)
{
    for (uint32_t k = 0; k < m->n_nets; k++) {
        const nerf__network *net = &m->nets[k];
        uint32_t row = nerf__network_sigma_col(net);
        memset(m->params + net->head.w + (size_t)row * net->head.in, 0,
               net->head.in * sizeof(float));
        m->params[net->head.b + row] = sigma;
    }
    float pos[9] = {0, 0, 0, 1.5f, -0.7f, 0.2f, -3, 2, 1}, sig[3];
    float dir[9] = {0, 0, 1, 0, 1, 0, 1, 0, 0};
    CHECK_OK(nerf_model_query(m, 0, 3, pos, dir, NULL, sig));
    for (int i = 0; i < 3; i++) {
        CHECK_NEAR(sig[i], sigma, 1e-6);
    }
}

static nerf_renderer *make_renderer(nerf_model *m, nerf_sampler **s,
                                    uint32_t ndc)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, NERF_PRESET_TINY);
    /* A quarter of the preset's samples, as in test_render_image.c: under
     * qemu (CI's aarch64 stage) each sample is costly. */
    so.n_coarse = 8;
    so.n_fine = 16;
    if (ndc) {
        so.ndc = 1;
        so.t_near = 0.0f;
        so.t_far = 1.0f;
    }
    CHECK_OK(nerf_sampler_create(s, &so));
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = 2;
    nerf_renderer *r = NULL;
    CHECK_OK(nerf_renderer_create(&r, m, *s, &ro));
    return r;
}

/* A camera 4 units from the origin, turned a little about y so that
 * camera and world axes differ, looking at the origin. */
static void test_camera(nerf_camera *c, uint32_t w, uint32_t h)
{
    NERF_CAMERA_INIT(c);
    c->width = w;
    c->height = h;
    c->fx = c->fy = 0.5f * (float)w / tanf(0.35f);
    c->cx = 0.5f * (float)w;
    c->cy = 0.5f * (float)h;
    const float eye[3] = {0.8f, -0.3f, 4.0f}, at[3] = {0, 0, 0},
                up[3] = {0, 1, 0};
    CHECK_OK(nerf_camera_look_at(c, eye, at, up));
}

static float norm3(const float *v)
{
    return sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* distance = z |d|, z = raw / opacity, 0 where opacity is 0; colours and
 * opacity as render_image gives them. */
TEST(depth_matches_raw_render)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = NULL;
    nerf_renderer *r = make_renderer(m, &s, 0);
    nerf_camera cam;
    test_camera(&cam, W, H);
    static float rgb0[3 * NPIX], raw[NPIX], op0[NPIX];
    static float rgb[3 * NPIX], dist[NPIX], z[NPIX], op[NPIX], z2[NPIX];
    static float o[3 * NPIX], d[3 * NPIX];
    CHECK_OK(nerf_renderer_render_image(r, &cam, rgb0, raw, op0, NPIX));
    CHECK_OK(nerf_renderer_render_depth(r, &cam, rgb, dist, z, op, NPIX));
    CHECK_OK(nerf_renderer_render_depth(r, &cam, NULL, NULL, z2, NULL, NPIX));
    CHECK_OK(nerf_camera_rays(&cam, 0, NPIX, o, d));
    CHECK(memcmp(rgb, rgb0, sizeof rgb) == 0);
    CHECK(memcmp(op, op0, sizeof op) == 0);
    CHECK(memcmp(z, z2, sizeof z) == 0);
    int opaque = 0;
    for (int k = 0; k < NPIX; k++) {
        float want = op0[k] > 0.0f ? raw[k] / op0[k] : 0.0f;
        CHECK_NEAR(z[k], want, 1e-5 * fabsf(want) + 1e-7);
        CHECK_NEAR(dist[k], z[k] * norm3(d + 3 * k), 1e-5 * dist[k] + 1e-7);
        /* The sampler's range [2, 6] along d bounds z. */
        if (op0[k] > 0.0f) {
            CHECK(z[k] >= 2.0f - 1e-4f && z[k] <= 6.0f + 1e-4f);
            opaque++;
        }
    }
    CHECK(opaque > 0);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* Through NDC: the world point o + z d lies at the expected NDC depth. */
TEST(depth_through_ndc)
{
    nerf_model *m = tiny_model();
    constant_density(m, 0.3f);
    nerf_sampler *s = NULL;
    nerf_renderer *r = make_renderer(m, &s, 1);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    cam.width = W;
    cam.height = H;
    cam.fx = cam.fy = 20.0f;
    cam.cx = 0.5f * W;
    cam.cy = 0.5f * H;
    cam.c2w[3] = 0.1f;
    cam.c2w[11] = 0.5f; /* in front of the near plane z = -1 */
    static float raw[NPIX], op[NPIX], dist[NPIX], z[NPIX];
    static float o[3 * NPIX], d[3 * NPIX];
    CHECK_OK(nerf_renderer_render_image(r, &cam, NULL, raw, op, NPIX));
    CHECK_OK(nerf_renderer_render_depth(r, &cam, NULL, dist, z, NULL, NPIX));
    CHECK_OK(nerf_camera_rays(&cam, 0, NPIX, o, d));
    for (int k = 0; k < NPIX; k++) {
        CHECK(op[k] > 0.5f);
        double t = raw[k] / op[k];
        double zw = o[3 * k + 2] + (double)z[k] * d[3 * k + 2];
        double ndc_z = 1.0 + 2.0 / zw; /* near plane at world depth 1 */
        CHECK_NEAR(ndc_z, -1.0 + 2.0 * t, 1e-4);
        CHECK_NEAR(dist[k], z[k] * norm3(d + 3 * k), 1e-5 * dist[k]);
        CHECK(z[k] > 1.5f); /* beyond the near plane, 1.5 units ahead */
    }
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

static nerf_points *points_of(nerf_renderer *r, const nerf_camera *cams,
                              size_t n, float threshold, uint64_t max,
                              uint32_t stride)
{
    nerf_points_options po;
    NERF_POINTS_OPTIONS_INIT(&po);
    po.opacity_threshold = threshold;
    po.max_points = max;
    po.stride = stride;
    nerf_points *p = NULL;
    CHECK_OK(nerf_points_from_views(&p, r, cams, n, &po));
    return p;
}

/* A density so high that each ray stops at its first sample, which every
 * ray has at the same t: the points form the plane z_cam = const and
 * their normals are the camera's back axis (toward the camera). */
TEST(opaque_density_plane)
{
    nerf_model *m = tiny_model();
    constant_density(m, 1e4f);
    nerf_sampler *s = NULL;
    nerf_renderer *r = make_renderer(m, &s, 0);
    nerf_camera cam;
    test_camera(&cam, W, H);
    static float z[NPIX], op[NPIX], o[3 * NPIX], d[3 * NPIX];
    CHECK_OK(nerf_renderer_render_depth(r, &cam, NULL, NULL, z, op, NPIX));
    CHECK_OK(nerf_camera_rays(&cam, 0, NPIX, o, d));
    for (int k = 1; k < NPIX; k++) {
        CHECK_NEAR(z[k], z[0], 1e-4 * z[0]);
    }
    CHECK(z[0] >= 2.0f && z[0] < 6.0f);
    /* Opacity exactly 1 on every ray.  A ray's first sample, in both
     * passes the first coarse one (fine samples lie beyond the midpoint
     * after it), is half a coarse interval (0.25) or more from the next,
     * with |d| >= 1: 1e4 delta > 17.4, where expf(-x) < 2^-25 and
     * 1 - expf(-x) rounds to 1.  Its weight is 1 * 1, T drops to 1e-10,
     * and the weights after it, below 2^-25 in all, leave the float sum
     * at 1.  So threshold 1 keeps them all. */
    for (int k = 0; k < NPIX; k++) {
        CHECK(op[k] == 1.0f);
    }
    nerf_points *p = points_of(r, &cam, 1, 1.0f, 1000000, 1);
    CHECK_EQ_INT((int)nerf_points_count(p), NPIX);
    nerf_points_destroy(p);
    p = points_of(r, &cam, 1, 0.5f, 1000000, 1);
    CHECK_EQ_INT((int)nerf_points_count(p), NPIX);
    const float *pos = NULL, *nrm = NULL;
    const uint8_t *col = NULL;
    CHECK_OK(nerf_points_arrays(p, &pos, &col, &nrm));
    const float back[3] = {cam.c2w[2], cam.c2w[6], cam.c2w[10]};
    for (int k = 0; k < NPIX; k++) {
        for (int c = 0; c < 3; c++) {
            CHECK_NEAR(pos[3 * k + c], o[3 * k + c] + z[k] * d[3 * k + c],
                       1e-4);
        }
        double dot = nrm[3 * k] * back[0] + nrm[3 * k + 1] * back[1] +
                     nrm[3 * k + 2] * back[2];
        CHECK_NEAR(dot, 1.0, 1e-3);
    }
    nerf_points_destroy(p);
    /* Empty space (density 0 after the ReLU): no points, NULL arrays, and
     * depth 0 where the opacity is 0. */
    constant_density(m, -1.0f);
    p = points_of(r, &cam, 1, 0.0f, 1000000, 1);
    const float *none = pos;
    CHECK_OK(nerf_points_arrays(p, &none, NULL, NULL));
    CHECK(nerf_points_count(p) == 0 && none == NULL);
    CHECK_OK(nerf_renderer_render_depth(r, &cam, NULL, NULL, z, op, NPIX));
    CHECK(z[0] == 0.0f && op[0] == 0.0f && z[NPIX - 1] == 0.0f);
    nerf_points_destroy(p);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* The points of a random model: one per ray of opacity >= threshold (and
 * none else), at o + z d, normals unit or absent and facing the camera;
 * the cap keeps an ordered subset of that size; the stride renders fewer
 * rays. */
TEST(points_filter_cap_stride)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = NULL;
    nerf_renderer *r = make_renderer(m, &s, 0);
    nerf_camera cams[2];
    test_camera(&cams[0], W, H);
    test_camera(&cams[1], W, H);
    const float eye[3] = {-2.0f, 1.0f, 3.0f}, at[3] = {0, 0, 0},
                up[3] = {0, 1, 0};
    CHECK_OK(nerf_camera_look_at(&cams[1], eye, at, up));
    static float z[2][NPIX], op[2][NPIX], o[2][3 * NPIX], d[2][3 * NPIX];
    float sorted[2 * NPIX];
    for (int v = 0; v < 2; v++) {
        CHECK_OK(nerf_renderer_render_depth(r, &cams[v], NULL, NULL, z[v],
                                            op[v], NPIX));
        CHECK_OK(nerf_camera_rays(&cams[v], 0, NPIX, o[v], d[v]));
        memcpy(sorted + v * NPIX, op[v], sizeof op[v]);
    }
    /* A threshold that keeps about half of the rays. */
    for (int i = 1; i < 2 * NPIX; i++) {
        for (int j = i; j > 0 && sorted[j - 1] > sorted[j]; j--) {
            float t = sorted[j];
            sorted[j] = sorted[j - 1];
            sorted[j - 1] = t;
        }
    }
    float thr = sorted[NPIX];
    CHECK(thr > 0.0f && thr < 1.0f);
    nerf_points *p = points_of(r, cams, 2, thr, 1000000, 1);
    size_t n = nerf_points_count(p);
    const float *pos = NULL, *nrm = NULL;
    CHECK_OK(nerf_points_arrays(p, &pos, NULL, &nrm));
    size_t at_pt = 0, with_normal = 0;
    for (int v = 0; v < 2; v++) {
        for (int k = 0; k < NPIX; k++) {
            if (!(op[v][k] >= thr)) {
                continue;
            }
            CHECK(at_pt < n);
            if (at_pt >= n) {
                break;
            }
            const float *x = pos + 3 * at_pt, *nv = nrm + 3 * at_pt;
            for (int c = 0; c < 3; c++) {
                CHECK_NEAR(x[c], o[v][3 * k + c] + z[v][k] * d[v][3 * k + c],
                           1e-4);
            }
            float len = norm3(nv);
            if (len != 0.0f) {
                with_normal++;
                CHECK_NEAR(len, 1.0, 1e-5);
                /* The library turns the normal toward the camera by the
                 * sign of the same dot product (before rounding the normal
                 * to float); here each term rounds twice in float, the
                 * difference and the product: the dot is then no lower
                 * than -gamma(3) of its terms' magnitudes (with the
                 * double sum's rounding). */
                double facing = 0.0, terms = 0.0;
                for (int c = 0; c < 3; c++) {
                    facing += nv[c] * (o[v][3 * k + c] - x[c]);
                    terms += fabs(nv[c] * (o[v][3 * k + c] - x[c]));
                }
                CHECK(facing >= -float_gamma(3) * terms);
            }
            at_pt++;
        }
    }
    CHECK_EQ_INT((int)at_pt, (int)n);
    CHECK(with_normal > 0);

    /* Capped: that many points, each one of the full cloud, in order. */
    const uint64_t caps[3] = {1, 37, n - 1};
    for (int c = 0; c < 3; c++) {
        nerf_points *q = points_of(r, cams, 2, thr, caps[c], 1);
        CHECK_EQ_INT((int)nerf_points_count(q), (int)caps[c]);
        const float *qp = NULL;
        CHECK_OK(nerf_points_arrays(q, &qp, NULL, NULL));
        size_t from = 0;
        for (size_t i = 0; i < nerf_points_count(q); i++) {
            while (from < n && memcmp(pos + 3 * from, qp + 3 * i,
                                      3 * sizeof(float)) != 0) {
                from++;
            }
            CHECK(from < n);
            from++;
        }
        nerf_points_destroy(q);
    }
    /* Stride 3: the 8 x 6 views' rays, so at most 96 points. */
    nerf_points *q = points_of(r, cams, 2, 0.0f, 1000000, 3);
    CHECK(nerf_points_count(q) > 0 && nerf_points_count(q) <= 96);
    nerf_points_destroy(q);
    /* Threshold 1 keeps only the rays whose opacity is 1: the same
     * renders (same renderer, cameras and blocks), so the same count,
     * whatever it is here (whether a sum of weights rounds to 1 is the
     * arithmetic's; opaque_density_plane has rays of opacity exactly 1). */
    int full = 0;
    for (int k = 0; k < 2 * NPIX; k++) {
        full += sorted[k] >= 1.0f;
    }
    CHECK(full < NPIX);
    q = points_of(r, cams, 2, 1.0f, 1000000, 1);
    CHECK_EQ_INT((int)nerf_points_count(q), full);
    nerf_points_destroy(q);

    nerf_points_destroy(p);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 |
           (uint32_t)b[3] << 24;
}

/* Binary PLY: the header announces the count, the body holds exactly the
 * points' values; ASCII has a line a point. */
TEST(ply_round_trip)
{
    nerf_model *m = tiny_model();
    constant_density(m, 0.8f);
    nerf_sampler *s = NULL;
    nerf_renderer *r = make_renderer(m, &s, 0);
    nerf_camera cam;
    test_camera(&cam, W, H);
    nerf_points *p = points_of(r, &cam, 1, 0.5f, 100, 1);
    CHECK_EQ_INT((int)nerf_points_count(p), 100);
    char path[64];
    snprintf(path, sizeof path, "test_depth_points_%ld.ply", (long)getpid());
    CHECK_OK(nerf_points_write(p, path, NERF_POINTS_PLY_BINARY));
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL);
    static unsigned char buf[1 << 16];
    size_t size = f ? fread(buf, 1, sizeof buf, f) : 0;
    if (f) {
        fclose(f);
    }
    buf[size < sizeof buf ? size : sizeof buf - 1] = 0;
    const char *end = strstr((const char *)buf, "end_header\n");
    CHECK(strstr((const char *)buf, "element vertex 100\n") != NULL);
    CHECK(end != NULL);
    if (end) {
        size_t body = (size_t)(end - (const char *)buf) + 11;
        CHECK_EQ_INT((int)(size - body), 100 * 27);
        const float *pos = NULL, *nrm = NULL;
        const uint8_t *col = NULL;
        CHECK_OK(nerf_points_arrays(p, &pos, &col, &nrm));
        for (int i = 0; i < 100 && body + 27 * (size_t)i + 27 <= size; i++) {
            const unsigned char *v = buf + body + 27 * (size_t)i;
            uint32_t bits;
            memcpy(&bits, &pos[3 * i + 1], 4);
            CHECK(le32(v + 4) == bits);
            memcpy(&bits, &nrm[3 * i + 2], 4);
            CHECK(le32(v + 20) == bits);
            CHECK(memcmp(v + 24, col + 3 * i, 3) == 0);
        }
    }
    CHECK_OK(nerf_points_write(p, path, NERF_POINTS_PLY_ASCII));
    f = fopen(path, "rb");
    size = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
    if (f) {
        fclose(f);
    }
    buf[size] = 0;
    int lines = 0;
    end = strstr((const char *)buf, "end_header\n");
    for (const char *c = end ? end + 11 : ""; *c; c++) {
        lines += *c == '\n';
    }
    CHECK_EQ_INT(lines, 100);
    CHECK(strstr((const char *)buf, "format ascii 1.0\n") != NULL);
    remove(path);

    /* Unwritable: a folder that does not exist; the message names it. */
    CHECK_EQ_INT(nerf_points_write(p, "/nonexistent-dir/x.ply",
                                   NERF_POINTS_PLY_BINARY), NERF_EIO);
    CHECK(strstr(nerf_last_error(), "/nonexistent-dir/x.ply") != NULL);
    CHECK_EQ_INT(nerf_points_write(p, path, 7), NERF_EINVAL);
    CHECK_EQ_INT(nerf_points_write(NULL, path, 0), NERF_EINVAL);
    CHECK_EQ_INT(nerf_points_write(p, NULL, 0), NERF_EINVAL);
    nerf_points_destroy(p);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

typedef struct seen {
    uint64_t last_done, total;
    int calls, cancel_at;
} seen;

static int on_progress(const nerf_progress *p, void *user)
{
    seen *s = user;
    s->calls++;
    s->last_done = p->done;
    s->total = p->total;
    return s->cancel_at && s->calls >= s->cancel_at;
}

TEST(progress_cancel_and_bad_arguments)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = NULL;
    nerf_renderer *r = make_renderer(m, &s, 0);
    nerf_camera cams[3];
    for (int v = 0; v < 3; v++) {
        test_camera(&cams[v], W, H);
    }
    nerf_points_options po;
    NERF_POINTS_OPTIONS_INIT(&po);
    CHECK_NEAR(po.opacity_threshold, NERF_POINTS_DEFAULT_OPACITY, 0);
    CHECK(po.max_points == NERF_POINTS_DEFAULT_MAX && po.stride == 1);
    seen sn = {0, 0, 0, 0};
    po.progress = on_progress;
    po.progress_user = &sn;
    nerf_points *p = NULL;
    CHECK_OK(nerf_points_from_views(&p, r, cams, 3, &po));
    CHECK(sn.calls >= 3 && sn.total == 3 * NPIX && sn.last_done == sn.total);
    nerf_points_destroy(p);
    sn.calls = 0;
    sn.cancel_at = 2;
    CHECK_EQ_INT(nerf_points_from_views(&p, r, cams, 3, &po),
                 NERF_ECANCELLED);
    CHECK(p == NULL);
    po.progress = NULL;

    const struct {
        float thr;
        uint64_t max;
        uint32_t stride;
    } bad[] = {{-0.1f, 10, 1}, {1.5f, 10, 1}, {NAN, 10, 1}, {0.5f, 0, 1},
               {0.5f, 10, 0}, {0.5f, 10, 2000}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        po.opacity_threshold = bad[i].thr;
        po.max_points = bad[i].max;
        po.stride = bad[i].stride;
        CHECK_EQ_INT(nerf_points_from_views(&p, r, cams, 3, &po),
                     NERF_EINVAL);
        CHECK(strstr(nerf_last_error(), "nerf_points_options") != NULL);
        CHECK(p == NULL);
    }
    CHECK_EQ_INT(nerf_points_from_views(&p, r, cams, 0, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_points_from_views(&p, NULL, cams, 1, NULL),
                 NERF_EINVAL);
    CHECK_EQ_INT(nerf_points_from_views(NULL, r, cams, 1, NULL), NERF_EINVAL);
    cams[2].fx = -1.0f;
    CHECK_EQ_INT(nerf_points_from_views(&p, r, cams, 3, NULL), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "camera 2") != NULL);
    /* The renderer's own callback is back after the call. */
    float z[NPIX];
    CHECK_EQ_INT(nerf_renderer_render_depth(r, &cams[0], NULL, NULL, NULL,
                                            NULL, NPIX), NERF_EINVAL);
    CHECK_EQ_INT(nerf_renderer_render_depth(r, &cams[0], NULL, NULL, z,
                                            NULL, NPIX - 1), NERF_EINVAL);
    CHECK_EQ_INT(nerf_renderer_render_depth(NULL, &cams[0], NULL, NULL, z,
                                            NULL, NPIX), NERF_EINVAL);
    CHECK_EQ_INT(nerf_points_options_init(NULL, sizeof po), NERF_EINVAL);
    CHECK(nerf_points_count(NULL) == 0);
    CHECK_EQ_INT(nerf_points_arrays(NULL, NULL, NULL, NULL), NERF_EINVAL);
    nerf_points_destroy(NULL);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* nerf_npy_write_float: NumPy's header, the floats little-endian. */
TEST(npy_write_float)
{
    const float data[6] = {1.5f, -2.0f, 0.0f, 3.25f, 1e-3f, 7.0f};
    const size_t shape[2] = {2, 3};
    char path[64];
    snprintf(path, sizeof path, "test_depth_points_%ld.npy", (long)getpid());
    CHECK_OK(nerf_npy_write_float(path, data, shape, 2));
    unsigned char buf[256];
    FILE *f = fopen(path, "rb");
    size_t size = f ? fread(buf, 1, sizeof buf, f) : 0;
    if (f) {
        fclose(f);
    }
    remove(path);
    CHECK_EQ_INT((int)size, 128 + 24);
    CHECK(memcmp(buf, "\x93NUMPY\x01\x00", 8) == 0);
    buf[127] = 0;
    CHECK(strstr((const char *)buf + 10, "'descr': '<f4'") != NULL);
    CHECK(strstr((const char *)buf + 10, "'shape': (2, 3)") != NULL);
    buf[127] = '\n';
    CHECK(buf[127] == '\n');
    for (int i = 0; i < 6; i++) {
        uint32_t bits;
        memcpy(&bits, &data[i], 4);
        CHECK(le32(buf + 128 + 4 * i) == bits);
    }
    CHECK_EQ_INT(nerf_npy_write_float(path, data, shape, 0), NERF_EINVAL);
    CHECK_EQ_INT(nerf_npy_write_float(path, NULL, shape, 2), NERF_EINVAL);
    CHECK_EQ_INT(nerf_npy_write_float("/nonexistent-dir/a.npy", data, shape,
                                      2), NERF_EIO);
}

int main(void)
{
    RUN(depth_matches_raw_render);
    RUN(depth_through_ndc);
    RUN(opaque_density_plane);
    RUN(points_filter_cap_stride);
    RUN(ply_round_trip);
    RUN(progress_cancel_and_bad_arguments);
    RUN(npy_write_float);
    HARNESS_EXIT();
}
