/*
 * COLMAP models: the built-in scene written as COLMAP text and binary
 * models loads back with the poses the writer used (up to the similarity
 * of docs/formats.md), the camera models map onto fx fy cx cy k1 k2 p1 p2,
 * and broken models fail naming the file.
 */
#include <nerf.h>

#include <sys/stat.h>
#include <unistd.h>

#include "colmap.h"
#include "colmap_poses.h"
#include "data_fixtures.h"
#include "../harness.h"

enum { W = 32, H = 32, N_TRAIN = 14, N_VAL = 1, N_TEST = 1 };
#define N_ALL (N_TRAIN + N_VAL + N_TEST)

static char *tmp;

static void write_scene(const char *name, uint32_t layout)
{
    nerf_scene_options o;
    NERF_SCENE_OPTIONS_INIT(&o);
    o.width = W;
    o.height = H;
    o.n_train = N_TRAIN;
    o.n_val = N_VAL;
    o.n_test = N_TEST;
    o.threads = 1;
    o.layout = layout;
    char dir[1024];
    fx_path(dir, sizeof dir, tmp, name);
    CHECK_OK(nerf_scene_write(dir, &o));
}

static nerf_dataset *load(const char *name, uint32_t split)
{
    char dir[1024];
    fx_path(dir, sizeof dir, tmp, name);
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = split;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    return ds;
}

/* The writer's cameras in COLMAP image order (train, val, test), from the
 * same scene written as a Blender dataset. */
static void writer_cameras(nerf_camera *out)
{
    int k = 0;
    for (uint32_t split = 0; split < 3; split++) {
        nerf_dataset *ds = load("blender", split);
        for (uint32_t i = 0; ds && i < nerf_dataset_count(ds); i++) {
            NERF_CAMERA_INIT(&out[k]);
            CHECK_OK(nerf_dataset_camera(ds, i, &out[k]));
            k++;
        }
        nerf_dataset_destroy(ds);
    }
    CHECK_EQ_INT(k, N_ALL);
}

/* All cameras of a COLMAP folder in name order, from its two splits. */
static void colmap_cameras(const char *name, nerf_camera *out, float *near,
                           float *far)
{
    nerf_dataset *train = load(name, NERF_SPLIT_TRAIN);
    nerf_dataset *test = load(name, NERF_SPLIT_TEST);
    if (train == NULL || test == NULL) {
        nerf_dataset_destroy(train);
        nerf_dataset_destroy(test);
        return;
    }
    CHECK_EQ_INT(nerf_dataset_get_format(train), NERF_DATASET_COLMAP);
    CHECK_EQ_INT(nerf_dataset_is_ndc(train), 0);
    /* Every 8th image, from the first, is held out. */
    uint32_t w = 0, h = 0;
    CHECK_OK(nerf_dataset_image_size(train, &w, &h));
    CHECK_EQ_INT(w, W);
    CHECK_EQ_INT(h, H);
    CHECK_EQ_INT(nerf_dataset_count(test), 2);
    CHECK_EQ_INT(nerf_dataset_count(train), N_ALL - 2);
    uint32_t it = 0, ie = 0;
    for (int k = 0; k < N_ALL; k++) {
        NERF_CAMERA_INIT(&out[k]);
        if (k % 8 == 0) {
            CHECK_OK(nerf_dataset_camera(test, ie++, &out[k]));
        } else {
            CHECK_OK(nerf_dataset_camera(train, it++, &out[k]));
        }
    }
    CHECK_OK(nerf_dataset_bounds(train, near, far));
    nerf_dataset_destroy(train);
    nerf_dataset_destroy(test);
}

/* No images_2/: downscale 2 averages images/ and halves the intrinsics. */
TEST(downscale_halves_the_intrinsics)
{
    char dir[1024];
    fx_path(dir, sizeof dir, tmp, "bin");
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 2;
    nerf_dataset *full = load("bin", NERF_SPLIT_TRAIN), *half = NULL;
    CHECK_OK(nerf_dataset_load(&half, dir, &o));
    if (full && half) {
        uint32_t w, h;
        CHECK_OK(nerf_dataset_image_size(half, &w, &h));
        CHECK_EQ_INT(w, W / 2);
        CHECK_EQ_INT(h, H / 2);
        nerf_camera a, b;
        NERF_CAMERA_INIT(&a);
        NERF_CAMERA_INIT(&b);
        CHECK_OK(nerf_dataset_camera(full, 3, &a));
        CHECK_OK(nerf_dataset_camera(half, 3, &b));
        CHECK_NEAR(b.fx, 0.5 * a.fx, 1e-4);
        CHECK_NEAR(b.cy, 0.5 * a.cy, 1e-4);
        for (int i = 0; i < 12; i++) {
            CHECK_NEAR(b.c2w[i], a.c2w[i], 0);
        }
    }
    nerf_dataset_destroy(full);
    nerf_dataset_destroy(half);
}

TEST(text_and_binary_agree_with_the_writer)
{
    write_scene("blender", NERF_SCENE_LAYOUT_BLENDER);
    write_scene("text", NERF_SCENE_LAYOUT_COLMAP_TEXT);
    write_scene("bin", NERF_SCENE_LAYOUT_COLMAP_BINARY);
    static nerf_camera ref[N_ALL], txt[N_ALL], bin[N_ALL];
    float near_t = 0, far_t = 0, near_b = 0, far_b = 0;
    writer_cameras(ref);
    colmap_cameras("text", txt, &near_t, &far_t);
    colmap_cameras("bin", bin, &near_b, &far_b);
    CHECK_NEAR(near_t, near_b, 1e-5);
    CHECK_NEAR(far_t, far_b, 1e-5);
    CHECK(near_b > 0.0f && far_b > near_b);
    for (int k = 0; k < N_ALL; k++) {
        for (int i = 0; i < 12; i++) {
            CHECK_NEAR(txt[k].c2w[i], bin[k].c2w[i], 1e-5);
        }
        CHECK_NEAR(bin[k].fx, ref[k].fx, 1e-3);
        CHECK_NEAR(bin[k].fy, ref[k].fy, 1e-3);
        CHECK_NEAR(bin[k].cx, 0.5 * W, 1e-4);
        CHECK_NEAR(bin[k].cy, 0.5 * H, 1e-4);
    }
    /*
     * One rotation A takes every written camera frame to the loaded one:
     * R_loaded = A R_written.  Positions: A^T c_loaded = s (c - centre).
     */
    double a[9];
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            double v = 0;
            for (int k = 0; k < 3; k++) {
                v += bin[0].c2w[4 * r + k] * ref[0].c2w[4 * c + k];
            }
            a[3 * r + c] = v;
        }
    }
    double p[N_ALL][3], far_cam = 0, up[3] = {0, 0, 0};
    for (int k = 0; k < N_ALL; k++) {
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 3; c++) {
                double v = 0;
                for (int i = 0; i < 3; i++) {
                    v += a[3 * r + i] * ref[k].c2w[4 * i + c];
                }
                CHECK_NEAR(v, bin[k].c2w[4 * r + c], 1e-5);
            }
            up[r] += bin[k].c2w[4 * r + 1];
        }
        double d2 = 0;
        for (int r = 0; r < 3; r++) {
            p[k][r] = a[r] * bin[k].c2w[3] + a[3 + r] * bin[k].c2w[7] +
                      a[6 + r] * bin[k].c2w[11];
            d2 += (double)bin[k].c2w[4 * r + 3] * bin[k].c2w[4 * r + 3];
        }
        far_cam = d2 > far_cam ? d2 : far_cam;
    }
    /* One scale for all camera distances. */
    double s = 0;
    for (int k = 1; k < N_ALL; k++) {
        double dl = 0, dw = 0;
        for (int r = 0; r < 3; r++) {
            dl += (p[k][r] - p[0][r]) * (p[k][r] - p[0][r]);
            double w = (double)ref[k].c2w[4 * r + 3] - ref[0].c2w[4 * r + 3];
            dw += w * w;
        }
        if (k == 1) {
            s = sqrt(dl / dw);
        }
        CHECK_NEAR(sqrt(dl / dw), s, 1e-5 * s);
    }
    /* The rule: the farthest camera at distance 1, the mean up along +z,
     * the centre on the sparse points (inside the scene's sphere). */
    CHECK_NEAR(sqrt(far_cam), 1.0, 1e-5);
    double un = sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
    CHECK_NEAR(up[2] / un, 1.0, 1e-6);
    double centre[3];
    for (int r = 0; r < 3; r++) {
        centre[r] = ref[0].c2w[4 * r + 3] - p[0][r] / s;
    }
    CHECK(sqrt(centre[0] * centre[0] + centre[1] * centre[1] +
               centre[2] * centre[2]) < 1.6);
    /* Cameras 4 units from the origin: the scene's sphere (1.6) lies
     * between 2.4 and 5.6 units in front of each; the bounds (with their
     * 0.9 and 1.1 margins) must hold the surfaces seen, nearer and farther
     * than the centre. */
    CHECK(near_b < 3.5 * s && near_b > 0.9 * 2.4 * s);
    CHECK(far_b > 4.0 * s && far_b < 1.1 * 5.6 * s);
}

/*
 * The forward-facing capture written as LLFF and as COLMAP: loaded with
 * forward_facing, the COLMAP model is placed as LLFF places its poses.
 * The rotations agree; the positions agree up to one scale, since LLFF's
 * bounds are the writer's and COLMAP's come from the sparse points.
 */
TEST(forward_facing_colmap_is_placed_as_llff)
{
    char llff_dir[1024], colmap_dir[1024];
    fx_path(llff_dir, sizeof llff_dir, tmp, "ff-llff");
    fx_path(colmap_dir, sizeof colmap_dir, tmp, "ff-colmap");
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = W;
    so.height = H;
    so.n_train = N_ALL;
    so.n_val = so.n_test = 0;
    so.threads = 1;
    so.capture = NERF_SCENE_CAPTURE_FORWARD;
    so.layout = NERF_SCENE_LAYOUT_LLFF;
    CHECK_OK(nerf_scene_write(llff_dir, &so));
    so.layout = NERF_SCENE_LAYOUT_COLMAP_BINARY;
    CHECK_OK(nerf_scene_write(colmap_dir, &so));
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    nerf_dataset *unbounded = NULL, *llff = NULL, *colmap = NULL;
    CHECK_OK(nerf_dataset_load(&unbounded, colmap_dir, &o));
    o.forward_facing = 1;
    CHECK_OK(nerf_dataset_load(&llff, llff_dir, &o));
    CHECK_OK(nerf_dataset_load(&colmap, colmap_dir, &o));
    if (unbounded == NULL || llff == NULL || colmap == NULL) {
        goto done;
    }
    uint32_t space = 0;
    float bound = 0, near = -1, far = -1;
    CHECK_OK(nerf_dataset_space(unbounded, &space, &bound));
    CHECK_EQ_INT(space, NERF_SPACE_UNBOUNDED);
    CHECK_OK(nerf_dataset_space(colmap, &space, &bound));
    CHECK_EQ_INT(space, NERF_SPACE_NDC);
    CHECK_EQ_INT(nerf_dataset_is_ndc(colmap), 1);
    CHECK_OK(nerf_dataset_bounds(colmap, &near, &far));
    CHECK(near == 0.0f && far == 1.0f);
    uint32_t n = nerf_dataset_count(colmap);
    CHECK_EQ_INT(n, nerf_dataset_count(llff));
    double scale = 0;
    for (uint32_t k = 0; k < n; k++) {
        nerf_camera a, b;
        NERF_CAMERA_INIT(&a);
        NERF_CAMERA_INIT(&b);
        CHECK_OK(nerf_dataset_camera(llff, k, &a));
        CHECK_OK(nerf_dataset_camera(colmap, k, &b));
        CHECK_NEAR(b.fx, a.fx, 1e-3);
        double pa = 0, pb = 0;
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 3; c++) {
                CHECK_NEAR(b.c2w[4 * r + c], a.c2w[4 * r + c], 1e-4);
            }
            pa += (double)a.c2w[4 * r + 3] * a.c2w[4 * r + 3];
            pb += (double)b.c2w[4 * r + 3] * b.c2w[4 * r + 3];
        }
        if (pa < 1e-8) {
            continue;
        }
        double s = sqrt(pb / pa);
        scale = scale == 0 ? s : scale;
        CHECK_NEAR(s, scale, 1e-3 * scale);
        for (int r = 0; r < 3; r++) {
            CHECK_NEAR(b.c2w[4 * r + 3], scale * a.c2w[4 * r + 3],
                       1e-4 + 1e-3 * fabs(a.c2w[4 * r + 3]));
        }
    }
    /* Both near planes sit at depth 1/0.75 of their own bounds. */
    CHECK(scale > 0.5 && scale < 2.0);
    nerf_camera spiral;
    NERF_CAMERA_INIT(&spiral);
    CHECK_OK(nerf_dataset_spiral_camera(colmap, 3, 120, &spiral));
    CHECK_EQ_INT(nerf_dataset_spiral_camera(unbounded, 3, 120, &spiral),
                 NERF_EINVAL);
done:
    nerf_dataset_destroy(unbounded);
    nerf_dataset_destroy(llff);
    nerf_dataset_destroy(colmap);
}

/* ---- camera models ------------------------------------------------------ */

static int parse_cameras(const char *text, nerf__colmap_model *m)
{
    nerf__env env;
    nerf__env_from_hooks(&env, NULL);
    memset(m, 0, sizeof *m);
    return nerf__colmap_parse_cameras(&env, "cameras.txt",
                                      (const unsigned char *)text,
                                      strlen(text), 0, m);
}

static void free_model(nerf__colmap_model *m)
{
    nerf__env env;
    nerf__env_from_hooks(&env, NULL);
    nerf__colmap_free(&env, m);
}

TEST(camera_models_map_onto_opencv)
{
    nerf__colmap_model m;
    CHECK_OK(parse_cameras("# comment\n\n"
                           "5 OPENCV 640 480 500 510 320 240 0.1 0.2 0.01 "
                           "0.02\n"
                           "1 SIMPLE_PINHOLE 64 48 50 32 24\r\n"
                           "2 PINHOLE 64 48 50 51 31 23\n"
                           "3 SIMPLE_RADIAL 64 48 50 32 24 -0.1\n"
                           "4 RADIAL 64 48 50 32 24 -0.1 0.05",
                           &m));
    CHECK_EQ_INT(m.n_cameras, 5);
    if (m.n_cameras == 5) {
        /* Sorted by id. */
        const nerf__colmap_camera *c = m.cameras;
        CHECK_EQ_INT(c[0].id, 1);
        CHECK_NEAR(c[0].fy, 50, 0);
        CHECK_NEAR(c[0].cy, 24, 0);
        CHECK_NEAR(c[1].fy, 51, 0);
        CHECK_NEAR(c[1].cx, 31, 0);
        CHECK_NEAR(c[2].k1, -0.1, 0);
        CHECK_NEAR(c[2].k2, 0, 0);
        CHECK_NEAR(c[3].k2, 0.05, 0);
        CHECK_NEAR(c[3].cx, 32, 0);
        CHECK_NEAR(c[4].fx, 500, 0);
        CHECK_NEAR(c[4].fy, 510, 0);
        CHECK_NEAR(c[4].p1, 0.01, 0);
        CHECK_NEAR(c[4].p2, 0.02, 0);
        CHECK_EQ_INT(c[4].width, 640);
    }
    free_model(&m);
    /* Known to COLMAP, not supported here: named, with the camera. */
    CHECK(parse_cameras("7 OPENCV_FISHEYE 64 48 50 50 32 24 0 0 0 0\n", &m) ==
          NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "cameras.txt") &&
          fx_has(nerf_last_error(), "camera 7") &&
          fx_has(nerf_last_error(), "OPENCV_FISHEYE"));
    free_model(&m);
    CHECK(parse_cameras("1 PINHOLE 64 48 50 51 31\n", &m) == NERF_EFORMAT);
    free_model(&m);
    CHECK(parse_cameras("1 PINHOLE 64 48 50 51 31 23 9\n", &m) ==
          NERF_EFORMAT);
    free_model(&m);
    CHECK(parse_cameras("1 PINHOLE 64 48 0 51 31 23\n", &m) == NERF_EFORMAT);
    free_model(&m);
    CHECK(parse_cameras("1 PINHOLE 64 48 nan 51 31 23\n", &m) ==
          NERF_EFORMAT);
    free_model(&m);
    /* Found by fuzz_colmap_text: no camera at all reached qsort(NULL). */
    CHECK(parse_cameras("# only a comment\n", &m) == NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "no cameras"));
    free_model(&m);
    CHECK(parse_cameras("1 PINHOLE 64 48 5 5 3 3\n1 PINHOLE 64 48 5 5 3 3\n",
                        &m) == NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "twice"));
    free_model(&m);
}

/*
 * A lens no call that takes a camera accepts (beyond +-1000) is refused by
 * the parser, naming the file and the camera, in both forms; the bound
 * itself is a lens the calls take.
 */
TEST(lens_beyond_what_cameras_take)
{
    nerf__colmap_model m;
    CHECK_EQ_INT(parse_cameras("3 OPENCV 64 48 50 51 31 23 5000 0 0 0\n",
                               &m), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "cameras.txt: camera 3: distortion k1 "
                 "5000 is beyond +-1000"));
    free_model(&m);
    CHECK_OK(parse_cameras("3 RADIAL 64 48 50 31 23 -1000 1000\n", &m));
    free_model(&m);
    unsigned char bin[8 + 24 + 8 * 8];
    memset(bin, 0, sizeof bin);
    bin[0] = 1;        /* one camera */
    bin[8] = 7;        /* id 7 */
    bin[8 + 4] = 4;    /* OPENCV */
    bin[8 + 8] = 64;   /* width */
    bin[8 + 16] = 48;  /* height */
    const double p[8] = {50, 51, 31, 23, 0, -2000, 0, 0};
    memcpy(bin + 32, p, sizeof p); /* little-endian doubles, as COLMAP's */
    nerf__env env;
    nerf__env_from_hooks(&env, NULL);
    memset(&m, 0, sizeof m);
    CHECK_EQ_INT(nerf__colmap_parse_cameras(&env, "cameras.bin", bin,
                                            sizeof bin, 1, &m),
                 NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "cameras.bin: camera 7: distortion k2 "
                 "-2000 is beyond +-1000"));
    nerf__colmap_free(&env, &m);
}

/*
 * A binary file cut inside a record names it by its id, as every other
 * message does, once the id is read; before that, by how many records
 * came whole.
 */
TEST(truncation_names_the_record_by_id)
{
    enum { REC = 24 + 4 * 8 }; /* a PINHOLE camera */
    unsigned char bin[8 + 2 * REC];
    memset(bin, 0, sizeof bin);
    bin[0] = 2;
    for (int k = 0; k < 2; k++) {
        unsigned char *r = bin + 8 + k * REC;
        r[0] = k ? 9 : 7;
        r[4] = 1; /* PINHOLE */
        r[8] = 64;
        r[16] = 48;
        const double p[4] = {50, 51, 31, 23};
        memcpy(r + 24, p, sizeof p);
    }
    nerf__env env;
    nerf__env_from_hooks(&env, NULL);
    static const struct {
        size_t size;
        const char *says;
    } cuts[] = {
        {sizeof bin - 8, "cameras.bin: truncated in camera 9"},
        {8 + REC + 6, "cameras.bin: truncated in camera 9"},
        {8 + REC + 2, "cameras.bin: truncated after 1 of the 2 cameras"},
    };
    for (size_t i = 0; i < sizeof cuts / sizeof cuts[0]; i++) {
        nerf__colmap_model m;
        memset(&m, 0, sizeof m);
        int rc = nerf__colmap_parse_cameras(&env, "cameras.bin", bin,
                                            cuts[i].size, 1, &m);
        CHECK_EQ_INT(rc, NERF_EFORMAT);
        if (!fx_has(nerf_last_error(), cuts[i].says)) {
            FAILF("cut at %zu: '%s' lacks '%s'", cuts[i].size,
                  nerf_last_error(), cuts[i].says);
        }
        nerf__colmap_free(&env, &m);
    }
}

TEST(quaternions_round_trip)
{
    const double q[4] = {0.5, -0.3, 0.7, 0.1};
    double n = sqrt(0.25 + 0.09 + 0.49 + 0.01), qn[4], t[3] = {1, -2, 3};
    for (int i = 0; i < 4; i++) {
        qn[i] = q[i] / n;
    }
    double c2w[12], q2[4], t2[3];
    nerf__colmap_to_c2w(qn, t, c2w);
    nerf__c2w_to_colmap(c2w, q2, t2);
    for (int i = 0; i < 4; i++) {
        CHECK_NEAR(q2[i], qn[i], 1e-12);
    }
    for (int i = 0; i < 3; i++) {
        CHECK_NEAR(t2[i], t[i], 1e-12);
    }
    /* The camera looks along its OpenCV +z, which is OpenGL's -z column:
     * the world-to-camera z row of R. */
    double r[9];
    nerf__quat_to_matrix(qn, r);
    for (int i = 0; i < 3; i++) {
        CHECK_NEAR(-c2w[4 * i + 2], r[6 + i], 1e-12);
        CHECK_NEAR(-c2w[4 * i + 1], r[3 + i], 1e-12);
    }
}

/* ---- bad inputs --------------------------------------------------------- */

static void model_file(const char *scene, const char *file, char *out,
                       size_t size)
{
    char rel[256];
    snprintf(rel, sizeof rel, "%s/sparse/0/%s", scene, file);
    fx_path(out, size, tmp, rel);
}

/* Loading scene fails with status rc and a message holding all needles. */
static void expect_failure(const char *scene, int rc, const char *a,
                           const char *b, const char *c)
{
    char dir[1024];
    fx_path(dir, sizeof dir, tmp, scene);
    nerf_dataset *ds = NULL;
    int got = nerf_dataset_load(&ds, dir, NULL);
    CHECK_EQ_INT(got, rc);
    CHECK(ds == NULL);
    const char *msg = nerf_last_error();
    if (!fx_has(msg, a) || !fx_has(msg, b) || !fx_has(msg, c)) {
        FAILF("message '%s' lacks '%s', '%s' or '%s'", msg, a, b, c);
    }
    nerf_dataset_destroy(ds);
}

static unsigned char *read_all(const char *path, long *size)
{
    *size = fx_file_size(path);
    unsigned char *b = malloc((size_t)(*size > 0 ? *size : 1));
    FILE *f = fopen(path, "rb");
    if (f == NULL || fread(b, 1, (size_t)*size, f) != (size_t)*size) {
        perror(path);
        exit(1);
    }
    fclose(f);
    return b;
}

TEST(truncated_images_bin)
{
    write_scene("trunc", NERF_SCENE_LAYOUT_COLMAP_BINARY);
    char path[1024];
    model_file("trunc", "images.bin", path, sizeof path);
    long size = fx_file_size(path);
    /* In the middle of the first image's name and of a later record. */
    fx_truncate(path, size / 2);
    expect_failure("trunc", NERF_EFORMAT, "images.bin", "truncated", "");
    fx_truncate(path, 8 + 64 + 2);
    expect_failure("trunc", NERF_EFORMAT, "images.bin", "truncated", "");
    /* Only the last byte gone: inside the last image's 2D points. */
    write_scene("trunc", NERF_SCENE_LAYOUT_COLMAP_BINARY);
    fx_truncate(path, size - 1);
    expect_failure("trunc", NERF_EFORMAT, "images.bin", "truncated",
                   "00015.png");
}

TEST(counts_larger_than_the_file)
{
    write_scene("counts", NERF_SCENE_LAYOUT_COLMAP_BINARY);
    static const char *const files[] = {"cameras.bin", "images.bin",
                                        "points3D.bin"};
    for (int f = 0; f < 3; f++) {
        char path[1024];
        model_file("counts", files[f], path, sizeof path);
        long size;
        unsigned char *b = read_all(path, &size);
        unsigned char *bad = malloc((size_t)size);
        memcpy(bad, b, (size_t)size);
        bad[6] = 0x7f; /* count = 2^54 or so */
        fx_write_bytes(path, bad, (size_t)size);
        expect_failure("counts", NERF_EFORMAT, files[f], "claims", "");
        fx_write_bytes(path, b, (size_t)size);
        free(b);
        free(bad);
    }
    /* A track longer than the file, in points3D.bin: the first point's
     * track length follows its 43-byte head. */
    char path[1024];
    model_file("counts", "points3D.bin", path, sizeof path);
    long size;
    unsigned char *b = read_all(path, &size);
    b[8 + 43 + 7] = 0x40;
    fx_write_bytes(path, b, (size_t)size);
    expect_failure("counts", NERF_EFORMAT, "points3D.bin", "track", "");
    free(b);
}

TEST(unknown_camera_model)
{
    write_scene("model", NERF_SCENE_LAYOUT_COLMAP_TEXT);
    char path[1024];
    model_file("model", "cameras.txt", path, sizeof path);
    fx_write_bytes(path, "1 FANCY_LENS 32 32 30 16 16\n", 28);
    expect_failure("model", NERF_EFORMAT, "cameras.txt", "camera 1",
                   "FANCY_LENS");
    /* In a binary model: an id beyond COLMAP's, then a known but
     * unsupported one. */
    write_scene("model_bin", NERF_SCENE_LAYOUT_COLMAP_BINARY);
    model_file("model_bin", "cameras.bin", path, sizeof path);
    long size;
    unsigned char *b = read_all(path, &size);
    b[8 + 4] = 42;
    fx_write_bytes(path, b, (size_t)size);
    expect_failure("model_bin", NERF_EFORMAT, "cameras.bin", "camera 1",
                   "model id 42");
    b[8 + 4] = 6;
    fx_write_bytes(path, b, (size_t)size);
    expect_failure("model_bin", NERF_EFORMAT, "cameras.bin", "camera 1",
                   "FULL_OPENCV");
    free(b);
}

TEST(missing_photo)
{
    write_scene("photo", NERF_SCENE_LAYOUT_COLMAP_TEXT);
    char path[1024];
    fx_path(path, sizeof path, tmp, "photo/images/00003.png");
    CHECK(unlink(path) == 0);
    expect_failure("photo", NERF_ENOENT, "00003.png", "missing", "images.txt");
}

/*
 * The photos of every split are checked when any split loads: the test
 * split's 00008.png (held out: every 8th) is found by the train split's
 * load, and what is not a regular file is named for what it is.
 */
TEST(photos_of_every_split_are_checked)
{
    write_scene("held", NERF_SCENE_LAYOUT_COLMAP_TEXT);
    char path[1024];
    fx_path(path, sizeof path, tmp, "held/images/00008.png");
    CHECK(unlink(path) == 0);
    expect_failure("held", NERF_ENOENT, "00008.png: missing", "images.txt",
                   "image 9");
    CHECK(mkfifo(path, 0666) == 0);
    expect_failure("held", NERF_EUNRECOGNISED,
                   "00008.png: a FIFO (named pipe), not a regular file",
                   "images.txt names it for image 9", "");
    CHECK(unlink(path) == 0);
    CHECK(mkdir(path, 0777) == 0);
    expect_failure("held", NERF_EUNRECOGNISED,
                   "00008.png: a folder, not a file", "", "");
    CHECK(rmdir(path) == 0);
    fx_write_bytes(path, "not an image", 12);
    expect_failure("held", NERF_EFORMAT,
                   "00008.png: not a PNG or JPEG file", "", "");
}

/*
 * images_2/ must hold the photos at half the cameras' size: a copy of the
 * full-size photos is refused, naming both sizes.
 */
TEST(images_k_of_full_size_photos)
{
    write_scene("k2", NERF_SCENE_LAYOUT_COLMAP_BINARY);
    char from[1024], to[1024];
    fx_mkdir(tmp, "k2/images_2");
    for (int i = 0; i < N_ALL; i++) {
        char name[64];
        snprintf(name, sizeof name, "k2/images/%05d.png", i);
        fx_path(from, sizeof from, tmp, name);
        snprintf(name, sizeof name, "k2/images_2/%05d.png", i);
        fx_path(to, sizeof to, tmp, name);
        CHECK(link(from, to) == 0);
    }
    char dir[1024];
    fx_path(dir, sizeof dir, tmp, "k2");
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 2;
    nerf_dataset *ds = NULL;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "images_2: the photos are 32x32"));
    CHECK(fx_has(nerf_last_error(), "camera 1"));
    CHECK(fx_has(nerf_last_error(), "divided by 2 is 16x16"));
    CHECK(ds == NULL);
}

TEST(zero_quaternion)
{
    write_scene("quat", NERF_SCENE_LAYOUT_COLMAP_TEXT);
    char path[1024];
    model_file("quat", "images.txt", path, sizeof path);
    long size;
    char *text = (char *)read_all(path, &size);
    char *out = malloc((size_t)size + 64);
    /* Replace image 2's pose line with one whose quaternion is zero. */
    char *line = strstr(text, "\n2 ");
    CHECK(line != NULL);
    if (line != NULL) {
        char *end = strchr(line + 1, '\n');
        size_t head = (size_t)(line + 1 - text);
        memcpy(out, text, head);
        int n = sprintf(out + head, "2 0 0 0 0 1 2 3 1 00001.png");
        memcpy(out + head + n, end, (size_t)(text + size - end));
        fx_write_bytes(path, out, head + (size_t)n +
                                      (size_t)(text + size - end));
        expect_failure("quat", NERF_EFORMAT, "images.txt", "00001.png",
                       "zero length");
    }
    free(text);
    free(out);
}

TEST(unknown_folder_names_colmap)
{
    char dir[1024];
    fx_path(dir, sizeof dir, tmp, "empty");
    mkdir(dir, 0777);
    nerf_dataset *ds = NULL;
    CHECK(nerf_dataset_load(&ds, dir, NULL) == NERF_EUNRECOGNISED);
    CHECK(fx_has(nerf_last_error(), "COLMAP"));
}

int main(void)
{
    tmp = fx_make_temp_dir();
    RUN(text_and_binary_agree_with_the_writer);
    RUN(downscale_halves_the_intrinsics);
    RUN(forward_facing_colmap_is_placed_as_llff);
    RUN(camera_models_map_onto_opencv);
    RUN(quaternions_round_trip);
    RUN(truncated_images_bin);
    RUN(counts_larger_than_the_file);
    RUN(unknown_camera_model);
    RUN(missing_photo);
    RUN(lens_beyond_what_cameras_take);
    RUN(truncation_names_the_record_by_id);
    RUN(photos_of_every_split_are_checked);
    RUN(images_k_of_full_size_photos);
    RUN(zero_quaternion);
    RUN(unknown_folder_names_colmap);
    fx_remove_tree(tmp);
    HARNESS_EXIT();
}
