/* The Blender / instant-ngp loader on tiny scenes written by the test. */
#include <nerf.h>

#include <stddef.h>
#include <sys/stat.h>
#include <unistd.h>

#include "data_fixtures.h"
#include "dataset.h"
#include "../harness.h"

enum { W = 8, H = 6, FRAMES = 4 };
#define ANGLE 0.6911112070083618

static char *tmp;
static int scene_id;

/* Image f's straight RGBA at (x, y): exact multiples of 1/255. */
static void pixel(int f, int x, int y, float out[4])
{
    out[0] = (float)(x * 30 + f * 5) / 255.0f;
    out[1] = (float)(y * 40) / 255.0f;
    out[2] = (float)((x + y) * 10) / 255.0f;
    out[3] = (float)(((x + 2 * y + f) % 4) * 85) / 255.0f;
}

static float composite(int f, int x, int y, int c, float bg)
{
    float p[4];
    pixel(f, x, y, p);
    return (float)((double)p[c] * p[3] + bg * (1.0 - p[3]));
}

/* Frame f's camera-to-world: a turn about z and a shift. */
static void pose(int f, double m[12])
{
    double a = 0.3 * f, c = cos(a), s = sin(a);
    double rows[12] = {c, -s, 0, f, s, c, 0, 2, 0, 0, 1, 3 + f};
    memcpy(m, rows, sizeof rows);
}

static void frame_json(char *buf, size_t size, int f, const char *path)
{
    double m[12];
    pose(f, m);
    snprintf(buf, size,
             "{\"file_path\": \"%s\", \"rotation\": 0.1, "
             "\"transform_matrix\": [[%.17g, %.17g, %.17g, %.17g], "
             "[%.17g, %.17g, %.17g, %.17g], [%.17g, %.17g, %.17g, %.17g], "
             "[0, 0, 0, 1]]}",
             path, m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8],
             m[9], m[10], m[11]);
}

/* The transforms text: top-level fields, then the frames list. */
static void scene_json(char *buf, size_t size, const char *top, int ngp)
{
    int n = snprintf(buf, size, "{%s, \"frames\": [", top);
    for (int f = 0; f < FRAMES; f++) {
        char path[64], fr[1024];
        snprintf(path, sizeof path, ngp ? "train/r_%d.png" : "./train/r_%d",
                 f);
        frame_json(fr, sizeof fr, f, path);
        n += snprintf(buf + n, size - (size_t)n, "%s%s", f ? ", " : "", fr);
    }
    snprintf(buf + n, size - (size_t)n, "]}\n");
}

/* A new scene folder with the standard images; returns its path. */
static const char *make_scene(char *dir, size_t size)
{
    snprintf(dir, size, "%s/scene%d", tmp, scene_id++);
    mkdir(dir, 0777);
    fx_mkdir(dir, "train");
    float rgba[W * H * 4];
    for (int f = 0; f < FRAMES; f++) {
        for (int y = 0; y < H; y++) {
            for (int x = 0; x < W; x++) {
                pixel(f, x, y, rgba + 4 * (y * W + x));
            }
        }
        char p[1024];
        char name[32];
        snprintf(name, sizeof name, "train/r_%d.png", f);
        fx_path(p, sizeof p, dir, name);
        fx_write_rgba8(p, W, H, rgba);
    }
    return dir;
}

static const char *blender_scene(char *dir, size_t size)
{
    make_scene(dir, size);
    char json[16384];
    scene_json(json, sizeof json, "\"camera_angle_x\": 0.6911112070083618", 0);
    fx_write_text(dir, "transforms_train.json", json);
    return dir;
}

/* Replace the first occurrence of from by to in the scene's json. */
static void edit_json(const char *dir, const char *name, const char *from,
                      const char *to)
{
    char p[1024], text[16384], out[16384];
    fx_path(p, sizeof p, dir, name);
    FILE *f = fopen(p, "rb");
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    char *at = strstr(text, from);
    if (at == NULL) {
        FAILF("fixture: '%s' not in %s", from, name);
        return;
    }
    snprintf(out, sizeof out, "%.*s%s%s", (int)(at - text), text, to,
             at + strlen(from));
    fx_write_text(dir, name, out);
}

static char log_text[4096];

static void capture_log(int level, const char *msg, void *user)
{
    (void)level;
    (void)user;
    size_t n = strlen(log_text);
    snprintf(log_text + n, sizeof log_text - n, "%s\n", msg);
}

static void check_images(const nerf_dataset *ds, const int *frames, int n,
                         float bg)
{
    int bad = 0;
    for (int i = 0; i < n; i++) {
        const float *rgb = NULL;
        CHECK_OK(nerf_dataset_image(ds, (uint32_t)i, &rgb));
        for (int y = 0; y < H && rgb; y++) {
            for (int x = 0; x < W; x++) {
                for (int c = 0; c < 3; c++) {
                    float want = composite(frames[i], x, y, c, bg);
                    bad += fabsf(rgb[(y * W + x) * 3 + c] - want) > 1e-6f;
                }
            }
        }
    }
    CHECK_EQ_INT(bad, 0);
}

static void check_camera(const nerf_dataset *ds, uint32_t i, int frame,
                         double fx, double cx, double cy)
{
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_dataset_camera(ds, i, &cam));
    double m[12];
    pose(frame, m);
    for (int k = 0; k < 12; k++) {
        CHECK_NEAR(cam.c2w[k], m[k], 1e-6);
    }
    CHECK_NEAR(cam.fx, fx, 1e-4);
    CHECK_NEAR(cam.fy, fx, 1e-4);
    CHECK_NEAR(cam.cx, cx, 1e-6);
    CHECK_NEAR(cam.cy, cy, 1e-6);
    CHECK_EQ_INT(cam.flags, 0);
}

TEST(basic_load)
{
    char dir[1024];
    blender_scene(dir, sizeof dir);
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = capture_log;
    log_text[0] = '\0';
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.hooks = &hooks;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    if (ds == NULL) {
        return;
    }
    CHECK_EQ_INT(nerf_dataset_count(ds), FRAMES);
    CHECK_EQ_INT(nerf_dataset_get_format(ds), NERF_DATASET_BLENDER);
    CHECK_EQ_INT(nerf_dataset_is_ndc(ds), 0);
    uint32_t w, h;
    CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
    CHECK_EQ_INT(w, W);
    CHECK_EQ_INT(h, H);
    float near, far;
    CHECK_OK(nerf_dataset_bounds(ds, &near, &far));
    CHECK_NEAR(near, 2.0, 0.0);
    CHECK_NEAR(far, 6.0, 0.0);
    int frames[FRAMES] = {0, 1, 2, 3};
    check_images(ds, frames, FRAMES, 1.0f);
    double fx = 0.5 * W / tan(0.5 * ANGLE);
    for (int i = 0; i < FRAMES; i++) {
        check_camera(ds, (uint32_t)i, i, fx, W / 2.0, H / 2.0);
    }
    CHECK(fx_has(log_text, "Blender scene, 4 images of 8x6"));
    CHECK(fx_has(log_text, "focal"));
    /* Getters refuse bad indices and arguments. */
    const float *rgb;
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_EQ_INT(nerf_dataset_image(ds, FRAMES, &rgb), NERF_EINVAL);
    CHECK_EQ_INT(nerf_dataset_camera(ds, FRAMES, &cam), NERF_EINVAL);
    CHECK_EQ_INT(nerf_dataset_spiral_camera(ds, 0, 10, &cam), NERF_EINVAL);
    cam.struct_size = 0;
    CHECK_EQ_INT(nerf_dataset_camera(ds, 0, &cam), NERF_EINVAL);
    nerf_dataset_destroy(ds);
    CHECK_EQ_INT(nerf_dataset_count(NULL), 0);
    CHECK_EQ_INT(nerf_dataset_is_ndc(NULL), 0);
    nerf_dataset_destroy(NULL);
}

TEST(black_background_and_default_options)
{
    char dir[1024];
    blender_scene(dir, sizeof dir);
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.white_background = 0;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    int frames[FRAMES] = {0, 1, 2, 3};
    if (ds) {
        check_images(ds, frames, FRAMES, 0.0f);
    }
    nerf_dataset_destroy(ds);
    /* NULL options: the defaults (white). */
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    if (ds) {
        check_images(ds, frames, FRAMES, 1.0f);
    }
    nerf_dataset_destroy(ds);
}

/* Mean of the composited k x k block at output pixel (ox, oy). */
static double block(int f, int k, int ox, int oy, int c)
{
    double s = 0.0;
    for (int y = oy * k; y < (oy + 1) * k; y++) {
        for (int x = ox * k; x < (ox + 1) * k; x++) {
            s += composite(f, x, y, c, 1.0f);
        }
    }
    return s / (k * k);
}

TEST(downscale)
{
    char dir[1024];
    blender_scene(dir, sizeof dir);
    double fx = 0.5 * W / tan(0.5 * ANGLE);
    for (int k = 2; k <= 3; k++) {
        nerf_dataset_options o;
        NERF_DATASET_OPTIONS_INIT(&o);
        o.downscale = (uint32_t)k;
        nerf_dataset *ds = NULL;
        CHECK_OK(nerf_dataset_load(&ds, dir, &o));
        if (ds == NULL) {
            continue;
        }
        uint32_t w, h;
        CHECK_OK(nerf_dataset_image_size(ds, &w, &h));
        CHECK_EQ_INT(w, W / k);
        CHECK_EQ_INT(h, H / k);
        const float *rgb;
        CHECK_OK(nerf_dataset_image(ds, 3, &rgb));
        int bad = 0;
        for (uint32_t y = 0; y < h; y++) {
            for (uint32_t x = 0; x < w; x++) {
                for (int c = 0; c < 3; c++) {
                    double want = block(3, k, (int)x, (int)y, c);
                    bad += fabs(rgb[(y * w + x) * 3 + c] - want) > 1e-6;
                }
            }
        }
        CHECK_EQ_INT(bad, 0);
        check_camera(ds, 1, 1, fx / k, W / 2.0 / k, H / 2.0 / k);
        nerf_dataset_destroy(ds);
    }
}

TEST(skip_and_missing_images)
{
    char dir[1024], p[1024];
    blender_scene(dir, sizeof dir);
    double fx = 0.5 * W / tan(0.5 * ANGLE);
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.skip = 2;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), 2);
    if (ds) {
        check_camera(ds, 1, 2, fx, W / 2.0, H / 2.0);
    }
    nerf_dataset_destroy(ds);

    /* Frames 1 and 3 lose their images, as in the shared lego val split. */
    fx_path(p, sizeof p, dir, "train/r_1.png");
    unlink(p);
    fx_path(p, sizeof p, dir, "train/r_3.png");
    unlink(p);
    CHECK_OK(nerf_dataset_load(&ds, dir, &o)); /* skip 2: all present */
    CHECK_EQ_INT(nerf_dataset_count(ds), 2);
    nerf_dataset_destroy(ds);

    o.skip = 1;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_ENOENT);
    CHECK(ds == NULL);
    CHECK(fx_has(nerf_last_error(), "train/r_1.png"));

    o.skip_missing = 1;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), 2);
    if (ds) {
        int frames[2] = {0, 2};
        check_images(ds, frames, 2, 1.0f);
        check_camera(ds, 1, 2, fx, W / 2.0, H / 2.0);
    }
    nerf_dataset_destroy(ds);
}

TEST(instant_ngp_fields)
{
    char dir[1024], json[16384];
    make_scene(dir, sizeof dir);
    scene_json(json, sizeof json, "\"fl_x\": 7, \"fl_y\": 8, \"cx\": 3.5, "
               "\"cy\": 2.25, \"w\": 8, \"h\": 6, \"aabb_scale\": 4, "
               "\"k1\": -0.25, \"k2\": 0.0625, \"p1\": 0.001, "
               "\"p2\": -0.002", 1);
    fx_write_text(dir, "transforms.json", json);
    /* Frame 1 has its own focal, principal point and lens (k3 too);
     * frame 2 only its own k2. */
    edit_json(dir, "transforms.json", "\"file_path\": \"train/r_1.png\"",
              "\"fl_x\": 9, \"cx\": 4.5, \"cy\": 3.5, \"k1\": 0.125, "
              "\"k3\": 0.5, \"file_path\": \"train/r_1.png\"");
    edit_json(dir, "transforms.json", "\"file_path\": \"train/r_2.png\"",
              "\"k2\": -0.5, \"file_path\": \"train/r_2.png\"");
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = NERF_SPLIT_TEST;
    o.llff_holdout = 0; /* every frame in every split */
    o.downscale = 2;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), FRAMES);
    CHECK_NEAR(nerf__dataset_aabb_scale(ds), 4.0, 0.0);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    if (ds) {
        /* Downscaling scales the intrinsics in pixels, not the lens,
         * which acts on normalised coordinates. */
        CHECK_OK(nerf_dataset_camera(ds, 0, &cam));
        CHECK_NEAR(cam.fx, 3.5, 1e-6);
        CHECK_NEAR(cam.fy, 4.0, 1e-6);
        CHECK_NEAR(cam.cx, 1.75, 1e-6);
        CHECK_NEAR(cam.cy, 1.125, 1e-6);
        CHECK(cam.k1 == -0.25f && cam.k2 == 0.0625f && cam.p1 == 0.001f &&
              cam.p2 == -0.002f && cam.k3 == 0.0f);
        CHECK_OK(nerf_dataset_camera(ds, 1, &cam));
        CHECK_NEAR(cam.fx, 4.5, 1e-6);
        CHECK_NEAR(cam.fy, 4.0, 1e-6);
        CHECK_NEAR(cam.cx, 2.25, 1e-6);
        CHECK_NEAR(cam.cy, 1.75, 1e-6);
        CHECK(cam.k1 == 0.125f && cam.k2 == 0.0625f && cam.p1 == 0.001f &&
              cam.p2 == -0.002f && cam.k3 == 0.5f);
        CHECK_OK(nerf_dataset_camera(ds, 2, &cam));
        CHECK_NEAR(cam.fx, 3.5, 1e-6);
        CHECK(cam.k1 == -0.25f && cam.k2 == -0.5f && cam.k3 == 0.0f);
        /* A caller built before the lens fields gets the rest. */
        nerf_camera old;
        memset(&old, 0x55, sizeof old);
        old.struct_size = offsetof(nerf_camera, k1);
        CHECK_OK(nerf_dataset_camera(ds, 1, &old));
        CHECK_NEAR(old.fx, 4.5, 1e-6);
        CHECK(old.k1 != 0.125f); /* untouched: not part of its struct */
    }
    nerf_dataset_destroy(ds);
    /* A size that disagrees with the images is an error. */
    edit_json(dir, "transforms.json", "\"w\": 8", "\"w\": 16");
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "transforms.json"));
}

/* The frame numbers of a loaded split, from the poses' x shift. */
static int split_frames(const char *dir, uint32_t split, uint32_t holdout,
                        uint32_t skip, int *frames)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = split;
    o.llff_holdout = holdout;
    o.skip = skip;
    nerf_dataset *ds = NULL;
    int rc = nerf_dataset_load(&ds, dir, &o);
    if (rc != NERF_OK) {
        return rc;
    }
    int n = (int)nerf_dataset_count(ds);
    for (int i = 0; i < n; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(ds, (uint32_t)i, &cam));
        frames[i] = (int)lrintf(cam.c2w[3]);
    }
    nerf_dataset_destroy(ds);
    return n;
}

/*
 * One transforms.json for every split is split as LLFF scenes are: every
 * llff_holdout-th frame, from the first, is test and val, the others
 * train; a hold-out of 0 serves every frame to every split.
 */
TEST(single_transforms_split)
{
    char dir[1024], json[16384];
    make_scene(dir, sizeof dir);
    scene_json(json, sizeof json, "\"fl_x\": 7, \"w\": 8, \"h\": 6", 1);
    fx_write_text(dir, "transforms.json", json);
    int f[FRAMES];
    /* The default, 8: frame 0 held out. */
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TRAIN, 8, 1, f), 3);
    CHECK(f[0] == 1 && f[1] == 2 && f[2] == 3);
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TEST, 8, 1, f), 1);
    CHECK(f[0] == 0);
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_VAL, 8, 1, f), 1);
    CHECK(f[0] == 0);
    /* Every second frame; skip counts within the split. */
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TEST, 2, 1, f), 2);
    CHECK(f[0] == 0 && f[1] == 2);
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TRAIN, 2, 1, f), 2);
    CHECK(f[0] == 1 && f[1] == 3);
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TRAIN, 3, 2, f), 1);
    CHECK(f[0] == 1);
    /* 0: everything everywhere, as before. */
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TEST, 0, 1, f), FRAMES);
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TRAIN, 0, 1, f), FRAMES);
    /* A hold-out of 1 leaves the training split empty: said so. */
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TRAIN, 1, 1, f), NERF_EINVAL);
    CHECK(fx_has(nerf_last_error(), "transforms.json: the requested split "
                 "has no frames"));
    /* Files of one split are not split again. */
    blender_scene(dir, sizeof dir);
    CHECK_EQ_INT(split_frames(dir, NERF_SPLIT_TRAIN, 2, 1, f), FRAMES);
}

TEST(gray_and_16bit_frames)
{
    char dir[1024], p[1024];
    blender_scene(dir, sizeof dir);
    uint16_t g[W * H], rgb[W * H * 3];
    for (int i = 0; i < W * H; i++) {
        g[i] = (uint16_t)(i * 1000);
        for (int c = 0; c < 3; c++) {
            rgb[3 * i + c] = (uint16_t)(i * 1300 + c * 77);
        }
    }
    fx_path(p, sizeof p, dir, "train/r_0.png");
    fx_write_png(p, W, H, 0, 16, g, NULL, 0, NULL, 0);
    fx_path(p, sizeof p, dir, "train/r_1.png");
    fx_write_png(p, W, H, 2, 16, rgb, NULL, 0, NULL, 0);
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    const float *im0 = NULL, *im1 = NULL;
    if (ds) {
        CHECK_OK(nerf_dataset_image(ds, 0, &im0));
        CHECK_OK(nerf_dataset_image(ds, 1, &im1));
    }
    int bad = 0;
    for (int i = 0; i < W * H && im0 && im1; i++) {
        for (int c = 0; c < 3; c++) {
            bad += fabs(im0[3 * i + c] - g[i] / 65535.0) > 1e-6;
            bad += fabs(im1[3 * i + c] - rgb[3 * i + c] / 65535.0) > 1e-6;
        }
    }
    CHECK_EQ_INT(bad, 0);
    nerf_dataset_destroy(ds);
}

/* Frame f rewritten as an 8-bit RGB file (opaque = 1) or RGBA file with
 * every alpha 255 (opaque = 2). */
static void write_opaque(const char *dir, int f, int opaque)
{
    uint16_t px[W * H * 4];
    const int ch = opaque == 1 ? 3 : 4;
    for (int i = 0; i < W * H; i++) {
        float p[4];
        pixel(f, i % W, i / W, p);
        p[3] = 1.0f;
        for (int c = 0; c < ch; c++) {
            px[ch * i + c] = (uint16_t)(p[c] * 255.0f + 0.5f);
        }
    }
    char p[1024], name[32];
    snprintf(name, sizeof name, "train/r_%d.png", f);
    fx_path(p, sizeof p, dir, name);
    fx_write_png(p, W, H, opaque == 1 ? 2 : 6, 8, px, NULL, 0, NULL, 0);
}

/*
 * The loader keeps each stored pixel's coverage (the mean alpha of its
 * block) beside the composited colours, which random-background training
 * needs; scenes whose images are opaque keep none.  What the public API
 * hands out does not change.
 */
TEST(alpha_kept_beside_pixels)
{
    char dir[1024];
    blender_scene(dir, sizeof dir);
    int frames[FRAMES] = {0, 1, 2, 3};
    for (int k = 1; k <= 2; k++) {
        for (uint32_t white = 0; white <= 1; white++) {
            nerf_dataset_options o;
            NERF_DATASET_OPTIONS_INIT(&o);
            o.downscale = (uint32_t)k;
            o.white_background = white;
            nerf_dataset *ds = NULL;
            CHECK_OK(nerf_dataset_load(&ds, dir, &o));
            if (ds == NULL) {
                continue;
            }
            CHECK(ds->alpha != NULL);
            CHECK(ds->alpha_bg == (float)white);
            if (k == 1) {
                check_images(ds, frames, FRAMES, (float)white);
            }
            const int w = W / k, h = H / k;
            int bad = 0;
            for (int f = 0; f < FRAMES && ds->alpha; f++) {
                for (int y = 0; y < h; y++) {
                    for (int x = 0; x < w; x++) {
                        double a = 0.0;
                        for (int dy = 0; dy < k; dy++) {
                            for (int dx = 0; dx < k; dx++) {
                                float p[4];
                                pixel(f, x * k + dx, y * k + dy, p);
                                a += p[3];
                            }
                        }
                        double want = a / (k * k) * 65535.0;
                        uint16_t got = ds->alpha[((size_t)f * h + y) * w + x];
                        bad += fabs(got - want) > 0.5 + 1e-6;
                    }
                }
            }
            CHECK_EQ_INT(bad, 0);
            nerf_dataset_destroy(ds);
        }
    }
    /* One opaque frame among transparent ones: its coverage is full. */
    write_opaque(dir, 0, 1);
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    CHECK(ds && ds->alpha != NULL);
    if (ds && ds->alpha) {
        int bad = 0;
        for (int i = 0; i < W * H; i++) {
            bad += ds->alpha[i] != 65535;
        }
        CHECK_EQ_INT(bad, 0);
        CHECK(ds->alpha[W * H] != 65535 || ds->alpha[W * H + 1] != 65535);
    }
    nerf_dataset_destroy(ds);
    /* Opaque files, RGB or RGBA, keep no coverage. */
    for (int f = 0; f < FRAMES; f++) {
        write_opaque(dir, f, f % 2 ? 2 : 1);
    }
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    CHECK(ds && ds->alpha == NULL);
    nerf_dataset_destroy(ds);
}

/* One bad variant: edit the json (or not), load, expect status and words. */
static void expect_failure(const char *from, const char *to, int status,
                           const char *word)
{
    char dir[1024];
    blender_scene(dir, sizeof dir);
    if (from) {
        edit_json(dir, "transforms_train.json", from, to);
    }
    nerf_dataset *ds = (nerf_dataset *)dir;
    int rc = nerf_dataset_load(&ds, dir, NULL);
    if (rc != status || ds != NULL ||
        !fx_has(nerf_last_error(), "transforms_train.json") ||
        !fx_has(nerf_last_error(), word)) {
        FAILF("edit '%s' -> '%s': status %d (want %d), message '%s' "
              "(want '%s')", from ? from : "", to ? to : "", rc, status,
              nerf_last_error(), word);
    }
}

TEST(bad_json)
{
    expect_failure("\"frames\"", "\"framez\"", NERF_EFORMAT,
                   "missing field 'frames'");
    expect_failure("\"camera_angle_x\"", "\"camera_angle_z\"", NERF_EFORMAT,
                   "missing field 'camera_angle_x'");
    expect_failure("\"transform_matrix\"", "\"transform\"", NERF_EFORMAT,
                   "frame 0 (./train/r_0): missing field 'transform_matrix'");
    expect_failure("\"file_path\"", "\"path\"", NERF_EFORMAT,
                   "missing field 'file_path'");
    expect_failure("[0, 0, 0, 1]", "[0, 0, 0]", NERF_EFORMAT,
                   "row 3 is not a list of 4 numbers");
    expect_failure("[0, 0, 0, 1]]", "[0, 0, 0, 1], [0, 0, 0, 1]]",
                   NERF_EFORMAT, "4 rows of 4 numbers");
    expect_failure("[0, 0, 0, 1]", "[0, 0, 1, 1]", NERF_EFORMAT,
                   "[0, 0, 0, 1]");
    expect_failure("[1, ", "[1e999, ", NERF_EFORMAT, "not a finite number");
    expect_failure("\"rotation\"", "\"x\": NaN, \"rotation\"", NERF_EFORMAT,
                   "invalid JSON at line 1");
    expect_failure("]}", "]", NERF_EFORMAT, "invalid JSON");
    expect_failure("0.6911112070083618", "0", NERF_EFORMAT,
                   "camera_angle_x 0 is not in (0, pi)");
    expect_failure("0.6911112070083618", "0.69, \"fl_x\": -3", NERF_EFORMAT,
                   "focal length must be positive");
    expect_failure("0.6911112070083618", "\"wide\"", NERF_EFORMAT,
                   "'camera_angle_x' is not a finite number");
    expect_failure("[[1", "[[0", NERF_EFORMAT, "degenerate rotation");
    /* Finite but absurd values, named with the frame's file_path. */
    expect_failure("[1, ", "[1e308, ", NERF_EFORMAT,
                   "frame 0 (./train/r_0): transform_matrix has an entry of "
                   "magnitude 1e+308");
    expect_failure("[[1", "[[1e-9", NERF_EFORMAT,
                   "frame 0 (./train/r_0): transform_matrix has a degenerate "
                   "rotation (column 0");
    expect_failure("0.6911112070083618", "0.69, \"fl_x\": 1e-9", NERF_EFORMAT,
                   "focal length must be positive");
    expect_failure("\"rotation\"", "\"fl_x\": 1e-9, \"rotation\"",
                   NERF_EFORMAT, "frame 0 (./train/r_0): focal length must "
                   "be positive, within [0.001, 1e+06] pixels (fl_x 1e-09)");
    expect_failure("0.6911112070083618", "3.14159265358979", NERF_EFORMAT,
                   "frame 0 (./train/r_0): focal length must be positive");
    /* The lens: numbers, finite, not absurd, at top level or per frame. */
    expect_failure("0.6911112070083618", "0.69, \"k1\": \"strong\"",
                   NERF_EFORMAT, "field 'k1' is not a finite number");
    expect_failure("\"rotation\"", "\"p2\": 1e999, \"rotation\"",
                   NERF_EFORMAT, "frame 0 (./train/r_0): field 'p2' is not a "
                   "finite number");
    expect_failure("\"rotation\"", "\"k3\": -5e3, \"rotation\"",
                   NERF_EFORMAT, "frame 0 (./train/r_0): distortion k3 -5000 "
                   "is beyond +-1000");
    expect_failure("0.6911112070083618", "0.69, \"k2\": 1e300",
                   NERF_EFORMAT, "distortion k2 1e+300 is beyond");
    expect_failure("0.6911112070083618", "0.69, \"k1\": null",
                   NERF_EFORMAT, "field 'k1' is not a finite number");
    /* Other lens models are refused, not misread. */
    expect_failure("\"rotation\"", "\"k4\": 0.01, \"rotation\"",
                   NERF_EFORMAT, "frame 0 (./train/r_0): 'k4' (a fisheye or "
                   "rational lens model) is not supported");
    expect_failure("0.6911112070083618", "0.69, \"is_fisheye\": true",
                   NERF_EFORMAT, "a fisheye lens is not supported");
    expect_failure("0.6911112070083618",
                   "0.69, \"camera_model\": \"OPENCV_FISHEYE\"",
                   NERF_EFORMAT, "OPENCV_FISHEYE lens is not supported");
    /* ... but a k4 of 0 and the model this is are fine. */
    char dir[1024];
    blender_scene(dir, sizeof dir);
    edit_json(dir, "transforms_train.json", "0.6911112070083618",
              "0.69, \"k4\": 0, \"camera_model\": \"OPENCV\", "
              "\"is_fisheye\": false");
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    nerf_dataset_destroy(ds);
    /* instant-ngp's aabb_scale: a power of two, 1..128. */
    expect_failure("0.6911112070083618", "0.69, \"aabb_scale\": 3",
                   NERF_EFORMAT, "aabb_scale 3 is not a power of two in "
                   "1..128");
    expect_failure("0.6911112070083618", "0.69, \"aabb_scale\": 256",
                   NERF_EFORMAT, "aabb_scale 256 is not a power");
    expect_failure("0.6911112070083618", "0.69, \"aabb_scale\": 0.5",
                   NERF_EFORMAT, "aabb_scale 0.5 is not a power");
    expect_failure("0.6911112070083618", "0.69, \"aabb_scale\": \"16\"",
                   NERF_EFORMAT, "field 'aabb_scale' is not a finite number");
}

TEST(bad_images)
{
    char dir[1024], p[1024];
    nerf_dataset *ds = NULL;
    /* Truncated PNG. */
    blender_scene(dir, sizeof dir);
    fx_path(p, sizeof p, dir, "train/r_2.png");
    fx_truncate(p, fx_file_size(p) - 20);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, NULL), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "train/r_2.png"));
    /* An image of another size. */
    blender_scene(dir, sizeof dir);
    float big[(W + 1) * H * 4];
    memset(big, 0, sizeof big);
    fx_path(p, sizeof p, dir, "train/r_3.png");
    fx_write_rgba8(p, W + 1, H, big);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, NULL), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "train/r_3.png: image is 9x6"));
    CHECK(ds == NULL);
}

/*
 * A scene with a test split beside the train split: transforms_test.json
 * names test/r_0.png .. r_3.png, copies of the train images.
 */
static const char *scene_with_test_split(char *dir, size_t size)
{
    blender_scene(dir, size);
    fx_mkdir(dir, "test");
    float rgba[W * H * 4];
    for (int f = 0; f < FRAMES; f++) {
        for (int y = 0; y < H; y++) {
            for (int x = 0; x < W; x++) {
                pixel(f, x, y, rgba + 4 * (y * W + x));
            }
        }
        char p[1024], name[32];
        snprintf(name, sizeof name, "test/r_%d.png", f);
        fx_path(p, sizeof p, dir, name);
        fx_write_rgba8(p, W, H, rgba);
    }
    char json[16384];
    scene_json(json, sizeof json, "\"camera_angle_x\": 0.6911112070083618", 0);
    for (char *at = strstr(json, "./train/"); at; at = strstr(at, "./train/")) {
        memcpy(at, "./test/ ", 8); /* one byte longer: the space goes */
        memmove(at + 7, at + 8, strlen(at + 8) + 1);
    }
    fx_write_text(dir, "transforms_test.json", json);
    return dir;
}

/* Loading the train split of dir fails with status, naming what. */
static void expect_train_fails(const char *dir, int status, const char *what)
{
    nerf_dataset *ds = NULL;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, NULL), status);
    CHECK(ds == NULL);
    if (!fx_has(nerf_last_error(), what)) {
        FAILF("message '%s' lacks '%s'", nerf_last_error(), what);
    }
}

/*
 * Every image the scene names is checked when any split loads: the test
 * split's images by their headers when the train split loads, so that a
 * broken test image is found before training, not by the evaluation.  A
 * missing one is only a warning (a split may be a subset, as lego's val
 * split is; its own load decides, with skip_missing).
 */
TEST(frames_of_other_splits_are_checked)
{
    char dir[1024], p[1024];
    nerf_dataset *ds = NULL;
    scene_with_test_split(dir, sizeof dir);
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    CHECK_EQ_INT(nerf_dataset_count(ds), FRAMES);
    nerf_dataset_destroy(ds);

    fx_path(p, sizeof p, dir, "test/r_2.png");
    fx_write_bytes(p, "not an image", 12);
    expect_train_fails(dir, NERF_EFORMAT, "test/r_2.png: not a PNG or JPEG");
    CHECK(unlink(p) == 0);
    CHECK(mkfifo(p, 0666) == 0);
    expect_train_fails(dir, NERF_EUNRECOGNISED,
                       "test/r_2.png: a FIFO (named pipe), not a regular "
                       "file");
    CHECK(unlink(p) == 0);
    CHECK(mkdir(p, 0777) == 0);
    expect_train_fails(dir, NERF_EUNRECOGNISED,
                       "test/r_2.png: a folder, not a file");
    CHECK(rmdir(p) == 0);
    float wide[(W + 1) * H * 4];
    memset(wide, 0, sizeof wide);
    fx_write_rgba8(p, W + 1, H, wide);
    expect_train_fails(dir, NERF_EFORMAT, "test/r_2.png: image is 9x6");

    /* Missing: logged, once, naming the file; the train split loads. */
    CHECK(unlink(p) == 0);
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = capture_log;
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.hooks = &hooks;
    log_text[0] = '\0';
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    nerf_dataset_destroy(ds);
    CHECK(fx_has(log_text, "transforms_test.json: 1 frame(s)"));
    CHECK(fx_has(log_text, "test/r_2.png"));
    /* ... and the load of the test split itself refuses it. */
    o.split = NERF_SPLIT_TEST;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_ENOENT);
    CHECK(fx_has(nerf_last_error(), "test/r_2.png"));

    /* The other file is checked as its own load would check it. */
    scene_with_test_split(dir, sizeof dir);
    edit_json(dir, "transforms_test.json", "\"./test/r_1\"", "\".\"");
    expect_train_fails(dir, NERF_EFORMAT, "transforms_test.json: frame 1 "
                       "(.): file_path '.' names a folder, not an image");
    scene_with_test_split(dir, sizeof dir);
    edit_json(dir, "transforms_test.json", "\"rotation\"",
              "\"w\": 9, \"h\": 6, \"rotation\"");
    expect_train_fails(dir, NERF_EFORMAT, "transforms_test.json: frame 0 "
                       "(./test/r_0): w x h is 9x6");
    scene_with_test_split(dir, sizeof dir);
    edit_json(dir, "transforms_test.json", "]}", "]");
    expect_train_fails(dir, NERF_EFORMAT, "transforms_test.json: invalid "
                       "JSON");
    fx_path(p, sizeof p, dir, "transforms_test.json");
    CHECK(unlink(p) == 0);
    CHECK(mkfifo(p, 0666) == 0);
    expect_train_fails(dir, NERF_EUNRECOGNISED, "transforms_test.json: a "
                       "FIFO (named pipe)");

    /* The frames skip passes over are checked too. */
    blender_scene(dir, sizeof dir);
    fx_path(p, sizeof p, dir, "train/r_1.png");
    fx_write_bytes(p, "not an image", 12);
    NERF_DATASET_OPTIONS_INIT(&o);
    o.skip = 2;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "train/r_1.png: not a PNG or JPEG"));
}

TEST(folders_and_options)
{
    nerf_dataset *ds = NULL;
    char p[1024];
    fx_path(p, sizeof p, tmp, "nowhere");
    CHECK_EQ_INT(nerf_dataset_load(&ds, p, NULL), NERF_ENOENT);
    CHECK(fx_has(nerf_last_error(), "nowhere"));
    fx_path(p, sizeof p, tmp, "empty");
    mkdir(p, 0777);
    CHECK_EQ_INT(nerf_dataset_load(&ds, p, NULL), NERF_EUNRECOGNISED);
    CHECK(fx_has(nerf_last_error(), "not a known dataset layout"));
    CHECK_EQ_INT(nerf_dataset_load(NULL, p, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_dataset_load(&ds, NULL, NULL), NERF_EINVAL);

    char dir[1024];
    blender_scene(dir, sizeof dir);
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = NERF_SPLIT_VAL; /* no transforms_val.json */
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_ENOENT);
    CHECK(fx_has(nerf_last_error(), "transforms_val.json"));
    CHECK(fx_has(nerf_last_error(), "has no val split"));
    uint32_t *fields[] = {&o.split, &o.downscale, &o.skip,
                          &o.white_background, &o.skip_missing,
                          &o.forward_facing};
    uint32_t bad[] = {3, 0, 0, 2, 2, 2};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        NERF_DATASET_OPTIONS_INIT(&o);
        *fields[i] = bad[i];
        CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EINVAL);
    }
    /* A valid value, but a Blender scene is no forward-facing capture. */
    NERF_DATASET_OPTIONS_INIT(&o);
    o.forward_facing = 1;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EINVAL);
    CHECK(fx_has(nerf_last_error(), "forward_facing is for COLMAP"));
    CHECK(ds == NULL);
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = 9; /* larger than the 8x6 images */
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EINVAL);
    /* A struct from a newer header: unknown zero bytes are fine. */
    struct {
        nerf_dataset_options o;
        uint64_t extra;
    } big;
    CHECK_OK(nerf_dataset_options_init(&big.o, sizeof big));
    CHECK_OK(nerf_dataset_load(&ds, dir, &big.o));
    nerf_dataset_destroy(ds);
    big.extra = 1;
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &big.o), NERF_EVERSION);
    CHECK_EQ_INT(nerf_dataset_options_init(NULL, sizeof o), NERF_EINVAL);
}

static long live_blocks;

static void *count_alloc(size_t size, void *user)
{
    (void)user;
    live_blocks++;
    return malloc(size);
}

static void count_free(void *ptr, void *user)
{
    (void)user;
    live_blocks -= ptr != NULL;
    free(ptr);
}

TEST(allocator_hooks_balance)
{
    char dir[1024];
    blender_scene(dir, sizeof dir);
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.alloc = count_alloc;
    hooks.free = count_free;
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.hooks = &hooks;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    CHECK(live_blocks > 0);
    nerf_dataset_destroy(ds);
    CHECK_EQ_INT(live_blocks, 0);
    /* Failing loads release everything too. */
    edit_json(dir, "transforms_train.json", "[0, 0, 0, 1]", "[0, 0, 0]");
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK_EQ_INT(live_blocks, 0);
}

int main(void)
{
    tmp = fx_make_temp_dir();
    RUN(basic_load);
    RUN(black_background_and_default_options);
    RUN(downscale);
    RUN(skip_and_missing_images);
    RUN(instant_ngp_fields);
    RUN(single_transforms_split);
    RUN(gray_and_16bit_frames);
    RUN(alpha_kept_beside_pixels);
    RUN(bad_json);
    RUN(bad_images);
    RUN(frames_of_other_splits_are_checked);
    RUN(folders_and_options);
    RUN(allocator_hooks_balance);
    fx_remove_tree(tmp);
    HARNESS_EXIT();
}
