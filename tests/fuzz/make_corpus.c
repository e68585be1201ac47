/*
 * Writes seed inputs for the fuzz targets into <dir>/<target>/: small
 * valid files of each format, produced by the test writers and, for the
 * checkpoint, by nerf_model_save itself, so the fuzzers start past the
 * magic numbers.  Where a target reads a leading option byte, the seeds
 * carry one.  Usage: make_corpus <dir> <stamp file>.
 */
#include <nerf.h>

#include "../harness.h"
#include "../data/data_fixtures.h"
#include "../data/jpeg_fixtures.h"
#include "../model/npz_writer.h"

static const char *root;

static void out_path(char *buf, size_t size, const char *target,
                     const char *name)
{
    char dir[1024];
    fx_path(dir, sizeof dir, root, target);
    mkdir(dir, 0777);
    fx_path(buf, size, dir, name);
}

static void save(const char *target, const char *name, const void *data,
                 size_t n)
{
    char p[1024];
    out_path(p, sizeof p, target, name);
    fx_write_bytes(p, data, n);
}

/* Save data behind a leading byte (the targets' option byte). */
static void save_with(const char *target, const char *name, unsigned char first,
                      const void *data, size_t n)
{
    unsigned char *b = malloc(n + 1);
    b[0] = first;
    memcpy(b + 1, data, n);
    save(target, name, b, n + 1);
    free(b);
}

/* A whole file, in a malloc'd buffer of *n bytes. */
static unsigned char *slurp(const char *path, size_t *n)
{
    long size = fx_file_size(path);
    unsigned char *buf = malloc(size > 0 ? (size_t)size : 1);
    FILE *f = fopen(path, "rb");
    if (size < 0 || f == NULL || fread(buf, 1, (size_t)size, f) != (size_t)size) {
        perror(path);
        exit(1);
    }
    fclose(f);
    *n = (size_t)size;
    return buf;
}

static void npy_seeds(void)
{
    static const double v[6] = {0.5, -1.0, 2.25, 3.0, 1e-3, 7.0};
    static const size_t shape[2] = {2, 3};
    bytes b = {0};
    npy_write(&b, "<f4", false, shape, 2, v);
    save("npy", "f4_2x3.npy", b.p, b.n);
    b.n = 0;
    npy_write(&b, "<f8", true, shape, 2, v);
    save("npy", "f8_fortran.npy", b.p, b.n);
    b.n = 0;
    npy_write(&b, "<f8", false, shape, 0, v);
    save("npy", "f8_scalar.npy", b.p, b.n);
    free(b.p);
}

static void zip_seeds(void)
{
    static const double v[4] = {1.0, 2.0, 3.0, 4.0};
    static const size_t shape[1] = {4};
    archive a = {.n = 0};
    member *m = add_member(&a, "w.npy");
    npy_write(&m->data, "<f4", false, shape, 1, v);
    m->method = 8;
    m->zip64_local = true;
    m = add_member(&a, "b.npy");
    npy_write(&m->data, "<f8", false, shape, 1, v);
    bytes z = {0};
    zip_write(&a, &z);
    save("zip", "two_members.npz", z.p, z.n);
    free(z.p);
    free_archive(&a);
}

/* The checkpoint file of a new model, in a malloc'd buffer of *n bytes. */
static unsigned char *checkpoint_of(const nerf_model_options *o, size_t *n)
{
    nerf_model *model = NULL;
    char p[1024];
    out_path(p, sizeof p, "checkpoint", "tmp.ckpt");
    if (nerf_model_create(&model, o) != NERF_OK ||
        nerf_model_save(model, p) != NERF_OK) {
        fprintf(stderr, "make_corpus: %s\n", nerf_last_error());
        exit(1);
    }
    nerf_model_destroy(model);
    unsigned char *file = slurp(p, n);
    unlink(p);
    return file;
}

/* The decompressed payload of a checkpoint file, in a malloc'd buffer. */
static unsigned char *payload_of(const unsigned char *file, size_t n,
                                 size_t *plain_n)
{
    /* The payload's size is in the header (bytes 16..23). */
    uLongf plain = 0;
    for (int i = 7; i >= 0; i--) {
        plain = plain << 8 | file[16 + i];
    }
    unsigned char *payload = malloc(plain);
    if (uncompress(payload, &plain, file + 48, (uLong)n - 48) != Z_OK) {
        fprintf(stderr, "make_corpus: cannot inflate the checkpoint\n");
        exit(1);
    }
    *plain_n = plain;
    return payload;
}

static uint32_t get_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
           (uint32_t)p[3] << 24;
}

/* The sections of payload whose tag is not drop, then extra. */
static void filter_sections(const unsigned char *payload, size_t n,
                            const uint32_t *drop, int n_drop,
                            const bytes *extra, bytes *out)
{
    for (size_t at = 0; at + 12 <= n;) {
        uint32_t tag = get_le32(payload + at);
        size_t len = (size_t)get_le32(payload + at + 4) |
                     (size_t)get_le32(payload + at + 8) << 32;
        bool keep = true;
        for (int i = 0; i < n_drop; i++) {
            keep = keep && tag != drop[i];
        }
        if (keep) {
            put(out, payload + at, 12 + len);
        }
        at += 12 + len;
    }
    if (extra) {
        put(out, extra->p, extra->n);
    }
}

/*
 * fuzz_checkpoint's compact form of a payload (mode 3): each section with
 * at most max_given bytes of its body, the target repeating the last 4.
 */
static void compact_of(const unsigned char *payload, size_t n,
                       size_t max_given, bytes *out)
{
    for (size_t at = 0; at + 12 <= n;) {
        size_t len = (size_t)get_le32(payload + at + 4) |
                     (size_t)get_le32(payload + at + 8) << 32;
        size_t given = len < max_given ? len : max_given;
        put(out, payload + at, 12);
        put_le(out, given, 2);
        put(out, payload + at + 12, given);
        at += 12 + len;
    }
}

/*
 * Checkpoint seeds, for the target's four modes: raw files (byte 0),
 * files whose CRCs the target recomputes (byte 2), payloads the target
 * wraps (byte 1) and compact payloads it expands first (byte 3), in the
 * forms a reader meets: format 1 (no options2 or
 * training2 section), format 2, a bf16 model's matmul section, an
 * optional section it must skip, and a hash-grid model with its occupancy
 * grid.
 */
/* The weights-only export of a new model that records render settings
 * (libnerf 0.4's two sections), in a malloc'd buffer of *n bytes. */
static unsigned char *export_of(const nerf_model_options *o, size_t *n)
{
    nerf_model *model = NULL;
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    char p[1024];
    out_path(p, sizeof p, "checkpoint", "tmp.ckpt");
    if (nerf_model_create(&model, o) != NERF_OK ||
        nerf_model_set_render_settings(model, &so, 1) != NERF_OK ||
        nerf_model_export(model, p) != NERF_OK) {
        fprintf(stderr, "make_corpus: %s\n", nerf_last_error());
        exit(1);
    }
    nerf_model_destroy(model);
    unsigned char *file = slurp(p, n);
    unlink(p);
    return file;
}

static void checkpoint_seeds(void)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.pos_frequencies = 1;
    o.dir_frequencies = 1;
    o.depth = 2;
    o.width = 2;
    o.skip_layer = 0;
    o.view_width = 2;
    o.use_fine = 0;
    size_t n, plain_n;
    unsigned char *file = checkpoint_of(&o, &n);
    save_with("checkpoint", "raw.bin", 0, file, n);
    save_with("checkpoint", "fixup.bin", 2, file, n);
    unsigned char *payload = payload_of(file, n, &plain_n);
    save_with("checkpoint", "payload.bin", 1, payload, plain_n);

    static const uint32_t v2_only[2] = {0x80000006u, 8u};
    bytes b = {0};
    filter_sections(payload, plain_n, v2_only, 2, NULL, &b);
    save_with("checkpoint", "payload_v1.bin", 1, b.p, b.n);

    size_t export_n, export_plain_n;
    unsigned char *exported = export_of(&o, &export_n);
    unsigned char *exported_payload = payload_of(exported, export_n,
                                                 &export_plain_n);
    save_with("checkpoint", "payload_export.bin", 1, exported_payload,
              export_plain_n);
    free(exported_payload);
    free(exported);

    bytes extra = {0};
    put_le(&extra, 9, 4); /* matmul */
    put_le(&extra, 8, 8);
    put_le(&extra, NERF_MATMUL_BF16, 4);
    put_le(&extra, 0, 4);
    put_le(&extra, 18, 4); /* appearance codes: one code, its moments */
    put_le(&extra, 8 + 4 * 3 * 3, 8);
    put_le(&extra, 1, 4);
    put_le(&extra, 3, 4);
    for (int i = 0; i < 9; i++) {
        put_le(&extra, 0x3c23d70au, 4); /* 0.01f */
    }
    put_le(&extra, 0x1234, 4); /* optional, unknown: skipped */
    put_le(&extra, 3, 8);
    put(&extra, "abc", 3);
    b.n = 0;
    filter_sections(payload, plain_n, NULL, 0, &extra, &b);
    save_with("checkpoint", "payload_extra.bin", 1, b.p, b.n);
    free(extra.p);
    free(b.p);
    free(payload);
    free(file);

    NERF_MODEL_OPTIONS_INIT(&o);
    o.encoding = NERF_ENCODING_HASHGRID;
    o.hash_levels = 1;
    o.hash_features = 1;
    o.hash_log2_size = 10;
    o.width = 2;
    o.view_width = 2;
    o.geo_features = 1;
    o.use_fine = 0;
    file = checkpoint_of(&o, &n);
    save_with("checkpoint", "raw_hashgrid.bin", 0, file, n);
    /* Without its occupancy section: a 8 MB grid costs some 100 ms a run,
     * which would starve the fuzzer; raw_hashgrid.bin covers it. */
    payload = payload_of(file, n, &plain_n);
    bytes lean = {0};
    static const uint32_t occupancy[1] = {7u};
    filter_sections(payload, plain_n, occupancy, 1, NULL, &lean);
    b = (bytes){0};
    compact_of(lean.p, lean.n, 64, &b);
    free(lean.p);
    save_with("checkpoint", "compact_hashgrid.bin", 3, b.p, b.n);
    free(b.p);
    free(payload);
    free(file);
}

static void transforms_seeds(void)
{
    static const char blender[] =
        "{\"camera_angle_x\": 0.69, \"frames\": [\n"
        "{\"file_path\": \"./r_0\", \"transform_matrix\": [[1, 0, 0, 0], "
        "[0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]},\n"
        "{\"file_path\": \"r_0.png\", \"transform_matrix\": [[0, -1, 0, 1], "
        "[1, 0, 0, 0], [0, 0, 1, 3], [0, 0, 0, 1]]}]}\n";
    static const char ngp[] =
        "{\"fl_x\": 5, \"fl_y\": 6, \"cx\": 2, \"cy\": 2, \"w\": 4, \"h\": 4, "
        "\"frames\": [\n"
        "{\"file_path\": \"r_0.png\", \"transform_matrix\": [[1, 0, 0, 0], "
        "[0, 1, 0, 0], [0, 0, 1, 4]]},\n"
        "{\"file_path\": \"missing\", \"transform_matrix\": [[1, 0, 0, 0], "
        "[0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]},\n"
        "{\"file_path\": \"r_1\", \"camera_angle_x\": 1.0, "
        "\"transform_matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2], "
        "[0, 0, 0, 1]]}]}\n";
    /* instant-ngp's lens and aabb_scale, at top level and per frame. */
    static const char lens[] =
        "{\"fl_x\": 5, \"fl_y\": 6, \"cx\": 2, \"cy\": 2, \"w\": 4, \"h\": 4, "
        "\"k1\": -0.3, \"k2\": 0.1, \"p1\": 0.001, \"p2\": -0.002, "
        "\"k3\": 0.01, \"aabb_scale\": 16, \"frames\": [\n"
        "{\"file_path\": \"r_0.png\", \"transform_matrix\": [[1, 0, 0, 0], "
        "[0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]},\n"
        "{\"file_path\": \"r_0.png\", \"k1\": 0.2, \"k3\": -900, "
        "\"fl_x\": 3, \"cx\": 1.5, \"transform_matrix\": [[0, -1, 0, 1], "
        "[1, 0, 0, 0], [0, 0, 1, 3], [0, 0, 0, 1]]},\n"
        "{\"file_path\": \"r_0\", \"p1\": 999, \"p2\": -999, "
        "\"transform_matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2], "
        "[0, 0, 0, 1]]}]}\n";
    save("transforms", "blender.json", blender, sizeof blender - 1);
    save("transforms", "ngp.json", ngp, sizeof ngp - 1);
    /* nerfstudio's mask_path: a mask of the photo's size (m_0.png), one
     * of another size (r_1.png's 2x2 for r_0's 4x4), one missing; r_0's
     * second frame also has instant-ngp's dynamic_mask_r_0.png beside
     * it, which mask_path overrides and the third frame picks up. */
    static const char masks[] =
        "{\"camera_angle_x\": 0.69, \"frames\": [\n"
        "{\"file_path\": \"r_0.png\", \"mask_path\": \"./m_0.png\", "
        "\"transform_matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], "
        "[0, 0, 0, 1]]},\n"
        "{\"file_path\": \"r_0.png\", \"mask_path\": \"r_1.png\", "
        "\"transform_matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 3], "
        "[0, 0, 0, 1]]},\n"
        "{\"file_path\": \"r_0\", \"transform_matrix\": [[1, 0, 0, 0], "
        "[0, 1, 0, 0], [0, 0, 1, 2], [0, 0, 0, 1]]},\n"
        "{\"file_path\": \"r_0.png\", \"mask_path\": \"nope.png\", "
        "\"transform_matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 5], "
        "[0, 0, 0, 1]]}]}\n";
    save("transforms", "blender.json", blender, sizeof blender - 1);
    save("transforms", "ngp.json", ngp, sizeof ngp - 1);
    save("transforms", "lens.json", lens, sizeof lens - 1);
    save("transforms", "masks.json", masks, sizeof masks - 1);
}

/*
 * The raw-scanline form of a PNG file for fuzz_png's mode 2: its IDAT
 * data inflated (the target deflates it again).
 */
static void png_raw_form(const unsigned char *f, size_t n, size_t raw_n,
                         bytes *out)
{
    put(out, f, 8);
    bytes z = {0};
    size_t at = 8;
    while (at + 12 <= n) {
        size_t len = (size_t)f[at] << 24 | (size_t)f[at + 1] << 16 |
                     (size_t)f[at + 2] << 8 | f[at + 3];
        if (memcmp(f + at + 4, "IDAT", 4) == 0) {
            put(&z, f + at + 8, len);
            if (memcmp(f + at + 12 + len + 4, "IDAT", 4) != 0) {
                unsigned char *raw = malloc(raw_n);
                uLongf got = raw_n;
                if (uncompress(raw, &got, z.p, (uLong)z.n) != Z_OK ||
                    got != raw_n) {
                    fprintf(stderr, "make_corpus: bad IDAT\n");
                    exit(1);
                }
                unsigned char head[8];
                fx_be32(head, (uint32_t)raw_n);
                memcpy(head + 4, "IDAT", 4);
                put(out, head, 8);
                put(out, raw, raw_n);
                put(out, "\0\0\0\0", 4); /* the target computes it */
                free(raw);
            }
        } else {
            put(out, f + at, 12 + len);
        }
        at += 12 + len;
    }
    free(z.p);
}

/* One PNG seed: option byte first, mode from its bits 3-4. */
static void png_seed(const char *name, unsigned char first, uint32_t w,
                     uint32_t h, int color_type, int depth,
                     const unsigned char *plte, int n_plte,
                     const unsigned char *trns, int n_trns)
{
    static const int channels_of[7] = {1, 0, 3, 1, 2, 0, 4};
    int ch = channels_of[color_type];
    uint16_t px[8 * 8 * 4];
    for (int i = 0; i < (int)(w * h) * ch; i++) {
        int v = (i * 53 + 7) % (color_type == 3 ? n_plte : 256);
        px[i] = (uint16_t)(depth == 16 ? v * 257 + i : v);
    }
    char p[1024];
    out_path(p, sizeof p, "png", "tmp.png");
    fx_write_png(p, w, h, color_type, depth, px, plte, n_plte, trns, n_trns);
    size_t n;
    unsigned char *f = slurp(p, &n);
    unlink(p);
    if (((first >> 3) & 3) >= 2) {
        bytes b = {0};
        png_raw_form(f, n, h * (1 + (size_t)w * ch * (depth / 8)), &b);
        save_with("png", name, first, b.p, b.n);
        free(b.p);
    } else {
        save_with("png", name, first, f, n);
    }
    free(f);
}

static void png_seeds(void)
{
    static const unsigned char plte[9] = {255, 0, 0, 0, 255, 0, 0, 0, 255};
    static const unsigned char trns[2] = {0, 128};
    png_seed("gray8.bin", 0x00, 2, 2, 0, 8, NULL, 0, NULL, 0);
    png_seed("rgba8_crc.bin", 0x0b, 4, 4, 6, 8, NULL, 0, NULL, 0);
    png_seed("palette_raw.bin", 0x10, 3, 3, 3, 8, plte, 3, trns, 2);
    png_seed("gray_alpha16_raw.bin", 0x12, 4, 2, 4, 16, NULL, 0, NULL, 0);
    png_seed("rgb16.bin", 0x01, 2, 3, 2, 16, NULL, 0, NULL, 0);
    png_seed("rgba16_crc.bin", 0x0c, 5, 3, 6, 16, NULL, 0, NULL, 0);
}

/*
 * poses_bounds.npy of n cameras looking down -z from points on a line,
 * with the image size h x w and focal of the rows.
 */
static void llff_seed(const char *name, unsigned char first, size_t n,
                      double h, double w, double focal)
{
    double rows[4 * 17];
    for (size_t i = 0; i < n; i++) {
        double *r = rows + 17 * i;
        /* LLFF columns: [down, right, back | position | hwf]. */
        static const double rot[9] = {0, 1, 0, -1, 0, 0, 0, 0, 1};
        for (int k = 0; k < 3; k++) {
            r[5 * k + 0] = rot[3 * k + 0];
            r[5 * k + 1] = rot[3 * k + 1];
            r[5 * k + 2] = rot[3 * k + 2];
            r[5 * k + 3] = k == 0 ? 0.5 * i : k == 1 ? 0.25 * (i % 2) : 0.1;
        }
        r[4] = h;
        r[9] = w;
        r[14] = focal;
        r[15] = 1.5 + 0.1 * i;
        r[16] = 8.0 + i;
    }
    size_t shape[2] = {n, 17};
    bytes b = {0};
    npy_write(&b, "<f8", false, shape, 2, rows);
    save_with("llff", name, first, b.p, b.n);
    free(b.p);
}

/* See fuzz_llff.c for what the first byte picks. */
/* One JPEG seed for fuzz_jpeg's mode 0: the file behind the option byte. */
static void jpeg_seed(const char *name, unsigned char first, uint32_t w,
                      uint32_t h, J_COLOR_SPACE space, int flags,
                      uint32_t orientation)
{
    uint8_t px[16 * 16 * 3];
    for (size_t i = 0; i < sizeof px; i++) {
        px[i] = (uint8_t)((i * 29 + 5) % 256);
    }
    uint8_t exif[64];
    size_t n_exif = orientation ? fx_exif(exif, orientation & 1,
                                          orientation, 3)
                                : 0;
    char p[1024];
    out_path(p, sizeof p, "jpeg", "tmp.jpg");
    fx_write_jpeg(p, w, h, space, px, 75, flags, exif, n_exif);
    size_t n;
    unsigned char *f = slurp(p, &n);
    unlink(p);
    save_with("jpeg", name, first, f, n);
    free(f);
}

static void jpeg_seeds(void)
{
    jpeg_seed("rgb_orient6.bin", 0x00, 8, 5, JCS_RGB, 0, 6);
    jpeg_seed("gray_progressive.bin", 0x03, 6, 9, JCS_GRAYSCALE,
              FX_JPEG_PROGRESSIVE, 0);
    jpeg_seed("rgb_arith_orient3.bin", 0x02, 7, 7, JCS_RGB,
              FX_JPEG_ARITHMETIC, 3);
    jpeg_seed("cmyk.bin", 0x00, 4, 4, JCS_CMYK, 0, 0);
    /* Mode 1: Exif blocks alone, in both byte orders. */
    uint8_t exif[64];
    size_t n = fx_exif(exif, 1, 8, 3);
    save_with("jpeg", "exif_mm_orient8.bin", 0x08, exif, n);
    n = fx_exif(exif, 0, 5, 3);
    save_with("jpeg", "exif_ii_orient5.bin", 0x0b, exif, n);
}

static void llff_seeds(void)
{
    llff_seed("two_rgb.bin", 0x01, 2, 6, 8, 7);
    llff_seed("four_images2_holdout2.bin", 0x4b, 4, 12, 16, 14);
    llff_seed("three_rgba16_test.bin", 0xa6, 3, 4, 6, 5);
    llff_seed("one_downscale3.bin", 0x10, 1, 6, 8, 7);
}

static void camera_path_npy(const char *name, unsigned char first,
                            const char *descr, const size_t *shape,
                            int ndim)
{
    double v[2 * 16];
    size_t per = shape[0] ? (ndim == 3 ? shape[1] * shape[2] : shape[1]) : 0;
    for (size_t i = 0; i < shape[0]; i++) {
        static const double m[16] = {1, 0, 0, 0.5, 0, 0, -1, 0,
                                     0, 1, 0, 3, 0, 0, 0, 1};
        memcpy(v + per * i, m, per * sizeof *v);
        v[per * i + 3] += (double)i;
    }
    bytes b = {0};
    npy_write(&b, descr, false, shape, ndim, v);
    save_with("camera_path", name, first, b.p, b.n);
    free(b.p);
}

/* See fuzz_camera_path.c for what the first byte picks. */
static void camera_path_seeds(void)
{
    static const char blender[] =
        "{\"camera_angle_x\": 0.69, \"frames\": [\n"
        "{\"transform_matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], "
        "[0, 0, 0, 1]]},\n"
        "{\"transform_matrix\": [[0, -1, 0, 1], [1, 0, 0, 0], [0, 0, 1, 3], "
        "[0, 0, 0, 1]]}]}\n";
    static const char ngp[] =
        "{\"fl_x\": 5, \"fl_y\": 6, \"cx\": 2, \"cy\": 2, \"w\": 4, "
        "\"h\": 4, \"k1\": 0, \"frames\": [\n"
        "{\"file_path\": \"a.png\", \"transform_matrix\": [[1, 0, 0, 0], "
        "[0, 1, 0, 0], [0, 0, 1, 4]]},\n"
        "{\"w\": 8, \"h\": 2, \"camera_angle_x\": 1.0, "
        "\"camera_angle_y\": 0.5, \"transform_matrix\": [[1, 0, 0, 0], "
        "[0, 1, 0, 0], [0, 0, 1, 2], [0, 0, 0, 1]]}]}\n";
    save_with("camera_path", "blender_focal.bin", 0x02, blender,
              sizeof blender - 1);
    save_with("camera_path", "ngp.bin", 0x00, ngp, sizeof ngp - 1);
    save_with("camera_path", "ngp_file_first.bin", 0x06, ngp,
              sizeof ngp - 1);
    static const size_t s344[3] = {2, 3, 4}, s444[3] = {2, 4, 4};
    static const size_t s16[2] = {2, 16}, s12[2] = {1, 12};
    camera_path_npy("npy_3x4.bin", 0x03, "<f8", s344, 3);
    camera_path_npy("npy_4x4_magic.bin", 0x04, "<f4", s444, 3);
    camera_path_npy("npy_flat16.bin", 0x07, "<f8", s16, 2);
    camera_path_npy("npy_flat12_fov.bin", 0x05, "<f4", s12, 2);
}

/*
 * The COLMAP targets' seeds: each file of the model fuzz_colmap.h writes
 * (the built-in scene, 3 views of 8x8), behind option bytes that pick it,
 * and a model without points.
 */
static void colmap_seeds(const char *target, uint32_t layout,
                         const char *ext)
{
    static const char *const names[3] = {"cameras", "images", "points3D"};
    static const unsigned char firsts[3][2] = {{0x00, 0x2c},
                                               {0x01, 0x14},
                                               {0x02, 0x36}};
    char *dir = fx_make_temp_dir();
    nerf_scene_options o;
    NERF_SCENE_OPTIONS_INIT(&o);
    o.width = 8;
    o.height = 8;
    o.n_train = 3;
    o.n_val = 0;
    o.n_test = 0;
    o.threads = 1;
    o.layout = layout;
    CHECK_OK(nerf_scene_write(dir, &o));
    for (int f = 0; f < 3; f++) {
        char rel[64], path[1024], name[64];
        snprintf(rel, sizeof rel, "sparse/0/%s.%s", names[f], ext);
        fx_path(path, sizeof path, dir, rel);
        size_t n;
        unsigned char *b = slurp(path, &n);
        for (int k = 0; k < 2; k++) {
            snprintf(name, sizeof name, "%s_%02x.bin", names[f],
                     firsts[f][k]);
            save_with(target, name, firsts[f][k], b, n);
        }
        if (f == 1) {
            save_with(target, "images_no_points.bin", 0x03, b, n);
        }
        free(b);
    }
    fx_remove_tree(dir);
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: make_corpus <dir> <stamp file>\n");
        return 2;
    }
    root = argv[1];
    mkdir(root, 0777);
    npy_seeds();
    zip_seeds();
    checkpoint_seeds();
    transforms_seeds();
    png_seeds();
    jpeg_seeds();
    llff_seeds();
    camera_path_seeds();
    colmap_seeds("colmap_text", NERF_SCENE_LAYOUT_COLMAP_TEXT, "txt");
    colmap_seeds("colmap_bin", NERF_SCENE_LAYOUT_COLMAP_BINARY, "bin");
    FILE *stamp = fopen(argv[2], "w");
    if (stamp == NULL || fclose(stamp) != 0) {
        perror(argv[2]);
        return 1;
    }
    HARNESS_EXIT();
}
