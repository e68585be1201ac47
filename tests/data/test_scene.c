/* The built-in scene: its analytic field, and the dataset it writes. */
#include <cJSON.h>
#include <math.h>
#include <stdlib.h>
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

/*
 * The object capture as the writer made it before the other captures
 * existed (12x8, 2 train, 1 val, 1 test views), decoded to RGBA bytes: it
 * must not change.  Compared within one level, so that a libm rounding
 * differently elsewhere does not fail it.
 */
static const char pinned_train_1[] =
    "00000000000000000000000000000000c62f2326c72f23f1c62e230500000000"
    "00000000000000000000000000000000000000000000000000000000b92b211f"
    "c62f23ffc82f23ffc42e23ff000000002b4cc3ff2c4dc6ff2a4abf0200000000"
    "000000000000000000000000a9281edebc2c21ffbe2d22ffb92c21ff7c2e470e"
    "2846b5ff2947b8ff2643ad0800000000000000000000000000000000c19f2850"
    "a4271dffa8281eff4e7932ffc2a329ff9888455f223b97190000000000000000"
    "0000000000000000c0a2280fc0a229ff33993a1e2f983aff2f983aff2f983afd"
    "bfa229ffc0a2280f00000000000000000000000000000000bfa128feb79a26e2"
    "2d9439ff2f983aff2f983aff2f983aff3a9437fcbfa128fe0000000000000000"
    "0000000000000000b89b27d2c3a429ff25772efb2d9238ff2f983aff2c8e37ff"
    "94972affb89b27d20000000000000000000000000000000000000000bfa128ff"
    "c1a429ff24762dff2a8935ff226e2affbea128ff000000000000000000000000";
static const char pinned_test_0[] =
    "0000000000000000000000002d4ec99600000000000000000000000000000000"
    "0000000000000000000000000000000000000000000000002847b6fd2a49bbff"
    "2846b5ff000000002f993bfe2f993bfe2f993be5000000000000000000000000"
    "0000000000000000223c9b15253e9fffc63026f1c92f23f7309439ff2e9539ff"
    "2e9539ff000000000000000000000000000000000000000000000000c22e22ff"
    "c62f23ffc62f23ffc22e22ff288332ff288332ff000000000000000000000000"
    "0000000000000000ac281e0ab82b21ffbc2c21ffbc2c21ffb82b20ff316328ff"
    "226c29ff0000000000000000000000000000000000000000c2a329fea6271dff"
    "ac281effab281effa5271dff7e2e1c06b89b27ffc2a329fe0000000000000000"
    "0000000000000000c0a128ffb28024fc91221aff91221aff8620187100000000"
    "c1a329fbc0a128ff00000000000000000000000000000000ae932522bfa128ff"
    "c4a529ffc4a529fdc4a529fdc4a529ffbfa128ffae9325220000000000000000";

static int hex_nibble(char c)
{
    return c <= '9' ? c - '0' : c - 'a' + 10;
}

/* Largest difference, in 8-bit levels, between a PNG and a pinned image. */
static int png_off_pin(const char *path, const char *pin)
{
    nerf__env env;
    nerf__env_default(&env);
    uint32_t w = 0, h = 0;
    float *rgba = NULL;
    if (nerf__png_read_rgba(&env, path, &w, &h, &rgba) != NERF_OK ||
        w != 12 || h != 8 || strlen(pin) != 2 * 4 * 12 * 8) {
        nerf__free(&env, rgba);
        return 1000;
    }
    int worst = 0;
    for (size_t k = 0; k < 4 * 12 * 8; k++) {
        int want = 16 * hex_nibble(pin[2 * k]) + hex_nibble(pin[2 * k + 1]);
        int got = (int)lrintf(rgba[k] * 255.0f);
        int off = abs(got - want);
        worst = off > worst ? off : worst;
    }
    nerf__free(&env, rgba);
    return worst;
}

TEST(object_capture_unchanged)
{
    char *dir = fx_make_temp_dir();
    nerf_scene_options o;
    CHECK_OK(NERF_SCENE_OPTIONS_INIT(&o));
    CHECK_EQ_INT(o.capture, NERF_SCENE_CAPTURE_OBJECT);
    CHECK_EQ_INT(o.layout, NERF_SCENE_LAYOUT_BLENDER);
    o.width = 12;
    o.height = 8;
    o.n_train = 2;
    o.n_val = 1;
    o.n_test = 1;
    o.threads = 1;
    CHECK_OK(nerf_scene_write(dir, &o));
    char path[1024];
    snprintf(path, sizeof path, "%s/train/r_1.png", dir);
    CHECK(png_off_pin(path, pinned_train_1) <= 1);
    snprintf(path, sizeof path, "%s/test/r_0.png", dir);
    CHECK(png_off_pin(path, pinned_test_0) <= 1);
    /* The first train camera, as the writer put it. */
    static const double want[12] = {0, -0.3125, 0.949917733669281,
                                    3.799670934677124, 1, 0, 0, 0,
                                    0, 0.949917733669281, 0.3125, 1.25};
    nerf__env env;
    nerf__env_default(&env);
    unsigned char *text = NULL;
    size_t size = 0;
    snprintf(path, sizeof path, "%s/transforms_train.json", dir);
    CHECK_OK(nerf__file_read(&env, path, 1 << 20, &text, &size));
    cJSON *root = text ? cJSON_ParseWithLength((const char *)text, size) : NULL;
    nerf__free(&env, text);
    CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "camera_angle_x")),
               0.69111120700836182, 1e-12);
    CHECK(cJSON_GetObjectItem(root, "aabb_scale") == NULL);
    cJSON *m = cJSON_GetObjectItem(
        cJSON_GetArrayItem(cJSON_GetObjectItem(root, "frames"), 0),
        "transform_matrix");
    for (int k = 0; k < 12; k++) {
        cJSON *v = cJSON_GetArrayItem(cJSON_GetArrayItem(m, k / 4), k % 4);
        CHECK_NEAR(cJSON_GetNumberValue(v), want[k], 1e-6);
    }
    cJSON_Delete(root);
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
    /* Captures and layouts: unknown, not yet written, not fitting. */
    char out[600];
    snprintf(out, sizeof out, "%s/out", dir);
    o.capture = 4;
    CHECK_EQ_INT(nerf_scene_write(out, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "capture 4 is unknown") != NULL);
    o.capture = NERF_SCENE_CAPTURE_FORWARD;
    o.layout = 5;
    CHECK_EQ_INT(nerf_scene_write(out, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "layout 5 is unknown") != NULL);
    o.layout = NERF_SCENE_LAYOUT_LLFF;
    o.capture = NERF_SCENE_CAPTURE_UNBOUNDED;
    CHECK_EQ_INT(nerf_scene_write(out, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "forward-facing captures only") != NULL);
    o.capture = NERF_SCENE_CAPTURE_OBJECT;
    CHECK_EQ_INT(nerf_scene_write(out, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "not the object capture") != NULL);
    o.capture = NERF_SCENE_CAPTURE_WALK;
    CHECK_EQ_INT(nerf_scene_write(out, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "not the walk capture") != NULL);
    /* Lenses a layout cannot record. */
    o.capture = NERF_SCENE_CAPTURE_FORWARD;
    o.k1 = 0.1f;
    CHECK_EQ_INT(nerf_scene_write(out, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "no lens fields") != NULL);
    o.k1 = 0.0f;
    o.k3 = 0.01f;
    o.layout = NERF_SCENE_LAYOUT_COLMAP_TEXT;
    CHECK_EQ_INT(nerf_scene_write(out, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "no k3") != NULL);
    o.k3 = 0.0f;
    o.capture = NERF_SCENE_CAPTURE_OBJECT;
    /* Refused before anything is written. */
    CHECK(fx_file_size(out) < 0);
    /* Layouts this libnerf does not write, and lenses no camera has. */
    snprintf(below, sizeof below, "%s/never", dir);
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
    RUN(object_capture_unchanged);
    RUN(writes_through_a_lens);
    RUN(bad_options);
    HARNESS_EXIT();
}
