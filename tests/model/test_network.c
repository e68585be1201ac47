/*
 * The network against a plain double-precision reference written here.
 * The library's encodings against the reference's; every layer of its
 * forward against double from that layer's own float input, and its
 * parameter gradients against the exact gradient at its own float
 * activations, within bounds derived from the arithmetic
 * (layer_bounds.h), whatever kernel runs; and that exact gradient, taken
 * at the reference's activations, against central finite differences of
 * the reference, which validates the backward's formulas.  Covers every
 * layer, the skip concatenation, both heads and the view branch, and the
 * hash-grid form: its table, a G-wide head, a deeper colour branch,
 * spherical harmonics and the exponential density.
 */
#include <math.h>
#include <string.h>

#include "../harness.h"
#include "layer_bounds.h"
#include "model.h"
#include "rng.h"
#include "sh.h"
#include "smm.h"

#define N 12
#define MAXW 512

static double enc_value(const nerf__frequency *e, const float *x, uint32_t j)
{
    if (e->include_input) {
        if (j < 3) {
            return x[j];
        }
        j -= 3;
    }
    uint32_t k = j / 6, r = j % 6;
    double a = ldexp(e->scale_pi ? M_PI : 1.0, (int)k) * (double)x[r % 3];
    return r < 3 ? sin(a) : cos(a);
}

/* Trilinear interpolation of each level's table, in double, with the
 * library's cell convention (vertices at u N_l = 0..N_l, u clamped to the
 * unit cube, the far face in the last cell) and its entry index.  With
 * d not NULL, the backward instead: d (the encoding's gradient) spread
 * over the corners' entries of the table's gradient g. */
static void hash_spread(const nerf__network *net, const double *P,
                        const float *x, double *out, const double *d,
                        double *g)
{
    const nerf__hashgrid *hg = &net->pos_enc.u.hash;
    const uint32_t F = hg->features;
    for (uint32_t l = 0; l < hg->levels; l++) {
        const double res = hg->resolution[l];
        uint32_t cell[3];
        double frac[3];
        for (int a = 0; a < 3; a++) {
            double u = (x[a] - hg->bound_min[a]) /
                       (double)(hg->bound_max[a] - hg->bound_min[a]);
            u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
            double k = floor(u * res);
            k = k > res - 1 ? res - 1 : k;
            cell[a] = (uint32_t)k;
            frac[a] = u * res - k;
        }
        for (uint32_t f = 0; f < F && !d; f++) {
            out[l * F + f] = 0.0;
        }
        for (int c = 0; c < 8; c++) {
            int bx = c & 1, by = (c >> 1) & 1, bz = (c >> 2) & 1;
            double w = (bx ? frac[0] : 1 - frac[0]) *
                       (by ? frac[1] : 1 - frac[1]) *
                       (bz ? frac[2] : 1 - frac[2]);
            uint32_t e = nerf__hashgrid_index(hg, l, cell[0] + bx,
                                              cell[1] + by, cell[2] + bz);
            const size_t at = hg->offset[l] + (size_t)e * F;
            for (uint32_t f = 0; f < F; f++) {
                if (d) {
                    g[at + f] += w * d[l * F + f];
                } else {
                    out[l * F + f] += w * P[net->pos_params + at + f];
                }
            }
        }
    }
}

static void hash_value(const nerf__network *net, const double *P,
                       const float *x, double *out)
{
    hash_spread(net, P, x, out, NULL, NULL);
}

static void encode_dir(const nerf__network *net, const float *d, double *ed)
{
    if (net->dir_enc.kind == NERF_ENCODING_SPHERICAL_HARMONICS) {
        float v[16];
        nerf__sh_forward(net->dir_enc.u.sh_degree, 1, d, 3, v, 16);
        for (uint32_t j = 0; j < net->dir_width; j++) {
            ed[j] = v[j];
        }
        return;
    }
    for (uint32_t j = 0; j < net->dir_width; j++) {
        ed[j] = enc_value(&net->dir_enc.u.freq, d, j);
    }
}

/* A hash-grid network has no density outside its bound. */
static bool outside(const nerf__network *net, const float *p)
{
    if ((net->pos_enc.kind == NERF_ENCODING_HASHGRID)) {
        for (int a = 0; a < 3; a++) {
            if (p[a] < net->pos_enc.u.hash.bound_min[a] || p[a] > net->pos_enc.u.hash.bound_max[a]) {
                return true;
            }
        }
    }
    return false;
}

/* The activated density. */
static double density(const nerf__network *net, double x, const float *p)
{
    if (outside(net, p)) {
        return 0.0;
    }
    return net->exp_density ? exp(fmin(x, NERF__EXP_DENSITY_MAX)) : x;
}

static void linear(const nerf__linear *l, const double *P, const double *in,
                   double *out, bool relu)
{
    for (uint32_t o = 0; o < l->out; o++) {
        double s = P[l->b + o];
        for (uint32_t j = 0; j < l->in; j++) {
            s += P[l->w + (size_t)o * l->in + j] * in[j];
        }
        out[o] = relu && s < 0.0 ? 0.0 : s;
    }
}

/* The encoded position and direction of one sample. */
static void ref_encode(const nerf__network *net, const double *P,
                       const float *x, const float *d, double *ex, double *ed)
{
    if ((net->pos_enc.kind == NERF_ENCODING_HASHGRID)) {
        hash_value(net, P, x, ex);
    } else {
        for (uint32_t j = 0; j < net->pos_width; j++) {
            ex[j] = enc_value(&net->pos_enc.u.freq, x, j);
        }
    }
    if (net->use_viewdirs) {
        encode_dir(net, d, ed);
    }
}

/* One sample through the reference; with r not NULL, its activations
 * there too, in the workspace's layout (layer_bounds.h). */
static void ref_forward(const nerf__network *net, const double *P,
                        const float *x, const float *d, double rgb[3],
                        double *sigma, lb_row *r)
{
    double ex[MAXW], ed[MAXW], h[MAXW], in[MAXW], out[MAXW];
    ref_encode(net, P, x, d, ex, ed);
    memcpy(h, ex, net->pos_width * sizeof(double));
    uint32_t hw = net->pos_width;
    for (uint32_t i = 0; i < net->depth; i++) {
        uint32_t k = 0;
        if (i > 0 && i == net->skip) {
            memcpy(in, ex, net->pos_width * sizeof(double));
            k = net->pos_width;
        }
        memcpy(in + k, h, hw * sizeof(double));
        linear(&net->trunk[i], P, in, h, true);
        hw = net->width;
        if (r) {
            memcpy(r->trunk + i * hw, h, hw * sizeof(double));
        }
    }
    linear(&net->head, P, h, out, false);
    if (r) {
        memcpy(r->enc_pos, ex, net->pos_width * sizeof(double));
        memcpy(r->head, out,
               nerf__network_head_width(net) * sizeof(double));
        r->outside = outside(net, x);
    }
    if (net->use_viewdirs) {
        const uint32_t F = nerf__network_feature_width(net);
        const uint32_t V = net->view_width;
        *sigma = density(net, out[nerf__network_sigma_col(net)], x);
        memcpy(in, out, F * sizeof(double));
        memcpy(in + F, ed, net->dir_width * sizeof(double));
        double v[MAXW], z[3];
        linear(&net->view[0], P, in, v, true);
        for (uint32_t k = 0; k < net->view_depth; k++) {
            if (k > 0) {
                memcpy(in, v, V * sizeof(double));
                linear(&net->view[k], P, in, v, true);
            }
            if (r) {
                memcpy(r->view + k * V, v, V * sizeof(double));
            }
        }
        linear(&net->rgb, P, v, z, false);
        for (int c = 0; c < 3; c++) {
            rgb[c] = 1.0 / (1.0 + exp(-z[c]));
        }
        if (r) {
            memcpy(r->enc_dir, ed, net->dir_width * sizeof(double));
        }
    } else {
        *sigma = density(net, out[3], x);
        for (int c = 0; c < 3; c++) {
            rgb[c] = 1.0 / (1.0 + exp(-out[c]));
        }
    }
    if (r) {
        memcpy(r->rgb, rgb, sizeof r->rgb);
    }
}

typedef struct problem {
    float pos[N * 3], dir[N * 3];
    float a_rgb[N * 3], a_sigma[N];
} problem;

static void make_problem(problem *p, uint64_t seed)
{
    nerf__rng r = nerf__rng_make(seed, 1);
    for (int i = 0; i < N; i++) {
        double n2 = 0.0;
        for (int c = 0; c < 3; c++) {
            p->pos[3 * i + c] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
            p->dir[3 * i + c] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
            n2 += p->dir[3 * i + c] * p->dir[3 * i + c];
            p->a_rgb[3 * i + c] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
        }
        for (int c = 0; c < 3; c++) {
            p->dir[3 * i + c] /= (float)sqrt(n2);
        }
        p->a_sigma[i] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
    }
}

/* The loss whose gradient we check: sum a_rgb . rgb + a_sigma sigma. */
static double ref_loss(const nerf__network *net, const double *P,
                       const problem *p)
{
    double L = 0.0;
    for (int i = 0; i < N; i++) {
        double rgb[3], s;
        ref_forward(net, P, p->pos + 3 * i, p->dir + 3 * i, rgb, &s, NULL);
        L += p->a_sigma[i] * s;
        for (int c = 0; c < 3; c++) {
            L += p->a_rgb[3 * i + c] * rgb[c];
        }
    }
    return L;
}

/*
 * The library's encodings against the reference's, within bounds on the
 * library's float arithmetic.  Frequencies: float_frequency_bound().
 * Hash grid: the
 * position scaled to the level's grid in float, u N within 4.1 N u of
 * the exact (three roundings to u, one more for the product by N), and
 * the interpolation continuous and piecewise linear in it, with a slope
 * at most 2 T per axis (T the table's largest magnitude), whichever cell
 * the rounded position falls in; then weights within gamma(5) and a sum
 * of 8 products within gamma(8): at most (25 N + 14) u T in all.  The
 * harmonics are the library's own function on both sides.
 */
static void check_encodings(const nerf__network *net, const double *P,
                            const problem *p, const nerf__workspace *ws)
{
    const bool hash = net->pos_enc.kind == NERF_ENCODING_HASHGRID;
    double T = 0.0;
    for (size_t j = 0; hash && j < nerf__encoding_params(&net->pos_enc);
         j++) {
        T = fmax(T, fabs(P[net->pos_params + j]));
    }
    double worst = 0.0;
    int bad = 0;
    for (int i = 0; i < N; i++) {
        double ex[MAXW], ed[MAXW];
        ref_encode(net, P, p->pos + 3 * i, p->dir + 3 * i, ex, ed);
        for (uint32_t j = 0; j < net->pos_width; j++) {
            const nerf__hashgrid *hg = &net->pos_enc.u.hash;
            const double got = ws->enc_pos[i * net->pos_width + j];
            const double tol =
                hash ? (25.0 * hg->resolution[j / hg->features] + 14) *
                           FLOAT_U * T
                     : float_frequency_bound(ex[j]);
            worst = fmax(worst, fabs(got - ex[j]) / tol);
            if (!(fabs(got - ex[j]) <= tol) && bad++ < 5) {
                FAILF("sample %d, encoded position %u: %.9g, reference %.9g",
                      i, j, got, ex[j]);
            }
        }
        for (uint32_t j = 0; j < net->dir_width && net->use_viewdirs; j++) {
            const double got = ws->enc_dir[i * net->dir_width + j];
            const double tol = float_frequency_bound(ed[j]);
            worst = fmax(worst, fabs(got - ed[j]) / tol);
            if (!(fabs(got - ed[j]) <= tol) && bad++ < 5) {
                FAILF("sample %d, encoded direction %u: %.9g, reference %.9g",
                      i, j, got, ed[j]);
            }
        }
    }
    printf("  encodings: at most %.3f of the bounds\n", worst);
}

static void check_network(const nerf_model_options *o, int network)
{
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, o));
    if (m == NULL) {
        return;
    }
    int k = nerf__model_network(m, network);
    const nerf__network *net = &m->nets[k];
    problem p;
    make_problem(&p, 7 + (uint64_t)network);

    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    float rgb[N * 3], sigma[N];
    CHECK_OK(nerf__model_forward(m, k, &ws, N, p.pos, p.dir, rgb, sigma));
    nerf__model_zero_grad(m);
    CHECK_OK(nerf__model_backward(m, k, &ws, p.a_rgb, p.a_sigma));

    double *P = malloc(m->n_params * sizeof(double));
    for (size_t i = 0; i < m->n_params; i++) {
        P[i] = m->params[i];
    }
    check_encodings(net, P, &p, &ws);
    lb_net b;
    lb_open(&b, net, m->params);
    const double eps = lb_eps(net);
    double fw = lb_check_forward(&b, &ws, p.pos, sigma, eps, "forward");
    double bw = lb_check_backward(&b, &ws, p.pos, p.a_rgb, p.a_sigma,
                                  m->grads, eps, "backward");
    printf("  layers: at most %.3f of the bounds forward, %.3f backward\n",
           fw, bw);

    /* The exact gradient's formulas (lb_backward_row()) at the
     * reference's own activations, the table's through the reference's
     * interpolation weights. */
    lb_grad a;
    lb_grad_alloc(&b, N, 0.0, &a);
    lb_row r;
    lb_row_alloc(&b, &r);
    for (int i = 0; i < N; i++) {
        double want[3], s;
        ref_forward(net, P, p.pos + 3 * i, p.dir + 3 * i, want, &s, &r);
        lb_backward_row(&b, &a, &r, (size_t)i, p.a_rgb, p.a_sigma[i]);
        if (a.d_enc) {
            hash_spread(net, P, p.pos + 3 * i, NULL,
                        a.d_enc + i * net->pos_width,
                        a.g + (net->pos_params - net->offset));
        }
    }
    lb_row_free(&r);

    /* Every parameter of this network against central differences of the
     * reference: both sides double, the same arithmetic on every
     * processor (the library's float results are not in it), so the
     * tolerance holds wherever it holds here.  Parameters of the other
     * network must get no gradient at all. */
    double gmax = 0.0;
    /* Not fmax: GCC 12 for aarch64 crashes (internal compiler error)
     * vectorising an fmax reduction over widened floats. */
    for (size_t i = 0; i < net->count; i++) {
        const double g = fabs(a.g[i]);
        if (g > gmax) {
            gmax = g;
        }
    }
    CHECK(gmax > 0.0);
    int bad = 0;
    const double h = 1e-6;
    for (size_t i = 0; i < m->n_params; i++) {
        bool mine = i >= net->offset && i < net->offset + net->count;
        if (!mine) {
            if (m->grads[i] != 0.0f && bad++ < 5) {
                FAILF("parameter %zu of the other network got a gradient", i);
            }
            continue;
        }
        double keep = P[i];
        P[i] = keep + h;
        double lp = ref_loss(net, P, &p);
        P[i] = keep - h;
        double lm = ref_loss(net, P, &p);
        P[i] = keep;
        double fd = (lp - lm) / (2.0 * h);
        double want = a.g[i - net->offset];
        double err = fabs(want - fd);
        if (err > 1e-4 * fabs(fd) + 1e-5 * gmax && bad++ < 5) {
            FAILF("parameter %zu (offset %zu in network): analytic %.8g, "
                  "finite difference %.8g", i, i - net->offset, want, fd);
        }
    }
    lb_grad_free(&a);
    lb_close(&b);
    free(P);
    nerf__workspace_release(&m->env, &ws);
    nerf_model_destroy(m);
}

static void small_options(nerf_model_options *o)
{
    NERF_MODEL_OPTIONS_INIT(o);
    o->depth = 4;
    o->width = 9;
    o->skip_layer = 2;
    o->view_width = 5;
    o->pos_frequencies = 3;
    o->dir_frequencies = 2;
    o->seed = 42;
}

TEST(gradients_reference_form)
{
    nerf_model_options o;
    small_options(&o);
    check_network(&o, NERF_NETWORK_COARSE);
    check_network(&o, NERF_NETWORK_FINE);
}

TEST(gradients_without_viewdirs)
{
    nerf_model_options o;
    small_options(&o);
    o.use_viewdirs = 0;
    o.skip_layer = 1;
    check_network(&o, NERF_NETWORK_COARSE);
}

TEST(gradients_paper_form_no_skip)
{
    nerf_model_options o;
    small_options(&o);
    o.encoding_flags = NERF_ENCODING_SCALE_PI;
    o.skip_layer = 0;
    o.use_fine = 0;
    check_network(&o, NERF_NETWORK_COARSE);
}

TEST(gradients_no_positional_encoding)
{
    nerf_model_options o;
    small_options(&o);
    o.pos_frequencies = 0;
    o.dir_frequencies = 0;
    o.depth = 3;
    o.skip_layer = 2;
    check_network(&o, NERF_NETWORK_COARSE);
}

/* A small hash grid: dense coarse levels and a hashed fine one, a 4-wide
 * head, two colour layers, harmonics and exp density. */
TEST(gradients_hash_grid_form)
{
    nerf_model_options o;
    small_options(&o);
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
    o.hash_levels = 3;
    o.hash_log2_size = 10;
    o.hash_min_resolution = 2;
    o.hash_max_resolution = 16;
    o.bound = 0.8f; /* some of the points in [-1, 1]^3 fall outside */
    o.width = 9;
    o.geo_features = 4;
    o.view_width = 5;
    o.sh_degree = 3;
    check_network(&o, NERF_NETWORK_COARSE);
    o.sh_degree = 4;
    o.depth = 2;
    o.view_depth = 3;
    o.density_activation = NERF_DENSITY_RELU;
    o.encoding = NERF_ENCODING_FREQUENCY;
    check_network(&o, NERF_NETWORK_COARSE);
}

/* Counts allocations so that the test can see the training path reuse
 * its buffers. */
static size_t n_allocs;

static void *counting_alloc(size_t size, void *user)
{
    (void)user;
    n_allocs++;
    return malloc(size);
}

static void counting_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

TEST(buffers_are_reused)
{
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.alloc = counting_alloc;
    hooks.free = counting_free;
    nerf_model_options o;
    small_options(&o);
    o.hooks = &hooks;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m == NULL) {
        return;
    }
    problem p;
    make_problem(&p, 3);
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    size_t after_first = 0;
    /* A oneDNN backend (NERF_FP32_PRODUCTS=onednn) makes a primitive for
     * each product shape the first time it comes: there the batches run
     * twice, and the second round must allocate nothing. */
    const int rounds = m->onednn ? 2 : 1;
    for (int round = 0; round < rounds; round++) {
        for (int step = 0; step < 4; step++) {
            /* smaller batches fit */
            size_t n = step == 0 ? N : N - (size_t)step;
            CHECK_OK(nerf__model_forward(m, 0, &ws, n, p.pos, p.dir, NULL,
                                         NULL));
            nerf__model_zero_grad(m);
            nerf__model_backward(m, 0, &ws, p.a_rgb, p.a_sigma);
            nerf__model_adam_step(m);
            if (round == rounds - 1 && step == 0) {
                after_first = n_allocs;
            }
        }
    }
    CHECK_EQ_INT(n_allocs, after_first);
    nerf__workspace_release(&m->env, &ws);
    nerf_model_destroy(m);
}

int main(void)
{
    /* These networks are narrow enough for the fused small-MLP path
     * (network_fused.h), which they take where the processor has its
     * kernels; then the same with those kernels off: through the
     * per-layer path (the CBLAS, or oneDNN under NERF_FP32_PRODUCTS). */
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1) {
            if (nerf__smm_variant() == NERF__SMM_OFF) {
                break;
            }
            nerf__smm_use(NERF__SMM_OFF);
            printf("again with the fused kernels off:\n");
        }
        RUN(gradients_reference_form);
        RUN(gradients_without_viewdirs);
        RUN(gradients_paper_form_no_skip);
        RUN(gradients_no_positional_encoding);
        RUN(gradients_hash_grid_form);
        RUN(buffers_are_reused);
    }
    HARNESS_EXIT();
}
