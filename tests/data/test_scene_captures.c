/*
 * The built-in scene's forward-facing and all-round captures: their far
 * surroundings, the integration that skips the empty space between, and
 * the files, read back by the loaders.
 */
#include <cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../harness.h"
#include "camera.h"
#include "data_fixtures.h"
#include "../fail_alloc.h"
#include "env.h"
#include "field.h"
#include "file_io.h"
#include "nerf.h"
#include "npy.h"
#include "png_io.h"
#include "scene_internal.h"

#define W 32
#define H 24

static void small_options(nerf_scene_options *o, uint32_t capture,
                          uint32_t layout)
{
    NERF_SCENE_OPTIONS_INIT(o);
    o->width = W;
    o->height = H;
    o->capture = capture;
    o->layout = layout;
    o->threads = 2;
}

static float norm3(const float v[3])
{
    return sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/*
 * The volume rendering integral by brute force: the midpoint rule with
 * one fixed step, finer than any edge of the field, over all of
 * [near, far], empty or not.
 */
static float brute_force(nerf__scene_world world, const float o[3],
                         const float d[3], float near, float far,
                         float rgb[3], float *depth)
{
    double n = norm3(d), dt = 0.002 / n;
    long steps = (long)ceil((far - near) / dt);
    dt = (far - near) / steps;
    double T = 1.0, acc[3] = {0, 0, 0}, dep = 0.0;
    for (long i = 0; i < steps && T > 1e-9; i++) {
        double t = near + (i + 0.5) * dt;
        float x[3] = {(float)(o[0] + t * d[0]), (float)(o[1] + t * d[1]),
                      (float)(o[2] + t * d[2])};
        float c[3];
        double sigma = nerf__scene_field_in(world, x, c);
        double alpha = 1.0 - exp(-sigma * dt * n);
        for (int k = 0; k < 3; k++) {
            acc[k] += T * alpha * c[k];
        }
        dep += T * alpha * t;
        T *= 1.0 - alpha;
    }
    for (int k = 0; k < 3; k++) {
        rgb[k] = (float)acc[k];
    }
    *depth = (float)dep;
    return (float)(1.0 - T);
}

static int compared;

static void compare_ray_in(nerf__scene_world world, const float o[3],
                           const float d[3])
{
    float want[3], got[3], want_depth, got_depth;
    float far = NERF__SCENE_WORLD_FAR;
    float wa = brute_force(world, o, d, 0.0f, far, want, &want_depth);
    float ga = nerf__scene_render_ray_in(world, o, d, 0.0f, far, got,
                                         &got_depth);
    bool ok = fabsf(ga - wa) < 1e-4f && wa > 0.9999f &&
              fabsf(got_depth - want_depth) < 2e-3f * want_depth;
    for (int k = 0; k < 3; k++) {
        ok = ok && fabsf(got[k] - want[k]) < 2e-3f;
    }
    if (!ok) {
        FAILF("world %d ray o (%g %g %g) d (%g %g %g): adaptive alpha %g "
              "rgb %g %g %g depth %g, brute force %g, %g %g %g, %g",
              (int)world, o[0], o[1], o[2],
              d[0], d[1], d[2], ga, got[0], got[1], got[2], got_depth, wa,
              want[0], want[1], want[2], want_depth);
    }
    compared++;
}

static void compare_ray(const float o[3], const float d[3])
{
    compare_ray_in(NERF__SCENE_SURROUNDED, o, d);
}

TEST(adaptive_integration_matches_brute_force)
{
    /* Rays of both captures' cameras, across their views: solids, near
     * and far ground, hills, sky. */
    nerf_scene_options o;
    small_options(&o, NERF_SCENE_CAPTURE_FORWARD, NERF_SCENE_LAYOUT_LLFF);
    nerf_camera cams[3];
    nerf__scene_forward_camera(&o, 0, 0, 9, &cams[0]);
    nerf__scene_unbounded_camera(&o, 0, 0, 6, &cams[1]);
    nerf__scene_unbounded_camera(&o, 0, 2, 6, &cams[2]);
    for (int c = 0; c < 3; c++) {
        for (uint32_t y = 1; y < H; y += 5) {
            for (uint32_t x = 2; x < W; x += 9) {
                float org[3], dir[3];
                nerf__camera_rays(&cams[c], (size_t)y * W + x, 1, org, dir);
                compare_ray(org, dir);
            }
        }
    }
    /* Rays only a few hit: grazing the ground far off, towards the sun,
     * along the ground's edge, straight up and down, unnormalised. */
    static const float rays[][6] = {
        {0.0f, -3.0f, 0.3f, 0.2f, 1.0f, -0.03f},
        {0.0f, 0.0f, 2.0f, 0.62f, 0.70f, 0.35f},
        {2.0f, 2.0f, -0.6f, -1.0f, 0.2f, 0.0f},
        {0.5f, 0.5f, 1.5f, 0.0f, 0.0f, 1.0f},
        {0.5f, 0.5f, 1.5f, 0.0f, 0.0f, -2.0f},
        {-2.5f, 1.0f, 0.4f, 3.0f, -1.0f, -0.1f},
    };
    for (size_t k = 0; k < sizeof rays / sizeof rays[0]; k++) {
        compare_ray(rays[k], rays[k] + 3);
    }
    /* A fan of rays down to the ground, meeting it ever more obliquely
     * (from 1 to 25 units away), where the checker has most contrast. */
    for (int k = 0; k < 12; k++) {
        const float org[3] = {0.3f, -2.0f, 0.25f};
        float fall = 1.0f / (1.0f + 2.0f * k * k / 6.0f);
        const float dir[3] = {0.3f * sinf((float)k), 1.0f, -fall};
        compare_ray(org, dir);
    }
    CHECK(compared == 3 * 5 * 4 + 6 + 12);
}

TEST(surroundings)
{
    float rgb[3];
    /* Deep in the ground and beyond the backdrop: dense; between: empty
     * but for the solids. */
    const float below[3] = {5.0f, -3.0f, -1.0f}, beyond[3] = {0, 45.0f, 3.0f};
    const float between[3] = {5.0f, -3.0f, 1.0f};
    CHECK(nerf__scene_field_in(NERF__SCENE_SURROUNDED, below, rgb) > 55.0f);
    CHECK(nerf__scene_field_in(NERF__SCENE_SURROUNDED, beyond, rgb) > 55.0f);
    CHECK(nerf__scene_field_in(NERF__SCENE_SURROUNDED, between, rgb) == 0.0f);
    /* The object capture's field has none of it. */
    CHECK(nerf__scene_field(below, NULL) == 0.0f);
    CHECK(nerf__scene_field_in(NERF__SCENE_SOLIDS, beyond, NULL) == 0.0f);
    /* The sky is bluer at the zenith than at the horizon; the ground is
     * not blue. */
    const float zenith[3] = {0, 0, 41.0f}, horizon[3] = {41.0f, 0, 0.5f};
    float z[3], h[3], g[3];
    nerf__scene_field_in(NERF__SCENE_SURROUNDED, zenith, z);
    nerf__scene_field_in(NERF__SCENE_SURROUNDED, horizon, h);
    nerf__scene_field_in(NERF__SCENE_SURROUNDED, below, g);
    CHECK(z[2] > z[0] + 0.3f && h[2] - h[0] < z[2] - z[0]);
    CHECK(g[2] < g[0]);
}

/* Read poses_bounds.npy into rows (n x 17); returns n, 0 on failure. */
static size_t read_rows(const char *dir, double **rows)
{
    char path[1024];
    fx_path(path, sizeof path, dir, "poses_bounds.npy");
    nerf__env env;
    nerf__env_default(&env);
    unsigned char *buf = NULL;
    size_t size = 0, n = 0;
    nerf__npy a;
    *rows = NULL;
    if (nerf__file_read(&env, path, 1 << 20, &buf, &size) == NERF_OK &&
        nerf__npy_parse(buf, size, &a) == NERF_OK &&
        a.dtype == NERF__NPY_F8 && !a.fortran_order && a.ndim == 2 &&
        a.shape[1] == 17 && (a.data - buf) % 64 == 0) {
        n = a.shape[0];
        *rows = malloc(a.count * sizeof **rows);
        nerf__npy_to_double(&a, *rows, a.count);
    }
    nerf__free(&env, buf);
    return n;
}

/* The largest difference, in [0, 1], between a view of the dataset and
 * the field rendered through the world camera. */
static float image_off(const nerf_dataset *ds, uint32_t view,
                       const nerf_camera *world)
{
    const float *img = NULL;
    if (nerf_dataset_image(ds, view, &img) != NERF_OK) {
        return 1.0f;
    }
    float worst = 0.0f;
    for (size_t p = 0; p < (size_t)W * H; p += 7) {
        float org[3], dir[3], rgb[3], depth;
        nerf__camera_rays(world, p, 1, org, dir);
        nerf__scene_render_ray_in(NERF__SCENE_SURROUNDED, org, dir, 0.0f,
                                  NERF__SCENE_WORLD_FAR, rgb, &depth);
        for (int k = 0; k < 3; k++) {
            float off = fabsf(img[3 * p + k] - rgb[k]);
            worst = off > worst ? off : worst;
        }
    }
    return worst;
}

TEST(forward_capture_in_llff_layout)
{
    char *dir = fx_make_temp_dir();
    nerf_scene_options o;
    small_options(&o, NERF_SCENE_CAPTURE_FORWARD, NERF_SCENE_LAYOUT_LLFF);
    /* 11 views, so that names sorting as text and as numbers differ. */
    o.n_train = 9;
    o.n_val = 5; /* not used by this layout */
    o.n_test = 2;
    CHECK_OK(nerf_scene_write(dir, &o));
    enum { N = 11 };
    double *rows = NULL;
    CHECK_EQ_INT(read_rows(dir, &rows), N);
    if (rows == NULL) {
        fx_remove_tree(dir);
        return;
    }
    /* Bounds from depths: the nearest ground or solid, the backdrop. */
    double least = 1e30;
    for (int i = 0; i < N; i++) {
        const double *r = rows + 17 * i;
        CHECK(r[15] > 0.5 && r[15] < 3.0 && r[16] > 35.0 && r[16] < 45.0);
        CHECK(r[4] == H && r[9] == W);
        least = r[15] < least ? r[15] : least;
    }
    nerf_dataset *ds = NULL, *test = NULL;
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    CHECK_OK(nerf_dataset_load(&ds, dir, &dopt));
    dopt.split = NERF_SPLIT_TEST;
    CHECK_OK(nerf_dataset_load(&test, dir, &dopt));
    CHECK_EQ_INT(nerf_dataset_get_format(ds), NERF_DATASET_LLFF);
    CHECK_EQ_INT(nerf_dataset_is_ndc(ds), 1);
    CHECK_EQ_INT(nerf_dataset_count(ds), 9);  /* all but 0 and 8 */
    CHECK_EQ_INT(nerf_dataset_count(test), 2);
    uint32_t w = 0, h = 0;
    CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
    CHECK(w == W && h == H);

    /*
     * The loader scales positions by s = 1 / (0.75 least bound) and
     * recentres on the average pose (rotation A, centre the mean position
     * m): loaded = A^T (s p - s m).  Undo that with the writer's cameras.
     */
    nerf_camera wc[N];
    double m[3] = {0, 0, 0}, z[3] = {0, 0, 0}, up[3] = {0, 0, 0};
    for (int i = 0; i < N; i++) {
        nerf__scene_forward_camera(&o, 0, (uint32_t)i, N, &wc[i]);
        for (int r = 0; r < 3; r++) {
            m[r] += wc[i].c2w[4 * r + 3] / N;
            up[r] += wc[i].c2w[4 * r + 1];
            z[r] += wc[i].c2w[4 * r + 2];
        }
    }
    double A[3][3]; /* columns x, y, z */
    double zn = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
    for (int r = 0; r < 3; r++) {
        A[r][2] = z[r] / zn;
    }
    double x[3] = {up[1] * A[2][2] - up[2] * A[1][2],
                   up[2] * A[0][2] - up[0] * A[2][2],
                   up[0] * A[1][2] - up[1] * A[0][2]};
    double xn = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (int r = 0; r < 3; r++) {
        A[r][0] = x[r] / xn;
    }
    for (int r = 0; r < 3; r++) {
        int a = (r + 1) % 3, b = (r + 2) % 3;
        A[r][1] = A[a][2] * A[b][0] - A[b][2] * A[a][0];
    }
    double s = 1.0 / (0.75 * least);
    for (uint32_t j = 0; j < 9; j++) {
        uint32_t i = j + 1 + (j >= 7); /* 0 and 8 are held out */
        nerf_camera lc;
        NERF_CAMERA_INIT(&lc);
        CHECK_OK(nerf_dataset_camera(ds, j, &lc));
        CHECK_NEAR(lc.fx, wc[i].fx, 1e-3 * wc[i].fx);
        CHECK_NEAR(lc.fy, wc[i].fx, 1e-3 * wc[i].fx);
        CHECK_NEAR(lc.cx, 0.5 * W, 1e-6);
        CHECK_NEAR(lc.cy, 0.5 * H, 1e-6);
        nerf_camera back = lc; /* the loaded camera in world units */
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 4; c++) {
                double v = 0.0;
                for (int k = 0; k < 3; k++) {
                    v += A[r][k] * lc.c2w[4 * k + c];
                }
                v = c == 3 ? v / s + m[r] : v;
                back.c2w[4 * r + c] = (float)v;
                CHECK_NEAR(v, wc[i].c2w[4 * r + c], 1e-4);
            }
        }
        /* Each image is the view of its pose. */
        CHECK(image_off(ds, j, &back) < 1.5f / 255.0f);
    }
    nerf_camera spiral;
    NERF_CAMERA_INIT(&spiral);
    CHECK_OK(nerf_dataset_spiral_camera(ds, 3, 120, &spiral));
    nerf_dataset_destroy(ds);
    nerf_dataset_destroy(test);
    free(rows);
    fx_remove_tree(dir);
}

/* The JSON file name in dir, parsed; NULL (and a failed check) if it
 * cannot be read. */
static cJSON *read_json(const char *dir, const char *name)
{
    char path[1024];
    fx_path(path, sizeof path, dir, name);
    nerf__env env;
    nerf__env_default(&env);
    unsigned char *text = NULL;
    size_t size = 0;
    CHECK_OK(nerf__file_read(&env, path, 1 << 20, &text, &size));
    cJSON *root = text ? cJSON_ParseWithLength((const char *)text, size) : NULL;
    nerf__free(&env, text);
    return root;
}

TEST(unbounded_capture_in_blender_layout)
{
    char *dir = fx_make_temp_dir();
    nerf_scene_options o;
    small_options(&o, NERF_SCENE_CAPTURE_UNBOUNDED, NERF_SCENE_LAYOUT_BLENDER);
    o.n_train = 6;
    o.n_val = 1;
    o.n_test = 2;
    CHECK_OK(nerf_scene_write(dir, &o));

    /* instant-ngp's hint of a far background, beside Blender's fields. */
    cJSON *root = read_json(dir, "transforms_train.json");
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "aabb_scale")) == 16);
    CHECK_NEAR(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "camera_angle_x")),
               1.0, 1e-12);
    cJSON_Delete(root);

    /* Photographs: no transparent pixel in any file. */
    static const char *const files[] = {"train/r_0.png", "val/r_0.png",
                                        "test/r_1.png"};
    char path[1024];
    nerf__env env;
    nerf__env_default(&env);
    for (int f = 0; f < 3; f++) {
        fx_path(path, sizeof path, dir, files[f]);
        uint32_t w = 0, h = 0;
        float *rgba = NULL;
        CHECK_OK(nerf__png_read_rgba(&env, path, &w, &h, &rgba));
        CHECK(w == W && h == H);
        float least = 1.0f;
        for (size_t p = 0; rgba && p < (size_t)w * h; p++) {
            least = rgba[4 * p + 3] < least ? rgba[4 * p + 3] : least;
        }
        CHECK(rgba != NULL && least == 1.0f);
        nerf__free(&env, rgba);
    }

    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    CHECK_EQ_INT(nerf_dataset_get_format(ds), NERF_DATASET_BLENDER);
    CHECK_EQ_INT(nerf_dataset_is_ndc(ds), 0);
    CHECK_EQ_INT(nerf_dataset_count(ds), 6);
    int views_far = 0;
    size_t near_px = 0, far_px = 0, all_px = 0;
    for (uint32_t j = 0; j < nerf_dataset_count(ds); j++) {
        nerf_camera lc, wc;
        NERF_CAMERA_INIT(&lc);
        CHECK_OK(nerf_dataset_camera(ds, j, &lc));
        nerf__scene_unbounded_camera(&o, 0, j, 6, &wc);
        for (int k = 0; k < 12; k++) {
            CHECK_NEAR(lc.c2w[k], wc.c2w[k], 1e-6);
        }
        CHECK_NEAR(lc.fx, wc.fx, 1e-3);
        /* Cameras 2.2 to 3 units from the centre. */
        float centre[3] = {lc.c2w[3], lc.c2w[7], lc.c2w[11]};
        CHECK(norm3(centre) > 2.1f && norm3(centre) < 3.1f);
        CHECK(image_off(ds, j, &lc) < 1.5f / 255.0f);
        /* Every ray ends opaque; some end on the solids or the ground
         * near by, some on the backdrop far off. */
        size_t far_here = 0;
        float least = 1.0f;
        for (size_t p = 0; p < (size_t)W * H; p++) {
            float org[3], ray[3], rgb[3], depth;
            nerf__camera_rays(&lc, p, 1, org, ray);
            float a = nerf__scene_render_ray_in(NERF__SCENE_SURROUNDED, org,
                                                ray, 0.0f,
                                                NERF__SCENE_WORLD_FAR, rgb,
                                                &depth);
            least = a < least ? a : least;
            float dist = depth / a * norm3(ray);
            near_px += dist < 5.0f;
            far_here += dist > 30.0f;
            all_px++;
        }
        CHECK(least > 1.0f - 1e-5f);
        far_px += far_here;
        views_far += far_here > 0;
    }
    CHECK(views_far >= 5);
    CHECK(near_px > all_px / 3 && far_px > all_px / 20);
    nerf_dataset_destroy(ds);
    fx_remove_tree(dir);
}

TEST(npy_writer)
{
    char *dir = fx_make_temp_dir();
    char path[1024];
    fx_path(path, sizeof path, dir, "a.npy");
    nerf__env env;
    nerf__env_default(&env);
    const double v[6] = {1.5, -2.0, 0.1, 1e300, -0.0, 42.0};
    CHECK_OK(nerf__npy_write_f8(&env, path, v, 2, 3));
    unsigned char *buf = NULL;
    size_t size = 0;
    CHECK_OK(nerf__file_read(&env, path, 1 << 20, &buf, &size));
    nerf__npy a;
    CHECK_OK(buf ? nerf__npy_parse(buf, size, &a) : NERF_EIO);
    if (buf) {
        CHECK(a.dtype == NERF__NPY_F8 && a.ndim == 2 && a.shape[0] == 2 &&
              a.shape[1] == 3 && !a.fortran_order);
        /* NumPy starts the data on a multiple of 64 bytes. */
        CHECK((a.data - buf) % 64 == 0);
        double back[6];
        nerf__npy_to_double(&a, back, 6);
        CHECK(memcmp(back, v, sizeof v) == 0);
    }
    nerf__free(&env, buf);
    fx_remove_tree(dir);
}

/*
 * Every allocation of each capture's writer failing in turn: NERF_ENOMEM
 * with a message and nothing left allocated, until the write succeeds.
 */
TEST(out_of_memory)
{
    static const uint32_t kinds[][2] = {
        {NERF_SCENE_CAPTURE_FORWARD, NERF_SCENE_LAYOUT_LLFF},
        {NERF_SCENE_CAPTURE_UNBOUNDED, NERF_SCENE_LAYOUT_BLENDER},
        {NERF_SCENE_CAPTURE_FORWARD, NERF_SCENE_LAYOUT_BLENDER},
    };
    char *dir = fx_make_temp_dir();
    for (int c = 0; c < 3; c++) {
        nerf_scene_options o;
        small_options(&o, kinds[c][0], kinds[c][1]);
        o.width = 16;
        o.height = 12;
        o.n_train = 2;
        o.n_val = 1;
        o.n_test = 1;
        fail_alloc f;
        nerf_hooks hooks;
        fail_alloc_hooks(&hooks, &f);
        o.hooks = &hooks;
        bool done = false;
        for (int k = 1; k <= 200 && !done; k++) {
            f = (fail_alloc){0, k, 0};
            nerf_clear_error();
            int rc = nerf_scene_write(dir, &o);
            if (rc == NERF_OK) {
                CHECK(f.calls < k);
                done = true;
            } else if (rc != NERF_ENOMEM || nerf_last_error()[0] == '\0') {
                FAILF("capture %u layout %u, failing allocation %d: status "
                      "%d (%s)", kinds[c][0], kinds[c][1], k, rc,
                      nerf_last_error());
                break;
            }
            CHECK_EQ_INT(f.live, 0);
        }
        CHECK(done);
    }
    fx_remove_tree(dir);
}

/* Mean absolute difference of neighbouring pixels of an RGB view: how
 * much detail a feature detector has to find. */
static double detail(const uint8_t *px, uint32_t w, uint32_t h)
{
    double sum = 0.0;
    for (uint32_t y = 0; y < h; y++) {
        for (uint32_t x = 0; x + 1 < w; x++) {
            for (int c = 0; c < 3; c++) {
                size_t a = 3 * ((size_t)y * w + x) + (size_t)c;
                sum += abs((int)px[a] - (int)px[a + 3]);
            }
        }
    }
    return sum / ((double)h * (w - 1) * 3);
}

/*
 * The texture: off, the field and the views are the plain scene's (the
 * option's default changes nothing); on, the solids and the ground carry
 * blotches that leave far more detail between neighbouring pixels, and
 * the integration that skips empty space still agrees with brute force.
 */
TEST(texture)
{
    const nerf__scene_world plain = NERF__SCENE_SURROUNDED;
    const nerf__scene_world textured =
        (nerf__scene_world)(NERF__SCENE_SURROUNDED | NERF__SCENE_TEXTURED);
    nerf_scene_options o;
    small_options(&o, NERF_SCENE_CAPTURE_WALK, NERF_SCENE_LAYOUT_BLENDER);
    CHECK_EQ_INT(o.texture, 0);
    nerf__scene_look look = nerf__scene_look_of(&o);
    CHECK_EQ_INT(look.world, plain);
    o.texture = 1;
    look = nerf__scene_look_of(&o);
    CHECK_EQ_INT(look.world, textured);
    o.capture = NERF_SCENE_CAPTURE_OBJECT;
    CHECK_EQ_INT(nerf__scene_look_of(&o).world, NERF__SCENE_TEXTURED);

    /* On the sphere, the box and the ground, colours differ between the
     * worlds only with the texture; densities never. */
    const float pts[][3] = {{0.45f, -0.2f, 0.55f}, {-0.5f, 0.35f, 0.35f},
                            {1.3f, -1.1f, -0.76f}};
    int differ = 0;
    for (int k = 0; k < 3; k++) {
        float a[3], b[3];
        float sa = nerf__scene_field_in(plain, pts[k], a);
        float sb = nerf__scene_field_in(textured, pts[k], b);
        CHECK(sa > 1.0f && sa == sb);
        differ += fabsf(a[0] - b[0]) + fabsf(a[1] - b[1]) +
                      fabsf(a[2] - b[2]) > 1e-3f;
    }
    CHECK(differ >= 2);

    /* A view of the walk, 64 x 48, plain and textured. */
    enum { VW = 64, VH = 48 };
    nerf_scene_options v;
    small_options(&v, NERF_SCENE_CAPTURE_WALK, NERF_SCENE_LAYOUT_BLENDER);
    v.width = VW;
    v.height = VH;
    nerf_camera cam;
    nerf__scene_walk_camera(&v, 0, 3, 20, &cam);
    static uint8_t px[2][VW * VH * 3];
    for (int t = 0; t < 2; t++) {
        v.texture = (uint32_t)t;
        nerf__scene_look lk = nerf__scene_look_of(&v);
        nerf__scene_render_view(&cam, &lk, 2, px[t], NULL);
    }
    double d0 = detail(px[0], VW, VH), d1 = detail(px[1], VW, VH);
    printf("  neighbouring pixels differ by %.2f levels plain, %.2f "
           "textured\n", d0, d1);
    CHECK(d1 > 2.0 * d0);

    /* Rays of the textured walk into the solids and down to the ground,
     * near and far, against brute force. */
    compared = 0;
    v.width = W;
    v.height = H;
    for (uint32_t view = 0; view < 20; view += 7) {
        nerf__scene_walk_camera(&v, 0, view, 20, &cam);
        for (uint32_t y = 3; y < H; y += 6) {
            for (uint32_t x = 1; x < W; x += 10) {
                float org[3], dir[3];
                nerf__camera_rays(&cam, (size_t)y * W + x, 1, org, dir);
                compare_ray_in(textured, org, dir);
            }
        }
    }
    for (int k = 0; k < 8; k++) {
        const float org[3] = {-0.4f, -2.5f, 0.3f};
        float fall = 1.0f / (1.0f + 1.5f * k * k / 6.0f);
        const float dir[3] = {0.2f * cosf((float)k), 1.0f, -fall};
        compare_ray_in(textured, org, dir);
    }
    CHECK(compared == 3 * 4 * 4 + 8);

    /* Neither 2 nor any other value than 0 and 1 is taken. */
    char *dir = fx_make_temp_dir();
    v.texture = 2;
    v.n_train = 1;
    v.n_val = 0;
    v.n_test = 0;
    nerf_clear_error();
    CHECK_EQ_INT(nerf_scene_write(dir, &v), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "texture 2") != NULL);
    fx_remove_tree(dir);
}

/*
 * The walk: train views in order along one path round the solids, each a
 * short step from the one before (the last from the first too: one whole
 * turn), so that a video of them overlaps from frame to frame; test views
 * between them; written in the Blender layout, read back with the
 * far-background hint.
 */
TEST(walk_capture)
{
    enum { N = 24 };
    nerf_scene_options o;
    small_options(&o, NERF_SCENE_CAPTURE_WALK, NERF_SCENE_LAYOUT_BLENDER);
    double longest = 0.0, turned = 0.0;
    for (uint32_t i = 0; i < N; i++) {
        nerf_camera a, b;
        nerf__scene_walk_camera(&o, 0, i, N, &a);
        nerf__scene_walk_camera(&o, 0, (i + 1) % N, N, &b);
        float ca[3] = {a.c2w[3], a.c2w[7], a.c2w[11]};
        float step[3] = {b.c2w[3] - ca[0], b.c2w[7] - ca[1],
                         b.c2w[11] - ca[2]};
        CHECK(norm3(ca) > 2.2f && norm3(ca) < 3.0f);
        double s = norm3(step);
        longest = s > longest ? s : longest;
        /* Azimuth always increasing: one way round. */
        double da = atan2(b.c2w[7], b.c2w[3]) - atan2(ca[1], ca[0]);
        da = da < -M_PI ? da + 2.0 * M_PI : da;
        CHECK(da > 0.0 && da < 2.0 * M_PI / N * 1.01);
        turned += da;
        /* Looking at the solids: the optical axis (-z column) passes
         * within a unit of the origin. */
        float fwd[3] = {-a.c2w[2], -a.c2w[6], -a.c2w[10]};
        float along = -(ca[0] * fwd[0] + ca[1] * fwd[1] + ca[2] * fwd[2]);
        float miss[3] = {ca[0] + along * fwd[0], ca[1] + along * fwd[1],
                         ca[2] + along * fwd[2]};
        CHECK(norm3(miss) < 0.2f);
    }
    CHECK_NEAR(turned, 2.0 * M_PI, 1e-6);
    /* 24 views: a turn of some 16 units in steps under a unit. */
    CHECK(longest < 0.9);

    char *dir = fx_make_temp_dir();
    o.n_train = 6;
    o.n_val = 1;
    o.n_test = 2;
    o.texture = 1;
    CHECK_OK(nerf_scene_write(dir, &o));
    cJSON *root = read_json(dir, "transforms_train.json");
    CHECK(cJSON_GetNumberValue(cJSON_GetObjectItem(root, "aabb_scale")) == 16);
    cJSON_Delete(root);
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    CHECK_EQ_INT(nerf_dataset_count(ds), 6);
    for (uint32_t j = 0; ds && j < 6; j++) {
        nerf_camera lc, wc;
        NERF_CAMERA_INIT(&lc);
        CHECK_OK(nerf_dataset_camera(ds, j, &lc));
        nerf__scene_walk_camera(&o, 0, j, 6, &wc);
        for (int k = 0; k < 12; k++) {
            CHECK_NEAR(lc.c2w[k], wc.c2w[k], 1e-6);
        }
    }
    nerf_dataset_destroy(ds);
    fx_remove_tree(dir);
}

int main(void)
{
    RUN(surroundings);
    RUN(adaptive_integration_matches_brute_force);
    RUN(npy_writer);
    RUN(forward_capture_in_llff_layout);
    RUN(unbounded_capture_in_blender_layout);
    RUN(out_of_memory);
    RUN(texture);
    RUN(walk_capture);
    HARNESS_EXIT();
}
