/*
 * The LLFF loader on tiny scenes whose expected poses are worked out by
 * hand below.
 */
#include <nerf.h>

#include <sys/stat.h>

#include "data_fixtures.h"
#include "../harness.h"

enum { N = 9, FW = 16, FH = 12, IW = 8, IH = 6 };
#define FOCAL 20.0

static char *tmp;
static int scene_id;

/* Camera i's position before scaling. */
static void position(int i, double t[3])
{
    t[0] = i - 4;
    t[1] = 0.5 * (i % 3 - 1);
    t[2] = 0.2 * i;
}

/* All cameras share the NeRF-axes rotation q (row-major 3x3). */
static void make_rows(double *rows, const double q[9])
{
    for (int i = 0; i < N; i++) {
        double *r = rows + 17 * i, t[3];
        position(i, t);
        for (int k = 0; k < 3; k++) {
            /* LLFF columns [down, right, back] = [-q1, q0, q2]. */
            r[5 * k + 0] = -q[3 * k + 1];
            r[5 * k + 1] = q[3 * k + 0];
            r[5 * k + 2] = q[3 * k + 2];
            r[5 * k + 3] = t[k];
        }
        r[4] = FH;
        r[9] = FW;
        r[14] = FOCAL;
        r[15] = 2.0 + 0.25 * i;
        r[16] = 10.0 + i;
    }
}

static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

static void pixel(int i, int x, int y, uint16_t out[3])
{
    out[0] = (uint16_t)(i * 20);
    out[1] = (uint16_t)(x * 25);
    out[2] = (uint16_t)(y * 30);
}

static void image_path(char *buf, size_t size, const char *dir, int i)
{
    char name[32];
    snprintf(name, sizeof name, "images_2/IMG_%04d.png", 4026 + i);
    fx_path(buf, size, dir, name);
}

/* Every photo of images_2/ replaced by a black one of w x h. */
static void resize_images(const char *dir, uint32_t w, uint32_t h)
{
    uint16_t *px = calloc((size_t)w * h * 3, sizeof *px);
    char p[1024];
    for (int i = 0; px && i < N; i++) {
        image_path(p, sizeof p, dir, i);
        fx_write_png(p, w, h, 2, 8, px, NULL, 0, NULL, 0);
    }
    free(px);
}

/* A scene folder: poses_bounds.npy from rows, images_2/ with N images. */
static void make_scene(char *dir, size_t size, const double *rows)
{
    snprintf(dir, size, "%s/llff%d", tmp, scene_id++);
    mkdir(dir, 0777);
    fx_mkdir(dir, "images_2");
    char p[1024];
    fx_path(p, sizeof p, dir, "poses_bounds.npy");
    fx_write_npy(p, "<f8", "False", "(9, 17)", rows, sizeof(double) * N * 17);
    uint16_t px[IW * IH * 3];
    /* Written last-first: the loader must sort, not trust readdir. */
    for (int i = N - 1; i >= 0; i--) {
        for (int y = 0; y < IH; y++) {
            for (int x = 0; x < IW; x++) {
                pixel(i, x, y, px + 3 * (y * IW + x));
            }
        }
        image_path(p, sizeof p, dir, i);
        fx_write_png(p, IW, IH, 2, 8, px, NULL, 0, NULL, 0);
    }
    fx_write_text(dir, "images_2/notes.txt", "not an image");
}

static nerf_dataset *load(const char *dir, uint32_t split, uint32_t downscale)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = split;
    o.downscale = downscale;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    return ds;
}

/*
 * Hand derivation for the identity-rotation scene.  Bounds: the smallest
 * is row 0's near, 2, so scale s = 1 / (2 * 0.75) = 2/3.  All rotations are
 * I, so the average pose is [I | mean position]; the mean of position() is
 * (0, 0, 0.8).  Recentred: R = I, t = s (t_i - (0, 0, 0.8)).
 */
static void expected_position(int i, double t[3])
{
    position(i, t);
    t[2] -= 0.8;
    for (int k = 0; k < 3; k++) {
        t[k] *= 2.0 / 3.0;
    }
}

static void check_pose(const nerf_camera *cam, const double r[9],
                       const double t[3])
{
    for (int k = 0; k < 3; k++) {
        for (int c = 0; c < 3; c++) {
            CHECK_NEAR(cam->c2w[4 * k + c], r[3 * k + c], 1e-6);
        }
        CHECK_NEAR(cam->c2w[4 * k + 3], t[k], 1e-6);
    }
}

TEST(splits_and_poses)
{
    double rows[N * 17];
    make_rows(rows, identity);
    char dir[1024];
    make_scene(dir, sizeof dir, rows);
    /* Train: every image but 0 and 8. */
    nerf_dataset *ds = load(dir, NERF_SPLIT_TRAIN, 2);
    if (ds == NULL) {
        return;
    }
    CHECK_EQ_INT(nerf_dataset_count(ds), 7);
    CHECK_EQ_INT(nerf_dataset_get_format(ds), NERF_DATASET_LLFF);
    CHECK_EQ_INT(nerf_dataset_is_ndc(ds), 1);
    float near, far;
    CHECK_OK(nerf_dataset_bounds(ds, &near, &far));
    CHECK_NEAR(near, 0.0, 0.0);
    CHECK_NEAR(far, 1.0, 0.0);
    uint32_t w, h;
    CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
    CHECK_EQ_INT(w, IW);
    CHECK_EQ_INT(h, IH);
    for (uint32_t i = 0; i < 7; i++) {
        int row = (int)i + 1;
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(ds, i, &cam));
        double t[3];
        expected_position(row, t);
        check_pose(&cam, identity, t);
        /* hwf 12 x 16, focal 20 at full size; the images are 8 wide. */
        CHECK_NEAR(cam.fx, 10.0, 1e-6);
        CHECK_NEAR(cam.fy, 10.0, 1e-6);
        CHECK_NEAR(cam.cx, 4.0, 0.0);
        CHECK_NEAR(cam.cy, 3.0, 0.0);
        const float *rgb;
        CHECK_OK(nerf_dataset_image(ds, i, &rgb));
        uint16_t px[3];
        pixel(row, 5, 4, px);
        for (int c = 0; c < 3; c++) {
            CHECK_NEAR(rgb[(4 * IW + 5) * 3 + c], px[c] / 255.0, 1e-6);
        }
    }
    nerf_dataset_destroy(ds);
    /* Test (and val): images 0 and 8. */
    for (uint32_t split = NERF_SPLIT_VAL; split <= NERF_SPLIT_TEST; split++) {
        ds = load(dir, split, 2);
        CHECK_EQ_INT(nerf_dataset_count(ds), 2);
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        if (ds) {
            CHECK_OK(nerf_dataset_camera(ds, 1, &cam));
            /* Row 8: s ((4, 0.5, 1.6) - (0, 0, 0.8)). */
            double t[3] = {8.0 / 3.0, 1.0 / 3.0, 1.6 / 3.0};
            check_pose(&cam, identity, t);
        }
        nerf_dataset_destroy(ds);
    }
}

TEST(recentring_removes_common_rotation)
{
    /* Every camera turned 30 degrees about y: the average pose carries the
     * turn, so recentred rotations are I and positions are Q^T s (t - c). */
    double a = 30.0 * M_PI / 180.0, c = cos(a), s = sin(a);
    double q[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
    double rows[N * 17];
    make_rows(rows, q);
    char dir[1024];
    make_scene(dir, sizeof dir, rows);
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 2;
    o.llff_holdout = 0; /* all nine images in train */
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), N);
    for (uint32_t i = 0; i < N && ds; i++) {
        double t[3], d[3], qt[3];
        position((int)i, t);
        double mean[3] = {0.0, 0.0, 0.8};
        for (int k = 0; k < 3; k++) {
            d[k] = (t[k] - mean[k]) * 2.0 / 3.0;
        }
        for (int k = 0; k < 3; k++) {
            qt[k] = q[k] * d[0] + q[3 + k] * d[1] + q[6 + k] * d[2];
        }
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(ds, i, &cam));
        check_pose(&cam, identity, qt);
    }
    nerf_dataset_destroy(ds);
}

TEST(spiral_path)
{
    double rows[N * 17];
    make_rows(rows, identity);
    char dir[1024];
    make_scene(dir, sizeof dir, rows);
    nerf_dataset *ds = load(dir, NERF_SPLIT_TEST, 2);
    if (ds == NULL) {
        return;
    }
    /*
     * Scaled bounds: nearest 4/3, farthest 18 * 2/3 = 12.  Focus depth
     * 1 / (0.25 / (0.9 * 4/3) + 0.75 / (5 * 12)).  Radii: the 90th
     * percentile (NumPy's linear rule, position 0.9 * 8 = 7.2 in the
     * sorted list) of |x| = 2/3 {4,3,2,1,0,1,2,3,4} is 8/3; of
     * |y| = 1/3 {1,0,1,...} is 1/3; of |z| = 2/15 |i - 4| is 8/15.
     * The average recentred pose is [I | 0] and up is +y.
     */
    double focus = 1.0 / (0.25 / 1.2 + 0.75 / 60.0);
    double rx = 8.0 / 3.0, rz = 8.0 / 15.0;
    /* View 0 of 8: centre (rx, 0, 0), looking at (0, 0, -focus). */
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_dataset_spiral_camera(ds, 0, 8, &cam));
    double n0 = sqrt(rx * rx + focus * focus);
    double r0[9] = {focus / n0, 0, rx / n0, 0, 1, 0, -rx / n0, 0, focus / n0};
    double t0[3] = {rx, 0, 0};
    check_pose(&cam, r0, t0);
    CHECK_NEAR(cam.fx, 10.0, 1e-6);
    CHECK_EQ_INT(cam.width, IW);
    /* View 2 of 8 is half way round the first turn (theta = pi), where
     * the depth wobble sin(theta / 2) peaks: centre (-rx, 0, -rz). */
    CHECK_OK(nerf_dataset_spiral_camera(ds, 2, 8, &cam));
    double zx = -rx, zz = -rz + focus, n2 = sqrt(zx * zx + zz * zz);
    double r2[9] = {zz / n2, 0, zx / n2, 0, 1, 0, -zx / n2, 0, zz / n2};
    double t2[3] = {-rx, 0, -rz};
    check_pose(&cam, r2, t2);
    CHECK_EQ_INT(nerf_dataset_spiral_camera(ds, 8, 8, &cam), NERF_EINVAL);
    CHECK_EQ_INT(nerf_dataset_spiral_camera(ds, 0, 0, &cam), NERF_EINVAL);
    CHECK_EQ_INT(nerf_dataset_spiral_camera(NULL, 0, 8, &cam), NERF_EINVAL);
    nerf_dataset_destroy(ds);
}

TEST(downscale_from_smaller_folder)
{
    double rows[N * 17];
    make_rows(rows, identity);
    char dir[1024];
    make_scene(dir, sizeof dir, rows);
    /* No images_4/: images_2/ averaged by 2 more. */
    nerf_dataset *ds = load(dir, NERF_SPLIT_TEST, 4);
    if (ds) {
        uint32_t w, h;
        CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
        CHECK_EQ_INT(w, IW / 2);
        CHECK_EQ_INT(h, IH / 2);
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(ds, 1, &cam));
        CHECK_NEAR(cam.fx, 5.0, 1e-6);
        CHECK_NEAR(cam.cx, 2.0, 0.0);
        const float *rgb;
        CHECK_OK(nerf_dataset_image(ds, 1, &rgb));
        /* Output (1, 2) averages source x 2..3, y 4..5 of image 8. */
        double g = (2 * 25 + 3 * 25) / 2.0 / 255.0;
        double b = (4 * 30 + 5 * 30) / 2.0 / 255.0;
        CHECK_NEAR(rgb[(2 * 4 + 1) * 3 + 0], 160 / 255.0, 1e-6);
        CHECK_NEAR(rgb[(2 * 4 + 1) * 3 + 1], g, 1e-6);
        CHECK_NEAR(rgb[(2 * 4 + 1) * 3 + 2], b, 1e-6);
    }
    nerf_dataset_destroy(ds);
    /* No images/ at all for downscale 1. */
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_ENOENT);
    CHECK(fx_has(nerf_last_error(), "no image folder"));
    /* Skip applies within the split: train 1..7, every second. */
    o.downscale = 2;
    o.skip = 2;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), 4);
    nerf_dataset_destroy(ds);
}

/* Write rows (or a raw npy) into a fresh scene and expect a failure. */
static void expect_failure(const double *rows, const char *descr,
                           const char *fortran, const char *shape,
                           size_t bytes, const char *word)
{
    double good[N * 17];
    make_rows(good, identity);
    char dir[1024], p[1024];
    make_scene(dir, sizeof dir, good);
    fx_path(p, sizeof p, dir, "poses_bounds.npy");
    fx_write_npy(p, descr, fortran, shape, rows, bytes);
    nerf_dataset *ds = (nerf_dataset *)dir;
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 2;
    int rc = nerf_dataset_load(&ds, dir, &o);
    if (rc != NERF_EFORMAT || ds != NULL ||
        !fx_has(nerf_last_error(), "poses_bounds.npy") ||
        !fx_has(nerf_last_error(), word)) {
        FAILF("status %d, message '%s' (want '%s')", rc, nerf_last_error(),
              word);
    }
}

TEST(bad_npy)
{
    double rows[N * 17];
    make_rows(rows, identity);
    size_t full = sizeof rows;
    expect_failure(rows, "<f4", "False", "(9, 17)", full / 2,
                   "dtype is '<f4'");
    expect_failure(rows, "<i8", "False", "(9, 17)", full, "dtype");
    expect_failure(rows, "<f8", "True", "(9, 17)", full, "Fortran order");
    expect_failure(rows, "<f8", "False", "(9, 15)", 9 * 15 * 8,
                   "shape is (9, 15)");
    expect_failure(rows, "<f8", "False", "(153,)", full, "shape is (153,)");
    expect_failure(rows, "<f8", "False", "(9, 17)", full - 8, "");
    double bad[N * 17];
    memcpy(bad, rows, sizeof bad);
    bad[17 * 3 + 7] = NAN;
    expect_failure(bad, "<f8", "False", "(9, 17)", full,
                   "row 3 (image IMG_4029.png) holds a non-finite value");
    memcpy(bad, rows, sizeof bad);
    bad[17 * 5 + 16] = bad[17 * 5 + 15];
    expect_failure(bad, "<f8", "False", "(9, 17)", full,
                   "row 5 (image IMG_4031.png): bounds");
    memcpy(bad, rows, sizeof bad);
    bad[17 * 2 + 14] = 0.0;
    expect_failure(bad, "<f8", "False", "(9, 17)", full, "focal 0");
    memcpy(bad, rows, sizeof bad);
    bad[17 * 0 + 14] = -20.0;
    expect_failure(bad, "<f8", "False", "(9, 17)", full, "must be positive");
    /* Finite but absurd: a translation of 1e308, a focal of (nearly)
     * zero, a rotation column of (nearly) zero length.  Each names the
     * row and its image (sorted names: row 1 is IMG_4027.png). */
    memcpy(bad, rows, sizeof bad);
    bad[17 * 1 + 3] = 1e308;
    expect_failure(bad, "<f8", "False", "(9, 17)", full,
                   "row 1 (image IMG_4027.png): has an entry of magnitude "
                   "1e+308");
    memcpy(bad, rows, sizeof bad);
    bad[17 * 1 + 8] = -2e6; /* the far bound */
    expect_failure(bad, "<f8", "False", "(9, 17)", full, "beyond");
    memcpy(bad, rows, sizeof bad);
    bad[17 * 2 + 14] = 1e-9;
    expect_failure(bad, "<f8", "False", "(9, 17)", full,
                   "row 2 (image IMG_4028.png): height 12, width 16 and "
                   "focal 1e-09");
    memcpy(bad, rows, sizeof bad);
    for (int r = 0; r < 3; r++) {
        bad[17 * 4 + 5 * r + 1] *= 1e-9;
    }
    expect_failure(bad, "<f8", "False", "(9, 17)", full,
                   "row 4 (image IMG_4030.png): has a degenerate rotation");
}

TEST(bad_images)
{
    double rows[N * 17];
    make_rows(rows, identity);
    char dir[1024], p[1024];
    nerf_dataset *ds = NULL;
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 2;
    /* One image fewer than rows. */
    make_scene(dir, sizeof dir, rows);
    fx_path(p, sizeof p, dir, "images_2/IMG_4030.png");
    unlink(p);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "8 image files"));
    CHECK(fx_has(nerf_last_error(), "9 rows"));
    /* An image of another size. */
    make_scene(dir, sizeof dir, rows);
    uint16_t px[(IW + 2) * IH * 3] = {0};
    fx_path(p, sizeof p, dir, "images_2/IMG_4029.png");
    fx_write_png(p, IW + 2, IH, 2, 8, px, NULL, 0, NULL, 0);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "IMG_4029.png: image is 10x6"));
    /* Files are told apart by their bytes, not their names: a PNG named
     * .jpg loads; text named .jpg is refused by name. */
    make_scene(dir, sizeof dir, rows);
    char q[1024];
    fx_path(p, sizeof p, dir, "images_2/IMG_4028.png");
    fx_path(q, sizeof q, dir, "images_2/IMG_4028.jpg");
    rename(p, q);
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    nerf_dataset_destroy(ds);
    ds = NULL;
    fx_write_text(dir, "images_2/IMG_4028.jpg", "not an image");
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "IMG_4028.jpg: not a PNG or JPEG file"));
    /* Images whose aspect ratio does not fit the poses' hwf: in
     * images_2/ they are not half the poses' size either, which is found
     * first; in images/, which may hold any size, the aspect is. */
    make_scene(dir, sizeof dir, rows);
    resize_images(dir, IW + 2, IH);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "images_2: the photos are 10x6"));
    fx_path(p, sizeof p, dir, "images_2");
    fx_path(q, sizeof q, dir, "images");
    CHECK(rename(p, q) == 0);
    o.downscale = 1;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "does not match"));
    CHECK(ds == NULL);
}

/*
 * The images the train split does not load (0 and 8 are held out) are
 * checked by their headers all the same, so that the test split's load
 * finds nothing the train split's did not.
 */
TEST(held_out_images_are_checked)
{
    double rows[N * 17];
    make_rows(rows, identity);
    char dir[1024], p[1024];
    nerf_dataset *ds = NULL;
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 2;
    make_scene(dir, sizeof dir, rows);
    image_path(p, sizeof p, dir, 8);
    fx_write_text(dir, "images_2/IMG_4034.png", "not an image");
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "IMG_4034.png: not a PNG or JPEG file"));
    unlink(p);
    CHECK(mkfifo(p, 0666) == 0);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EUNRECOGNISED);
    CHECK(fx_has(nerf_last_error(), "IMG_4034.png: a FIFO (named pipe)"));
    unlink(p);
    uint16_t px[IW * 2 * IH * 3] = {0};
    fx_write_png(p, IW * 2, IH, 2, 8, px, NULL, 0, NULL, 0);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "IMG_4034.png: image is 16x6"));
    /* The frames skip passes over are checked too. */
    make_scene(dir, sizeof dir, rows);
    o.skip = 2;
    fx_write_text(dir, "images_2/IMG_4028.png", "not an image");
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "IMG_4028.png: not a PNG or JPEG file"));
    CHECK(ds == NULL);
}

/*
 * An images_2/ folder holding the full-size photos (16 x 12, the poses'
 * size) rather than photos half as large: refused, naming both sizes,
 * instead of trained at four times the pixels asked for.
 */
TEST(images_k_of_full_size_photos)
{
    double rows[N * 17];
    make_rows(rows, identity);
    char dir[1024];
    make_scene(dir, sizeof dir, rows);
    resize_images(dir, FW, FH);
    nerf_dataset *ds = NULL;
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 2;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "images_2: the photos are 16x12"));
    CHECK(fx_has(nerf_last_error(), "divided by 2 is 8x6"));
    /* Within a pixel of the poses' size over 2 is what the name says,
     * whichever way the tool that shrank them rounded: 9 x 7 is read. */
    resize_images(dir, IW + 1, IH + 1);
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    nerf_dataset_destroy(ds);
}

int main(void)
{
    tmp = fx_make_temp_dir();
    RUN(splits_and_poses);
    RUN(recentring_removes_common_rotation);
    RUN(spiral_path);
    RUN(downscale_from_smaller_folder);
    RUN(bad_npy);
    RUN(bad_images);
    RUN(held_out_images_are_checked);
    RUN(images_k_of_full_size_photos);
    fx_remove_tree(tmp);
    HARNESS_EXIT();
}
