/*
 * The public mesh and grid calls on a model whose density is known: a
 * one-layer network set by hand so that sigma = relu(k (r - |x|_1)), an
 * octahedron, with a constant colour.  Its mesh is closed, lies on the
 * octahedron and has its volume and colour; the files read back; bad
 * arguments, progress and cancelling behave.
 */
#include <cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../harness.h"
#include "file_io.h"
#include "mesh_check.h"
#include "model.h"
#include "model_field.h"
#include "npy.h"

#define K 100.0f
#define R 0.8f
#define THRESHOLD 25.0f
/* Where the density crosses THRESHOLD: |x|_1 = C. */
#define C (R - THRESHOLD / K)

/* Octahedra at the given centres (|x - c|_1), one hidden unit per signed
 * axis; the head sums them. */
static nerf_model *octahedron(void)
{
    nerf_model_options o;
    nerf_model_options_init(&o, sizeof o);
    o.pos_frequencies = 0;
    o.encoding_flags = NERF_ENCODING_INCLUDE_INPUT;
    o.depth = 1;
    o.width = 6;
    o.skip_layer = 0;
    o.use_viewdirs = 0;
    o.use_fine = 0;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m == NULL) {
        return NULL;
    }
    nerf__network *net = &m->nets[0];
    float *p = m->params;
    memset(p + net->offset, 0, net->count * sizeof(float));
    for (int u = 0; u < 6; u++) {
        p[net->trunk[0].w + (size_t)u * 3 + (size_t)u / 2] = u % 2 ? -1.0f : 1.0f;
    }
    /* Head rows: r, g, b (sigmoid), sigma. */
    for (int u = 0; u < 6; u++) {
        p[net->head.w + 3 * 6 + (size_t)u] = -K;
    }
    p[net->head.b + 0] = 2.0f;
    p[net->head.b + 1] = -2.0f;
    p[net->head.b + 2] = 0.0f;
    p[net->head.b + 3] = K * R;
    nerf__model_weights_changed(m);
    return m;
}

static float l1(const float *v)
{
    return fabsf(v[0]) + fabsf(v[1]) + fabsf(v[2]);
}

TEST(known_density)
{
    nerf_model *m = octahedron();
    float x[3] = {0.1f, -0.2f, 0.3f}, sigma = 0.0f;
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_COARSE, 1, x, NULL, NULL, &sigma));
    CHECK_NEAR(sigma, K * (R - 0.6f), 1e-3);
    nerf_model_destroy(m);
}

TEST(mesh_of_known_density)
{
    nerf_model *m = octahedron();
    nerf_mesh_options o;
    CHECK_OK(nerf_mesh_options_init(&o, sizeof o));
    CHECK_EQ_INT(o.resolution, 256);
    CHECK_NEAR(o.threshold, 25.0, 0.0);
    o.resolution = 48;
    nerf_mesh *mesh = NULL;
    CHECK_OK(nerf_mesh_extract(&mesh, m, &o));
    const size_t nv = nerf_mesh_vertex_count(mesh), nf = nerf_mesh_face_count(mesh);
    CHECK(nv > 100 && nf > 100);
    mesh_stats st;
    mesh_stats_compute(nerf_mesh_vertices(mesh), nv, nerf_mesh_faces(mesh), nf, &st);
    CHECK_EQ_INT(st.bad_edges, 0);
    CHECK_EQ_INT(st.misoriented, 0);
    CHECK_EQ_INT(st.euler, 2);
    CHECK_EQ_INT(st.components, 1);
    const double volume = 4.0 / 3.0 * C * C * C;
    CHECK_NEAR(st.volume, volume, 0.03 * volume);
    /* The default box is the model's bound, 1.5: 3 / 48 per cell. */
    const double half_cell = 0.5 * 3.0 / 48.0;
    const float *v = nerf_mesh_vertices(mesh);
    const uint8_t *c = nerf_mesh_colours(mesh);
    const float *n = nerf_mesh_normals(mesh);
    CHECK(c != NULL && n != NULL);
    size_t far = 0, wrong_colour = 0;
    for (size_t i = 0; c && i < nv; i++) {
        far += !(fabs(l1(v + 3 * i) - C) <= half_cell);
        wrong_colour += abs(c[3 * i] - 224) > 1 || abs(c[3 * i + 1] - 30) > 1 ||
                        abs(c[3 * i + 2] - 128) > 1;
    }
    CHECK_EQ_INT(far, 0);
    CHECK_EQ_INT(wrong_colour, 0);
    nerf_mesh_destroy(mesh);

    o.colour = NERF_MESH_COLOUR_NONE;
    o.threshold = 1e9f; /* nothing that dense: an empty mesh */
    CHECK_OK(nerf_mesh_extract(&mesh, m, &o));
    CHECK_EQ_INT(nerf_mesh_vertex_count(mesh), 0);
    CHECK(nerf_mesh_vertices(mesh) == NULL && nerf_mesh_colours(mesh) == NULL);
    nerf_mesh_destroy(mesh);
    nerf_model_destroy(m);
}

TEST(box_and_threads)
{
    /* A box around one corner of the octahedron, and results that do
     * not depend on the thread count. */
    nerf_model *m = octahedron();
    nerf_mesh_options o;
    nerf_mesh_options_init(&o, sizeof o);
    o.resolution = 20;
    const float box[6] = {0.2f, -0.2f, -0.2f, 0.8f, 0.2f, 0.2f};
    memcpy(o.box, box, sizeof box);
    nerf_mesh *a = NULL, *b = NULL;
    o.threads = 1;
    CHECK_OK(nerf_mesh_extract(&a, m, &o));
    o.threads = 0;
    CHECK_OK(nerf_mesh_extract(&b, m, &o));
    /* The same vertices bit for bit (below) by construction: the density
     * is sampled a plane of the grid at a time, at most (resolution + 1)^2
     * points, which is one network call whatever the thread count while
     * fewer than 2 NERF__FIELD_CHUNK (model_field.h); beyond that, blocks
     * of other sizes give the same bits only where each sample is
     * computed alone (nerf__model_rows_alone(): not the CBLAS). */
    CHECK((o.resolution + 1) * (o.resolution + 1) < 2 * NERF__FIELD_CHUNK ||
          nerf__model_rows_alone(m));
    CHECK(nerf_mesh_face_count(a) > 0);
    CHECK_EQ_INT(nerf_mesh_face_count(a), nerf_mesh_face_count(b));
    CHECK(nerf_mesh_vertex_count(a) == nerf_mesh_vertex_count(b) &&
          memcmp(nerf_mesh_vertices(a), nerf_mesh_vertices(b),
                 12 * nerf_mesh_vertex_count(a)) == 0);
    for (size_t i = 0; i < nerf_mesh_vertex_count(a); i++) {
        const float *v = nerf_mesh_vertices(a) + 3 * i;
        if (v[0] < 0.2f || v[0] > 0.8f || fabsf(v[1]) > 0.2f) {
            FAILF("vertex %zu outside the box", i);
            break;
        }
    }
    nerf_mesh_destroy(a);
    nerf_mesh_destroy(b);
    nerf_model_destroy(m);
}

typedef struct progress_log {
    uint64_t calls, last_done, total;
    uint64_t cancel_at;
    int wrong_kind;
} progress_log;

static int on_progress(const nerf_progress *p, void *user)
{
    progress_log *l = user;
    l->calls++;
    l->last_done = p->done;
    l->total = p->total;
    l->wrong_kind += p->kind != NERF_PROGRESS_GEOMETRY;
    return l->cancel_at && p->done >= l->cancel_at;
}

TEST(progress_and_cancel)
{
    nerf_model *m = octahedron();
    nerf_mesh_options o;
    nerf_mesh_options_init(&o, sizeof o);
    o.resolution = 16;
    progress_log log = {0};
    o.progress = on_progress;
    o.progress_user = &log;
    nerf_mesh *mesh = NULL;
    CHECK_OK(nerf_mesh_extract(&mesh, m, &o));
    CHECK_EQ_INT(log.total, 17);
    CHECK_EQ_INT(log.last_done, 17);
    CHECK_EQ_INT(log.calls, 17);
    CHECK_EQ_INT(log.wrong_kind, 0);
    nerf_mesh_destroy(mesh);
    memset(&log, 0, sizeof log);
    log.cancel_at = 5;
    mesh = (nerf_mesh *)&log;
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, &o), NERF_ECANCELLED);
    CHECK(mesh == NULL);
    CHECK_EQ_INT(log.last_done, 5);
    nerf_model_destroy(m);
}

TEST(bad_arguments)
{
    nerf_model *m = octahedron();
    nerf_mesh_options o;
    nerf_mesh *mesh = NULL;
    CHECK_EQ_INT(nerf_mesh_options_init(NULL, sizeof o), NERF_EINVAL);
    nerf_mesh_options_init(&o, sizeof o);
    CHECK_EQ_INT(nerf_mesh_extract(NULL, m, &o), NERF_EINVAL);
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, NULL, &o), NERF_EINVAL);
    o.resolution = 0;
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "resolution 0") != NULL);
    nerf_mesh_options_init(&o, sizeof o);
    o.threshold = NAN;
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "threshold") != NULL);
    nerf_mesh_options_init(&o, sizeof o);
    const float flat[6] = {-1, -1, 0.5f, 1, 1, 0.5f};
    memcpy(o.box, flat, sizeof flat);
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "no volume") != NULL);
    nerf_mesh_options_init(&o, sizeof o);
    o.colour = 7;
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, &o), NERF_EINVAL);
    CHECK(mesh == NULL);
    /* A newer caller's struct with unknown fields set. */
    unsigned char big[sizeof o + 8];
    memset(big, 0, sizeof big);
    nerf_mesh_options_init((nerf_mesh_options *)big, sizeof big);
    big[sizeof o + 3] = 1;
    CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, (nerf_mesh_options *)big),
                 NERF_EVERSION);
    CHECK_EQ_INT(nerf_density_grid_write(m, NULL, NULL), NERF_EINVAL);
    nerf_model_destroy(m);
}

/* The element, vertex and face counts of a PLY header, and its format. */
static int ply_counts(const char *path, size_t *nv, size_t *nf, char *format,
                      size_t format_size)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return -1;
    }
    char line[256];
    *nv = *nf = 0;
    int ok = 0;
    while (fgets(line, sizeof line, f)) {
        sscanf(line, "element vertex %zu", nv);
        sscanf(line, "element face %zu", nf);
        if (strncmp(line, "format ", 7) == 0) {
            size_t len = strlen(line + 7);
            len = len < format_size - 1 ? len : format_size - 1;
            memcpy(format, line + 7, len);
            format[len] = '\0';
        }
        if (strcmp(line, "end_header\n") == 0) {
            ok = 1;
            break;
        }
    }
    fclose(f);
    return ok ? 0 : -1;
}

TEST(files)
{
    nerf_model *m = octahedron();
    nerf_mesh_options o;
    nerf_mesh_options_init(&o, sizeof o);
    o.resolution = 12;
    nerf_mesh *mesh = NULL;
    CHECK_OK(nerf_mesh_extract(&mesh, m, &o));
    char dir[] = "/tmp/nerf-mesh-test-XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char ply[256], ascii[256], obj[256], other[256], missing[256];
    snprintf(ply, sizeof ply, "%s/m.ply", dir);
    snprintf(ascii, sizeof ascii, "%s/a.ply", dir);
    snprintf(obj, sizeof obj, "%s/m.OBJ", dir);
    snprintf(other, sizeof other, "%s/m.stl", dir);
    snprintf(missing, sizeof missing, "%s/no/such/folder/m.ply", dir);
    CHECK_OK(nerf_mesh_write(mesh, ply, NERF_MESH_FORMAT_AUTO));
    CHECK_OK(nerf_mesh_write(mesh, ascii, NERF_MESH_FORMAT_PLY_ASCII));
    CHECK_OK(nerf_mesh_write(mesh, obj, NERF_MESH_FORMAT_AUTO));
    CHECK_EQ_INT(nerf_mesh_write(mesh, other, NERF_MESH_FORMAT_AUTO), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "m.stl") != NULL);
    CHECK_EQ_INT(nerf_mesh_write(mesh, missing, NERF_MESH_FORMAT_PLY), NERF_EIO);
    CHECK(strstr(nerf_last_error(), "no/such/folder") != NULL);
    CHECK_EQ_INT(nerf_mesh_write(mesh, ply, 99), NERF_EINVAL);
    size_t nv, nf;
    char format[64] = "";
    CHECK_EQ_INT(ply_counts(ply, &nv, &nf, format, sizeof format), 0);
    CHECK_EQ_INT(nv, nerf_mesh_vertex_count(mesh));
    CHECK_EQ_INT(nf, nerf_mesh_face_count(mesh));
    CHECK(strcmp(format, "binary_little_endian 1.0\n") == 0);
    CHECK_EQ_INT(ply_counts(ascii, &nv, &nf, format, sizeof format), 0);
    CHECK_EQ_INT(nf, nerf_mesh_face_count(mesh));
    CHECK(strcmp(format, "ascii 1.0\n") == 0);
    /* The binary file's size: header + 27 bytes a vertex + 13 a face. */
    FILE *f = fopen(ply, "rb");
    if (f) {
        char line[256];
        long header = 0;
        while (fgets(line, sizeof line, f)) {
            header += (long)strlen(line);
            if (strcmp(line, "end_header\n") == 0) {
                break;
            }
        }
        fseek(f, 0, SEEK_END);
        CHECK_EQ_INT(ftell(f), header + 27 * (long)nv + 13 * (long)nf);
        fclose(f);
    }
    f = fopen(obj, "r");
    size_t ov = 0, of = 0;
    if (f) {
        char line[256];
        while (fgets(line, sizeof line, f)) {
            ov += strncmp(line, "v ", 2) == 0;
            of += strncmp(line, "f ", 2) == 0;
        }
        fclose(f);
    }
    CHECK_EQ_INT(ov, nerf_mesh_vertex_count(mesh));
    CHECK_EQ_INT(of, nerf_mesh_face_count(mesh));
    remove(ply);
    remove(ascii);
    remove(obj);
    rmdir(dir);
    nerf_mesh_destroy(mesh);
    nerf_model_destroy(m);
}

TEST(density_grid)
{
    nerf_model *m = octahedron();
    nerf_mesh_options o;
    nerf_mesh_options_init(&o, sizeof o);
    o.resolution = 10;
    const float box[6] = {-1, -1, -0.5f, 1, 1, 0.5f};
    memcpy(o.box, box, sizeof box);
    char dir[] = "/tmp/nerf-grid-test-XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char path[256], json[256], rgb[256], bad[256];
    snprintf(path, sizeof path, "%s/g.npy", dir);
    snprintf(json, sizeof json, "%s/g.json", dir);
    snprintf(rgb, sizeof rgb, "%s/g_rgb.npy", dir);
    snprintf(bad, sizeof bad, "%s/missing/g.npy", dir);
    CHECK_OK(nerf_density_grid_write(m, path, &o));
    nerf__env env;
    nerf__env_from_hooks(&env, NULL);
    unsigned char *data = NULL;
    size_t size = 0;
    CHECK_OK(nerf__file_read(&env, path, 1u << 24, &data, &size));
    nerf__npy a;
    if (data) {
        CHECK_OK(nerf__npy_parse(data, size, &a));
        CHECK_EQ_INT(a.ndim, 3);
        /* (nz, ny, nx): the short side gets half the cells. */
        CHECK(a.shape[0] == 5 && a.shape[1] == 10 && a.shape[2] == 10);
        float *v = malloc(a.count * sizeof(float));
        nerf__npy_to_float(&a, v, a.count);
        size_t wrong = 0;
        for (size_t k = 0; k < 5; k++) {
            for (size_t j = 0; j < 10; j++) {
                for (size_t i = 0; i < 10; i++) {
                    const float p[3] = {-1.0f + 0.2f * (i + 0.5f),
                                        -1.0f + 0.2f * (j + 0.5f),
                                        -0.5f + 0.2f * (k + 0.5f)};
                    const float want = fmaxf(0.0f, K * (R - l1(p)));
                    wrong += fabsf(v[(k * 10 + j) * 10 + i] - want) > 1e-2f;
                }
            }
        }
        CHECK_EQ_INT(wrong, 0);
        free(v);
        nerf__free(&env, data);
    }
    CHECK(access(json, R_OK) == 0);
    CHECK(access(rgb, R_OK) == 0);
    data = NULL;
    CHECK_OK(nerf__file_read(&env, json, 1u << 20, &data, &size));
    if (data) {
        /* The box and the axis order are recorded. */
        cJSON *root = cJSON_ParseWithLength((const char *)data, size);
        CHECK(root != NULL);
        const cJSON *order = cJSON_GetObjectItem(root, "order");
        const cJSON *lo = cJSON_GetObjectItem(root, "box_min");
        const cJSON *shape = cJSON_GetObjectItem(root, "shape");
        CHECK(cJSON_IsString(order) && strcmp(order->valuestring, "zyx") == 0);
        CHECK(cJSON_GetArraySize(lo) == 3 &&
              cJSON_GetArrayItem(lo, 2)->valuedouble == -0.5);
        CHECK(cJSON_GetArraySize(shape) == 3 &&
              cJSON_GetArrayItem(shape, 0)->valuedouble == 5);
        cJSON_Delete(root);
        nerf__free(&env, data);
    }
    CHECK_EQ_INT(nerf_density_grid_write(m, bad, &o), NERF_EIO);
    CHECK(strstr(nerf_last_error(), "missing/g.npy") != NULL);
    remove(path);
    remove(json);
    remove(rgb);
    rmdir(dir);
    nerf_model_destroy(m);
}

TEST(ndc_back_to_world)
{
    /* A forward-facing model: its mesh is made in NDC, and with the NDC
     * frustum in its render settings each vertex goes back to the world
     * point that the NDC warp takes to it, faces rewound. */
    nerf_model_options mo;
    nerf_model_options_init(&mo, sizeof mo);
    CHECK_OK(nerf_model_options_preset(&mo, NERF_PRESET_FAST));
    mo.space = NERF_SPACE_NDC;
    mo.hash_log2_size = 12;
    mo.hash_levels = 4;
    mo.seed = 2;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &mo));
    if (m == NULL) {
        return;
    }
    nerf_mesh_options o;
    nerf_mesh_options_init(&o, sizeof o);
    o.resolution = 10;
    o.colour = NERF_MESH_COLOUR_NONE;
    /* The density of random weights varies little: cut at its median. */
    const float box[6] = {-1, -1, -0.9f, 1, 1, 0.8f};
    memcpy(o.box, box, sizeof box);
    float pts[3 * 64], sigma[64];
    for (int i = 0; i < 64; i++) {
        pts[3 * i] = -0.9f + 0.028f * i;
        pts[3 * i + 1] = 0.5f - 0.015f * i;
        pts[3 * i + 2] = -0.8f + 0.025f * i;
    }
    float dirs[3 * 64] = {0};
    for (int i = 0; i < 64; i++) {
        dirs[3 * i + 2] = -1.0f;
    }
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_COARSE, 64, pts, dirs, NULL, sigma));
    float sorted[64];
    memcpy(sorted, sigma, sizeof sorted);
    for (int i = 1; i < 64; i++) {
        for (int j = i; j > 0 && sorted[j - 1] > sorted[j]; j--) {
            float t = sorted[j];
            sorted[j] = sorted[j - 1];
            sorted[j - 1] = t;
        }
    }
    o.threshold = sorted[32];
    nerf_mesh *ndc = NULL, *world = NULL;
    CHECK_OK(nerf_mesh_extract(&ndc, m, &o));
    nerf_sampler_options so;
    nerf_sampler_options_init(&so, sizeof so);
    CHECK_OK(nerf_sampler_options_preset(&so, NERF_PRESET_FAST));
    so.ndc = 1;
    so.t_near = 0.0f;
    so.t_far = 1.0f;
    so.ndc_focal = 50.0f;
    so.ndc_width = 80;
    so.ndc_height = 60;
    CHECK_OK(nerf_model_set_render_settings(m, &so, 0));
    CHECK_OK(nerf_mesh_extract(&world, m, &o));
    const size_t nv = nerf_mesh_vertex_count(ndc), nf = nerf_mesh_face_count(ndc);
    CHECK(nf > 0);
    CHECK_EQ_INT(nerf_mesh_vertex_count(world), nv);
    CHECK_EQ_INT(nerf_mesh_face_count(world), nf);
    if (nf == 0 || nerf_mesh_face_count(world) != nf) {
        nerf_mesh_destroy(ndc);
        nerf_mesh_destroy(world);
        nerf_model_destroy(m);
        return;
    }
    size_t off = 0;
    for (size_t i = 0; i < nv; i++) {
        const float *w = nerf_mesh_vertices(world) + 3 * i;
        const float *n = nerf_mesh_vertices(ndc) + 3 * i;
        /* The warp of camera/ndc.c with the near plane at depth 1. */
        const double x = -2.0 * 50.0 / 80.0 * w[0] / w[2];
        const double y = -2.0 * 50.0 / 60.0 * w[1] / w[2];
        const double z = 1.0 + 2.0 / w[2];
        off += !(w[2] < 0.0f && fabs(x - n[0]) < 1e-4 &&
                 fabs(y - n[1]) < 1e-4 && fabs(z - n[2]) < 1e-4);
    }
    CHECK_EQ_INT(off, 0);
    const uint32_t *fa = nerf_mesh_faces(ndc), *fb = nerf_mesh_faces(world);
    size_t unwound = 0;
    for (size_t f = 0; f < nf; f++) {
        unwound += !(fa[3 * f] == fb[3 * f] && fa[3 * f + 1] == fb[3 * f + 2] &&
                     fa[3 * f + 2] == fb[3 * f + 1]);
    }
    CHECK_EQ_INT(unwound, 0);
    nerf_mesh_destroy(ndc);
    nerf_mesh_destroy(world);
    nerf_model_destroy(m);
}

int main(void)
{
    RUN(known_density);
    RUN(mesh_of_known_density);
    RUN(box_and_threads);
    RUN(progress_and_cancel);
    RUN(bad_arguments);
    RUN(files);
    RUN(density_grid);
    RUN(ndc_back_to_world);
    HARNESS_EXIT();
}
