/*
 * Writes seed inputs for the fuzz targets into <dir>/<target>/: small
 * valid files of each format, produced by the test writers and, for the
 * checkpoint, by nerf_model_save itself, so the fuzzers start past the
 * magic numbers.  Usage: make_corpus <dir> <stamp file>.
 */
#include <nerf.h>

#include "../harness.h"
#include "../data/data_fixtures.h"
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

/* A raw checkpoint (mode byte 0) and its payload (mode byte 1). */
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
    nerf_model *model = NULL;
    char p[1024];
    out_path(p, sizeof p, "checkpoint", "tmp.ckpt");
    if (nerf_model_create(&model, &o) != NERF_OK ||
        nerf_model_save(model, p) != NERF_OK) {
        fprintf(stderr, "make_corpus: %s\n", nerf_last_error());
        exit(1);
    }
    nerf_model_destroy(model);
    long n = fx_file_size(p);
    unsigned char *file = malloc((size_t)n + 1);
    FILE *f = fopen(p, "rb");
    if (f == NULL || fread(file + 1, 1, (size_t)n, f) != (size_t)n) {
        perror(p);
        exit(1);
    }
    fclose(f);
    unlink(p);
    file[0] = 0;
    save("checkpoint", "raw.bin", file, (size_t)n + 1);
    /* The payload's size is in the header (bytes 16..23). */
    uLongf plain = 0;
    for (int i = 7; i >= 0; i--) {
        plain = plain << 8 | file[1 + 16 + i];
    }
    unsigned char *payload = malloc(plain + 1);
    payload[0] = 1;
    if (uncompress(payload + 1, &plain, file + 1 + 48, (uLong)n - 48) !=
        Z_OK) {
        fprintf(stderr, "make_corpus: cannot inflate the checkpoint\n");
        exit(1);
    }
    save("checkpoint", "payload.bin", payload, plain + 1);
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
    save("transforms", "blender.json", blender, sizeof blender - 1);
    save("transforms", "ngp.json", ngp, sizeof ngp - 1);
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
    FILE *stamp = fopen(argv[2], "w");
    if (stamp == NULL || fclose(stamp) != 0) {
        perror(argv[2]);
        return 1;
    }
    HARNESS_EXIT();
}
