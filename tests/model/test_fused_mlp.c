/*
 * The fused small-MLP path (lib/mlp/network_fused.h, smm.h): its products
 * against a double-precision reference for every kernel variant this
 * processor runs, on sizes that are not multiples of the tiles; the
 * AVX-512 and AVX2 variants bit for bit against each other; and whole
 * networks (the fast preset's shape, a skip trunk, a reference head, no
 * view directions) through each variant and through the per-layer sgemm
 * path: forward, density, the forward in two halves and backward, each
 * against the network in double from that path's own activations
 * (layer_bounds.h), on sample counts that leave partial blocks and
 * chunks, with two runs giving the same bits.
 */
#include <math.h>
#include <string.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "dispatch.h"
#include "layer_bounds.h"
#include "model.h"
#include "network_fused.h"
#include "rng.h"
#include "smm.h"

static const char *variant_name(int v)
{
    static const char *names[] = {"off (sgemm)", "portable", "avx2",
                                  "avx512"};
    return names[v];
}

static float uniform(nerf__rng *r)
{
    return 2.0f * nerf__rng_uniform(r) - 1.0f;
}

/* C[i, j] as smm defines it, in double, with the sum of |terms| as the
 * scale of its rounding error. */
static void ref_entry(size_t i, uint32_t j, const nerf__smm_seg *seg, int ns,
                      const float *b, size_t ldb, const float *bias,
                      unsigned flags, const float *c0, size_t ldc,
                      double *value, double *scale)
{
    double s = 0.0, mag = 0.0;
    if (flags & NERF__SMM_ADD) {
        s = c0[i * ldc + j];
    } else if (bias) {
        s = bias[j];
    }
    mag = fabs(s);
    size_t kb = 0;
    for (int q = 0; q < ns; q++) {
        for (uint32_t k = 0; k < seg[q].k; k++) {
            double t = (double)seg[q].a[i * seg[q].sm + k * seg[q].sk] *
                       b[(kb + k) * ldb + j];
            s += t;
            mag += fabs(t);
        }
        kb += seg[q].k;
    }
    if ((flags & NERF__SMM_RELU) && !(s > 0.0)) {
        s = 0.0;
    }
    *value = s;
    *scale = mag;
}

/* One product of m x n from k1 + k2 rows of B, with A read by rows
 * (transposed = 0) or down its columns (1), for the current variant;
 * the result goes to out (ldc = n + 3, so rows are not line-aligned). */
static void run_case(size_t m, uint32_t n, uint32_t k1, uint32_t k2,
                     int transposed, unsigned flags, bool with_bias,
                     uint64_t seed, float *out, int *bad)
{
    nerf__rng r = nerf__rng_make(seed, 5);
    const uint32_t K = k1 + k2;
    const size_t lda = K + 5, ldb = n + 7, ldc = n + 3;
    const size_t a_rows = transposed ? K : m, a_cols = transposed ? m : K;
    float *a = malloc((a_rows * lda + a_cols + 1) * sizeof(float));
    float *b = malloc((K * ldb + 1) * sizeof(float));
    float *bias = malloc((n + 1) * sizeof(float));
    float *c0 = malloc((m * ldc + 1) * sizeof(float));
    for (size_t i = 0; i < a_rows * lda + a_cols + 1; i++) {
        a[i] = uniform(&r);
    }
    for (size_t i = 0; i < K * ldb + 1; i++) {
        b[i] = uniform(&r);
    }
    for (size_t i = 0; i <= n; i++) {
        bias[i] = uniform(&r);
    }
    for (size_t i = 0; i < m * ldc + 1; i++) {
        c0[i] = uniform(&r);
    }
    nerf__smm_seg seg[2];
    int ns = 0;
    /* The second segment starts at column (or row) k1 of the same A. */
    if (transposed) {
        seg[ns++] = (nerf__smm_seg){a, 1, lda, k1};
        if (k2) {
            seg[ns++] = (nerf__smm_seg){a + k1 * lda, 1, lda, k2};
        }
    } else {
        seg[ns++] = (nerf__smm_seg){a, lda, 1, k1};
        if (k2) {
            seg[ns++] = (nerf__smm_seg){a + k1, lda, 1, k2};
        }
    }
    memcpy(out, c0, (m * ldc + 1) * sizeof(float));
    nerf__smm(m, n, seg, ns, b, ldb, with_bias ? bias : NULL, flags, out,
              ldc);
    for (size_t i = 0; i < m; i++) {
        for (uint32_t j = 0; j < ldc; j++) {
            float got = out[i * ldc + j];
            if (j >= n) { /* between rows: untouched */
                if (got != c0[i * ldc + j] && (*bad)++ < 5) {
                    FAILF("%s m=%zu n=%u: wrote column %u beyond n",
                          variant_name(nerf__smm_variant()), m, n, j);
                }
                continue;
            }
            double want, scale;
            ref_entry(i, j, seg, ns, b, ldb, with_bias ? bias : NULL, flags,
                      c0, ldc, &want, &scale);
            /* Any order of the K products' sum (and the double's own
             * rounding): within float_product_bound() of the sum. */
            const double tol = float_product_bound(K + 1, 0.0, 0.0, scale);
            if (!(fabs(got - want) <= tol) && (*bad)++ < 5) {
                FAILF("%s m=%zu n=%u k=%u+%u t=%d flags=%u: C[%zu,%u] = %.9g, "
                      "reference %.9g", variant_name(nerf__smm_variant()), m,
                      n, k1, k2, transposed, flags, i, j, (double)got, want);
            }
        }
    }
    if (out[m * ldc] != c0[m * ldc] && (*bad)++ < 5) {
        FAILF("wrote past the last row");
    }
    free(a);
    free(b);
    free(bias);
    free(c0);
}

static const size_t ms[] = {1, 5, 7, 13, 37, 128, 131};
static const uint32_t ns_[] = {1, 3, 8, 15, 16, 17, 31, 33, 64, 65, 100};
static const uint32_t ks[][2] = {{1, 0}, {7, 0}, {32, 0}, {16, 15}, {63, 1},
                                 {130, 0}};

static void products_for(int variant, float **results)
{
    int bad = 0;
    size_t at = 0;
    for (size_t a = 0; a < sizeof ms / sizeof *ms; a++) {
        for (size_t b = 0; b < sizeof ns_ / sizeof *ns_; b++) {
            for (size_t c = 0; c < sizeof ks / sizeof *ks; c++) {
                const size_t m = ms[a];
                const uint32_t n = ns_[b];
                const unsigned flags = (unsigned)((a + b + c) % 4);
                float *out = results[at++];
                run_case(m, n, ks[c][0], ks[c][1], (int)((a + c) % 2), flags,
                         (b % 2) == 0, 1000 + 17 * a + 5 * b + c, out, &bad);
            }
        }
    }
    (void)variant;
}

#define N_CASES (7 * 11 * 6)

TEST(products_against_double_every_variant)
{
    float *res[4][N_CASES];
    for (int v = NERF__SMM_PORTABLE; v <= NERF__SMM_AVX512; v++) {
        for (size_t i = 0; i < N_CASES; i++) {
            res[v][i] = malloc((131 * 103 + 1) * sizeof(float));
        }
    }
    int ran = 0;
    for (int v = NERF__SMM_PORTABLE; v <= NERF__SMM_AVX512; v++) {
        if (nerf__smm_use(v) != 0) {
            printf("  %s: not on this processor\n", variant_name(v));
            continue;
        }
        ran++;
        products_for(v, res[v]);
    }
    CHECK(ran >= 1);
    /* Both FMA variants run one multiply-add chain per element in the
     * same order: they must agree bit for bit. */
    if (nerf__smm_supported(NERF__SMM_AVX2) &&
        nerf__smm_supported(NERF__SMM_AVX512)) {
        size_t at = 0;
        int differ = 0;
        for (size_t a = 0; a < sizeof ms / sizeof *ms; a++) {
            for (size_t b = 0; b < sizeof ns_ / sizeof *ns_; b++) {
                for (size_t c = 0; c < sizeof ks / sizeof *ks; c++, at++) {
                    size_t size = ms[a] * (ns_[b] + 3) + 1;
                    if (memcmp(res[NERF__SMM_AVX2][at],
                               res[NERF__SMM_AVX512][at],
                               size * sizeof(float)) != 0) {
                        differ++;
                    }
                }
            }
        }
        CHECK_EQ_INT(differ, 0);
    }
    for (int v = NERF__SMM_PORTABLE; v <= NERF__SMM_AVX512; v++) {
        for (size_t i = 0; i < N_CASES; i++) {
            free(res[v][i]);
        }
    }
    nerf__smm_use(nerf__smm_default());
}

/* ---- whole networks ------------------------------------------------------ */

/* Points, directions and loss gradients a network is run on. */
typedef struct problem {
    size_t n;
    float *pos, *dir, *a_rgb, *a_sigma;
} problem;

typedef struct outputs {
    float *rgb, *sigma, *density, *grads;
    double worst[3]; /* of the bounds: forward, backward, density */
} outputs;

/*
 * The forward in two halves, as a renderer runs it: nerf__model_head()
 * over every sample, a third of the head's rows dropped and the rest
 * moved to the front, nerf__model_colour() on those.  The densities are
 * the forward's (o) bit for bit: the same trunk and head products.  The
 * kept rows' colours are the forward's bit for bit where each row is
 * computed alone (nerf__model_rows_alone()), and without view directions
 * (a sigmoid of the same head rows).  Elsewhere a product over fewer rows
 * may round otherwise: the colours of both passes, computed from the same
 * head rows and encoded directions, must then lie within the colour
 * branch's carried bound of the branch in double (lb_colour_row()).
 */
static void check_halves(nerf_model *m, int k, lb_net *b, const problem *p,
                         const outputs *o)
{
    const size_t n = p->n;
    const nerf__network *net = &m->nets[k];
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    float *sigma = malloc(n * sizeof(float));
    float *rgb = malloc(3 * n * sizeof(float));
    float *dirs = malloc(3 * n * sizeof(float));
    size_t *rows = malloc(n * sizeof(size_t));
    CHECK_OK(nerf__model_head(m, k, &ws, n, p->pos, sigma));
    CHECK(memcmp(sigma, o->sigma, n * sizeof(float)) == 0);
    const uint32_t HW = nerf__network_head_width(net);
    size_t kept = 0;
    for (size_t i = 0; i < n; i++) {
        if (i % 3 == 1) {
            continue;
        }
        memmove(ws.head + kept * HW, ws.head + i * HW, HW * sizeof(float));
        memcpy(dirs + 3 * kept, p->dir + 3 * i, 3 * sizeof(float));
        rows[kept++] = i;
    }
    CHECK_OK(nerf__model_colour(m, k, &ws, kept, dirs, rgb));
    const bool alone = nerf__model_rows_alone(m) || !net->use_viewdirs;
    int bad = 0;
    for (size_t r = 0; r < kept; r++) {
        const float *fwd = o->rgb + 3 * rows[r];
        if (alone) {
            if (memcmp(rgb + 3 * r, fwd, 3 * sizeof(float)) != 0 &&
                bad++ < 5) {
                FAILF("sample %zu: colours of the two halves differ from the "
                      "forward's", rows[r]);
            }
            continue;
        }
        double want[3], err[3];
        lb_colour_row(b, ws.head + r * HW, ws.enc_dir + r * net->dir_width,
                      lb_eps(net), want, err);
        for (int c = 0; c < 3; c++) {
            if (!(fabs(rgb[3 * r + c] - want[c]) <= err[c] &&
                  fabs(fwd[c] - want[c]) <= err[c]) &&
                bad++ < 5) {
                FAILF("sample %zu: colour %.9g (forward %.9g), in double "
                      "%.9g, bound %.3g", rows[r], (double)rgb[3 * r + c],
                      (double)fwd[c], want[c], err[c]);
            }
        }
    }
    nerf__workspace_release(&m->env, &ws);
    free(sigma);
    free(rgb);
    free(dirs);
    free(rows);
}

/*
 * Network k forward (keeping its activations) and backward on p, each
 * layer checked against the network in double from its own float inputs
 * (layer_bounds.h); the same forward without kept activations, the
 * density pass and the forward in two halves against it.
 */
static void run_network(nerf_model *m, int k, const problem *p, outputs *o,
                        const char *name)
{
    const size_t n = p->n;
    const nerf__network *net = &m->nets[k];
    const double eps = lb_eps(net);
    lb_net b;
    lb_open(&b, net, m->params);
    nerf__workspace ws, wd;
    memset(&ws, 0, sizeof ws);
    memset(&wd, 0, sizeof wd);
    o->rgb = malloc(3 * n * sizeof(float));
    o->sigma = malloc(n * sizeof(float));
    o->density = malloc(n * sizeof(float));
    o->grads = malloc(m->n_params * sizeof(float));
    CHECK_OK(nerf__model_forward(m, k, &ws, n, p->pos, p->dir, o->rgb,
                                 o->sigma));
    nerf__model_zero_grad(m);
    CHECK_OK(nerf__model_backward(m, k, &ws, p->a_rgb, p->a_sigma));
    memcpy(o->grads, m->grads, m->n_params * sizeof(float));
    CHECK_OK(nerf__model_density(m, k, &wd, n, p->pos, o->density));
    o->worst[0] = lb_check_forward(&b, &ws, p->pos, o->sigma, eps, name);
    o->worst[1] = lb_check_backward(&b, &ws, p->pos, p->a_rgb, p->a_sigma,
                                    o->grads, eps, name);
    o->worst[2] = lb_check_density(&b, &ws, p->pos, o->density, eps, name);
    nerf__workspace_release(&m->env, &ws);
    nerf__workspace_release(&m->env, &wd);
    memset(&ws, 0, sizeof ws);
    /* Without kept activations (rendering) the same values, bit for bit:
     * the same products, whatever buffers hold them. */
    float *rgb = malloc(3 * n * sizeof(float));
    float *sigma = malloc(n * sizeof(float));
    CHECK_OK(nerf__model_evaluate(m, k, &ws, n, p->pos, p->dir, rgb, sigma));
    CHECK(memcmp(rgb, o->rgb, 3 * n * sizeof(float)) == 0);
    CHECK(memcmp(sigma, o->sigma, n * sizeof(float)) == 0);
    nerf__workspace_release(&m->env, &ws);
    free(rgb);
    free(sigma);
    check_halves(m, k, &b, p, o);
    lb_close(&b);
}

static void print_worst(const char *name, size_t n, const outputs *o)
{
    printf("  %s, %zu samples: at most %.3f of the bounds forward, %.3f "
           "backward, %.3f density\n", name, n, o->worst[0], o->worst[1],
           o->worst[2]);
}

static void free_outputs(outputs *o)
{
    free(o->rgb);
    free(o->sigma);
    free(o->density);
    free(o->grads);
}

static bool same_bits(const outputs *a, const outputs *b, size_t n,
                      size_t params)
{
    return memcmp(a->rgb, b->rgb, 3 * n * sizeof(float)) == 0 &&
           memcmp(a->sigma, b->sigma, n * sizeof(float)) == 0 &&
           memcmp(a->density, b->density, n * sizeof(float)) == 0 &&
           memcmp(a->grads, b->grads, params * sizeof(float)) == 0;
}

/*
 * A network through the per-layer sgemm path and through every fused
 * variant this processor runs.  Each path is checked against the network
 * in double from its own activations, not against another path: two
 * paths round differently, so a ReLU whose input is within rounding of
 * zero may be off on one and on on the other, which moves that sample's
 * whole term of a gradient.  `fits`: the network's shape suits the fused
 * path, which it then takes unless its products go through oneDNN
 * (NERF_FP32_PRODUCTS=onednn gives every fp32 model a oneDNN backend where
 * oneDNN runs): the path is asked of the library, not assumed.
 */
static void check_model(const nerf_model_options *opts, size_t n, bool fits)
{
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, opts));
    if (m == NULL) {
        return;
    }
    const int k = nerf__model_network(m, NERF_NETWORK_COARSE);
    const nerf__network *net = &m->nets[k];
    const bool fused = fits && net->onednn == NULL;
    CHECK(nerf__fused_fits(net) == fused);
    /* Trained weights are no longer PyTorch's uniform draw: perturb them
     * so that some ReLUs are off and the head is not near zero. */
    nerf__rng r = nerf__rng_make(99, 3);
    for (size_t i = net->offset; i < net->offset + net->count; i++) {
        m->params[i] += 0.05f * uniform(&r);
    }
    problem p = {n, malloc(3 * n * sizeof(float)),
                 malloc(3 * n * sizeof(float)),
                 malloc(3 * n * sizeof(float)), malloc(n * sizeof(float))};
    for (size_t i = 0; i < n; i++) {
        double n2 = 0.0;
        for (int c = 0; c < 3; c++) {
            p.pos[3 * i + c] = 1.1f * uniform(&r);
            p.dir[3 * i + c] = uniform(&r);
            n2 += p.dir[3 * i + c] * p.dir[3 * i + c];
            p.a_rgb[3 * i + c] = uniform(&r);
        }
        for (int c = 0; c < 3; c++) {
            p.dir[3 * i + c] /= (float)sqrt(n2);
        }
        p.a_sigma[i] = 0.01f * uniform(&r);
    }
    CHECK_EQ_INT(nerf__smm_use(NERF__SMM_OFF), 0);
    CHECK(!nerf__fused_active(net));
    outputs ref;
    const char *path = net->onednn ? "oneDNN" : "sgemm path";
    run_network(m, k, &p, &ref, path);
    print_worst(path, n, &ref);
    free_outputs(&ref);
    if (net->onednn) {
        printf("  products through oneDNN: the fused kernels do not apply\n");
    }
    for (int v = NERF__SMM_PORTABLE; v <= NERF__SMM_AVX512 && !net->onednn;
         v++) {
        if (nerf__smm_use(v) != 0) {
            continue;
        }
        CHECK(nerf__fused_active(net) == fused);
        outputs got, again;
        run_network(m, k, &p, &got, variant_name(v));
        run_network(m, k, &p, &again, variant_name(v));
        print_worst(variant_name(v), n, &got);
        CHECK(same_bits(&got, &again, n, m->n_params));
        free_outputs(&got);
        free_outputs(&again);
    }
    nerf__smm_use(nerf__smm_default());
    free(p.pos);
    free(p.dir);
    free(p.a_rgb);
    free(p.a_sigma);
    nerf_model_destroy(m);
}

/*
 * Sample counts: on a processor with AVX2 (which runs the portable
 * kernels natively too), counts that leave partial blocks and chunks;
 * elsewhere (the aarch64 CI stage runs this under qemu, where a call that
 * wakes the thread pool costs seconds) only counts small enough to run on
 * the calling thread: the products test above covers the portable kernels
 * at every size.
 */
static size_t count(size_t full, size_t emulated)
{
    return nerf__isa_cpu() >= NERF__ISA_AVX2 ? full : emulated;
}

/* The fast preset's network with a small table: 2,500 samples are a whole
 * chunk, then a partial one ending in a partial block. */
TEST(fast_preset_network)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.seed = 5;
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
    o.hash_log2_size = 12;
    check_model(&o, count(2500, 3), true);
    check_model(&o, 1, true);
    check_model(&o, count(131, 2), true);
}

/* Reference-style heads (width + 1 columns, sigma last), a skip layer with
 * a two-part input, and no view directions. */
TEST(reference_forms)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.seed = 9;
    o.depth = 4;
    o.width = 40;
    o.skip_layer = 2;
    o.view_width = 24;
    o.pos_frequencies = 4;
    o.dir_frequencies = 2;
    check_model(&o, count(777, 3), true);
    o.use_viewdirs = 0;
    check_model(&o, count(300, 2), true);
    /* Too wide for the fused path: both runs are the sgemm path. */
    o.width = 96;
    check_model(&o, count(50, 1), false);
}

/* One evaluation through ws, into rgb [n, 3]. */
static void evaluate(nerf_model *m, int k, nerf__workspace *ws, size_t n,
                     const float *pos, const float *dir, float *rgb,
                     bool vouch)
{
    /* After the reserve inside, which may drop the packing. */
    ws->params_unchanged = vouch;
    CHECK_OK(nerf__model_evaluate(m, k, ws, n, pos, dir, rgb, NULL));
    ws->params_unchanged = false;
}

/*
 * A renderer vouches that the weights did not change between the rounds
 * of a block (nerf__workspace.params_unchanged), and the fused path then
 * keeps the weights it packed: the same results while that holds, a
 * fresh packing after a reserve or where fewer layers were packed.
 */
TEST(packed_weights_kept_when_vouched)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.seed = 7;
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
    o.hash_log2_size = 12;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m == NULL) {
        return;
    }
    const int k = nerf__model_network(m, NERF_NETWORK_COARSE);
    const nerf__network *net = &m->nets[k];
    /* The fused kernels, this processor's fastest, whatever NERF_FUSED
     * chose; never for a model whose products go through oneDNN, which
     * reads the weights in place (NERF_FP32_PRODUCTS=onednn). */
    nerf__smm_use(nerf__smm_best());
    if (!nerf__fused_active(net)) {
        CHECK(net->onednn != NULL);
        printf("  skipped: this model's products go through oneDNN, not the "
               "fused kernels\n");
        nerf__smm_use(nerf__smm_default());
        nerf_model_destroy(m);
        return;
    }
    enum { N = 300 };
    static float pos[3 * N], dir[3 * N], sigma[N];
    static float first[3 * N], got[3 * N], fresh[3 * N];
    nerf__rng r = nerf__rng_make(7, 1);
    for (size_t i = 0; i < 3 * N; i++) {
        pos[i] = uniform(&r);
        dir[i] = i % 3 == 2 ? 1.0f : 0.0f;
    }
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    CHECK_OK(nerf__model_reserve(m, k, &ws, N, false));
    evaluate(m, k, &ws, N, pos, dir, first, false);
    evaluate(m, k, &ws, N, pos, dir, got, true);
    CHECK(memcmp(got, first, sizeof got) == 0);
    /* A density pass packs the trunk alone: a vouched forward after it
     * packs the colour branch too. */
    CHECK_OK(nerf__model_density(m, k, &ws, N, pos, sigma));
    evaluate(m, k, &ws, N, pos, dir, got, true);
    CHECK(memcmp(got, first, sizeof got) == 0);
    /* Vouching is taken at its word: changed colour weights are not seen
     * until a forward that does not vouch. */
    for (uint32_t i = 0; i < net->view[0].in * net->view[0].out; i++) {
        m->params[net->view[0].w + i] += 0.1f * uniform(&r);
    }
    evaluate(m, k, &ws, N, pos, dir, got, true);
    CHECK(memcmp(got, first, sizeof got) == 0);
    evaluate(m, k, &ws, N, pos, dir, fresh, false);
    CHECK(memcmp(fresh, first, sizeof fresh) != 0);
    /* A workspace that grows has packed nothing. */
    for (uint32_t i = 0; i < net->view[0].in * net->view[0].out; i++) {
        m->params[net->view[0].w + i] += 0.1f * uniform(&r);
    }
    CHECK_OK(nerf__model_reserve(m, k, &ws, 2 * N, false));
    evaluate(m, k, &ws, N, pos, dir, got, true);
    CHECK(memcmp(got, fresh, sizeof got) != 0);
    evaluate(m, k, &ws, N, pos, dir, fresh, false);
    CHECK(memcmp(got, fresh, sizeof got) == 0);
    nerf__workspace_release(nerf__model_env(m), &ws);
    nerf__smm_use(nerf__smm_default());
    nerf_model_destroy(m);
}

int main(void)
{
    RUN(products_against_double_every_variant);
    RUN(fast_preset_network);
    RUN(reference_forms);
    RUN(packed_weights_kept_when_vouched);
    HARNESS_EXIT();
}
