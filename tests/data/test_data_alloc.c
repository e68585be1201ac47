/*
 * Allocation-failure injection for the dataset loaders: every allocation
 * of a load is failed in turn, and each failure must come back as
 * NERF_ENOMEM with a message, no dataset and no block left behind.  Only
 * libnerf's own allocations go through the hooks (libpng, libjpeg, zlib
 * and cJSON use malloc directly), so those are the ones exercised here.
 */
#include <nerf.h>

#include "data_fixtures.h"
#include "jpeg_fixtures.h"
#include "../fail_alloc.h"
#include "../harness.h"

enum { W = 4, H = 4, LLFF_N = 3 };

/* Beyond this many allocations a tiny load has clearly gone wrong. */
#define MAX_STEPS 10000

static char *tmp;

static void write_image(const char *dir, const char *name, int seed)
{
    uint16_t px[W * H * 4];
    for (int i = 0; i < W * H; i++) {
        px[4 * i + 0] = (uint16_t)((i * 13 + seed * 40) % 256);
        px[4 * i + 1] = (uint16_t)((i * 7) % 256);
        px[4 * i + 2] = (uint16_t)(seed * 60);
        px[4 * i + 3] = (uint16_t)(i % 2 ? 255 : 128);
    }
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    fx_write_png(p, W, H, 6, 8, px, NULL, 0, NULL, 0);
}

/*
 * Two frames, one named bare with "./" (the loader appends ".png") and one
 * with its extension; with_missing adds a third whose image is absent, for
 * the skip_missing path.
 */
static void make_blender(char *dir, size_t size, const char *name,
                         int with_missing)
{
    snprintf(dir, size, "%s/%s", tmp, name);
    mkdir(dir, 0777);
    fx_mkdir(dir, "train");
    write_image(dir, "train/r_0.png", 0);
    write_image(dir, "train/r_1.png", 1);
    char json[2048];
    snprintf(json, sizeof json,
             "{\"camera_angle_x\": 0.69, \"frames\": ["
             "{\"file_path\": \"./train/r_0\", \"transform_matrix\": "
             "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]}, "
             "{\"file_path\": \"train/r_1.png\", \"fl_x\": 5.0, "
             "\"transform_matrix\": "
             "[[0, -1, 0, 1], [1, 0, 0, 0], [0, 0, 1, 3], [0, 0, 0, 1]]}%s"
             "]}\n",
             with_missing
                 ? ", {\"file_path\": \"train/gone\", \"transform_matrix\": "
                   "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2]]}"
                 : "");
    fx_write_text(dir, "transforms_train.json", json);
}

/* The same picture as write_image, opaque, as a JPEG; orientation 6 (a
 * quarter turn, square images keep their size) when turned. */
static void write_jpeg(const char *dir, const char *name, int seed,
                       int turned)
{
    uint8_t px[W * H * 3];
    for (int i = 0; i < W * H; i++) {
        px[3 * i + 0] = (uint8_t)((i * 13 + seed * 40) % 256);
        px[3 * i + 1] = (uint8_t)((i * 7) % 256);
        px[3 * i + 2] = (uint8_t)(seed * 60);
    }
    uint8_t exif[64];
    size_t n = turned ? fx_exif(exif, 1, 6, 3) : 0;
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    fx_write_jpeg(p, W, H, JCS_RGB, px, 90, 0, exif, n);
}

/* poses_bounds.npy with LLFF_N identity-rotation rows and images/ of PNGs
 * or JPEGs. */
static void make_llff(char *dir, size_t size, int jpeg)
{
    snprintf(dir, size, "%s/llff%s", tmp, jpeg ? "_jpeg" : "");
    mkdir(dir, 0777);
    fx_mkdir(dir, "images");
    double rows[LLFF_N * 17];
    memset(rows, 0, sizeof rows);
    for (int i = 0; i < LLFF_N; i++) {
        double *r = rows + 17 * i;
        /* LLFF columns [down, right, back] of the identity: [-y, x, z]. */
        r[1] = 1.0;
        r[5] = -1.0;
        r[12] = 1.0;
        r[3] = 0.5 * i;
        r[8] = 0.1 * i;
        r[13] = 0.2 * i;
        r[4] = H;
        r[9] = W;
        r[14] = 3.0;
        r[15] = 1.5 + 0.1 * i;
        r[16] = 8.0 + i;
    }
    char p[1024];
    fx_path(p, sizeof p, dir, "poses_bounds.npy");
    fx_write_npy(p, "<f8", "False", "(3, 17)", rows, sizeof rows);
    for (int i = 0; i < LLFF_N; i++) {
        char name[64];
        snprintf(name, sizeof name, "images/IMG_%d.%s", i,
                 jpeg ? "JPG" : "png");
        if (jpeg) {
            write_jpeg(dir, name, i, i == 1);
        } else {
            write_image(dir, name, i);
        }
    }
}

/*
 * Fail allocation 1, 2, ... of the load until one succeeds; returns how
 * many allocations the successful load made.
 */
static int sweep(const char *dir, nerf_dataset_options *o, uint32_t expect)
{
    fail_alloc f;
    nerf_hooks hooks;
    fail_alloc_hooks(&hooks, &f);
    o->hooks = &hooks;
    for (int k = 1; k <= MAX_STEPS; k++) {
        f = (fail_alloc){0, k, 0};
        nerf_clear_error();
        nerf_dataset *ds = (nerf_dataset *)&f; /* must be overwritten */
        int rc = nerf_dataset_load(&ds, dir, o);
        if (rc == NERF_OK) {
            /* Success means the injected failure was never reached. */
            CHECK(f.calls < k);
            CHECK(ds != NULL);
            CHECK_EQ_INT(nerf_dataset_count(ds), expect);
            nerf_dataset_destroy(ds);
            CHECK_EQ_INT(f.live, 0);
            return f.calls;
        }
        if (rc != NERF_ENOMEM || ds != NULL || f.live != 0 ||
            nerf_last_error()[0] == '\0') {
            FAILF("%s: failing allocation %d: status %d (%s), out %p, %d "
                  "live blocks", dir, k, rc, nerf_last_error(), (void *)ds,
                  f.live);
            return -1;
        }
    }
    FAILF("%s: still failing after %d allocations", dir, MAX_STEPS);
    return -1;
}

TEST(blender)
{
    char dir[1024];
    make_blender(dir, sizeof dir, "blender", 0);
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    CHECK(sweep(dir, &o, 2) > 0);
    o.downscale = 2;
    o.white_background = 0;
    CHECK(sweep(dir, &o, 2) > 0);
}

TEST(blender_skip_missing)
{
    char dir[1024];
    make_blender(dir, sizeof dir, "blender_missing", 1);
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.skip_missing = 1;
    CHECK(sweep(dir, &o, 2) > 0);
    o.skip = 2;
    CHECK(sweep(dir, &o, 1) > 0);
}

TEST(llff)
{
    char dir[1024];
    for (int jpeg = 0; jpeg < 2; jpeg++) {
        make_llff(dir, sizeof dir, jpeg);
        nerf_dataset_options o;
        NERF_DATASET_OPTIONS_INIT(&o);
        CHECK(sweep(dir, &o, LLFF_N - 1) > 0);
        /* No images_2/: the loader searches, then filters images/ by 2. */
        o.downscale = 2;
        o.split = NERF_SPLIT_TEST;
        CHECK(sweep(dir, &o, 1) > 0);
    }
}

int main(void)
{
    tmp = fx_make_temp_dir();
    RUN(blender);
    RUN(blender_skip_missing);
    RUN(llff);
    fx_remove_tree(tmp);
    HARNESS_EXIT();
}
