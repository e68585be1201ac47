/*
 * The shared real scenes (lego, fern) from $NERF_DATA_DIR, when present.
 * Without them the test is skipped (exit 77): CI clones the data beside
 * the project, developers may not have it.
 */
#include <nerf.h>

#include <string.h>
#include <sys/stat.h>

#include "../harness.h"

static char lego[1024], fern[1024];

static int have(const char *dir, const char *file)
{
    char p[1200];
    struct stat st;
    snprintf(p, sizeof p, "%s/%s", dir, file);
    return stat(p, &st) == 0;
}

TEST(lego_val)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = NERF_SPLIT_VAL;
    o.skip = 8;      /* the shared copy holds val images 0, 8, ..., 96 */
    o.downscale = 8;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, lego, &o));
    if (ds == NULL) {
        return;
    }
    CHECK_EQ_INT(nerf_dataset_count(ds), 13);
    uint32_t w, h;
    CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
    CHECK_EQ_INT(w, 100);
    CHECK_EQ_INT(h, 100);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_dataset_camera(ds, 0, &cam));
    /* 0.5 * 800 / tan(0.5 * 0.6911112070083618) = 1111.111, over 8. */
    CHECK_NEAR(cam.fx, 1111.1110311 / 8.0, 1e-3);
    CHECK_NEAR(cam.fy, cam.fx, 0.0);
    CHECK_NEAR(cam.cx, 50.0, 0.0);
    /* Cameras sit on a sphere of radius about 4.03 around the object. */
    double r = sqrt(cam.c2w[3] * cam.c2w[3] + cam.c2w[7] * cam.c2w[7] +
                    cam.c2w[11] * cam.c2w[11]);
    CHECK_NEAR(r, 4.031, 0.01);
    float near, far;
    CHECK_OK(nerf_dataset_bounds(ds, &near, &far));
    CHECK(near == 2.0f && far == 6.0f);
    /* Transparent corners come out white; the object does not. */
    const float *rgb;
    CHECK_OK(nerf_dataset_image(ds, 0, &rgb));
    CHECK_NEAR(rgb[0], 1.0, 1e-6);
    double mean = 0.0;
    for (size_t i = 0; i < (size_t)w * h * 3; i++) {
        mean += rgb[i];
    }
    mean /= (double)w * h * 3;
    CHECK(mean > 0.5 && mean < 0.99);
    /* The metrics agree an image equals itself and differs from another. */
    const float *other;
    CHECK_OK(nerf_dataset_image(ds, 1, &other));
    double ssim, psnr;
    CHECK_OK(nerf_ssim(rgb, rgb, w, h, 3, &ssim));
    CHECK_NEAR(ssim, 1.0, 1e-12);
    CHECK_OK(nerf_psnr(rgb, other, (size_t)w * h * 3, &psnr));
    CHECK(psnr > 5.0 && psnr < 30.0);
    nerf_dataset_destroy(ds);

    /* Without skip the missing val images are reported, by name. */
    o.skip = 1;
    CHECK_EQ_INT(nerf_dataset_load(&ds, lego, &o), NERF_ENOENT);
    CHECK(strstr(nerf_last_error(), "val/r_1.png") != NULL);
    o.skip_missing = 1;
    CHECK_OK(nerf_dataset_load(&ds, lego, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), 13);
    nerf_dataset_destroy(ds);
}

TEST(fern)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 8;
    o.llff_holdout = 0; /* every image */
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, fern, &o));
    if (ds == NULL) {
        return;
    }
    CHECK_EQ_INT(nerf_dataset_count(ds), 20);
    CHECK_EQ_INT(nerf_dataset_is_ndc(ds), 1);
    uint32_t w, h;
    CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
    CHECK_EQ_INT(w, 504);
    CHECK_EQ_INT(h, 378);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_dataset_camera(ds, 0, &cam));
    CHECK_NEAR(cam.fx, 407.57, 0.01); /* 3260.53 * 504 / 4032 */
    CHECK_NEAR(cam.cx, 252.0, 0.0);
    CHECK_NEAR(cam.cy, 189.0, 0.0);
    /* Recentred: the mean camera position is the origin. */
    double mean[3] = {0.0, 0.0, 0.0};
    for (uint32_t i = 0; i < 20; i++) {
        CHECK_OK(nerf_dataset_camera(ds, i, &cam));
        for (int k = 0; k < 3; k++) {
            mean[k] += cam.c2w[4 * k + 3] / 20.0;
        }
    }
    for (int k = 0; k < 3; k++) {
        CHECK_NEAR(mean[k], 0.0, 1e-5);
    }
    for (uint32_t i = 0; i < 120; i += 17) {
        CHECK_OK(nerf_dataset_spiral_camera(ds, i, 120, &cam));
    }
    nerf_dataset_destroy(ds);

    /* The reference protocol: every 8th image (0, 8, 16) is the test set. */
    o.llff_holdout = 8;
    o.split = NERF_SPLIT_TEST;
    CHECK_OK(nerf_dataset_load(&ds, fern, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), 3);
    nerf_dataset_destroy(ds);
    o.split = NERF_SPLIT_TRAIN;
    CHECK_OK(nerf_dataset_load(&ds, fern, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), 17);
    nerf_dataset_destroy(ds);

    /*
     * Downscale 64 has no folder of its own: images_8 averaged by 8 more.
     * 504 / 8 = 63 exactly; 378 / 8 = 47.25 is rounded down to 47 (the
     * last two source rows are dropped), where the reference's ImageMagick
     * resize would round to nearest (also 47 here).
     */
    o.downscale = 64;
    CHECK_OK(nerf_dataset_load(&ds, fern, &o));
    if (ds) {
        CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
        CHECK_EQ_INT(w, 63);
        CHECK_EQ_INT(h, 47);
        CHECK_OK(nerf_dataset_camera(ds, 0, &cam));
        CHECK_NEAR(cam.fx, 407.57 / 8.0, 0.01);
    }
    nerf_dataset_destroy(ds);
}

int main(void)
{
    /* The user's folder first; meson's default is the one beside the
     * project, where the development machines keep it. */
    const char *root = getenv("NERF_DATA_DIR");
    if (root == NULL || root[0] == '\0') {
        root = getenv("NERF_DEFAULT_DATA_DIR");
    }
    if (root == NULL || root[0] == '\0') {
        printf("skipped: NERF_DATA_DIR is not set (it should name the "
               "folder holding lego/ and fern/)\n");
        return 77;
    }
    snprintf(lego, sizeof lego, "%s/lego", root);
    snprintf(fern, sizeof fern, "%s/fern", root);
    if (!have(lego, "transforms_val.json") ||
        !have(fern, "poses_bounds.npy")) {
        printf("skipped: the lego and fern scenes are not in %s\n", root);
        return 77;
    }
    RUN(lego_val);
    RUN(fern);
    HARNESS_EXIT();
}
