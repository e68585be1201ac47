/* The built-in scene: its analytic field, and the dataset it writes. */
#include <cJSON.h>
#include <math.h>
#include <stdbool.h>
#include <string.h>

#include "../harness.h"
#include "data_fixtures.h"
#include "dataset.h"
#include "env.h"
#include "field.h"
#include "file_io.h"
#include "nerf.h"
#include "png_io.h"

TEST(field_rays)
{
    float rgb[3], depth;
    /* Straight down outside the torus and clear of every solid. */
    const float above[3] = {1.2f, 1.2f, 4.0f}, down[3] = {0.0f, 0.0f, -1.0f};
    float a = nerf__scene_render_ray(above, down, 2.0f, 6.0f, rgb, &depth);
    CHECK(a < 1e-3f);
    /* Towards the red sphere's centre: opaque, red, at its surface. */
    const float o[3] = {0.45f, -4.0f, 0.1f}, d[3] = {0.0f, 1.0f, 0.0f};
    a = nerf__scene_render_ray(o, d, 2.0f, 6.0f, rgb, &depth);
    CHECK(a > 0.999f);
    CHECK(rgb[0] > 2.0f * rgb[1] && rgb[0] > 2.0f * rgb[2]);
    /* The surface is at y = -0.2 - 0.45 = -0.65, t = 3.35 from y = -4. */
    CHECK_NEAR(depth, 3.35, 0.03);
    /* A ray missing the bounding sphere. */
    const float far_o[3] = {5.0f, 5.0f, 5.0f}, away[3] = {1.0f, 0.0f, 0.0f};
    CHECK(nerf__scene_render_ray(far_o, away, 0.0f, 10.0f, rgb, &depth) == 0.0f);
    /* Density vanishes far from every surface, peaks inside. */
    const float inside[3] = {0.45f, -0.2f, 0.1f}, empty[3] = {1.2f, 1.2f, 1.2f};
    CHECK(nerf__scene_field(inside, NULL) > 50.0f);
    CHECK(nerf__scene_field(empty, NULL) == 0.0f);
}

static int count_frames(const char *dir, const char *split)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/transforms_%s.json", dir, split);
    nerf__env env;
    nerf__env_default(&env);
    unsigned char *text;
    size_t size;
    if (nerf__file_read(&env, path, 1 << 24, &text, &size) != NERF_OK) {
        return -1;
    }
    cJSON *root = cJSON_ParseWithLength((const char *)text, size);
    nerf__free(&env, text);
    int n = -1;
    cJSON *angle = cJSON_GetObjectItem(root, "camera_angle_x");
    cJSON *frames = cJSON_GetObjectItem(root, "frames");
    if (cJSON_IsNumber(angle) && cJSON_IsArray(frames)) {
        n = cJSON_GetArraySize(frames);
        cJSON *m = cJSON_GetObjectItem(cJSON_GetArrayItem(frames, 0),
                                       "transform_matrix");
        if (n > 0 && cJSON_GetArraySize(m) != 4) {
            n = -2;
        }
    }
    cJSON_Delete(root);
    return n;
}

TEST(writes_a_blender_dataset)
{
    char *dir = fx_make_temp_dir();
    char sub[1024];
    snprintf(sub, sizeof sub, "%s/scene", dir);
    nerf_scene_options o;
    CHECK_OK(NERF_SCENE_OPTIONS_INIT(&o));
    o.width = 24;
    o.height = 16;
    o.n_train = 3;
    o.n_val = 1;
    o.n_test = 2;
    o.threads = 2;
    CHECK_OK(nerf_scene_write(sub, &o));
    CHECK_EQ_INT(count_frames(sub, "train"), 3);
    CHECK_EQ_INT(count_frames(sub, "val"), 1);
    CHECK_EQ_INT(count_frames(sub, "test"), 2);

    nerf__env env;
    nerf__env_default(&env);
    char png[1200];
    snprintf(png, sizeof png, "%s/test/r_1.png", sub);
    uint32_t w = 0, h = 0;
    float *rgba = NULL;
    CHECK_OK(nerf__png_read_rgba(&env, png, &w, &h, &rgba));
    CHECK_EQ_INT(w, 24);
    CHECK_EQ_INT(h, 16);
    if (rgba) {
        /* The solids fill the middle of every view and miss the corner. */
        CHECK(rgba[4 * (8 * 24 + 12) + 3] > 0.9f);
        CHECK(rgba[3] < 0.01f);
        nerf__free(&env, rgba);
    }

    /* Same options, same bytes, whatever the thread count. */
    char again[1024];
    snprintf(again, sizeof again, "%s/again", dir);
    o.threads = 1;
    CHECK_OK(nerf_scene_write(again, &o));
    unsigned char *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    char pa[1200], pb[1200];
    snprintf(pa, sizeof pa, "%s/train/r_2.png", sub);
    snprintf(pb, sizeof pb, "%s/train/r_2.png", again);
    CHECK_OK(nerf__file_read(&env, pa, 1 << 24, &a, &na));
    CHECK_OK(nerf__file_read(&env, pb, 1 << 24, &b, &nb));
    CHECK(na == nb && a && b && memcmp(a, b, na) == 0);
    nerf__free(&env, a);
    nerf__free(&env, b);
    fx_remove_tree(dir);
}

/* The lens of the tests below: strong barrel, a little of the rest. */
static void set_lens(nerf_scene_options *o)
{
    o->k1 = -0.45f;
    o->k2 = 0.15f;
    o->p1 = 0.003f;
    o->p2 = -0.002f;
    o->k3 = 0.02f;
}

static bool has_lens(const nerf_camera *c, const nerf_scene_options *o)
{
    return c->k1 == o->k1 && c->k2 == o->k2 && c->p1 == o->p1 &&
           c->p2 == o->p2 && c->k3 == o->k3;
}

/*
 * PSNR of view i of ds against the ground truth rendered along the rays
 * of its camera (composited on white, as the loader composites the
 * images), with the camera's lens or without it.
 */
static double truth_psnr(const nerf_dataset *ds, uint32_t i, bool lens)
{
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    const float *img = NULL;
    if (nerf_dataset_camera(ds, i, &cam) != NERF_OK ||
        nerf_dataset_image(ds, i, &img) != NERF_OK) {
        return -1.0;
    }
    if (!lens) {
        cam.k1 = cam.k2 = cam.p1 = cam.p2 = cam.k3 = 0.0f;
    }
    size_t n = (size_t)cam.width * cam.height;
    double se = 0.0;
    for (size_t p = 0; p < n; p++) {
        float o[3], d[3], rgb[3], depth;
        nerf_camera_rays(&cam, p, 1, o, d);
        float a = nerf__scene_render_ray(o, d, 2.0f, 6.0f, rgb, &depth);
        for (int c = 0; c < 3; c++) {
            double e = rgb[c] + (1.0 - a) - img[3 * p + c];
            se += e * e;
        }
    }
    return 10.0 * log10(1.0 / (se / (3.0 * n)));
}

/*
 * The scene photographed through a known lens, as one instant-ngp
 * transforms.json: loaded back, its cameras carry the lens, and the
 * ground truth along their (undistorted) rays is what the images hold;
 * along pinhole rays it is not.
 */
TEST(writes_through_a_lens)
{
    char *dir = fx_make_temp_dir();
    char sub[1024];
    snprintf(sub, sizeof sub, "%s/lens", dir);
    nerf_scene_options o;
    CHECK_OK(NERF_SCENE_OPTIONS_INIT(&o));
    o.width = 48;
    o.height = 36;
    o.n_train = 12;
    o.n_val = 2;
    o.n_test = 2;
    o.threads = 2;
    o.layout = NERF_SCENE_LAYOUT_TRANSFORMS;
    set_lens(&o);
    CHECK_OK(nerf_scene_write(sub, &o));

    /* instant-ngp's fields at top level. */
    nerf__env env;
    nerf__env_default(&env);
    char path[1200];
    snprintf(path, sizeof path, "%s/transforms.json", sub);
    unsigned char *text = NULL;
    size_t size = 0;
    CHECK_OK(nerf__file_read(&env, path, 1 << 24, &text, &size));
    cJSON *root = text ? cJSON_ParseWithLength((const char *)text, size)
                       : NULL;
    nerf__free(&env, text);
    static const char *const keys[] = {"fl_x", "fl_y", "cx", "cy", "w", "h",
                                       "k1", "k2", "p1", "p2", "k3",
                                       "aabb_scale"};
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++) {
        if (!cJSON_IsNumber(cJSON_GetObjectItem(root, keys[k]))) {
            FAILF("transforms.json has no number '%s'", keys[k]);
        }
    }
    CHECK_EQ_INT(cJSON_GetArraySize(cJSON_GetObjectItem(root, "frames")), 16);
    cJSON_Delete(root);

    /* Split every 8th frame: 14 train, 2 test. */
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    nerf_dataset *train = NULL, *test = NULL;
    CHECK_OK(nerf_dataset_load(&train, sub, &dopt));
    dopt.split = NERF_SPLIT_TEST;
    CHECK_OK(nerf_dataset_load(&test, sub, &dopt));
    CHECK_EQ_INT(nerf_dataset_count(train), 14);
    CHECK_EQ_INT(nerf_dataset_count(test), 2);
    if (train == NULL || test == NULL) {
        nerf_dataset_destroy(train);
        nerf_dataset_destroy(test);
        fx_remove_tree(dir);
        return;
    }
    CHECK_NEAR(nerf__dataset_aabb_scale(train), 2.0, 0.0);
    double worst_lens = 1e9, best_pinhole = 0.0;
    for (uint32_t k = 0; k < 4; k++) {
        const nerf_dataset *ds = k < 2 ? train : test;
        uint32_t i = k % 2;
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(ds, i, &cam));
        CHECK(has_lens(&cam, &o));
        double with = truth_psnr(ds, i, true);
        double without = truth_psnr(ds, i, false);
        worst_lens = with < worst_lens ? with : worst_lens;
        best_pinhole = without > best_pinhole ? without : best_pinhole;
    }
    printf("  ground truth vs images: %.1f dB or more along the lens's rays, "
           "%.1f dB or less along pinhole rays\n", worst_lens, best_pinhole);
    /* 8-bit images: about 50 dB when the rays are right. */
    CHECK(worst_lens > 40.0);
    CHECK(best_pinhole < worst_lens - 15.0);
    nerf_dataset_destroy(train);
    nerf_dataset_destroy(test);

    /* The Blender layout records the lens too. */
    snprintf(sub, sizeof sub, "%s/blender", dir);
    o.layout = NERF_SCENE_LAYOUT_BLENDER;
    o.n_train = 1;
    o.n_val = 0;
    o.n_test = 0;
    CHECK_OK(nerf_scene_write(sub, &o));
    CHECK_OK(nerf_dataset_load(&train, sub, NULL));
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    if (train) {
        CHECK_OK(nerf_dataset_camera(train, 0, &cam));
        CHECK(has_lens(&cam, &o));
        CHECK(truth_psnr(train, 0, true) > 40.0);
    }
    nerf_dataset_destroy(train);
    fx_remove_tree(dir);
}

TEST(bad_options)
{
    nerf_scene_options o;
    NERF_SCENE_OPTIONS_INIT(&o);
    o.width = 2;
    CHECK_EQ_INT(nerf_scene_write("/tmp/unused", &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "image size") != NULL);
    NERF_SCENE_OPTIONS_INIT(&o);
    CHECK_EQ_INT(nerf_scene_write(NULL, &o), NERF_EINVAL);
    o.width = 16;
    o.height = 16;
    o.n_train = 1;
    o.n_val = 0;
    o.n_test = 0;
    /* A folder cannot be made below a regular file. */
    char *dir = fx_make_temp_dir();
    char file[600], below[700];
    snprintf(file, sizeof file, "%s/file", dir);
    snprintf(below, sizeof below, "%s/sub", file);
    FILE *f = fopen(file, "w");
    if (f) {
        fclose(f);
    }
    CHECK_EQ_INT(nerf_scene_write(below, &o), NERF_EIO);
    CHECK(strstr(nerf_last_error(), file) != NULL);
    /* Layouts this libnerf does not write, and lenses no camera has. */
    snprintf(below, sizeof below, "%s/never", dir);
    o.layout = 5;
    CHECK_EQ_INT(nerf_scene_write(below, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "layout 5 is not supported") != NULL);
    o.layout = NERF_SCENE_LAYOUT_TRANSFORMS;
    o.k2 = NAN;
    CHECK_EQ_INT(nerf_scene_write(below, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "distortion k2 is not finite") != NULL);
    o.k2 = 0.0f;
    o.p1 = 2e3f;
    CHECK_EQ_INT(nerf_scene_write(below, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "distortion p1 2000 is beyond") != NULL);
    fx_remove_tree(dir);
}

int main(void)
{
    RUN(field_rays);
    RUN(writes_a_blender_dataset);
    RUN(writes_through_a_lens);
    RUN(bad_options);
    HARNESS_EXIT();
}
