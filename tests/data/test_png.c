/* PNG reading and writing: every colour type and depth, and bad files. */
#include <nerf.h>

#include <sys/stat.h>

#include "data_fixtures.h"
#include "image_read.h"
#include "largest_alloc.h"
#include "png_io.h"
#include "../harness.h"

static char *tmp;

static void path_of(char *buf, const char *name)
{
    fx_path(buf, 1024, tmp, name);
}

/* Deterministic sample values covering the full range. */
static uint16_t sample(size_t i, uint32_t max)
{
    return (uint16_t)((i * 2654435761u) % (max + 1u));
}

TEST(float_rgb_round_trip)
{
    char p[1024];
    path_of(p, "rgb.png");
    enum { W = 7, H = 5 };
    float px[W * H * 3];
    for (int i = 0; i < W * H * 3; i++) {
        px[i] = (float)sample((size_t)i, 255) / 255.0f;
    }
    CHECK_OK(nerf_image_write_png(p, W, H, 3, px));
    uint32_t w, h;
    float *rgba = NULL;
    CHECK_OK(nerf_image_read_png(p, &w, &h, &rgba));
    CHECK_EQ_INT(w, W);
    CHECK_EQ_INT(h, H);
    int bad = 0;
    for (int i = 0; i < W * H && rgba; i++) {
        for (int c = 0; c < 3; c++) {
            bad += rgba[4 * i + c] != px[3 * i + c];
        }
        bad += rgba[4 * i + 3] != 1.0f;
    }
    CHECK_EQ_INT(bad, 0);
    nerf_free(rgba);
}

TEST(float_write_clamps_and_rounds)
{
    char p[1024];
    path_of(p, "clamp.png");
    float px[6] = {-1.0f, 2.0f, NAN, 0.5f, 0.25f, 0.75f};
    CHECK_OK(nerf_image_write_png(p, 2, 1, 3, px));
    uint32_t w, h;
    float *rgba = NULL;
    CHECK_OK(nerf_image_read_png(p, &w, &h, &rgba));
    if (rgba) {
        CHECK_EQ_INT(rgba[0] * 255.0f, 0);
        CHECK_EQ_INT(rgba[1] * 255.0f, 255);
        CHECK_EQ_INT(rgba[2] * 255.0f, 0);
        CHECK_NEAR(rgba[4] * 255.0f, 128, 1e-4); /* 127.5 rounds up */
        CHECK_NEAR(rgba[5] * 255.0f, 64, 1e-4);  /* 63.75 */
        CHECK_NEAR(rgba[6] * 255.0f, 191, 1e-4); /* 191.25 */
    }
    nerf_free(rgba);
}

TEST(gray_write_and_8bit_variant)
{
    char p[1024];
    path_of(p, "depth.png");
    uint8_t g[12];
    for (int i = 0; i < 12; i++) {
        g[i] = (uint8_t)(i * 21);
    }
    CHECK_OK(nerf_image_write_png8(p, 4, 3, 1, g));
    uint32_t w, h;
    float *rgba = NULL;
    CHECK_OK(nerf_image_read_png(p, &w, &h, &rgba));
    int bad = 0;
    for (int i = 0; i < 12 && rgba; i++) {
        for (int c = 0; c < 3; c++) {
            bad += rgba[4 * i + c] != g[i] / 255.0f;
        }
        bad += rgba[4 * i + 3] != 1.0f;
    }
    CHECK_EQ_INT(bad, 0);
    nerf_free(rgba);
}

/* Read a fixture written by the hand encoder and compare with expected
 * RGBA values. */
static void check_fixture(const char *name, uint32_t w, uint32_t h,
                          const float *expect, double tol)
{
    char p[1024];
    path_of(p, name);
    uint32_t rw = 0, rh = 0;
    float *rgba = NULL;
    CHECK_OK(nerf_image_read_png(p, &rw, &rh, &rgba));
    CHECK_EQ_INT(rw, w);
    CHECK_EQ_INT(rh, h);
    double worst = 0.0;
    for (size_t i = 0; i < (size_t)w * h * 4 && rgba; i++) {
        double d = fabs((double)rgba[i] - expect[i]);
        worst = d > worst ? d : worst;
    }
    CHECK(rgba != NULL);
    if (!(worst <= tol)) {
        FAILF("%s: worst difference %g (tol %g)", name, worst, tol);
    }
    nerf_free(rgba);
}

TEST(gray8_and_gray_alpha8)
{
    enum { W = 5, H = 4, N = W * H };
    uint16_t g[N], ga[2 * N];
    float e1[4 * N], e2[4 * N];
    for (int i = 0; i < N; i++) {
        g[i] = sample((size_t)i, 255);
        ga[2 * i] = sample((size_t)i + 7, 255);
        ga[2 * i + 1] = sample((size_t)i + 3, 255);
        for (int c = 0; c < 3; c++) {
            e1[4 * i + c] = g[i] / 255.0f;
            e2[4 * i + c] = ga[2 * i] / 255.0f;
        }
        e1[4 * i + 3] = 1.0f;
        e2[4 * i + 3] = ga[2 * i + 1] / 255.0f;
    }
    char p[1024];
    path_of(p, "g8.png");
    fx_write_png(p, W, H, 0, 8, g, NULL, 0, NULL, 0);
    path_of(p, "ga8.png");
    fx_write_png(p, W, H, 4, 8, ga, NULL, 0, NULL, 0);
    check_fixture("g8.png", W, H, e1, 0.0);
    check_fixture("ga8.png", W, H, e2, 0.0);
}

TEST(rgba8_and_palette)
{
    enum { W = 6, H = 3, N = W * H };
    uint16_t s[4 * N], idx[N];
    float e[4 * N], ep[4 * N];
    unsigned char plte[3 * 4] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 10, 20, 30};
    unsigned char trns[4] = {255, 128, 0, 255};
    for (int i = 0; i < 4 * N; i++) {
        s[i] = sample((size_t)i, 255);
        e[i] = s[i] / 255.0f;
    }
    for (int i = 0; i < N; i++) {
        idx[i] = (uint16_t)(i % 4);
        for (int c = 0; c < 3; c++) {
            ep[4 * i + c] = plte[3 * idx[i] + c] / 255.0f;
        }
        ep[4 * i + 3] = trns[idx[i]] / 255.0f;
    }
    char p[1024];
    path_of(p, "rgba8.png");
    fx_write_png(p, W, H, 6, 8, s, NULL, 0, NULL, 0);
    path_of(p, "pal.png");
    fx_write_png(p, W, H, 3, 8, idx, plte, 4, trns, 4);
    check_fixture("rgba8.png", W, H, e, 0.0);
    check_fixture("pal.png", W, H, ep, 0.0);
}

TEST(sixteen_bit)
{
    enum { W = 4, H = 3, N = W * H };
    uint16_t g[N], rgb[3 * N], rgba[4 * N];
    float eg[4 * N], ergb[4 * N], ergba[4 * N];
    for (int i = 0; i < N; i++) {
        g[i] = sample((size_t)i * 977 + 5, 65535);
        for (int c = 0; c < 3; c++) {
            rgb[3 * i + c] = sample((size_t)(3 * i + c) * 7919 + 11, 65535);
            rgba[4 * i + c] = sample((size_t)(4 * i + c) * 104729 + 3, 65535);
            eg[4 * i + c] = g[i] / 65535.0f;
            ergb[4 * i + c] = rgb[3 * i + c] / 65535.0f;
            ergba[4 * i + c] = rgba[4 * i + c] / 65535.0f;
        }
        /* Alphas from 1/4 to opaque: premultiplication round-off stays
         * below 4/65535 there. */
        rgba[4 * i + 3] = (uint16_t)(16384 + (49151u * (unsigned)i) / (N - 1));
        eg[4 * i + 3] = ergb[4 * i + 3] = 1.0f;
        ergba[4 * i + 3] = rgba[4 * i + 3] / 65535.0f;
    }
    char p[1024];
    path_of(p, "g16.png");
    fx_write_png(p, W, H, 0, 16, g, NULL, 0, NULL, 0);
    path_of(p, "rgb16.png");
    fx_write_png(p, W, H, 2, 16, rgb, NULL, 0, NULL, 0);
    path_of(p, "rgba16.png");
    fx_write_png(p, W, H, 6, 16, rgba, NULL, 0, NULL, 0);
    check_fixture("g16.png", W, H, eg, 1e-7);
    check_fixture("rgb16.png", W, H, ergb, 1e-7);
    check_fixture("rgba16.png", W, H, ergba, 4.0 / 65535.0);
}

static void expect_read_error(const char *name, int status, const char *what)
{
    char p[1024];
    path_of(p, name);
    uint32_t w = 1, h = 1;
    float *rgba = (float *)&w;
    int rc = nerf_image_read_png(p, &w, &h, &rgba);
    CHECK_EQ_INT(rc, status);
    CHECK(rgba == NULL);
    CHECK(fx_has(nerf_last_error(), p));
    if (what && !fx_has(nerf_last_error(), what)) {
        FAILF("%s: message '%s' lacks '%s'", name, nerf_last_error(), what);
    }
}

TEST(bad_files)
{
    char p[1024];
    expect_read_error("missing.png", NERF_ENOENT, "cannot open");

    path_of(p, "empty.png");
    fx_write_bytes(p, "", 0);
    expect_read_error("empty.png", NERF_EFORMAT, NULL);

    path_of(p, "text.png");
    fx_write_bytes(p, "this is not a png at all", 24);
    expect_read_error("text.png", NERF_EFORMAT, NULL);

    /* Cut inside the image data: the header reads, the pixels do not. */
    enum { W = 32, H = 32 };
    uint16_t s[W * H * 3];
    for (int i = 0; i < W * H * 3; i++) {
        s[i] = sample((size_t)i, 255);
    }
    path_of(p, "cut.png");
    fx_write_png(p, W, H, 2, 8, s, NULL, 0, NULL, 0);
    fx_truncate(p, fx_file_size(p) / 2);
    expect_read_error("cut.png", NERF_EFORMAT, NULL);

    /* A flipped byte in the compressed data breaks the IDAT CRC. */
    path_of(p, "crc.png");
    fx_write_png(p, W, H, 2, 8, s, NULL, 0, NULL, 0);
    FILE *f = fopen(p, "r+b");
    fseek(f, 60, SEEK_SET);
    int ch = fgetc(f);
    fseek(f, 60, SEEK_SET);
    fputc(ch ^ 0x55, f);
    fclose(f);
    expect_read_error("crc.png", NERF_EFORMAT, NULL);

    /* A valid header announcing an absurd width is refused up front. */
    uint16_t *row = calloc(20000 * 3, sizeof *row);
    path_of(p, "huge.png");
    fx_write_png(p, 20000, 1, 2, 8, row, NULL, 0, NULL, 0);
    free(row);
    expect_read_error("huge.png", NERF_EFORMAT, "limit");

    CHECK_EQ_INT(nerf_image_read_png(NULL, NULL, NULL, NULL), NERF_EINVAL);
}

/* Rewrite the IHDR of the PNG at path to claim w x h, CRC included. */
static void claim_size(const char *path, uint32_t w, uint32_t h)
{
    FILE *f = fopen(path, "r+b");
    unsigned char ihdr[17]; /* "IHDR" and its 13 bytes */
    if (f == NULL || fseek(f, 12, SEEK_SET) != 0 ||
        fread(ihdr, 1, sizeof ihdr, f) != sizeof ihdr) {
        perror(path);
        exit(1);
    }
    fx_be32(ihdr + 4, w);
    fx_be32(ihdr + 8, h);
    unsigned char crc[4];
    fx_be32(crc, (uint32_t)crc32(0L, ihdr, sizeof ihdr));
    fseek(f, 12, SEEK_SET);
    fwrite(ihdr, 1, sizeof ihdr, f);
    fwrite(crc, 1, sizeof crc, f);
    fclose(f);
}

/*
 * A header claiming 16384 x 16384 pixels in a file of a hundred bytes:
 * such a PNG takes at least 16384^2 / 8 / 1032 = 32520 bytes (1 bit a
 * pixel, deflated 1032 times), so it is refused before the 4 GiB of its
 * float pixels are asked for; nothing larger than the file is.
 */
TEST(header_claiming_more_than_the_file)
{
    char p[1024];
    path_of(p, "claims.png");
    uint16_t s[4 * 4 * 4] = {0};
    fx_write_png(p, 4, 4, 6, 8, s, NULL, 0, NULL, 0);
    claim_size(p, 16384, 16384);
    nerf__env env;
    largest_alloc_env(&env);
    uint32_t w = 0, h = 0;
    float *rgba = NULL;
    CHECK_EQ_INT(nerf__png_read_rgba(&env, p, &w, &h, &rgba), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), p));
    CHECK(fx_has(nerf_last_error(), "claims 16384x16384 pixels"));
    CHECK_EQ_INT(nerf__image_read_rgba(&env, p, &w, &h, &rgba),
                 NERF_EFORMAT);
    CHECK_EQ_INT(nerf__image_read_size(&env, p, &w, &h), NERF_EFORMAT);
    CHECK(fx_has(nerf_last_error(), "claims 16384x16384 pixels"));
    CHECK(largest_alloc < 4096);
    /* A large picture that deflates well is no such claim: 2048 x 2048
     * of one grey in under 20 KB, read at its size. */
    uint16_t *flat = calloc((size_t)2048 * 2048, sizeof *flat);
    path_of(p, "flat.png");
    fx_write_png(p, 2048, 2048, 0, 8, flat, NULL, 0, NULL, 0);
    free(flat);
    CHECK(fx_file_size(p) < 20000);
    CHECK_OK(nerf__image_read_size(&env, p, &w, &h));
    CHECK(w == 2048 && h == 2048);
    CHECK_OK(nerf__image_read_rgba(&env, p, &w, &h, &rgba));
    nerf__free(&env, rgba);
}

/* What is not a regular file is refused, saying what it is, and never
 * opened for reading: a FIFO without a writer would block. */
TEST(not_regular_files)
{
    char p[1024];
    path_of(p, "fifo.png");
    CHECK(mkfifo(p, 0666) == 0);
    expect_read_error("fifo.png", NERF_EUNRECOGNISED,
                      "a FIFO (named pipe), not a regular file");
    uint32_t w, h;
    CHECK_EQ_INT(nerf__image_read_size(NULL, p, &w, &h), NERF_EUNRECOGNISED);
    float *rgba = NULL;
    CHECK_EQ_INT(nerf_image_read(p, &w, &h, &rgba), NERF_EUNRECOGNISED);
    CHECK(fx_has(nerf_last_error(), "a FIFO"));
    path_of(p, "folder.png");
    CHECK(mkdir(p, 0777) == 0);
    expect_read_error("folder.png", NERF_EUNRECOGNISED,
                      "a folder, not a file");
    CHECK_EQ_INT(nerf_image_read("/dev/null", &w, &h, &rgba),
                 NERF_EUNRECOGNISED);
    CHECK(fx_has(nerf_last_error(), "/dev/null: a character device"));
}

TEST(write_errors_and_atomicity)
{
    char p[1024];
    float px[12] = {0};
    path_of(p, "w.png");
    CHECK_EQ_INT(nerf_image_write_png(p, 2, 2, 2, px), NERF_EINVAL);
    CHECK_EQ_INT(nerf_image_write_png(p, 0, 2, 3, px), NERF_EINVAL);
    CHECK_EQ_INT(nerf_image_write_png(p, 20000, 1, 3, px), NERF_EINVAL);
    CHECK_EQ_INT(nerf_image_write_png(NULL, 2, 2, 3, px), NERF_EINVAL);
    CHECK_EQ_INT(nerf_image_write_png(p, 2, 2, 3, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_image_write_png8(p, 2, 2, 5, (const uint8_t *)px),
                 NERF_EINVAL);
    path_of(p, "no/such/folder/w.png");
    CHECK_EQ_INT(nerf_image_write_png(p, 2, 2, 3, px), NERF_EIO);
    CHECK(fx_has(nerf_last_error(), p));

    /* Replacing a file leaves the new image and no temporary behind. */
    path_of(p, "replace.png");
    fx_write_bytes(p, "old", 3);
    CHECK_OK(nerf_image_write_png(p, 2, 2, 3, px));
    uint32_t w, h;
    float *rgba = NULL;
    CHECK_OK(nerf_image_read_png(p, &w, &h, &rgba));
    nerf_free(rgba);
    DIR *d = opendir(tmp);
    int temps = 0;
    for (struct dirent *e = d ? readdir(d) : NULL; e; e = readdir(d)) {
        temps += strstr(e->d_name, ".tmp") != NULL;
    }
    if (d) {
        closedir(d);
    }
    CHECK_EQ_INT(temps, 0);
    nerf_free(NULL);
}

int main(void)
{
    tmp = fx_make_temp_dir();
    RUN(float_rgb_round_trip);
    RUN(float_write_clamps_and_rounds);
    RUN(gray_write_and_8bit_variant);
    RUN(gray8_and_gray_alpha8);
    RUN(rgba8_and_palette);
    RUN(sixteen_bit);
    RUN(bad_files);
    RUN(header_claiming_more_than_the_file);
    RUN(not_regular_files);
    RUN(write_errors_and_atomicity);
    fx_remove_tree(tmp);
    HARNESS_EXIT();
}
