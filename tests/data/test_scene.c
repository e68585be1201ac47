/* The built-in scene: its analytic field, and the dataset it writes. */
#include <cJSON.h>
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "data_fixtures.h"
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
    fx_remove_tree(dir);
}

int main(void)
{
    RUN(field_rays);
    RUN(writes_a_blender_dataset);
    RUN(bad_options);
    HARNESS_EXIT();
}
