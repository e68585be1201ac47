/*
 * nerf_camera_path_load: .npy arrays of every accepted shape and dtype,
 * transforms-style JSON files, the options, and a refusal with a clear
 * message (naming the file) for each kind of bad input.
 */
#include <math.h>
#include <string.h>

#include "../data/data_fixtures.h"
#include "../fail_alloc.h"
#include "../harness.h"
#include "nerf.h"

static char dir[512];

/* Three distinct rigid poses: a camera at (i, 2i, 4 + i) turned by i/2
 * radians about world y. */
static void pose(int i, double m[16])
{
    double a = 0.5 * i, c = cos(a), s = sin(a);
    const double v[16] = {c, 0, s, i, 0, 1, 0, 2 * i, -s, 0, c, 4 + i,
                          0, 0, 0, 1};
    memcpy(m, v, sizeof v);
}

/*
 * Write N = 3 poses as a .npy: rows 3 or 4 of each matrix, as float32 or
 * float64, shaped as shape (such as "(3, 3, 4)" or "(3, 12)").
 */
static void write_poses(const char *name, int rows, int f8, const char *shape)
{
    double d[3 * 16];
    float f[3 * 16];
    size_t n = 0;
    for (int i = 0; i < 3; i++) {
        double m[16];
        pose(i, m);
        for (int k = 0; k < rows * 4; k++, n++) {
            d[n] = m[k];
            f[n] = (float)m[k];
        }
    }
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    fx_write_npy(p, f8 ? "<f8" : "<f4", "False", shape,
                 f8 ? (const void *)d : (const void *)f,
                 n * (f8 ? sizeof *d : sizeof *f));
}

static nerf_camera_path *load(const char *name,
                              const nerf_camera_path_options *o)
{
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    nerf_camera_path *cp = NULL;
    int rc = nerf_camera_path_load(&cp, p, o);
    if (rc != NERF_OK) {
        FAILF("loading %s: %d: %s", name, rc, nerf_last_error());
    }
    return cp;
}

static void opts(nerf_camera_path_options *o, uint32_t w, uint32_t h,
                 float focal, float fov_x)
{
    NERF_CAMERA_PATH_OPTIONS_INIT(o);
    o->width = w;
    o->height = h;
    o->focal = focal;
    o->fov_x = fov_x;
}

/* Camera i of cp against pose(i), with the given size and intrinsics. */
static void check_camera(const nerf_camera_path *cp, uint32_t i, uint32_t w,
                         uint32_t h, double fx, double fy, double cx,
                         double cy)
{
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_camera_path_camera(cp, i, &cam));
    double m[16];
    pose((int)i, m);
    for (int k = 0; k < 12; k++) {
        CHECK_NEAR(cam.c2w[k], m[k], 1e-6);
    }
    CHECK_EQ_INT(cam.width, w);
    CHECK_EQ_INT(cam.height, h);
    CHECK_EQ_INT(cam.flags, 0);
    CHECK_NEAR(cam.fx, fx, 1e-3);
    CHECK_NEAR(cam.fy, fy, 1e-3);
    CHECK_NEAR(cam.cx, cx, 1e-4);
    CHECK_NEAR(cam.cy, cy, 1e-4);
}

TEST(npy_shapes_and_dtypes)
{
    static const struct {
        const char *name;
        int rows, f8;
        const char *shape;
    } files[] = {
        {"a.npy", 3, 0, "(3, 3, 4)"}, {"b.npy", 4, 0, "(3, 4, 4)"},
        {"c.npy", 3, 1, "(3, 3, 4)"}, {"d.npy", 4, 1, "(3, 4, 4)"},
        {"e.npy", 3, 0, "(3, 12)"},   {"f.npy", 4, 1, "(3, 16)"},
    };
    nerf_camera_path_options o;
    /* fov_x 90 degrees: focal = half the width. */
    opts(&o, 64, 48, 0.0f, 90.0f);
    for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
        write_poses(files[k].name, files[k].rows, files[k].f8,
                    files[k].shape);
        nerf_camera_path *cp = load(files[k].name, &o);
        CHECK_EQ_INT(nerf_camera_path_count(cp), 3);
        for (uint32_t i = 0; i < 3 && cp; i++) {
            check_camera(cp, i, 64, 48, 32.0, 32.0, 32.0, 24.0);
        }
        nerf_camera_path_destroy(cp);
    }
    /* An explicit focal, and a .npy recognised by its magic whatever its
     * name. */
    write_poses("poses.bin", 3, 1, "(3, 3, 4)");
    opts(&o, 20, 10, 17.5f, 0.0f);
    nerf_camera_path *cp = load("poses.bin", &o);
    check_camera(cp, 2, 20, 10, 17.5, 17.5, 10.0, 5.0);
    nerf_camera_path_destroy(cp);
}

/* Expect load(name, o) to fail with status and a message naming the file
 * and holding word. */
static void expect_failure(const char *name, const nerf_camera_path_options *o,
                           int status, const char *word)
{
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    nerf_camera_path *cp = (nerf_camera_path *)dir;
    int rc = nerf_camera_path_load(&cp, p, o);
    if (rc != status || cp != NULL || !fx_has(nerf_last_error(), name) ||
        !fx_has(nerf_last_error(), word)) {
        FAILF("%s: status %d (want %d), message '%s' (want '%s')", name, rc,
              status, nerf_last_error(), word);
    }
}

TEST(npy_needs_size_and_focal)
{
    write_poses("p.npy", 3, 0, "(3, 3, 4)");
    nerf_camera_path_options o;
    opts(&o, 0, 0, 0.0f, 50.0f);
    expect_failure("p.npy", &o, NERF_EINVAL, "set width and height");
    expect_failure("p.npy", NULL, NERF_EINVAL, "set width and height");
    opts(&o, 32, 32, 0.0f, 0.0f);
    expect_failure("p.npy", &o, NERF_EINVAL, "set focal or fov_x");
    /* The file-size flag alone does not help a file without a size. */
    opts(&o, 32, 32, 0.0f, 50.0f);
    o.flags = NERF_CAMERA_PATH_FILE_SIZE;
    nerf_camera_path *cp = load("p.npy", &o);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_camera_path_camera(cp, 0, &cam));
    CHECK_EQ_INT(cam.width, 32);
    CHECK_NEAR(cam.fx, 16.0 / tan(25.0 * M_PI / 180.0), 1e-3);
    nerf_camera_path_destroy(cp);
}

/* A .npy of 2 poses, 4 x 4 float64, with value v at flat index at. */
static void write_edited(const char *name, size_t at, double v)
{
    double d[2 * 16];
    pose(0, d);
    pose(1, d + 16);
    d[at] = v;
    char p[1024];
    fx_path(p, sizeof p, dir, name);
    fx_write_npy(p, "<f8", "False", "(2, 4, 4)", d, sizeof d);
}

TEST(npy_bad)
{
    nerf_camera_path_options o;
    opts(&o, 16, 16, 0.0f, 50.0f);
    char p[1024];
    float z[64] = {0};
    fx_path(p, sizeof p, dir, "shape.npy");
    fx_write_npy(p, "<f4", "False", "(4, 3, 3)", z, 36 * sizeof *z);
    expect_failure("shape.npy", &o, NERF_EFORMAT, "shape is (4, 3, 3)");
    fx_path(p, sizeof p, dir, "one.npy");
    fx_write_npy(p, "<f4", "False", "(4, 4)", z, 16 * sizeof *z);
    expect_failure("one.npy", &o, NERF_EFORMAT, "(N, 3, 4), (N, 4, 4)");
    fx_path(p, sizeof p, dir, "flat.npy");
    fx_write_npy(p, "<f4", "False", "(24,)", z, 24 * sizeof *z);
    expect_failure("flat.npy", &o, NERF_EFORMAT, "shape is (24,)");
    fx_path(p, sizeof p, dir, "empty.npy");
    fx_write_npy(p, "<f4", "False", "(0, 3, 4)", z, 0);
    expect_failure("empty.npy", &o, NERF_EFORMAT, "no poses");
    fx_path(p, sizeof p, dir, "int.npy");
    fx_write_npy(p, "<i4", "False", "(1, 3, 4)", z, 12 * 4);
    expect_failure("int.npy", &o, NERF_EFORMAT, "dtype '<i4'");
    fx_path(p, sizeof p, dir, "big.npy");
    fx_write_npy(p, ">f4", "False", "(1, 3, 4)", z, 12 * 4);
    expect_failure("big.npy", &o, NERF_EFORMAT, "big-endian");
    fx_path(p, sizeof p, dir, "fortran.npy");
    fx_write_npy(p, "<f4", "True", "(1, 3, 4)", z, 12 * 4);
    expect_failure("fortran.npy", &o, NERF_EFORMAT, "Fortran order");
    fx_path(p, sizeof p, dir, "short.npy");
    fx_write_npy(p, "<f4", "False", "(2, 3, 4)", z, 12 * 4);
    expect_failure("short.npy", &o, NERF_EFORMAT, "npy");

    /* Truncated anywhere: in the data, in the header, in the magic. */
    write_poses("cut.npy", 4, 1, "(3, 4, 4)");
    fx_path(p, sizeof p, dir, "cut.npy");
    long size = fx_file_size(p);
    const long keep[] = {size - 1, 70, 20, 3, 0};
    for (size_t k = 0; k < sizeof keep / sizeof keep[0]; k++) {
        write_poses("cut.npy", 4, 1, "(3, 4, 4)");
        fx_truncate(p, keep[k]);
        expect_failure("cut.npy", &o, NERF_EFORMAT, "cut.npy: ");
    }

    write_edited("nan.npy", 16 + 5, NAN);
    expect_failure("nan.npy", &o, NERF_EFORMAT, "pose 1 has a NaN");
    write_edited("inf.npy", 3, -INFINITY);
    expect_failure("inf.npy", &o, NERF_EFORMAT, "pose 0 has a NaN or "
                   "infinite value");
    write_edited("inf_row.npy", 16 + 14, INFINITY);
    expect_failure("inf_row.npy", &o, NERF_EFORMAT, "pose 1 has a NaN");
    write_edited("row.npy", 16 + 14, 0.5);
    expect_failure("row.npy", &o, NERF_EFORMAT, "[0, 0, 0, 1]");
    write_edited("huge.npy", 3, 1e300);
    expect_failure("huge.npy", &o, NERF_EFORMAT, "pose 0 has an entry of "
                   "magnitude 1e+300, beyond");
    write_edited("far.npy", 16 + 7, -2e6);
    expect_failure("far.npy", &o, NERF_EFORMAT, "pose 1 has an entry of "
                   "magnitude 2e+06, beyond");
    double flat[2 * 16];
    pose(0, flat);
    pose(1, flat + 16);
    for (int k = 0; k < 3; k++) {
        flat[16 + 4 + k] = 0.0; /* pose 1's second row of R: degenerate */
    }
    fx_path(p, sizeof p, dir, "degenerate.npy");
    fx_write_npy(p, "<f8", "False", "(2, 16)", flat, sizeof flat);
    expect_failure("degenerate.npy", &o, NERF_EFORMAT,
                   "pose 1 has a degenerate rotation");
    expect_failure("missing.npy", &o, NERF_ENOENT, "missing.npy");
}

/* A Blender test split: camera_angle_x, no image size. */
static void write_blender(const char *name)
{
    char text[4096];
    size_t n = (size_t)snprintf(text, sizeof text,
                                "{\"camera_angle_x\": 0.6911112070083618,\n"
                                " \"frames\": [");
    for (int i = 0; i < 3; i++) {
        double m[16];
        pose(i, m);
        n += (size_t)snprintf(text + n, sizeof text - n,
                              "%s\n  {\"file_path\": \"./test/r_%d\", "
                              "\"rotation\": 0.1, \"transform_matrix\": [",
                              i ? "," : "", i);
        for (int r = 0; r < 4; r++) {
            n += (size_t)snprintf(text + n, sizeof text - n,
                                  "%s[%.17g, %.17g, %.17g, %.17g]",
                                  r ? ", " : "", m[4 * r], m[4 * r + 1],
                                  m[4 * r + 2], m[4 * r + 3]);
        }
        n += (size_t)snprintf(text + n, sizeof text - n, "]}");
    }
    snprintf(text + n, sizeof text - n, "\n]}\n");
    fx_write_text(dir, name, text);
}

TEST(json_blender)
{
    write_blender("transforms_test.json");
    nerf_camera_path_options o;
    /* No size in the file, none in the options. */
    expect_failure("transforms_test.json", NULL, NERF_EINVAL,
                   "frame 0 (./test/r_0): the file gives no image size "
                   "(w, h): set width and height");
    opts(&o, 100, 80, 0.0f, 0.0f);
    nerf_camera_path *cp = load("transforms_test.json", &o);
    CHECK_EQ_INT(nerf_camera_path_count(cp), 3);
    double f = 50.0 / tan(0.5 * 0.6911112070083618);
    for (uint32_t i = 0; i < 3 && cp; i++) {
        check_camera(cp, i, 100, 80, f, f, 50.0, 40.0);
    }
    nerf_camera_path_destroy(cp);
    /* With the file-size flag, width and height are the fallback. */
    o.flags = NERF_CAMERA_PATH_FILE_SIZE;
    cp = load("transforms_test.json", &o);
    check_camera(cp, 1, 100, 80, f, f, 50.0, 40.0);
    nerf_camera_path_destroy(cp);
    /* fov_x replaces the file's angle. */
    opts(&o, 100, 80, 0.0f, 90.0f);
    cp = load("transforms_test.json", &o);
    check_camera(cp, 0, 100, 80, 50.0, 50.0, 50.0, 40.0);
    nerf_camera_path_destroy(cp);
}

/* instant-ngp style: intrinsics and size at top level, frame 1 its own. */
static const char ngp_json[] =
    "{\"fl_x\": 40, \"fl_y\": 36, \"cx\": 31, \"cy\": 23, \"w\": 64,"
    " \"h\": 48,\n \"frames\": [\n"
    "  {\"transform_matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4],"
    " [0, 0, 0, 1]]},\n"
    "  {\"fl_x\": 20, \"fl_y\": 20, \"cx\": 16, \"cy\": 8, \"w\": 32,"
    " \"h\": 16, \"transform_matrix\": [[1, 0, 0, 1], [0, 1, 0, 2],"
    " [0, 0, 1, 3]]}\n]}\n";

TEST(json_instant_ngp)
{
    fx_write_text(dir, "transforms.json", ngp_json);
    nerf_camera_path *cp = load("transforms.json", NULL);
    CHECK_EQ_INT(nerf_camera_path_count(cp), 2);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_camera_path_camera(cp, 0, &cam));
    CHECK(cam.width == 64 && cam.height == 48);
    CHECK(cam.fx == 40.0f && cam.fy == 36.0f && cam.cx == 31.0f &&
          cam.cy == 23.0f);
    CHECK(cam.c2w[0] == 1.0f && cam.c2w[11] == 4.0f);
    /* The centre pixel of the first camera looks down -z from (0, 0, 4). */
    float o3[3], d3[3];
    CHECK_OK(nerf_camera_rays(&cam, 23 * 64 + 31, 1, o3, d3));
    CHECK(o3[2] == 4.0f);
    CHECK_NEAR(d3[2], -1.0, 1e-6);
    CHECK_OK(nerf_camera_path_camera(cp, 1, &cam));
    CHECK(cam.width == 32 && cam.height == 16 && cam.fx == 20.0f &&
          cam.cy == 8.0f && cam.c2w[3] == 1.0f && cam.c2w[7] == 2.0f);
    nerf_camera_path_destroy(cp);

    /* Half the width, a third of the height: intrinsics follow. */
    nerf_camera_path_options o;
    opts(&o, 32, 16, 0.0f, 0.0f);
    cp = load("transforms.json", &o);
    CHECK_OK(nerf_camera_path_camera(cp, 0, &cam));
    CHECK(cam.width == 32 && cam.height == 16);
    CHECK_NEAR(cam.fx, 20.0, 1e-5);
    CHECK_NEAR(cam.fy, 12.0, 1e-5);
    CHECK_NEAR(cam.cx, 15.5, 1e-5);
    CHECK_NEAR(cam.cy, 23.0 / 3.0, 1e-5);
    CHECK_OK(nerf_camera_path_camera(cp, 1, &cam));
    CHECK(cam.width == 32 && cam.height == 16 && cam.fx == 20.0f &&
          cam.cx == 16.0f && cam.cy == 8.0f);
    nerf_camera_path_destroy(cp);
    /* The file-size flag keeps the file's sizes. */
    o.flags = NERF_CAMERA_PATH_FILE_SIZE;
    cp = load("transforms.json", &o);
    CHECK_OK(nerf_camera_path_camera(cp, 0, &cam));
    CHECK(cam.width == 64 && cam.fx == 40.0f);
    nerf_camera_path_destroy(cp);
    /* An explicit focal replaces the file's, principal point centred. */
    opts(&o, 0, 0, 10.0f, 0.0f);
    cp = load("transforms.json", &o);
    CHECK_OK(nerf_camera_path_camera(cp, 1, &cam));
    CHECK(cam.width == 32 && cam.fx == 10.0f && cam.fy == 10.0f &&
          cam.cx == 16.0f && cam.cy == 8.0f);
    nerf_camera_path_destroy(cp);
    /* Unless the file's intrinsics come first. */
    o.flags = NERF_CAMERA_PATH_FILE_INTRINSICS;
    cp = load("transforms.json", &o);
    CHECK_OK(nerf_camera_path_camera(cp, 1, &cam));
    CHECK(cam.width == 32 && cam.fx == 20.0f && cam.cx == 16.0f);
    nerf_camera_path_destroy(cp);
}

TEST(json_fallback_intrinsics)
{
    /* No focal in the file: focal or fov_x serve, whatever the flags. */
    fx_write_text(dir, "bare.json",
                  "{\"frames\": [{\"transform_matrix\": [[1, 0, 0, 0], "
                  "[0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]}]}");
    expect_failure("bare.json", NULL, NERF_EINVAL, "set width and height");
    nerf_camera_path_options o;
    opts(&o, 10, 10, 0.0f, 0.0f);
    expect_failure("bare.json", &o, NERF_EFORMAT,
                   "missing field 'camera_angle_x' (or 'fl_x')");
    opts(&o, 10, 10, 0.0f, 90.0f);
    o.flags = NERF_CAMERA_PATH_FILE_SIZE | NERF_CAMERA_PATH_FILE_INTRINSICS;
    nerf_camera_path *cp = load("bare.json", &o);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_camera_path_camera(cp, 0, &cam));
    CHECK(cam.width == 10 && cam.height == 10);
    CHECK_NEAR(cam.fx, 5.0, 1e-5);
    nerf_camera_path_destroy(cp);
    /* The Blender file's angle wins over fov_x with the flag. */
    write_blender("angle.json");
    cp = load("angle.json", &o);
    double f = 5.0 / tan(0.5 * 0.6911112070083618);
    check_camera(cp, 2, 10, 10, f, f, 5.0, 5.0);
    nerf_camera_path_destroy(cp);
}

/* ngp_json with one edit; expect failure with status and word. */
static void expect_json_failure(const char *from, const char *to, int status,
                                const char *word)
{
    char text[4096];
    const char *at = strstr(ngp_json, from);
    if (at == NULL) {
        FAILF("'%s' is not in the fixture", from);
        return;
    }
    snprintf(text, sizeof text, "%.*s%s%s", (int)(at - ngp_json), ngp_json,
             to, at + strlen(from));
    fx_write_text(dir, "bad.json", text);
    expect_failure("bad.json", NULL, status, word);
}

TEST(json_bad)
{
    expect_json_failure("\"frames\"", "\"framez\"", NERF_EFORMAT,
                        "missing field 'frames'");
    expect_json_failure("\"frames\": [", "\"frames\": {", NERF_EFORMAT,
                        "invalid JSON");
    expect_json_failure("[\n  {", "[], \"x\": [{", NERF_EFORMAT,
                        "the file holds no frames");
    expect_json_failure("{\"transform_matrix\"", "{\"matrix\"",
                        NERF_EFORMAT,
                        "frame 0: missing field 'transform_matrix'");
    expect_json_failure("[0, 0, 1, 4]", "[0, 0, 1e999, 4]", NERF_EFORMAT,
                        "frame 0: transform_matrix[2][2] is not a finite");
    expect_json_failure("[0, 0, 1, 4]", "[0, 0, null, 4]", NERF_EFORMAT,
                        "is not a finite number");
    expect_json_failure("[0, 0, 1, 4]", "[0, 0, 0, 4]", NERF_EFORMAT,
                        "frame 0: transform_matrix has a degenerate rotation");
    expect_json_failure("[0, 0, 0, 1]]}", "[0, 0, 0, 2]]}", NERF_EFORMAT,
                        "[0, 0, 0, 1]");
    expect_json_failure("[[1, 0, 0, 1]", "[[1, 0, 0]", NERF_EFORMAT,
                        "frame 1: transform_matrix row 0 is not a list");
    expect_json_failure("{\"fl_x\": 40,", "{", NERF_EFORMAT,
                        "frame 0: missing field 'camera_angle_x' (or "
                        "'fl_x')");
    expect_json_failure("{\"fl_x\": 20", "{\"fl_x\": -20", NERF_EFORMAT,
                        "frame 1: focal length must be positive");
    expect_json_failure("{\"fl_x\": 20", "{\"fl_x\": 1e-9", NERF_EFORMAT,
                        "frame 1: focal length must be positive");
    expect_json_failure("[0, 0, 1, 4]", "[0, 0, 1e308, 4]", NERF_EFORMAT,
                        "frame 0: transform_matrix has an entry of magnitude "
                        "1e+308");
    expect_json_failure("{\"transform_matrix\": [[1, 0, 0, 0]",
                        "{\"file_path\": \"views/v0.png\", "
                        "\"transform_matrix\": [[1e-9, 0, 0, 0]",
                        NERF_EFORMAT, "frame 0 (views/v0.png): "
                        "transform_matrix has a degenerate rotation");
    expect_json_failure("{\"fl_x\": 40", "{\"fl_x\": \"40\"", NERF_EFORMAT,
                        "field 'fl_x' is not a finite number");
    expect_json_failure("\"w\": 64,", "", NERF_EFORMAT,
                        "frame 0: gives h but not w");
    expect_json_failure("\"w\": 64", "\"w\": 64.5", NERF_EFORMAT,
                        "w 64.5 is not a whole number");
    expect_json_failure("\"h\": 16", "\"h\": 0", NERF_EFORMAT,
                        "frame 1: h 0 is not a whole number");
    expect_json_failure("\"fl_x\": 40", "\"camera_angle_x\": 4", NERF_EFORMAT,
                        "camera_angle_x 4 is not in (0, pi)");
    expect_json_failure("\"fl_x\": 20", "\"fl_x\": 1e300", NERF_EFORMAT,
                        "frame 1: focal length must be positive, within");
    expect_json_failure("{\"fl_x\": 20", "3, {\"fl_x\": 20", NERF_EFORMAT,
                        "frame 1: not a JSON object");
    fx_write_text(dir, "list.json", "[1, 2]");
    expect_failure("list.json", NULL, NERF_EFORMAT, "not a JSON object");
    /* A JSON file cut short. */
    char p[1024];
    fx_write_text(dir, "cut.json", ngp_json);
    fx_path(p, sizeof p, dir, "cut.json");
    fx_truncate(p, (long)strlen(ngp_json) / 2);
    expect_failure("cut.json", NULL, NERF_EFORMAT, "invalid JSON at line");
    fx_write_text(dir, "empty.json", "");
    expect_failure("empty.json", NULL, NERF_EFORMAT, "invalid JSON");
}

TEST(options_and_arguments)
{
    fx_write_text(dir, "ok.json", ngp_json);
    char p[1024];
    fx_path(p, sizeof p, dir, "ok.json");
    nerf_camera_path *cp = (nerf_camera_path *)dir;
    nerf_camera_path_options o;
    opts(&o, 32, 0, 0.0f, 0.0f);
    CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &o), NERF_EINVAL);
    CHECK(cp == NULL);
    CHECK(fx_has(nerf_last_error(), "width and height together"));
    opts(&o, 70000, 70000, 0.0f, 0.0f);
    CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &o), NERF_EINVAL);
    const float bad_focal[] = {-1.0f, NAN, INFINITY};
    for (int k = 0; k < 3; k++) {
        opts(&o, 0, 0, bad_focal[k], 0.0f);
        CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &o), NERF_EINVAL);
        CHECK(fx_has(nerf_last_error(), "focal must be positive"));
    }
    const float bad_fov[] = {-10.0f, 180.0f, NAN};
    for (int k = 0; k < 3; k++) {
        opts(&o, 0, 0, 0.0f, bad_fov[k]);
        CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &o), NERF_EINVAL);
        CHECK(fx_has(nerf_last_error(), "fov_x must be in (0, 180)"));
    }
    opts(&o, 0, 0, 10.0f, 40.0f);
    CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &o), NERF_EINVAL);
    CHECK(fx_has(nerf_last_error(), "not both"));
    opts(&o, 0, 0, 0.0f, 0.0f);
    o.flags = 0x4u;
    CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &o), NERF_EINVAL);
    CHECK(fx_has(nerf_last_error(), "unknown flags"));
    opts(&o, 0, 0, 0.0f, 0.0f);
    o.struct_size = 0;
    CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &o), NERF_EINVAL);

    /* A struct from a newer header: fine while its extra bytes are 0. */
    struct {
        nerf_camera_path_options o;
        uint64_t extra;
    } newer;
    memset(&newer, 0, sizeof newer);
    CHECK_OK(nerf_camera_path_options_init(&newer.o, sizeof newer));
    CHECK_OK(nerf_camera_path_load(&cp, p, &newer.o));
    nerf_camera_path_destroy(cp);
    newer.extra = 1;
    CHECK_EQ_INT(nerf_camera_path_load(&cp, p, &newer.o), NERF_EVERSION);
    CHECK(cp == NULL);

    CHECK_EQ_INT(nerf_camera_path_load(NULL, p, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_camera_path_load(&cp, NULL, NULL), NERF_EINVAL);
    CHECK(cp == NULL);
    CHECK_EQ_INT(nerf_camera_path_options_init(NULL, sizeof o), NERF_EINVAL);
    CHECK_EQ_INT(nerf_camera_path_count(NULL), 0);
    nerf_camera_path_destroy(NULL);

    cp = load("ok.json", NULL);
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_EQ_INT(nerf_camera_path_camera(cp, 2, &cam), NERF_EINVAL);
    CHECK(fx_has(nerf_last_error(), "index 2 is out of range"));
    CHECK_EQ_INT(nerf_camera_path_camera(NULL, 0, &cam), NERF_EINVAL);
    CHECK_EQ_INT(nerf_camera_path_camera(cp, 0, NULL), NERF_EINVAL);
    cam.struct_size = 8;
    CHECK_EQ_INT(nerf_camera_path_camera(cp, 0, &cam), NERF_EINVAL);
    /* An older caller's camera receives only the bytes it has. */
    unsigned char big[sizeof(nerf_camera) + 8];
    memset(big, 0xab, sizeof big);
    nerf_camera *older = (nerf_camera *)(void *)big;
    older->struct_size = sizeof *older;
    CHECK_OK(nerf_camera_path_camera(cp, 0, older));
    CHECK(big[sizeof(nerf_camera)] == 0xab);
    CHECK(older->width == 64);
    nerf_camera_path_destroy(cp);
}

static char log_text[1024];

static void capture(int level, const char *msg, void *user)
{
    (void)user;
    if (level == NERF_LOG_INFO) {
        snprintf(log_text, sizeof log_text, "%s", msg);
    }
}

TEST(hooks_and_allocation_failures)
{
    write_poses("alloc.npy", 4, 1, "(3, 4, 4)");
    fx_write_text(dir, "alloc.json", ngp_json);
    const char *names[] = {"alloc.npy", "alloc.json"};
    for (int k = 0; k < 2; k++) {
        char p[1024];
        fx_path(p, sizeof p, dir, names[k]);
        fail_alloc f;
        nerf_hooks hooks;
        fail_alloc_hooks(&hooks, &f);
        hooks.log_cb = capture;
        nerf_camera_path_options o;
        opts(&o, 16, 16, 0.0f, 60.0f);
        o.hooks = &hooks;
        int rc = NERF_ENOMEM;
        for (int at = 1; at < 50 && rc == NERF_ENOMEM; at++) {
            f = (fail_alloc){0, at, 0};
            nerf_camera_path *cp = NULL;
            rc = nerf_camera_path_load(&cp, p, &o);
            if (rc == NERF_ENOMEM) {
                CHECK(cp == NULL);
            } else {
                CHECK_OK(rc);
                CHECK_EQ_INT(nerf_camera_path_count(cp), k ? 2 : 3);
            }
            nerf_camera_path_destroy(cp);
            CHECK_EQ_INT(f.live, 0);
        }
        CHECK_OK(rc);
        CHECK(fx_has(log_text, names[k]));
        CHECK(fx_has(log_text, "camera path of"));
    }
}

int main(void)
{
    snprintf(dir, sizeof dir, "%s", fx_make_temp_dir());
    RUN(npy_shapes_and_dtypes);
    RUN(npy_needs_size_and_focal);
    RUN(npy_bad);
    RUN(json_blender);
    RUN(json_instant_ngp);
    RUN(json_fallback_intrinsics);
    RUN(json_bad);
    RUN(options_and_arguments);
    RUN(hooks_and_allocation_failures);
    fx_remove_tree(dir);
    HARNESS_EXIT();
}
