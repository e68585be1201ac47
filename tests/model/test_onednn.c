/*
 * oneDNN's products, bf16 (NERF_MATMUL_BF16, by default) or, with
 * --fp32-onednn, NERF_MATMUL_FP32_ONEDNN, checked layer by layer against
 * the network in double from the float inputs the products were given
 * (layer_bounds.h): bounds derived from the arithmetic, which hold for
 * any order of the sums, any processor, any of oneDNN's kernels.
 *
 * bf16 rounds both operands of every product to 8 significant bits, each
 * within 2^-8 of itself, so a product term within FLOAT_BF16_PRODUCT
 * (about 2^-7) of the exact one; the sums accumulate in fp32, within
 * gamma(K) of their terms, as fp32 products are (../float_bounds.h).
 * Forward: every layer's output against its double value from its own
 * input.  Backward: the gradient against the exact gradient at the same
 * activations, its bound carried down the layers.
 *
 * How far the bf16 or oneDNN model lands from an fp32 model end to end is
 * printed, not asserted: the rounding of one layer's output moves some
 * ReLU inputs across zero in the next, which bf16 does to many units, and
 * no bound on the whole chain is worth having.  That oneDNN ran, and bf16
 * rounded, is asked of the model (its backend, its primitives), not read
 * from results that differ.
 *
 * Without oneDNN, or where nerf_matmul_supported() says no, only the
 * checks of that refusal run, and the program reports itself skipped.
 */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>
#include <unistd.h>

#include "../harness.h"
#include "dispatch.h"
#include "gemm_onednn.h"
#include "layer.h"
#include "layer_bounds.h"
#include "model.h"
#include "nerf.h"
#include "nerf_config.h"

/* What the tests compare. */
static int kind = NERF_MATMUL_BF16;
static const char *kind_name = "bf16";

static int have_kind;

/* ---- helpers ------------------------------------------------------------ */

static uint64_t rng_state = 88172645463325252u;

static float uniform(float lo, float hi)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return lo + (hi - lo) * (float)((rng_state >> 40) / 16777216.0);
}

/* n points inside the scene's bound and unit directions. */
static void make_points(size_t n, float *pos, float *dir)
{
    for (size_t i = 0; i < n; i++) {
        float d[3], len = 0.0f;
        for (int c = 0; c < 3; c++) {
            pos[3 * i + c] = uniform(-1.2f, 1.2f);
            d[c] = uniform(-1.0f, 1.0f);
            len += d[c] * d[c];
        }
        len = sqrtf(len) + 1e-6f;
        for (int c = 0; c < 3; c++) {
            dir[3 * i + c] = d[c] / len;
        }
    }
}

static nerf_model *make_model(int preset, int matmul)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, preset);
    o.seed = 7;
    o.matmul = (uint32_t)matmul;
    if (preset == NERF_PRESET_FAST) {
        o.hash_log2_size = 14; /* a small table: tests need no more */
    }
    nerf_model *m = NULL;
    int rc = nerf_model_create(&m, &o);
    if (rc != NERF_OK) {
        FAILF("nerf_model_create(preset %d, matmul %d): %s", preset, matmul,
              nerf_last_error());
    }
    return m;
}

/* RMS of a - b relative to the RMS of b (a measurement, printed). */
static double rel_rms(const float *a, const float *b, size_t n)
{
    double d2 = 0.0, b2 = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)a[i] - b[i];
        d2 += d * d;
        b2 += (double)b[i] * b[i];
    }
    return b2 > 0.0 ? sqrt(d2 / b2) : sqrt(d2);
}

/*
 * Whether this process computes fp32 models through oneDNN
 * (NERF_FP32_PRODUCTS=onednn, where oneDNN has fp32 products): their
 * options still say NERF_MATMUL_FP32, but they have a oneDNN backend.
 */
static bool fp32_through_onednn(void)
{
    return nerf__fp32_onednn_override() &&
           nerf_matmul_supported(NERF_MATMUL_FP32_ONEDNN);
}

/* m runs kind's products through oneDNN, which made primitives. */
static void check_backend(nerf_model *m)
{
    CHECK(m->onednn != NULL);
    if (m->onednn) {
        CHECK(nerf__onednn_primitives(m->onednn) > 0);
        CHECK_EQ_INT(nerf__onednn_rounds(m->onednn), kind == NERF_MATMUL_BF16);
    }
}

/* The fast preset makes a random hash table; its weights move the same
 * way in both models, so only the products differ. */
static void copy_params(nerf_model *to, const nerf_model *from)
{
    memcpy(to->params, from->params, from->n_params * sizeof(float));
    nerf__model_weights_changed(to);
}

/* ---- what works without bf16 -------------------------------------------- */

TEST(supported_query)
{
    CHECK_EQ_INT(nerf_matmul_supported(NERF_MATMUL_FP32), 1);
    CHECK_EQ_INT(nerf_matmul_supported(3), 0);
    CHECK_EQ_INT(nerf_matmul_supported(-1), 0);
    CHECK_EQ_INT(nerf_matmul_supported(1000), 0);
    const int kinds[2] = {NERF_MATMUL_BF16, NERF_MATMUL_FP32_ONEDNN};
    for (int k = 0; k < 2; k++) {
        int yes = nerf_matmul_supported(kinds[k]);
        CHECK(yes == 0 || yes == 1);
        if (!NERF_HAVE_BF16) {
            CHECK_EQ_INT(yes, 0);
        }
        /* The answer is computed once. */
        CHECK_EQ_INT(nerf_matmul_supported(kinds[k]), yes);
    }
    CHECK(strstr(nerf_build_info(), "bf16") != NULL);
}

TEST(options)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    CHECK_EQ_INT(o.matmul, NERF_MATMUL_FP32);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    nerf_model *m = NULL;

    o.matmul = NERF_MATMUL_FP32_FASTEST + 1;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    CHECK(m == NULL);
    CHECK(strstr(nerf_last_error(), "matmul") != NULL);

    /* Presets keep the choice. */
    o.matmul = (uint32_t)kind;
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
    CHECK_EQ_INT(o.matmul, kind);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_TINY));

    int rc = nerf_model_create(&m, &o);
    if (have_kind) {
        CHECK_OK(rc);
        nerf_model_options got;
        NERF_MODEL_OPTIONS_INIT(&got);
        CHECK_OK(nerf_model_get_options(m, &got));
        CHECK_EQ_INT(got.matmul, kind);
    } else {
        CHECK_EQ_INT(rc, NERF_EINVAL);
        CHECK(m == NULL);
        CHECK(strstr(nerf_last_error(), kind == NERF_MATMUL_BF16
                                            ? "NERF_MATMUL_BF16"
                                            : "NERF_MATMUL_FP32_ONEDNN"));
        printf("  %s refused: %s\n", kind_name, nerf_last_error());
    }
    nerf_model_destroy(m);
    m = NULL;

    /* A caller built before the field existed passes a struct that ends
     * before it: whatever follows in its memory is not read, and the
     * model computes in fp32. */
    o.matmul = NERF_MATMUL_BF16;
    o.struct_size = offsetof(nerf_model_options, matmul);
    CHECK_OK(nerf_model_create(&m, &o));
    if (m) {
        nerf_model_options got;
        NERF_MODEL_OPTIONS_INIT(&got);
        CHECK_OK(nerf_model_get_options(m, &got));
        CHECK_EQ_INT(got.matmul, NERF_MATMUL_FP32);
        CHECK((m->onednn != NULL) == fp32_through_onednn());
        /* And it reads back only as much as it knows. */
        got.matmul = 77;
        got.struct_size = offsetof(nerf_model_options, matmul);
        CHECK_OK(nerf_model_get_options(m, &got));
        CHECK_EQ_INT(got.matmul, 77);
    }
    nerf_model_destroy(m);
}

/* m saved to a temporary file and loaded back (NULL, with a failure
 * reported, if that fails); the file is gone afterwards. */
static nerf_model *saved_and_loaded(const nerf_model *m)
{
    char dir[] = "/tmp/nerf-onednn-XXXXXX";
    if (m == NULL || mkdtemp(dir) == NULL) {
        FAILF("no model or no temporary folder");
        return NULL;
    }
    char path[64];
    snprintf(path, sizeof path, "%s/model.ckpt", dir);
    nerf_model *l = NULL;
    CHECK_OK(nerf_model_save(m, path));
    CHECK_OK(nerf_model_load(&l, path, NULL));
    unlink(path);
    rmdir(dir);
    return l;
}

/* The matmul a model computes with, as its options say. */
static uint32_t matmul_of(const nerf_model *m)
{
    nerf_model_options got;
    NERF_MODEL_OPTIONS_INIT(&got);
    CHECK_OK(nerf_model_get_options(m, &got));
    return got.matmul;
}

TEST(fp32_checkpoint_loads_as_fp32)
{
    nerf_model *m = make_model(NERF_PRESET_TINY, NERF_MATMUL_FP32);
    nerf_model *l = saved_and_loaded(m);
    if (l) {
        CHECK_EQ_INT(matmul_of(l), NERF_MATMUL_FP32);
        CHECK((l->onednn != NULL) == fp32_through_onednn());
    }
    nerf_model_destroy(l);
    nerf_model_destroy(m);
}

/* ---- bf16 against fp32 -------------------------------------------------- */

#if NERF_HAVE_BF16
static float bf16_value(uint16_t h)
{
    uint32_t u = (uint32_t)h << 16;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

#endif

TEST(rounding)
{
#if NERF_HAVE_BF16
    /* Exact values, ties (to even), just above a tie, signs, extremes. */
    const float in[] = {0.0f, -0.0f, 1.0f, -2.5f, 1.0f + 1.0f / 256,
                        1.0f + 3.0f / 256, 1.0f + 1.0f / 256 + 1.0f / 65536,
                        FLT_MAX, INFINITY, -INFINITY, 1e-40f};
    const float want[] = {0.0f, -0.0f, 1.0f, -2.5f, 1.0f, 1.0f + 4.0f / 256,
                          1.0f + 2.0f / 256, INFINITY, INFINITY, -INFINITY,
                          bf16_value(0x0001)};
    const size_t n = sizeof in / sizeof in[0];
    uint16_t out[sizeof in / sizeof in[0]];
    nerf__bf16_round(in, n, out);
    for (size_t i = 0; i < n; i++) {
        float got = bf16_value(out[i]);
        if (memcmp(&got, &want[i], sizeof got) != 0) {
            FAILF("round(%.9g) = %.9g, want %.9g", (double)in[i],
                  (double)got, (double)want[i]);
        }
    }
    float nan = NAN;
    uint16_t h;
    nerf__bf16_round(&nan, 1, &h);
    CHECK(isnan(bf16_value(h)));
    /* Against the definition, on random values: the nearest bf16. */
    for (int i = 0; i < 100000; i++) {
        float x = uniform(-1.0f, 1.0f) * powf(2.0f, uniform(-30.0f, 30.0f));
        nerf__bf16_round(&x, 1, &h);
        float r = bf16_value(h), up = bf16_value((uint16_t)(h + 1));
        float down = bf16_value((uint16_t)(h - 1));
        double e = fabs((double)r - x);
        if (e > fabs((double)up - x) || e > fabs((double)down - x)) {
            FAILF("round(%.9g) = %.9g is not the nearest", (double)x,
                  (double)r);
            break;
        }
    }
#endif
}

/*
 * A forward of network net of m, keeping its activations, checked layer
 * by layer against double (layer_bounds.h) with m's products as they are
 * now; rgb and sigma, when not NULL, receive its outputs.
 */
static void forward_checked(nerf_model *m, int net, size_t n,
                            const float *pos, const float *dir,
                            nerf__workspace *ws, float *rgb, float *sigma,
                            const char *what)
{
    float *s = sigma ? sigma : malloc(n * sizeof(float));
    CHECK_OK(nerf__model_forward(m, net, ws, n, pos, dir, rgb, s));
    lb_net b;
    lb_open(&b, &m->nets[net], m->params);
    double worst = lb_check_forward(&b, ws, pos, s, lb_eps(&m->nets[net]),
                                    what);
    printf("  %s, network %d forward: at most %.3f of the bounds\n", what,
           net, worst);
    lb_close(&b);
    if (s != sigma) {
        free(s);
    }
}

/*
 * The oneDNN model's forward, layer by layer against double.  Its query
 * is the same products without the kept activations (the same bits), and
 * how far it lands from the fp32 model's is printed.
 */
static void compare_forward(int preset, const char *name, size_t n)
{
    nerf_model *f = make_model(preset, NERF_MATMUL_FP32);
    nerf_model *b = make_model(preset, kind);
    if (f == NULL || b == NULL) {
        nerf_model_destroy(f);
        nerf_model_destroy(b);
        return;
    }
    copy_params(b, f);
    float *pos = malloc(n * 3 * sizeof(float));
    float *dir = malloc(n * 3 * sizeof(float));
    float *rgb[3], *sigma[3];
    for (int k = 0; k < 3; k++) {
        rgb[k] = malloc(n * 3 * sizeof(float));
        sigma[k] = malloc(n * sizeof(float));
    }
    make_points(n, pos, dir);
    for (uint32_t net = 0; net < f->n_nets; net++) {
        nerf__workspace ws;
        memset(&ws, 0, sizeof ws);
        forward_checked(b, (int)net, n, pos, dir, &ws, rgb[2], sigma[2],
                        name);
        nerf__workspace_release(&b->env, &ws);
        check_backend(b);
        CHECK_OK(nerf_model_query(f, (int)net, n, pos, dir, rgb[0], sigma[0]));
        CHECK_OK(nerf_model_query(b, (int)net, n, pos, dir, rgb[1], sigma[1]));
        CHECK(memcmp(rgb[1], rgb[2], n * 3 * sizeof(float)) == 0);
        CHECK(memcmp(sigma[1], sigma[2], n * sizeof(float)) == 0);
        printf("  %s, network %u: against fp32, relative RMS rgb %.2e, "
               "sigma %.2e\n", name, net, rel_rms(rgb[1], rgb[0], 3 * n),
               rel_rms(sigma[1], sigma[0], n));
    }
    for (int k = 0; k < 3; k++) {
        free(rgb[k]);
        free(sigma[k]);
    }
    free(pos);
    free(dir);
    nerf_model_destroy(f);
    nerf_model_destroy(b);
}

/* 3001 samples: odd, so that the last row runs padded; the reference
 * network in 257 (256 and a padded row), its layers being a hundred times
 * the others' work to check in double. */
TEST(forward_matches_fp32)
{
    compare_forward(NERF_PRESET_REFERENCE, "reference", 257);
    compare_forward(NERF_PRESET_FAST, "fast", 3001);
    compare_forward(NERF_PRESET_TINY, "tiny", 3001);
}

/* The layers of a network, in order: trunk, head, colour branch. */
static int network_layers(const nerf__network *nw, nerf__linear *layers)
{
    int count = 0;
    for (uint32_t i = 0; i < nw->depth; i++) {
        layers[count++] = nw->trunk[i];
    }
    layers[count++] = nw->head;
    if (nw->use_viewdirs) {
        for (uint32_t k = 0; k < nw->view_depth; k++) {
            layers[count++] = nw->view[k];
        }
        layers[count++] = nw->rgb;
    }
    return count;
}

/* The largest relative RMS difference of a layer's gradient (W and b)
 * or the hash table's, g against want: a measurement. */
static double worst_layer(const nerf__network *nw, const float *g,
                          const float *want)
{
    nerf__linear layers[NERF__MAX_DEPTH + NERF__MAX_VIEW_DEPTH + 2];
    int count = network_layers(nw, layers);
    double worst = 0.0;
    for (int l = 0; l < count; l++) {
        size_t len = (size_t)layers[l].in * layers[l].out + layers[l].out;
        double e = rel_rms(g + layers[l].w, want + layers[l].w, len);
        worst = e > worst ? e : worst;
    }
    if (nerf__encoding_params(&nw->pos_enc)) {
        double e = rel_rms(g + nw->pos_params, want + nw->pos_params,
                           nw->pos_enc.u.hash.count);
        worst = e > worst ? e : worst;
    }
    return worst;
}

static double cosine(const float *a, const float *b, size_t n)
{
    double ab = 0.0, aa = 0.0, bb = 0.0;
    for (size_t i = 0; i < n; i++) {
        ab += (double)a[i] * b[i];
        aa += (double)a[i] * a[i];
        bb += (double)b[i] * b[i];
    }
    return ab / sqrt(aa * bb + 1e-300);
}

/* The backward of the forward kept in ws into m's zeroed gradients,
 * checked against the exact gradient at ws's activations. */
static void backward_checked(nerf_model *m, int net, nerf__workspace *ws,
                             const float *pos, const float *d_rgb,
                             const float *d_sigma, const char *what)
{
    nerf__model_zero_grad(m);
    CHECK_OK(nerf__model_backward(m, net, ws, d_rgb, d_sigma));
    lb_net b;
    lb_open(&b, &m->nets[net], m->params);
    double worst = lb_check_backward(&b, ws, pos, d_rgb, d_sigma, m->grads,
                                     lb_eps(&m->nets[net]), what);
    printf("  %s, network %d backward: at most %.3f of the bounds\n", what,
           net, worst);
    lb_close(&b);
}

/*
 * Each layer's backward products alone (nerf__layer_backward()), through
 * network net's backend, on the inputs the forward kept in ws and a
 * gradient drawn here: dW and dX against double, each within one
 * product's bound.  The whole backward's bound carries the error of every
 * layer's gradient to the layers below; for bf16 over the reference
 * network's eleven layers that grows past the gradients themselves, so
 * these products are checked one by one as well.  Returns the worst ratio
 * to a bound.
 */
static double check_layer_products(nerf_model *m, int net,
                                   nerf__workspace *ws, const char *what)
{
    const nerf__network *nw = &m->nets[net];
    const double eps = lb_eps(nw);
    const nerf__layer_ctx ctx = {nw->onednn, &ws->onednn, &ws->env};
    const size_t n = ws->n;
    const uint32_t W = nw->width, V = nw->view_width, Ep = nw->pos_width;
    const uint32_t HW = nerf__network_head_width(nw);
    nerf__linear layers[NERF__MAX_DEPTH + NERF__MAX_VIEW_DEPTH + 2];
    const int count = network_layers(nw, layers);
    lb_result res = {0.0, 0};
    for (int li = 0; li < count; li++) {
        const nerf__linear *l = &layers[li];
        const uint32_t i = (uint32_t)li;
        /* The layer's input parts, as network.c gives them. */
        nerf__layer_part parts[2];
        int np = 1;
        if (i == 0) {
            parts[0] = (nerf__layer_part){ws->enc_pos, Ep, Ep};
        } else if (i < nw->depth) {
            const nerf__layer_part h = {nerf__trunk_buffer(nw, ws, i - 1), W,
                                        W};
            parts[0] = h;
            if (i == nw->skip) {
                parts[0] = (nerf__layer_part){ws->enc_pos, Ep, Ep};
                parts[np++] = h;
            }
        } else if (i == nw->depth) {
            parts[0] = (nerf__layer_part){
                nerf__trunk_buffer(nw, ws, nw->depth - 1), W, W};
        } else if (i == nw->depth + 1) {
            const uint32_t F = nerf__network_feature_width(nw);
            parts[0] = (nerf__layer_part){ws->head, HW, F};
            parts[np++] = (nerf__layer_part){ws->enc_dir, nw->dir_width,
                                             nw->dir_width};
        } else {
            parts[0] = (nerf__layer_part){
                nerf__view_buffer(nw, ws, i - nw->depth - 2), V, V};
        }
        /* The gradient goes on through the last part (the skip's h),
         * but through the head's part of the colour branch's input. */
        const int dx_part = i == nw->depth + 1 ? 0 : np - 1;
        size_t col = 0;
        for (int p = 0; p < dx_part; p++) {
            col += parts[p].in;
        }
        const uint32_t out = l->out, in = l->in, dxw = parts[dx_part].in;
        float *dy = malloc(n * out * sizeof(float));
        float *dw = calloc((size_t)out * in, sizeof(float));
        float *dx = malloc(n * dxw * sizeof(float));
        for (size_t k = 0; k < n * out; k++) {
            dy[k] = uniform(-1.0f, 1.0f);
        }
        CHECK_OK(nerf__layer_backward(&ctx, n, out, dy, out, NULL, parts, np,
                                      NULL, m->params + l->w, in, dw, dx_part,
                                      dx, dxw));
        /* dW = dY^T X in double, sample by sample, with sum |dY| |X|. */
        double *s = calloc((size_t)out * in, sizeof(double));
        double *mag = calloc((size_t)out * in, sizeof(double));
        double *x = malloc(in * sizeof(double));
        for (size_t r = 0; r < n; r++) {
            for (int p = 0, at = 0; p < np; at += (int)parts[p].in, p++) {
                lb_widen(parts[p].x + r * parts[p].ldx, parts[p].in, x + at);
            }
            for (uint32_t o = 0; o < out; o++) {
                const double d = dy[r * out + o], a = fabs(d);
                double *so = s + (size_t)o * in, *mo = mag + (size_t)o * in;
                for (uint32_t k = 0; k < in; k++) {
                    so[k] += d * x[k];
                    mo[k] += a * fabs(x[k]);
                }
            }
        }
        for (size_t j = 0; j < (size_t)out * in; j++) {
            lb_compare(&res, what, "dW of", li, j / in, j % in, dw[j], s[j],
                       float_product_bound((double)n + 1, eps, 0.0, mag[j]));
        }
        free(s);
        free(mag);
        free(x);
        for (size_t r = 0; r < n; r++) {
            for (uint32_t k = 0; k < dxw; k++) {
                double v = 0.0, a = 0.0;
                for (uint32_t o = 0; o < out; o++) {
                    const double t = (double)dy[r * out + o] *
                                     m->params[l->w + o * in + col + k];
                    v += t;
                    a += fabs(t);
                }
                lb_compare(&res, what, "dX of", li, r, k, dx[r * dxw + k], v,
                           float_product_bound((double)out + 1, eps, 0.0, a));
            }
        }
        free(dy);
        free(dw);
        free(dx);
    }
    return res.worst;
}

/*
 * Gradients, two ways.
 *
 * The backward products alone: one forward of the oneDNN model, then its
 * backward against the exact gradient at those activations
 * (layer_bounds.h), and each layer's products alone
 * (check_layer_products()); how far the same backward through the CBLAS
 * lands from it is printed.
 *
 * The whole chain: an fp32 and a oneDNN model, each forward and backward,
 * with the gradient of a loss that pulls every colour towards grey and
 * every density up, each checked against double from its own
 * activations.  Between the two models the forward's rounding moves some
 * ReLU inputs across zero, and each unit that flips adds or drops a whole
 * sample's term, so how far apart their gradients land (several percent
 * on the reference trunk's first layer in bf16) is printed, not asserted.
 */
static void compare_gradients(int preset, const char *name, size_t n)
{
    nerf_model *m[2] = {make_model(preset, NERF_MATMUL_FP32),
                        make_model(preset, kind)};
    if (m[0] == NULL || m[1] == NULL) {
        nerf_model_destroy(m[0]);
        nerf_model_destroy(m[1]);
        return;
    }
    copy_params(m[1], m[0]);
    const size_t P = m[0]->n_params;
    float *pos = malloc(n * 3 * sizeof(float));
    float *dir = malloc(n * 3 * sizeof(float));
    float *rgb = malloc(n * 3 * sizeof(float));
    float *d_rgb = malloc(n * 3 * sizeof(float));
    float *d_sigma = malloc(n * sizeof(float));
    float *g_onednn = malloc(P * sizeof(float));
    char what[96];
    make_points(n, pos, dir);

    for (uint32_t net = 0; net < m[1]->n_nets; net++) {
        nerf__workspace ws;
        memset(&ws, 0, sizeof ws);
        snprintf(what, sizeof what, "%s, %s", name, kind_name);
        /* A forward checked in forward_matches_fp32. */
        CHECK_OK(nerf__model_forward(m[1], (int)net, &ws, n, pos, dir, NULL,
                                     NULL));
        for (size_t i = 0; i < 3 * n; i++) {
            d_rgb[i] = uniform(-1.0f, 1.0f);
        }
        for (size_t i = 0; i < n; i++) {
            d_sigma[i] = uniform(-1.0f, 1.0f);
        }
        backward_checked(m[1], (int)net, &ws, pos, d_rgb, d_sigma, what);
        memcpy(g_onednn, m[1]->grads, P * sizeof(float));
        printf("  %s, network %u: each layer's backward products at most "
               "%.3f of their bounds\n", what, net,
               check_layer_products(m[1], (int)net, &ws, what));
        /* The same backward through the CBLAS (whose path the fp32 model
         * below is checked on), for the distance printed. */
        struct nerf__onednn *keep = m[1]->nets[net].onednn;
        m[1]->nets[net].onednn = NULL;
        nerf__model_zero_grad(m[1]);
        CHECK_OK(nerf__model_backward(m[1], (int)net, &ws, d_rgb, d_sigma));
        m[1]->nets[net].onednn = keep;
        nerf__workspace_release(&m[1]->env, &ws);
        printf("  %s, network %u: backward products apart from the CBLAS's "
               "by at most %.2e (relative RMS of a layer)\n", name, net,
               worst_layer(&m[1]->nets[net], g_onednn, m[1]->grads));
    }

    float *g[2] = {malloc(P * sizeof(float)), malloc(P * sizeof(float))};
    for (uint32_t net = 0; net < m[0]->n_nets; net++) {
        for (int k = 0; k < 2; k++) {
            nerf__workspace ws;
            memset(&ws, 0, sizeof ws);
            snprintf(what, sizeof what, "%s, %s, whole chain", name,
                     k ? kind_name : "fp32");
            if (k == 0) {
                forward_checked(m[k], (int)net, n, pos, dir, &ws, rgb, NULL,
                                what);
            } else { /* checked in forward_matches_fp32 */
                CHECK_OK(nerf__model_forward(m[k], (int)net, &ws, n, pos, dir,
                                             rgb, NULL));
            }
            for (size_t i = 0; i < 3 * n; i++) {
                d_rgb[i] = 2.0f * (rgb[i] - 0.5f) / (float)n;
            }
            for (size_t i = 0; i < n; i++) {
                d_sigma[i] = -1.0f / (float)n;
            }
            backward_checked(m[k], (int)net, &ws, pos, d_rgb, d_sigma, what);
            memcpy(g[k], m[k]->grads, P * sizeof(float));
            nerf__workspace_release(&m[k]->env, &ws);
        }
        const nerf__network *nw = &m[0]->nets[net];
        printf("  %s, network %u: whole chain against fp32, worst layer "
               "%.2e (relative RMS), cosine %.6f\n", name, net,
               worst_layer(nw, g[1], g[0]),
               cosine(g[1] + nw->offset, g[0] + nw->offset, nw->count));
    }
    check_backend(m[1]);
    free(g[0]);
    free(g[1]);
    free(pos);
    free(dir);
    free(rgb);
    free(d_rgb);
    free(d_sigma);
    free(g_onednn);
    nerf_model_destroy(m[0]);
    nerf_model_destroy(m[1]);
}

/* 2049 samples: 2048 and a padded row; the reference network in 257, as
 * above. */
TEST(gradients_match_fp32)
{
    compare_gradients(NERF_PRESET_REFERENCE, "reference", 257);
    compare_gradients(NERF_PRESET_FAST, "fast", 2049);
    compare_gradients(NERF_PRESET_TINY, "tiny", 2049);
}

/* Network net's parameter gradients for d_rgb at n points, into g. */
static void gradients_of(nerf_model *m, int net, size_t n, const float *pos,
                         const float *dir, const float *d_rgb, float *g)
{
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    nerf__model_zero_grad(m);
    CHECK_OK(nerf__model_forward(m, net, &ws, n, pos, dir, NULL, NULL));
    CHECK_OK(nerf__model_backward(m, net, &ws, d_rgb, NULL));
    nerf__workspace_release(&m->env, &ws);
    memcpy(g, m->grads, m->n_params * sizeof(float));
}

/*
 * Repeating a forward and a backward gives the same bits, and a row's
 * output does not depend on which rows share its call (so images do not
 * depend on chunk sizes or thread counts) while oneDNN's primitives are
 * its brgemm kernels, as the model records (nerf__model_rows_alone()):
 * another kernel may order a row's sums by the call's size, and then
 * only the layer bounds above hold.
 */
TEST(deterministic)
{
    nerf_model *m = make_model(NERF_PRESET_REFERENCE, kind);
    if (m == NULL) {
        return;
    }
    const size_t n = 1500, cut = 701;
    float *pos = malloc(n * 3 * sizeof(float));
    float *dir = malloc(n * 3 * sizeof(float));
    float *a = malloc(n * 4 * sizeof(float));
    float *b = malloc(n * 4 * sizeof(float));
    make_points(n, pos, dir);
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_FINE, n, pos, dir, a, a + 3 * n));
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_FINE, n, pos, dir, b, b + 3 * n));
    CHECK(memcmp(a, b, n * 4 * sizeof(float)) == 0);
    /* The same rows in two calls of other sizes (odd: padded rows), and
     * single rows. */
    memset(b, 0, n * 4 * sizeof(float));
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_FINE, cut, pos, dir, b,
                              b + 3 * n));
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_FINE, n - cut, pos + 3 * cut,
                              dir + 3 * cut, b + 3 * cut, b + 3 * n + cut));
    float rgb[4][3], sigma[4];
    for (size_t i = 1; i < 5; i++) {
        CHECK_OK(nerf_model_query(m, NERF_NETWORK_FINE, 1, pos + 3 * (i * 97),
                                  dir + 3 * (i * 97), rgb[i - 1],
                                  &sigma[i - 1]));
    }
    if (nerf__model_rows_alone(m)) {
        CHECK(memcmp(a, b, n * 4 * sizeof(float)) == 0);
        for (size_t i = 1; i < 5; i++) {
            CHECK(memcmp(rgb[i - 1], a + 3 * (i * 97), sizeof rgb[0]) == 0);
            CHECK(memcmp(&sigma[i - 1], a + 3 * n + i * 97,
                         sizeof sigma[0]) == 0);
        }
    } else {
        printf("  not every primitive oneDNN made is brgemm: rows in calls "
               "of other sizes may round otherwise, not compared\n");
    }
    /* Gradients: twice the same. */
    float *g[2] = {malloc(m->n_params * sizeof(float)),
                   malloc(m->n_params * sizeof(float))};
    float *d_rgb = malloc(n * 3 * sizeof(float));
    for (size_t i = 0; i < 3 * n; i++) {
        d_rgb[i] = uniform(-1.0f, 1.0f);
    }
    for (int rep = 0; rep < 2; rep++) {
        gradients_of(m, 1, n, pos, dir, d_rgb, g[rep]);
    }
    CHECK(memcmp(g[0], g[1], m->n_params * sizeof(float)) == 0);
    free(g[0]);
    free(g[1]);
    free(d_rgb);
    free(pos);
    free(dir);
    free(a);
    free(b);
    nerf_model_destroy(m);
}

/*
 * Signals caught while products run change nothing.  oneDNN 2.x's
 * generated gemm kernels point the stack pointer into the heap while they
 * run, so a signal frame written there used to corrupt the heap (seen as
 * nerf-train's Ctrl-C aborting in free() about one time in ten): a timer
 * signal every 20 microseconds over forward and backward passes of the
 * tiny network, whose first layer's weight gradient gets such a kernel,
 * then gave other gradients or an abort.
 */
static volatile sig_atomic_t alarms;

static void count_alarm(int sig)
{
    (void)sig;
    alarms++;
}

TEST(signals_during_products)
{
    nerf_model *m = make_model(NERF_PRESET_TINY, kind);
    if (m == NULL) {
        return;
    }
    const size_t n = 6144;
    float *pos = malloc(n * 3 * sizeof(float));
    float *dir = malloc(n * 3 * sizeof(float));
    float *d_rgb = malloc(n * 3 * sizeof(float));
    float *want = malloc(m->n_params * sizeof(float));
    float *got = malloc(m->n_params * sizeof(float));
    make_points(n, pos, dir);
    for (size_t i = 0; i < 3 * n; i++) {
        d_rgb[i] = uniform(-1.0f, 1.0f);
    }
    gradients_of(m, 0, n, pos, dir, d_rgb, want);
    struct sigaction sa, old_sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = count_alarm;
    sa.sa_flags = SA_RESTART;
    sigemptyset(&sa.sa_mask);
    CHECK(sigaction(SIGALRM, &sa, &old_sa) == 0);
    const struct itimerval every = {{0, 20}, {0, 20}}, off = {{0, 0}, {0, 0}};
    alarms = 0;
    CHECK(setitimer(ITIMER_REAL, &every, NULL) == 0);
    int same = 0;
    const int rounds = 30;
    for (int r = 0; r < rounds; r++) {
        gradients_of(m, 0, n, pos, dir, d_rgb, got);
        same += memcmp(got, want, m->n_params * sizeof(float)) == 0;
    }
    setitimer(ITIMER_REAL, &off, NULL);
    sigaction(SIGALRM, &old_sa, NULL);
    printf("  %d signals caught over %d passes, %d with the same gradients\n",
           (int)alarms, rounds, same);
    CHECK(alarms > 0);
    CHECK_EQ_INT(same, rounds);
    free(pos);
    free(dir);
    free(d_rgb);
    free(want);
    free(got);
    nerf_model_destroy(m);
}

/*
 * bf16: the rounded weights are a cache: a product does not round them
 * again, so a write the model was not told about goes unseen, and after an
 * optimiser step (or nerf__model_weights_changed) the new weights count.
 * fp32 reads the weights in place, so every write counts at once.
 */
TEST(weights_refresh_when_they_change)
{
    nerf_model *b = make_model(NERF_PRESET_TINY, kind);
    nerf_model *f = make_model(NERF_PRESET_TINY, NERF_MATMUL_FP32);
    if (b == NULL || f == NULL) {
        nerf_model_destroy(b);
        nerf_model_destroy(f);
        return;
    }
    enum { N = 257 };
    float pos[3 * N], dir[3 * N], r0[4 * N], r1[4 * N], r2[4 * N];
    make_points(N, pos, dir);
    CHECK_OK(nerf_model_query(b, 0, N, pos, dir, r0, r0 + 3 * N));
    /* Scale every layer's weights (not the biases, which the products
     * read in fp32) behind the model's back. */
    nerf__linear layers[NERF__MAX_DEPTH + NERF__MAX_VIEW_DEPTH + 2];
    int count = network_layers(&b->nets[0], layers);
    for (int l = 0; l < count; l++) {
        for (size_t i = 0; i < (size_t)layers[l].in * layers[l].out; i++) {
            b->params[layers[l].w + i] *= 1.5f;
        }
    }
    CHECK_OK(nerf_model_query(b, 0, N, pos, dir, r1, r1 + 3 * N));
    if (kind == NERF_MATMUL_BF16) {
        CHECK(memcmp(r0, r1, sizeof r0) == 0);
    } else {
        CHECK(memcmp(r0, r1, sizeof r0) != 0);
    }
    nerf__model_weights_changed(b);
    CHECK_OK(nerf_model_query(b, 0, N, pos, dir, r1, r1 + 3 * N));
    CHECK(memcmp(r0, r1, sizeof r0) != 0);

    /* An Adam step: the oneDNN model follows its new weights, as an fp32
     * model holding the same weights says. */
    for (size_t i = 0; i < b->n_params; i++) {
        b->grads[i] = uniform(-1.0f, 1.0f);
    }
    nerf__model_adam_step(b);
    CHECK_OK(nerf_model_query(b, 0, N, pos, dir, r1, r1 + 3 * N));
    memcpy(f->params, b->params, b->n_params * sizeof(float));
    CHECK_OK(nerf_model_query(f, 0, N, pos, dir, r2, r2 + 3 * N));
    printf("  after a step: relative RMS against fp32 %.2e\n",
           rel_rms(r1, r2, 4 * N));
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    forward_checked(b, 0, N, pos, dir, &ws, NULL, NULL, "after a step");
    nerf__workspace_release(&b->env, &ws);
    nerf_model_destroy(b);
    nerf_model_destroy(f);
}

TEST(checkpoint_round_trip)
{
    nerf_model *m = make_model(NERF_PRESET_FAST, kind);
    if (m == NULL) {
        return;
    }
    for (size_t i = 0; i < m->n_params; i++) {
        m->grads[i] = uniform(-1.0f, 1.0f);
    }
    nerf__model_adam_step(m);
    nerf_model *l = saved_and_loaded(m);
    if (l) {
        CHECK_EQ_INT(matmul_of(l), kind);
        CHECK(l->onednn != NULL);
        CHECK(memcmp(l->params, m->params, m->n_params * sizeof(float)) == 0);
        enum { N = 333 };
        float pos[3 * N], dirs[3 * N], a[4 * N], b[4 * N];
        make_points(N, pos, dirs);
        CHECK_OK(nerf_model_query(m, 0, N, pos, dirs, a, a + 3 * N));
        CHECK_OK(nerf_model_query(l, 0, N, pos, dirs, b, b + 3 * N));
        CHECK(memcmp(a, b, sizeof a) == 0);
    }
    nerf_model_destroy(l);
    nerf_model_destroy(m);
}

/* Several threads querying one oneDNN model at once (the threading
 * contract allows it) get what one thread gets. */
typedef struct query_job {
    const nerf_model *m;
    size_t n;
    const float *pos, *dir;
    float *out;
    int rc;
} query_job;

static void *query_thread(void *arg)
{
    query_job *j = arg;
    for (int rep = 0; rep < 3 && j->rc == NERF_OK; rep++) {
        j->rc = nerf_model_query(j->m, NERF_NETWORK_FINE, j->n, j->pos, j->dir,
                                 j->out, j->out + 3 * j->n);
    }
    return NULL;
}

TEST(concurrent_queries)
{
    nerf_model *m = make_model(NERF_PRESET_TINY, kind);
    if (m == NULL) {
        return;
    }
    enum { N = 2500, T = 3 };
    float *pos = malloc(N * 3 * sizeof(float));
    float *dir = malloc(N * 3 * sizeof(float));
    float *want = malloc(N * 4 * sizeof(float));
    make_points(N, pos, dir);
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_FINE, N, pos, dir, want,
                              want + 3 * N));
    query_job jobs[T];
    pthread_t th[T];
    for (int t = 0; t < T; t++) {
        jobs[t] = (query_job){m, N, pos, dir, malloc(N * 4 * sizeof(float)),
                              NERF_OK};
        CHECK(pthread_create(&th[t], NULL, query_thread, &jobs[t]) == 0);
    }
    for (int t = 0; t < T; t++) {
        pthread_join(th[t], NULL);
        CHECK_EQ_INT(jobs[t].rc, NERF_OK);
        CHECK(memcmp(jobs[t].out, want, N * 4 * sizeof(float)) == 0);
        free(jobs[t].out);
    }
    free(pos);
    free(dir);
    free(want);
    nerf_model_destroy(m);
}

/*
 * With --fp32-onednn the tests compare NERF_MATMUL_FP32_ONEDNN instead of
 * bf16.  With --unsupported (meson runs it so with oneDNN's ISA capped at
 * AVX2, below AVX512-BF16 and without fp32 brgemm) that kind must be
 * refused, and the refusal is the test.
 */
int main(int argc, char **argv)
{
    int refusal = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--unsupported") == 0) {
            refusal = 1;
        } else if (strcmp(argv[i], "--fp32-onednn") == 0) {
            kind = NERF_MATMUL_FP32_ONEDNN;
            kind_name = "oneDNN fp32";
        }
    }
    have_kind = nerf_matmul_supported(kind);
    if (refusal && have_kind) {
        printf("FAIL: %s is still available (DNNL_MAX_CPU_ISA=%s)\n",
               kind_name, getenv("DNNL_MAX_CPU_ISA")
                              ? getenv("DNNL_MAX_CPU_ISA")
                              : "(unset)");
        return 1;
    }
    RUN(supported_query);
    RUN(options);
    RUN(fp32_checkpoint_loads_as_fp32);
    if (refusal) {
        HARNESS_EXIT();
    }
    if (!have_kind) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        o.matmul = (uint32_t)kind;
        nerf_model *m = NULL;
        nerf_model_create(&m, &o);
        printf("SKIP: %s products are not available, so only their "
               "refusal was tested (%s)\n", kind_name, nerf_last_error());
        return harness_failed ? 1 : 77;
    }
    if (kind == NERF_MATMUL_BF16) {
        RUN(rounding);
    }
    RUN(forward_matches_fp32);
    RUN(gradients_match_fp32);
    RUN(deterministic);
    RUN(weights_refresh_when_they_change);
    RUN(checkpoint_round_trip);
    RUN(concurrent_queries);
    RUN(signals_during_products);
    HARNESS_EXIT();
}
