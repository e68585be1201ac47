/*
 * JPEG photos: the reader (orientation, colour spaces, codings, bad
 * files), the scene writer's JPEG output and datasets made of JPEGs.
 * Test files come from libjpeg directly (jpeg_fixtures.h).
 */
#include <math.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../harness.h"
#include "data_fixtures.h"
#include "image_read.h"
#include "jpeg_fixtures.h"
#include "largest_alloc.h"
#include "nerf.h"

static const char *tmp;

/* Stored test picture: 3 x 2 blocks of 16 x 16 pixels, named
 *   A B C
 *   D E F                                                              */
#define BLK 16
static const uint8_t colours[6][3] = {
    {230, 20, 20},  /* A red */
    {20, 200, 20},  /* B green */
    {20, 20, 230},  /* C blue */
    {240, 240, 240},/* D white */
    {15, 15, 15},   /* E black */
    {230, 220, 30}, /* F yellow */
};

static void blocks(uint8_t *px)
{
    for (int y = 0; y < 2 * BLK; y++) {
        for (int x = 0; x < 3 * BLK; x++) {
            const uint8_t *c = colours[(y / BLK) * 3 + x / BLK];
            memcpy(px + 3 * (y * 3 * BLK + x), c, 3);
        }
    }
}

/*
 * The upright picture for each Exif orientation, by hand from the Exif
 * definitions (row 0 / column 0 of the stored image shown at ...), as
 * block letters row by row: 2 mirrors, 3 turns 180, 4 flips, 5
 * transposes, 6 shows the stored image turned clockwise, 7 the
 * transverse, 8 turned counter-clockwise.
 */
static const char *const upright[9] = {
    NULL, "ABC/DEF", "CBA/FED", "FED/CBA", "DEF/ABC",
    "AD/BE/CF", "DA/EB/FC", "FC/EB/DA", "CF/BE/AD",
};

/* Whether rgba (w x h) shows the block layout `want` ("AD/BE/CF"). */
static void check_layout(const float *rgba, uint32_t w, uint32_t h,
                         const char *want, uint32_t orientation)
{
    uint32_t cols = (uint32_t)strcspn(want, "/");
    uint32_t rows = (uint32_t)(strlen(want) + 1) / (cols + 1);
    CHECK_EQ_INT(w, cols * BLK);
    CHECK_EQ_INT(h, rows * BLK);
    if (w != cols * BLK || h != rows * BLK) {
        return;
    }
    for (uint32_t r = 0; r < rows; r++) {
        for (uint32_t c = 0; c < cols; c++) {
            const uint8_t *k = colours[want[r * (cols + 1) + c] - 'A'];
            /* A pixel inside the block, off its centre line, so that a
             * mirror within the block would show at its edges too. */
            uint32_t points[2][2] = {{2, 3}, {BLK - 3, BLK - 2}};
            for (int p = 0; p < 2; p++) {
                uint32_t x = c * BLK + points[p][0];
                uint32_t y = r * BLK + points[p][1];
                const float *v = rgba + 4 * ((size_t)y * w + x);
                for (int ch = 0; ch < 3; ch++) {
                    if (fabsf(v[ch] - k[ch] / 255.0f) > 0.04f) {
                        FAILF("orientation %u: pixel (%u, %u) channel %d is "
                              "%g, block %c wants %g", orientation, x, y, ch,
                              v[ch], want[r * (cols + 1) + c],
                              k[ch] / 255.0);
                        return;
                    }
                }
                CHECK(v[3] == 1.0f);
            }
        }
    }
}

TEST(exif_orientations)
{
    uint8_t px[3 * BLK * 2 * BLK * 3];
    blocks(px);
    char path[1024];
    fx_path(path, sizeof path, tmp, "orient.jpg");
    for (uint32_t o = 1; o <= 8; o++) {
        uint8_t exif[64];
        /* Both byte orders: odd orientations Motorola, even Intel. */
        size_t n = fx_exif(exif, (int)(o & 1), o, 3);
        fx_write_jpeg(path, 3 * BLK, 2 * BLK, JCS_RGB, px, 100, 0, exif, n);
        uint32_t w = 0, h = 0;
        float *rgba = NULL;
        CHECK_OK(nerf_image_read(path, &w, &h, &rgba));
        if (rgba != NULL) {
            check_layout(rgba, w, h, upright[o], o);
        }
        nerf_free(rgba);
        /* The header alone gives the same upright size. */
        uint32_t hw = 0, hh = 0;
        CHECK_OK(nerf__image_read_size(NULL, path, &hw, &hh));
        CHECK(hw == w && hh == h);
    }
    /* No Exif, or an APP1 that is XMP rather than Exif: as stored. */
    static const uint8_t xmp[] = "http://ns.adobe.com/xap/1.0/\0<x/>";
    for (int k = 0; k < 2; k++) {
        fx_write_jpeg(path, 3 * BLK, 2 * BLK, JCS_RGB, px, 100, 0, xmp,
                      k ? sizeof xmp : 0);
        uint32_t w = 0, h = 0;
        float *rgba = NULL;
        CHECK_OK(nerf_image_read(path, &w, &h, &rgba));
        if (rgba != NULL) {
            check_layout(rgba, w, h, upright[1], 1);
        }
        nerf_free(rgba);
    }
}

/* nerf_image_read on path fails with status, and the message names the
 * file and contains what. */
static void expect_read_error(const char *path, int status, const char *what)
{
    uint32_t w = 7, h = 7;
    float *rgba = (float *)&w;
    CHECK_EQ_INT(nerf_image_read(path, &w, &h, &rgba), status);
    CHECK(rgba == NULL);
    if (!fx_has(nerf_last_error(), path) || !fx_has(nerf_last_error(), what)) {
        FAILF("message '%s' should name %s and say '%s'", nerf_last_error(),
              path, what);
    }
}

/* A corrupted TIFF header or IFD, or an Orientation outside 1..8. */
TEST(bad_exif)
{
    uint8_t px[3 * BLK * 2 * BLK * 3];
    blocks(px);
    char path[1024];
    fx_path(path, sizeof path, tmp, "bad_exif.jpg");
    uint8_t exif[64];
    size_t n;
    const uint32_t bad_values[] = {0, 9, 0xffff};
    for (int k = 0; k < 3; k++) {
        n = fx_exif(exif, k & 1, bad_values[k], 3);
        fx_write_jpeg(path, 48, 32, JCS_RGB, px, 90, 0, exif, n);
        char what[64];
        snprintf(what, sizeof what, "Orientation is %u", bad_values[k]);
        expect_read_error(path, NERF_EFORMAT, what);
    }
    /* Orientation stored as a LONG. */
    n = fx_exif(exif, 0, 6, 4);
    fx_write_jpeg(path, 48, 32, JCS_RGB, px, 90, 0, exif, n);
    expect_read_error(path, NERF_EFORMAT, "type 4");
    /* IFD0 offset past the block. */
    n = fx_exif(exif, 0, 6, 3);
    exif[6 + 4] = 0xf0;
    fx_write_jpeg(path, 48, 32, JCS_RGB, px, 90, 0, exif, n);
    expect_read_error(path, NERF_EFORMAT, "IFD0 offset 240");
    /* More entries than the block holds. */
    n = fx_exif(exif, 1, 6, 3);
    exif[6 + 8] = 0x40;
    fx_write_jpeg(path, 48, 32, JCS_RGB, px, 90, 0, exif, n);
    expect_read_error(path, NERF_EFORMAT, "entries");
    /* No byte-order mark; then a block cut short after "Exif\0\0". */
    n = fx_exif(exif, 0, 6, 3);
    exif[6] = 'X';
    fx_write_jpeg(path, 48, 32, JCS_RGB, px, 90, 0, exif, n);
    expect_read_error(path, NERF_EFORMAT, "byte-order");
    fx_write_jpeg(path, 48, 32, JCS_RGB, px, 90, 0, exif, 9);
    expect_read_error(path, NERF_EFORMAT, "byte-order");
    /* An IFD0 entry cut off by the block's end. */
    n = fx_exif(exif, 1, 6, 3);
    fx_write_jpeg(path, 48, 32, JCS_RGB, px, 90, 0, exif, n - 8);
    expect_read_error(path, NERF_EFORMAT, "entries");
}

static void noise(uint8_t *px, size_t n, uint32_t seed)
{
    for (size_t i = 0; i < n; i++) {
        seed = seed * 1664525u + 1013904223u;
        px[i] = (uint8_t)(seed >> 24);
    }
}

TEST(bad_files)
{
    enum { W = 64, H = 48 };
    static uint8_t px[W * H * 4];
    noise(px, sizeof px, 1);
    char path[1024];
    fx_path(path, sizeof path, tmp, "bad.jpg");
    /* Cut in the middle of the entropy-coded data: libjpeg would pad
     * it with grey and only warn. */
    for (int flags = 0; flags < 2; flags++) {
        fx_write_jpeg(path, W, H, JCS_RGB, px, 90, flags, NULL, 0);
        fx_truncate(path, fx_file_size(path) / 2);
        expect_read_error(path, NERF_EFORMAT, "truncated JPEG");
    }
    /* Cut inside the headers. */
    fx_write_jpeg(path, W, H, JCS_RGB, px, 90, 0, NULL, 0);
    fx_truncate(path, 40);
    expect_read_error(path, NERF_EFORMAT, "JPEG");
    /* The JPEG magic, then garbage. */
    uint8_t garbage[300];
    noise(garbage, sizeof garbage, 7);
    garbage[0] = 0xff;
    garbage[1] = 0xd8;
    garbage[2] = 0xff;
    fx_write_bytes(path, garbage, sizeof garbage);
    expect_read_error(path, NERF_EFORMAT, "JPEG");
    /* Scan data before any frame header. */
    static const uint8_t sos_first[] = {0xff, 0xd8, 0xff, 0xda, 0x00, 0x08,
                                        0x01, 0x01, 0x00, 0x00, 0x3f, 0x00,
                                        0xff, 0xd9};
    fx_write_bytes(path, sos_first, sizeof sos_first);
    expect_read_error(path, NERF_EFORMAT, "not a valid JPEG file: Invalid");
    /* Neither magic; empty; missing. */
    fx_write_bytes(path, "GIF89a......", 12);
    expect_read_error(path, NERF_EFORMAT, "not a PNG or JPEG file");
    fx_write_bytes(path, "", 0);
    expect_read_error(path, NERF_EFORMAT, "not a PNG or JPEG file");
    fx_path(path, sizeof path, tmp, "missing.jpg");
    expect_read_error(path, NERF_ENOENT, "cannot open");
    /* CMYK (Adobe) JPEGs have no RGB conversion in libjpeg: refused. */
    fx_path(path, sizeof path, tmp, "cmyk.jpg");
    fx_write_jpeg(path, W, H, JCS_CMYK, px, 90, 0, NULL, 0);
    expect_read_error(path, NERF_EFORMAT, "CMYK");
}

/* Set the frame header (SOF0..SOF2) of the JPEG at path to w x h. */
static void claim_size(const char *path, uint32_t w, uint32_t h)
{
    long size = fx_file_size(path);
    uint8_t *b = malloc((size_t)size);
    FILE *f = fopen(path, "rb");
    if (f == NULL || fread(b, 1, (size_t)size, f) != (size_t)size) {
        perror(path);
        exit(1);
    }
    fclose(f);
    long i = 2;
    while (i + 9 < size && !(b[i + 1] >= 0xc0 && b[i + 1] <= 0xc2)) {
        i += 2 + (b[i + 2] << 8 | b[i + 3]);
    }
    CHECK(i + 9 < size);
    b[i + 5] = (uint8_t)(h >> 8);
    b[i + 6] = (uint8_t)h;
    b[i + 7] = (uint8_t)(w >> 8);
    b[i + 8] = (uint8_t)w;
    fx_write_bytes(path, b, (size_t)size);
    free(b);
}

/*
 * A JPEG of 64 x 48 pixels (a few KB) whose header claims 16384 x 16384:
 * Huffman coding spends at least 1 bit on each 8 x 8 block, and 16384^2
 * RGB pixels are 12.6 million blocks, 1.5 MB at least.  Refused before
 * the pixels are allocated, progressive or not; a large flat picture,
 * which Huffman codes in about 2 bits a block, still reads.
 */
TEST(header_claiming_more_than_the_file)
{
    enum { W = 64, H = 48 };
    static uint8_t px[W * H * 3];
    noise(px, sizeof px, 3);
    char path[1024];
    fx_path(path, sizeof path, tmp, "claims.jpg");
    nerf__env env;
    for (int flags = 0; flags < 2; flags++) {
        fx_write_jpeg(path, W, H, JCS_RGB, px, 90, flags, NULL, 0);
        claim_size(path, 16384, 16384);
        largest_alloc_env(&env);
        uint32_t w, h;
        float *rgba = NULL;
        CHECK_EQ_INT(nerf__image_read_rgba(&env, path, &w, &h, &rgba),
                     NERF_EFORMAT);
        CHECK(fx_has(nerf_last_error(), path));
        CHECK(fx_has(nerf_last_error(), "claims 16384x16384 pixels"));
        CHECK_EQ_INT(nerf__image_read_size(&env, path, &w, &h),
                     NERF_EFORMAT);
        CHECK(fx_has(nerf_last_error(), "claims 16384x16384 pixels"));
        /* The file's bytes and libjpeg's state, nothing for pixels. */
        CHECK(largest_alloc < (size_t)fx_file_size(path) + 4096);
    }
    static uint8_t flat[2048 * 2048];
    memset(flat, 128, sizeof flat);
    fx_path(path, sizeof path, tmp, "flat.jpg");
    for (int flags = 0; flags < 4; flags++) {
        fx_write_jpeg(path, 2048, 2048, JCS_GRAYSCALE, flat, 75, flags, NULL,
                      0);
        uint32_t w = 0, h = 0;
        CHECK_OK(nerf__image_read_size(NULL, path, &w, &h));
        CHECK(w == 2048 && h == 2048);
    }
}

/* Grayscale, progressive and arithmetic-coded files read as RGB. */
TEST(colour_spaces_and_codings)
{
    enum { W = 40, H = 24 };
    static uint8_t px[W * H * 3];
    noise(px, sizeof px, 3);
    char path[1024];
    fx_path(path, sizeof path, tmp, "coding.jpg");
    float *ref = NULL, *got = NULL;
    uint32_t w, h;
    fx_write_jpeg(path, W, H, JCS_RGB, px, 85, 0, NULL, 0);
    CHECK_OK(nerf_image_read(path, &w, &h, &ref));
    for (int flags = 1; flags <= 2 && ref != NULL; flags++) {
        /* Same quantised coefficients, another entropy coding: the very
         * same pixels. */
        fx_write_jpeg(path, W, H, JCS_RGB, px, 85, flags, NULL, 0);
        CHECK_OK(nerf_image_read(path, &w, &h, &got));
        CHECK(got != NULL && w == W && h == H &&
              memcmp(got, ref, sizeof(float) * W * H * 4) == 0);
        nerf_free(got);
        got = NULL;
    }
    nerf_free(ref);
    /* Gray: R = G = B, close to the written levels. */
    static uint8_t gray[W * H];
    for (int i = 0; i < W * H; i++) {
        gray[i] = (uint8_t)(16 * ((i % W) / 8) + 40 * ((i / W) / 8));
    }
    fx_write_jpeg(path, W, H, JCS_GRAYSCALE, gray, 100, 0, NULL, 0);
    CHECK_OK(nerf_image_read(path, &w, &h, &got));
    if (got != NULL) {
        double worst = 0.0;
        for (int i = 0; i < W * H; i++) {
            CHECK(got[4 * i] == got[4 * i + 1] && got[4 * i] == got[4 * i + 2]);
            double e = fabs(got[4 * i] - gray[i] / 255.0);
            worst = e > worst ? e : worst;
        }
        CHECK(worst < 3.0 / 255.0);
    }
    nerf_free(got);
}

static void scene_options(nerf_scene_options *o, uint32_t format,
                          uint32_t quality)
{
    NERF_SCENE_OPTIONS_INIT(o);
    o->width = 64;
    o->height = 48;
    o->n_train = 4;
    o->n_val = 0;
    o->n_test = 2;
    o->threads = 2;
    o->image_format = format;
    o->jpeg_quality = quality;
}

/* Mean PSNR of the scene's JPEG views against its PNG views composited
 * on white (what the JPEG writer should store). */
static double scene_psnr(const char *png_dir, const char *jpg_dir)
{
    double sum = 0.0;
    int views = 0;
    for (int i = 0; i < 4; i++) {
        char p[1024], q[1024], name[64];
        snprintf(name, sizeof name, "train/r_%d.png", i);
        fx_path(p, sizeof p, png_dir, name);
        snprintf(name, sizeof name, "train/r_%d.jpg", i);
        fx_path(q, sizeof q, jpg_dir, name);
        float *a = NULL, *b = NULL;
        uint32_t w, h, w2, h2;
        CHECK_OK(nerf_image_read(p, &w, &h, &a));
        CHECK_OK(nerf_image_read(q, &w2, &h2, &b));
        if (a != NULL && b != NULL && w == w2 && h == h2) {
            for (size_t k = 0; k < (size_t)w * h; k++) {
                float al = a[4 * k + 3];
                for (int c = 0; c < 3; c++) {
                    a[4 * k + c] = a[4 * k + c] * al + (1.0f - al);
                }
                a[4 * k + 3] = 1.0f;
            }
            double psnr = 0.0;
            CHECK_OK(nerf_psnr(a, b, (size_t)w * h * 4, &psnr));
            sum += psnr;
            views++;
        }
        nerf_free(a);
        nerf_free(b);
    }
    return views == 4 ? sum / views : 0.0;
}

TEST(scene_round_trip)
{
    char png_dir[1024], jpg_dir[1024], low_dir[1024], p[1024];
    fx_path(png_dir, sizeof png_dir, tmp, "scene_png");
    fx_path(jpg_dir, sizeof jpg_dir, tmp, "scene_jpg");
    fx_path(low_dir, sizeof low_dir, tmp, "scene_jpg10");
    nerf_scene_options o;
    scene_options(&o, NERF_IMAGE_FORMAT_PNG, 0);
    CHECK_OK(nerf_scene_write(png_dir, &o));
    scene_options(&o, NERF_IMAGE_FORMAT_JPEG, 0);
    CHECK_OK(nerf_scene_write(jpg_dir, &o));
    scene_options(&o, NERF_IMAGE_FORMAT_JPEG, 10);
    CHECK_OK(nerf_scene_write(low_dir, &o));
    /* JPEG files only, named in the transforms. */
    struct stat st;
    fx_path(p, sizeof p, jpg_dir, "train/r_0.png");
    CHECK(stat(p, &st) != 0);
    fx_path(p, sizeof p, jpg_dir, "test/r_1.jpg");
    CHECK(stat(p, &st) == 0);
    fx_path(p, sizeof p, jpg_dir, "transforms_train.json");
    FILE *f = fopen(p, "rb");
    char text[4096] = {0};
    if (f != NULL) {
        CHECK(fread(text, 1, sizeof text - 1, f) > 0);
        fclose(f);
    }
    CHECK(fx_has(text, "\"./train/r_3.jpg\""));
    double q95 = scene_psnr(png_dir, jpg_dir);
    double q10 = scene_psnr(png_dir, low_dir);
    printf("  scene JPEG vs PNG on white: %.2f dB at quality 95, %.2f dB "
           "at 10\n", q95, q10);
    CHECK(q95 > 38.0);
    CHECK(q10 < q95 - 8.0);
    /* Bad options. */
    scene_options(&o, 2, 0);
    CHECK_EQ_INT(nerf_scene_write(jpg_dir, &o), NERF_EINVAL);
    CHECK(fx_has(nerf_last_error(), "image_format"));
    scene_options(&o, NERF_IMAGE_FORMAT_JPEG, 101);
    CHECK_EQ_INT(nerf_scene_write(jpg_dir, &o), NERF_EINVAL);
    CHECK(fx_has(nerf_last_error(), "jpeg_quality"));
}

static nerf_dataset *load(const char *dir, uint32_t split)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.split = split;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    return ds;
}

/* The dataset of a JPEG scene: the PNG scene's, up to the coding. */
static void compare_datasets(const char *png_dir, const char *jpg_dir,
                             uint32_t split, uint32_t count)
{
    nerf_dataset *a = load(png_dir, split), *b = load(jpg_dir, split);
    CHECK_EQ_INT(nerf_dataset_count(b), count);
    CHECK_EQ_INT(nerf_dataset_count(a), count);
    for (uint32_t i = 0; a && b && i < count && i < nerf_dataset_count(b);
         i++) {
        const float *pa = NULL, *pb = NULL;
        uint32_t w, h;
        CHECK_OK(nerf_dataset_image(a, i, &pa));
        CHECK_OK(nerf_dataset_image(b, i, &pb));
        CHECK_OK(nerf_dataset_image_size(b, &w, &h));
        CHECK(w == 64 && h == 48);
        double psnr = 0.0;
        CHECK_OK(nerf_psnr(pa, pb, (size_t)w * h * 3, &psnr));
        CHECK(psnr > 38.0);
        nerf_camera ca, cb;
        NERF_CAMERA_INIT(&ca);
        NERF_CAMERA_INIT(&cb);
        CHECK_OK(nerf_dataset_camera(a, i, &ca));
        CHECK_OK(nerf_dataset_camera(b, i, &cb));
        CHECK(memcmp(ca.c2w, cb.c2w, sizeof ca.c2w) == 0 && ca.fx == cb.fx);
    }
    nerf_dataset_destroy(a);
    nerf_dataset_destroy(b);
}

TEST(dataset_from_jpeg_scene)
{
    char png_dir[1024], jpg_dir[1024], p[1024];
    fx_path(png_dir, sizeof png_dir, tmp, "scene_png");
    fx_path(jpg_dir, sizeof jpg_dir, tmp, "scene_jpg");
    compare_datasets(png_dir, jpg_dir, NERF_SPLIT_TRAIN, 4);
    /* Bare file_path names with only JPEGs on disk: found as .jpg. */
    fx_path(p, sizeof p, jpg_dir, "transforms_test.json");
    FILE *f = fopen(p, "rb");
    char text[8192] = {0}, out[8192] = {0};
    size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
    if (f) {
        fclose(f);
    }
    CHECK(n > 0 && fx_has(text, ".jpg\""));
    for (size_t i = 0, o = 0; i < n; i++) {
        if (strncmp(text + i, ".jpg\"", 5) == 0) {
            i += 3; /* keep the quote only */
            continue;
        }
        out[o++] = text[i];
    }
    CHECK(!fx_has(out, ".jpg"));
    fx_write_text(jpg_dir, "transforms_test.json", out);
    compare_datasets(png_dir, jpg_dir, NERF_SPLIT_TEST, 2);
}

/* An LLFF capture as cameras store it: .JPG files. */
TEST(llff_jpeg_folder)
{
    enum { N = 3, W = 32, H = 24 };
    char dir[1024], p[1024];
    fx_path(dir, sizeof dir, tmp, "llff");
    mkdir(dir, 0777);
    fx_mkdir(dir, "images");
    double rows[N * 17];
    for (int i = 0; i < N; i++) {
        double *r = rows + 17 * i;
        memset(r, 0, sizeof(double) * 17);
        r[0] = r[6] = r[12] = 1.0; /* identity rotation, columns x y z */
        r[3] = 0.1 * i;
        r[13] = 0.0;
        r[4] = H;
        r[9] = W;
        r[14] = 30.0;
        r[15] = 2.0;
        r[16] = 10.0;
    }
    fx_path(p, sizeof p, dir, "poses_bounds.npy");
    fx_write_npy(p, "<f8", "False", "(3, 17)", rows, sizeof rows);
    static uint8_t px[W * H * 3];
    for (int i = 0; i < N; i++) {
        memset(px, 60 + 60 * i, sizeof px);
        char name[64];
        snprintf(name, sizeof name, "images/DSC_%d.%s", i,
                 i == 1 ? "jpeg" : "JPG");
        fx_path(p, sizeof p, dir, name);
        fx_write_jpeg(p, W, H, JCS_RGB, px, 95, 0, NULL, 0);
    }
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.llff_holdout = 0;
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, &o));
    CHECK_EQ_INT(nerf_dataset_count(ds), N);
    for (uint32_t i = 0; ds && i < nerf_dataset_count(ds); i++) {
        const float *rgb = NULL;
        CHECK_OK(nerf_dataset_image(ds, i, &rgb));
        if (rgb != NULL) {
            CHECK_NEAR(rgb[0], (60 + 60 * i) / 255.0, 2.0 / 255.0);
        }
    }
    nerf_dataset_destroy(ds);
    /* A bad file among them is named. */
    fx_path(p, sizeof p, dir, "images/DSC_2.JPG");
    fx_truncate(p, fx_file_size(p) - 20);
    CHECK_EQ_INT(nerf_dataset_load(&ds, dir, &o), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "DSC_2.JPG: corrupted or truncated"));
    CHECK(ds == NULL);
}

int main(void)
{
    tmp = fx_make_temp_dir();
    RUN(exif_orientations);
    RUN(bad_exif);
    RUN(bad_files);
    RUN(header_claiming_more_than_the_file);
    RUN(colour_spaces_and_codings);
    RUN(scene_round_trip);
    RUN(dataset_from_jpeg_scene);
    RUN(llff_jpeg_folder);
    fx_remove_tree(tmp);
    HARNESS_EXIT();
}
