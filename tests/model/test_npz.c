/*
 * Importing reference weights from .npz.  The test writes its own archives
 * (float32 and float64 members, stored and deflated, NumPy's zip64-style
 * local headers) and checks nerf_model_query() against a plain
 * double-precision forward pass written here from the reference
 * implementation's definition, layer by layer from the library's own
 * float activations.
 */
#include <dirent.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>
#include <unistd.h>

#include "../harness.h"
#include "layer_bounds.h"
#include "model.h"
#include "nerf.h"
#include "npz_writer.h"

static char tmpdir[64];

static void spit(const char *path, const bytes *b)
{
    FILE *f = fopen(path, "wb");
    if (f != NULL) {
        fwrite(b->p, 1, b->n, f);
        fclose(f);
    }
}

/* ---- the reference network, in double precision ------------------------- */

typedef struct lin {
    size_t out, in;
    double *w, *b; /* w is [out, in] row-major, as in PyTorch */
} lin;

typedef struct refnet {
    const nerf_model_options *o;
    lin trunk[8], feature, alpha, views, rgb, output;
} refnet;

static uint64_t rng_state = 88172645463325252ull;

static double uniform(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Weights rounded to float, so that float and double members hold the
 * same values and the comparison measures only arithmetic. */
static void make_lin(lin *l, size_t out, size_t in)
{
    double bound = 1.0 / sqrt((double)in);
    l->out = out;
    l->in = in;
    l->w = malloc(out * in * sizeof(double));
    l->b = malloc(out * sizeof(double));
    for (size_t i = 0; i < out * in; i++) {
        l->w[i] = (float)((2 * uniform() - 1) * bound);
    }
    for (size_t i = 0; i < out; i++) {
        l->b[i] = (float)((2 * uniform() - 1) * bound);
    }
}

static size_t enc_width(const nerf_model_options *o, uint32_t L)
{
    bool raw = o->encoding_flags & NERF_ENCODING_INCLUDE_INPUT;
    return (raw ? 3 : 0) + 6 * (size_t)L;
}

/* output_rows: the reference's output_linear has 5 rows (one unused)
 * when it also trains a fine network. */
static void make_refnet(refnet *r, const nerf_model_options *o,
                        size_t output_rows)
{
    memset(r, 0, sizeof *r);
    r->o = o;
    size_t W = o->width, Ep = enc_width(o, o->pos_frequencies);
    for (uint32_t i = 0; i < o->depth; i++) {
        size_t in = i == 0 ? Ep : W + (i == o->skip_layer ? Ep : 0);
        make_lin(&r->trunk[i], W, in);
    }
    if (o->use_viewdirs) {
        make_lin(&r->feature, W, W);
        make_lin(&r->alpha, 1, W);
        make_lin(&r->views, o->view_width,
                 W + enc_width(o, o->dir_frequencies));
        make_lin(&r->rgb, 3, o->view_width);
    } else {
        make_lin(&r->output, output_rows, W);
    }
}

static void free_refnet(refnet *r)
{
    lin *all[13] = {&r->feature, &r->alpha, &r->views, &r->rgb, &r->output};
    for (int i = 0; i < 8; i++) {
        all[5 + i] = &r->trunk[i];
    }
    for (int i = 0; i < 13; i++) {
        free(all[i]->w);
        free(all[i]->b);
    }
}

/* [x, sin(x), cos(x), sin(2x), cos(2x), ...], three sines then three
 * cosines per frequency. */
static size_t encode(const nerf_model_options *o, const float *x, uint32_t L,
                     double *out)
{
    size_t n = 0;
    double scale = o->encoding_flags & NERF_ENCODING_SCALE_PI
                       ? 3.14159265358979323846
                       : 1.0;
    if (o->encoding_flags & NERF_ENCODING_INCLUDE_INPUT) {
        for (int c = 0; c < 3; c++) {
            out[n++] = x[c];
        }
    }
    for (uint32_t k = 0; k < L; k++) {
        for (int c = 0; c < 3; c++) {
            out[n + c] = sin(ldexp(scale * x[c], (int)k));
            out[n + 3 + c] = cos(ldexp(scale * x[c], (int)k));
        }
        n += 6;
    }
    return n;
}

static double sigmoid(double z)
{
    return 1 / (1 + exp(-z));
}

/* ---- archives of reference weights -------------------------------------- */

/* Members alternate between float32 and float64, stored and deflated, and
 * plain and zip64-style local headers, so every combination is read. */
static void add_array(archive *a, const char *name, const double *v,
                      size_t rows, size_t cols)
{
    int k = a->n;
    member *m = add_member(a, name);
    size_t shape[2] = {rows, cols};
    npy_write(&m->data, k % 3 == 1 ? "<f8" : "<f4", false, shape,
              cols ? 2 : 1, v);
    m->method = k % 2 == 0 ? 8 : 0;
    m->zip64_local = k % 4 >= 2;
}

static void add_lin(archive *a, const char *net, const char *layer,
                    const lin *l)
{
    char name[128];
    snprintf(name, sizeof name, "%s.%s.weight.npy", net, layer);
    add_array(a, name, l->w, l->out, l->in);
    snprintf(name, sizeof name, "%s.%s.bias.npy", net, layer);
    add_array(a, name, l->b, l->out, 0);
}

static void add_net(archive *a, const char *net, const refnet *r)
{
    for (uint32_t i = 0; i < r->o->depth; i++) {
        char layer[32];
        snprintf(layer, sizeof layer, "pts_linears.%u", (unsigned)i);
        add_lin(a, net, layer, &r->trunk[i]);
    }
    if (r->o->use_viewdirs) {
        add_lin(a, net, "feature_linear", &r->feature);
        add_lin(a, net, "alpha_linear", &r->alpha);
        add_lin(a, net, "views_linears.0", &r->views);
        add_lin(a, net, "rgb_linear", &r->rgb);
    } else {
        add_lin(a, net, "output_linear", &r->output);
    }
}

static member *find(archive *a, const char *name)
{
    for (int i = 0; i < a->n; i++) {
        if (strcmp(a->m[i].name, name) == 0) {
            return &a->m[i];
        }
    }
    FAILF("no member %s", name);
    return &a->m[0];
}

static void write_archive(const archive *a, const char *path)
{
    bytes z = {0};
    zip_write(a, &z);
    spit(path, &z);
    free(z.p);
}

static void tiny_options(nerf_model_options *o, bool viewdirs)
{
    NERF_MODEL_OPTIONS_INIT(o);
    nerf_model_options_preset(o, NERF_PRESET_TINY);
    o->use_viewdirs = viewdirs;
    o->use_fine = viewdirs;
}

static void temp_path(char *buf, size_t size, const char *name)
{
    snprintf(buf, size, "%s/%s", tmpdir, name);
}

/* ---- importing ---------------------------------------------------------- */

static char warnings[4096];

static void keep_warnings(int level, const char *msg, void *user)
{
    (void)user;
    size_t at = strlen(warnings);
    if (level == NERF_LOG_WARN && at + strlen(msg) + 2 < sizeof warnings) {
        snprintf(warnings + at, sizeof warnings - at, "%s\n", msg);
    }
}

/*
 * Reference layer l at the library's float input x (in double) against
 * the library's float output y: within float_product_bound() of its
 * double value (ReLU is 1-Lipschitz; the sigmoid's slope is at most 1/4,
 * and the library's sigmoid errs by FLOAT_SIGMOID_ABS).
 */
enum { LINEAR, RELU, SIGMOID };

static void check_lin(const char *name, const lin *l, size_t rows,
                      const double *x, const float *y, int act, double eps,
                      size_t sample, lb_result *res)
{
    for (size_t o = 0; o < rows; o++) {
        double s = l->b[o], mag = 0.0;
        for (size_t k = 0; k < l->in; k++) {
            const double t = l->w[o * l->in + k] * x[k];
            s += t;
            mag += fabs(t);
        }
        double e = float_product_bound((double)l->in + 1, eps, fabs(l->b[o]),
                                       mag);
        if (act == RELU) {
            s = s > 0 ? s : 0;
        } else if (act == SIGMOID) {
            s = sigmoid(s);
            e = e / 4 + FLOAT_SIGMOID_ABS;
        }
        lb_compare(res, "imported network", name, 0, sample, o, y[o], s, e);
    }
}

static void widen(const float *x, size_t n, double *out)
{
    for (size_t k = 0; k < n; k++) {
        out[k] = x[k];
    }
}

/*
 * The imported network's query against the reference's layers: the
 * query's outputs are those of a forward keeping its activations (the
 * same products), whose encodings are checked against the reference's
 * and each layer against the reference's layer from the same float
 * input.  So the bounds need no error carried through the layers, and
 * hold whatever kernel computes the products.
 */
static void compare_with_reference(nerf_model *m, int network,
                                   const refnet *r)
{
    enum { N = 64 };
    const nerf_model_options *o = r->o;
    float pos[3 * N], dir[3 * N], rgb[3 * N], sigma[N];
    float rgb2[3 * N], sigma2[N];
    for (int i = 0; i < N; i++) {
        double d[3], norm = 0;
        for (int c = 0; c < 3; c++) {
            pos[3 * i + c] = (float)(3 * uniform() - 1.5);
            d[c] = 2 * uniform() - 1;
            norm += d[c] * d[c];
        }
        for (int c = 0; c < 3; c++) {
            dir[3 * i + c] = (float)(d[c] / sqrt(norm));
        }
    }
    CHECK_OK(nerf_model_query(m, network, N, pos,
                              o->use_viewdirs ? dir : NULL, rgb, sigma));
    const int k = nerf__model_network(m, network);
    const nerf__network *net = &m->nets[k];
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    CHECK_OK(nerf__model_forward(m, k, &ws, N, pos,
                                 o->use_viewdirs ? dir : NULL, rgb2, sigma2));
    CHECK(memcmp(rgb, rgb2, sizeof rgb) == 0);
    CHECK(memcmp(sigma, sigma2, sizeof sigma) == 0);
    const double eps = lb_eps(net);
    const size_t W = o->width, Ep = net->pos_width, Ed = net->dir_width;
    const size_t HW = nerf__network_head_width(net);
    CHECK_EQ_INT(Ep, enc_width(o, o->pos_frequencies));
    lb_result res = {0.0, 0};
    double ep[64], ed[64], x[512];
    for (size_t i = 0; i < N; i++) {
        encode(o, pos + 3 * i, o->pos_frequencies, ep);
        const float *enc = ws.enc_pos + i * Ep;
        for (size_t j = 0; j < Ep; j++) {
            lb_compare(&res, "imported network", "position encoding", 0, i,
                       j, enc[j], ep[j], float_frequency_bound(ep[j]));
        }
        for (uint32_t l = 0; l < o->depth; l++) {
            size_t at = 0;
            if (l == 0 || l == o->skip_layer) {
                widen(enc, Ep, x);
                at = Ep;
            }
            if (l > 0) {
                widen(nerf__trunk_buffer(net, &ws, l - 1) + i * W, W, x + at);
            }
            check_lin("pts_linears", &r->trunk[l], W, x,
                      nerf__trunk_buffer(net, &ws, l) + i * W, RELU, eps, i,
                      &res);
        }
        widen(nerf__trunk_buffer(net, &ws, o->depth - 1) + i * W, W, x);
        const float *head = ws.head + i * HW;
        if (!o->use_viewdirs) {
            /* The first four of output_linear's rows. */
            check_lin("output_linear", &r->output, 4, x, head, LINEAR, eps,
                      i, &res);
            CHECK(sigma[i] == head[3]);
            for (int c = 0; c < 3; c++) {
                lb_compare(&res, "imported network", "rgb", 0, i, (size_t)c,
                           rgb[3 * i + c], sigmoid(head[c]),
                           FLOAT_SIGMOID_ABS);
            }
            continue;
        }
        check_lin("feature_linear", &r->feature, W, x, head, LINEAR, eps, i,
                  &res);
        check_lin("alpha_linear", &r->alpha, 1, x, head + W, LINEAR, eps, i,
                  &res);
        CHECK(sigma[i] == head[W]);
        encode(o, dir + 3 * i, o->dir_frequencies, ed);
        const float *encd = ws.enc_dir + i * Ed;
        for (size_t j = 0; j < Ed; j++) {
            lb_compare(&res, "imported network", "direction encoding", 0, i,
                       j, encd[j], ed[j], float_frequency_bound(ed[j]));
        }
        widen(head, W, x);
        widen(encd, Ed, x + W);
        check_lin("views_linears", &r->views, o->view_width, x,
                  nerf__view_buffer(net, &ws, 0) + i * o->view_width, RELU,
                  eps, i, &res);
        widen(nerf__view_buffer(net, &ws, 0) + i * o->view_width,
              o->view_width, x);
        check_lin("rgb_linear", &r->rgb, 3, x, rgb + 3 * i, SIGMOID, eps, i,
                  &res);
    }
    printf("  network %d: at most %.3f of the bounds\n", network, res.worst);
    nerf__workspace_release(nerf__model_env(m), &ws);
}

static void import_matches_reference(bool viewdirs)
{
    nerf_model_options o;
    tiny_options(&o, viewdirs);
    nerf_hooks h;
    NERF_HOOKS_INIT(&h);
    h.log_cb = keep_warnings;
    h.log_level = NERF_LOG_WARN;
    o.hooks = &h;
    refnet coarse, fine;
    make_refnet(&coarse, &o, viewdirs ? 4 : 5);
    make_refnet(&fine, &o, 4);
    static archive a;
    add_net(&a, "coarse", &coarse);
    if (viewdirs) {
        add_net(&a, "fine", &fine);
    }
    const double junk[2] = {1, 2};
    add_array(&a, "coarse.unused_thing.npy", junk, 2, 0);
    char path[128];
    temp_path(path, sizeof path, viewdirs ? "full.npz" : "small.npz");
    write_archive(&a, path);
    warnings[0] = '\0';
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_import_npz(&m, path, &o));
    CHECK(strstr(warnings, "'coarse.unused_thing.npy'") != NULL);
    CHECK(strstr(warnings, path) == warnings);
    if (m != NULL) {
        CHECK_EQ_INT(nerf_model_step(m), 0);
        size_t nonzero = 0;
        for (size_t i = 0; i < m->n_params; i++) {
            nonzero += m->adam_m[i] != 0 || m->adam_v[i] != 0;
        }
        CHECK_EQ_INT(nonzero, 0);
        compare_with_reference(m, NERF_NETWORK_COARSE, &coarse);
        if (viewdirs) {
            compare_with_reference(m, NERF_NETWORK_FINE, &fine);
        }
    }
    nerf_model_destroy(m);
    free_archive(&a);
    free_refnet(&coarse);
    free_refnet(&fine);
}

TEST(import_viewdirs_and_fine)
{
    import_matches_reference(true);
}

TEST(import_without_viewdirs)
{
    import_matches_reference(false);
}

/* ---- broken archives ---------------------------------------------------- */

static void rewrite(member *m, const char *descr, bool fortran, size_t rows,
                    size_t cols, double first)
{
    double *v = calloc(rows * (cols ? cols : 1), sizeof(double));
    v[0] = first;
    size_t shape[2] = {rows, cols};
    m->data.n = 0;
    npy_write(&m->data, descr, fortran, shape, cols ? 2 : 1, v);
    free(v);
}

static void drop_member(archive *a)
{
    member *m = find(a, "coarse.alpha_linear.bias.npy");
    free(m->data.p);
    *m = a->m[--a->n];
}

static void transpose(archive *a)
{
    rewrite(find(a, "coarse.pts_linears.0.weight.npy"), "<f4", false, 63, 64,
            0);
}

static void break_crc(archive *a)
{
    find(a, "fine.rgb_linear.weight.npy")->bad_crc = true;
}

static void fortran(archive *a)
{
    rewrite(find(a, "coarse.feature_linear.weight.npy"), "<f4", true, 64, 64,
            0);
}

static void int32(archive *a)
{
    rewrite(find(a, "coarse.pts_linears.1.bias.npy"), "<i4", false, 64, 0, 0);
}

static void not_finite(archive *a)
{
    rewrite(find(a, "fine.views_linears.0.bias.npy"), "<f8", false, 32, 0,
            NAN);
}

static void bad_npy_magic(archive *a)
{
    find(a, "fine.pts_linears.3.weight.npy")->data.p[1] = 'X';
}

static void big_endian(archive *a)
{
    member *m = find(a, "coarse.rgb_linear.bias.npy");
    char *d = memchr(m->data.p, '<', m->data.n);
    *d = '>';
}

static void expect_import_fails(const char *what, const char *path, int want,
                                const char *needle)
{
    nerf_model_options o;
    tiny_options(&o, true);
    nerf_model *m = (nerf_model *)&o; /* must come back NULL */
    int rc = nerf_model_import_npz(&m, path, &o);
    const char *msg = nerf_last_error();
    if (rc != want || m != NULL || strstr(msg, path) != msg ||
        strstr(msg, needle) == NULL) {
        FAILF("%s: status %d (want %d), message '%s' (want '%s')", what, rc,
              want, msg, needle);
    }
    if (rc == NERF_OK) {
        nerf_model_destroy(m);
    }
}

static void broken_archive(const char *what, void (*mutate)(archive *),
                           const char *needle)
{
    nerf_model_options o;
    tiny_options(&o, true);
    refnet coarse;
    make_refnet(&coarse, &o, 4);
    static archive a;
    add_net(&a, "coarse", &coarse);
    add_net(&a, "fine", &coarse);
    mutate(&a);
    char path[128];
    temp_path(path, sizeof path, "broken.npz");
    write_archive(&a, path);
    expect_import_fails(what, path, NERF_EFORMAT, needle);
    free_archive(&a);
    free_refnet(&coarse);
}

TEST(broken_members)
{
    broken_archive("missing member", drop_member,
                   "'coarse.alpha_linear.bias.npy' is missing");
    broken_archive("wrong shape", transpose,
                   "'coarse.pts_linears.0.weight.npy': expected shape "
                   "(64, 63), found (63, 64)");
    broken_archive("bad CRC", break_crc, "CRC");
    broken_archive("fortran order", fortran, "fortran_order");
    broken_archive("int32", int32, "'<i4'");
    broken_archive("NaN", not_finite, "finite");
    broken_archive("bad npy magic", bad_npy_magic, "npy");
    broken_archive("big-endian", big_endian, "big-endian");
}

TEST(output_linear_rows)
{
    nerf_model_options o;
    tiny_options(&o, false);
    refnet r;
    make_refnet(&r, &o, 6);
    static archive a;
    add_net(&a, "coarse", &r);
    char path[128];
    temp_path(path, sizeof path, "six.npz");
    write_archive(&a, path);
    nerf_model *m = NULL;
    CHECK_EQ_INT(nerf_model_import_npz(&m, path, &o), NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "'coarse.output_linear.weight.npy': "
                 "expected shape (4, 64) or (5, 64), found (6, 64)") != NULL);
    CHECK(m == NULL);
    free_archive(&a);
    free_refnet(&r);
}

TEST(not_an_archive)
{
    char path[128];
    temp_path(path, sizeof path, "text.npz");
    bytes b = {0};
    put(&b, "just some text, not a zip archive at all\n", 41);
    spit(path, &b);
    free(b.p);
    expect_import_fails("text file", path, NERF_EFORMAT, "not a zip archive");
    temp_path(path, sizeof path, "missing.npz");
    expect_import_fails("missing file", path, NERF_ENOENT, "cannot open");

    nerf_model_options o;
    tiny_options(&o, true);
    o.width = 0;
    nerf_model *m = NULL;
    CHECK_EQ_INT(nerf_model_import_npz(&m, path, &o), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_import_npz(NULL, path, &o), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_import_npz(&m, NULL, &o), NERF_EINVAL);
    CHECK(m == NULL);
}

/* Truncations and byte damage anywhere: a clean error or, where the damage
 * hits bytes nobody reads, success; never a crash or a leak. */
TEST(damaged_archive_files)
{
    nerf_model_options o;
    tiny_options(&o, false);
    refnet r;
    make_refnet(&r, &o, 4);
    static archive a;
    add_net(&a, "coarse", &r);
    bytes z = {0};
    zip_write(&a, &z);
    char path[128];
    temp_path(path, sizeof path, "damaged.npz");
    for (size_t len = 0; len < z.n; len += len < 100 ? 1 : 211) {
        bytes cut = {z.p, len, len};
        spit(path, &cut);
        nerf_model *m = NULL;
        CHECK_EQ_INT(nerf_model_import_npz(&m, path, &o), NERF_EFORMAT);
        CHECK(m == NULL);
    }
    /* Every byte of the directory and the local headers' neighbourhood is
     * what parsing reads; the data in between only needs sampling. */
    size_t dir_at = (size_t)z.p[z.n - 6] | (size_t)z.p[z.n - 5] << 8 |
                    (size_t)z.p[z.n - 4] << 16;
    for (size_t at = 0; at < z.n; at += at < 64 || at >= dir_at ? 1 : 61) {
        z.p[at] ^= 0x5a;
        spit(path, &z);
        z.p[at] ^= 0x5a;
        nerf_model *m = NULL;
        int rc = nerf_model_import_npz(&m, path, &o);
        if (rc != NERF_OK && rc != NERF_EFORMAT) {
            FAILF("byte %zu: status %d: %s", at, rc, nerf_last_error());
        }
        CHECK((rc == NERF_OK) == (m != NULL));
        nerf_model_destroy(m);
    }
    free(z.p);
    free_archive(&a);
    free_refnet(&r);
}

int main(void)
{
    snprintf(tmpdir, sizeof tmpdir, "/tmp/nerf-npz-XXXXXX");
    if (mkdtemp(tmpdir) == NULL) {
        printf("cannot create a temporary directory\n");
        return 1;
    }
    RUN(import_viewdirs_and_fine);
    RUN(import_without_viewdirs);
    RUN(broken_members);
    RUN(output_linear_rows);
    RUN(not_an_archive);
    RUN(damaged_archive_files);
    DIR *d = opendir(tmpdir);
    for (struct dirent *e; d && (e = readdir(d)) != NULL;) {
        char path[128];
        if (e->d_name[0] != '.' &&
            snprintf(path, sizeof path, "%s/%s", tmpdir, e->d_name) <
                (int)sizeof path) {
            unlink(path);
        }
    }
    if (d) {
        closedir(d);
    }
    rmdir(tmpdir);
    HARNESS_EXIT();
}
