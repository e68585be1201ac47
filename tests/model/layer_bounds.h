/*
 * A network's float results against the same network in double, each
 * layer from the float inputs the library itself used (issue 53): checks
 * that hold for every kernel the library may run (the fused small
 * products, the CBLAS, oneDNN in fp32 or bf16) on every processor, with
 * bounds derived from the arithmetic (../float_bounds.h).
 *
 * Forward (lb_check_forward): a workspace reserved with keep holds every
 * layer's float input and output.  For each layer and sample the output
 * lies within float_product_bound() of the layer computed in double from
 * that same input (ReLU is 1-Lipschitz; the sigmoid's slope is at most
 * 1/4).  No error is carried from layer to layer, so the bound is one
 * product's however deep the network, and a wrong weight, row or column
 * anywhere shows.
 *
 * Backward (lb_check_backward): the gradient the library added for the
 * loss sum_i d_rgb_i . rgb_i + d_sigma_i sigma_i lies within a bound of
 * the exact gradient at the same float activations (the same ReLU masks,
 * sigmoid outputs and density logits), computed here in double.  The
 * bound follows the float error E of each output gradient down the
 * layers: a product whose operand is known within E errs by at most
 * float_product_bound() over |dY| + E, plus sum E |other operand|; a mask
 * is the same on both sides and passes E on unchanged.  A hash table's
 * gradient goes through the library's own scatter, which adds
 * nonnegative weights times the encoding's gradient: the same weights on
 * both sides, so its bound is the scatter of the bounds.
 *
 * What the library computes with (its kept activations) is taken as
 * given, so a path's results are checked against its own inputs, never
 * against another path's, whose ReLU masks may differ where a unit's
 * input is within rounding of zero.
 */
#ifndef NERF_TESTS_LAYER_BOUNDS_H
#define NERF_TESTS_LAYER_BOUNDS_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "gemm_onednn.h"
#include "network.h"

#define LB_MAX_LAYERS (NERF__MAX_DEPTH + NERF__MAX_VIEW_DEPTH + 2)

/* A network's layers in double: trunk, head, colour branch, rgb. */
typedef struct lb_net {
    const nerf__network *net;
    const float *params;
    int n_layers, head, view, rgb; /* indices of the head, view[0], rgb */
    nerf__linear layer[LB_MAX_LAYERS];
    double *w[LB_MAX_LAYERS];  /* W [out, in] */
    double *wt[LB_MAX_LAYERS]; /* W^T [in, out] */
    size_t widest;
    double *tmp[6]; /* [widest] each */
} lb_net;

/* One sample's activations, in double, in the workspace's layout. */
typedef struct lb_row {
    double *enc_pos, *enc_dir; /* [Ep], [Ed] */
    double *trunk;             /* [depth][W], after ReLU */
    double *head;              /* [head width] */
    double *view;              /* [view depth][V], after ReLU */
    double rgb[3];             /* after the sigmoid */
    bool outside;              /* outside the space's domain: no density */
} lb_row;

/* Products' per-term relative error for the network as it is now: bf16
 * where its oneDNN backend rounds operands, else 0. */
static inline double lb_eps(const nerf__network *net)
{
    return nerf__onednn_rounds(net->onednn) ? FLOAT_BF16_PRODUCT : 0.0;
}

static inline void lb_open(lb_net *b, const nerf__network *net,
                           const float *params)
{
    memset(b, 0, sizeof *b);
    b->net = net;
    b->params = params;
    for (uint32_t i = 0; i < net->depth; i++) {
        b->layer[b->n_layers++] = net->trunk[i];
    }
    b->head = b->n_layers;
    b->layer[b->n_layers++] = net->head;
    b->view = b->rgb = -1;
    if (net->use_viewdirs) {
        b->view = b->n_layers;
        for (uint32_t k = 0; k < net->view_depth; k++) {
            b->layer[b->n_layers++] = net->view[k];
        }
        b->rgb = b->n_layers;
        b->layer[b->n_layers++] = net->rgb;
    }
    b->widest = net->pos_width + net->dir_width;
    for (int li = 0; li < b->n_layers; li++) {
        const nerf__linear *l = &b->layer[li];
        const size_t in = l->in, out = l->out;
        b->widest = in > b->widest ? in : b->widest;
        b->widest = out > b->widest ? out : b->widest;
        b->w[li] = malloc(in * out * sizeof(double));
        b->wt[li] = malloc(in * out * sizeof(double));
        for (size_t o = 0; o < out; o++) {
            for (size_t k = 0; k < in; k++) {
                const double v = params[l->w + o * in + k];
                b->w[li][o * in + k] = v;
                b->wt[li][k * out + o] = v;
            }
        }
    }
    for (int t = 0; t < 6; t++) {
        b->tmp[t] = malloc(b->widest * sizeof(double));
    }
}

static inline void lb_close(lb_net *b)
{
    for (int li = 0; li < b->n_layers; li++) {
        free(b->w[li]);
        free(b->wt[li]);
    }
    for (int t = 0; t < 6; t++) {
        free(b->tmp[t]);
    }
}

static inline void lb_row_alloc(const lb_net *b, lb_row *r)
{
    const nerf__network *net = b->net;
    memset(r, 0, sizeof *r);
    r->enc_pos = calloc(net->pos_width + 1, sizeof(double));
    r->enc_dir = calloc(net->dir_width + 1, sizeof(double));
    r->trunk = calloc((size_t)net->depth * net->width + 1, sizeof(double));
    r->head = calloc(nerf__network_head_width(net), sizeof(double));
    r->view =
        calloc((size_t)net->view_depth * net->view_width + 1, sizeof(double));
}

static inline void lb_row_free(lb_row *r)
{
    free(r->enc_pos);
    free(r->enc_dir);
    free(r->trunk);
    free(r->head);
    free(r->view);
}

static inline void lb_widen(const float *x, size_t n, double *out)
{
    for (size_t k = 0; k < n; k++) {
        out[k] = x[k];
    }
}

/* Sample i of a workspace that kept its activations (positions: those
 * the forward was given). */
static inline void lb_row_from_ws(const lb_net *b, nerf__workspace *ws,
                                  size_t i, const float *positions, lb_row *r)
{
    const nerf__network *net = b->net;
    const uint32_t W = net->width, V = net->view_width;
    const uint32_t HW = nerf__network_head_width(net);
    lb_widen(ws->enc_pos + i * net->pos_width, net->pos_width, r->enc_pos);
    for (uint32_t l = 0; l < net->depth; l++) {
        lb_widen(nerf__trunk_buffer(net, ws, l) + i * W, W, r->trunk + l * W);
    }
    lb_widen(ws->head + i * HW, HW, r->head);
    if (net->use_viewdirs) {
        lb_widen(ws->enc_dir + i * net->dir_width, net->dir_width, r->enc_dir);
        for (uint32_t k = 0; k < net->view_depth; k++) {
            lb_widen(nerf__view_buffer(net, ws, k) + i * V, V, r->view + k * V);
        }
    }
    lb_widen(ws->rgb + 3 * i, 3, r->rgb);
    r->outside = !nerf__space_contains(&net->space, positions + 3 * i);
}

/* Layer li's input for sample r, its parts side by side, into x. */
static inline void lb_input(const lb_net *b, int li, const lb_row *r, double *x)
{
    const nerf__network *net = b->net;
    const uint32_t W = net->width, V = net->view_width, Ep = net->pos_width;
    if (li < (int)net->depth) {
        if (li == 0) {
            memcpy(x, r->enc_pos, Ep * sizeof(double));
        } else if ((uint32_t)li == net->skip) {
            memcpy(x, r->enc_pos, Ep * sizeof(double));
            memcpy(x + Ep, r->trunk + (li - 1) * W, W * sizeof(double));
        } else {
            memcpy(x, r->trunk + (li - 1) * W, W * sizeof(double));
        }
    } else if (li == b->head) {
        memcpy(x, r->trunk + (net->depth - 1) * W, W * sizeof(double));
    } else if (li == b->view) {
        const uint32_t F = nerf__network_feature_width(net);
        memcpy(x, r->head, F * sizeof(double));
        memcpy(x + F, r->enc_dir, net->dir_width * sizeof(double));
    } else if (li < b->rgb) {
        memcpy(x, r->view + (li - b->view - 1) * V, V * sizeof(double));
    } else {
        memcpy(x, r->view + (net->view_depth - 1) * V, V * sizeof(double));
    }
}

/*
 * s = b + W x for layer li, in double, and in e the bound on a float
 * computation of it from inputs within ex of x (ex NULL: x exact).  The
 * double sum's own rounding, below 2^-52 (K + 1) of the terms, takes one
 * more term in the float bound.
 */
static inline void lb_dense(lb_net *b, int li, const double *x,
                            const double *ex, double eps, double *s, double *e)
{
    const nerf__linear *l = &b->layer[li];
    const size_t in = l->in, out = l->out;
    const double *wt = b->wt[li];
    double *mag = b->tmp[4], *carried = b->tmp[5];
    for (size_t o = 0; o < out; o++) {
        s[o] = mag[o] = carried[o] = 0.0;
    }
    for (size_t k = 0; k < in; k++) {
        const double xk = x[k], ek = ex ? ex[k] : 0.0, ak = fabs(xk) + ek;
        const double *row = wt + k * out;
        for (size_t o = 0; o < out; o++) {
            s[o] += row[o] * xk;
            mag[o] += fabs(row[o]) * ak;
        }
        if (ek > 0.0) {
            for (size_t o = 0; o < out; o++) {
                carried[o] += fabs(row[o]) * ek;
            }
        }
    }
    for (size_t o = 0; o < out; o++) {
        const double bias = b->params[l->b + o];
        s[o] += bias;
        e[o] = float_product_bound((double)in + 1, eps, fabs(bias), mag[o]) +
               carried[o];
    }
}

/* Worst |got - want| / bound of one check, and how many exceeded it.
 * Failures name the element: (sample, column) of an activation, (output,
 * input) of a weight's gradient. */
typedef struct lb_result {
    double worst;
    size_t bad;
} lb_result;

static inline const char *lb_layer_name(const lb_net *b, int li)
{
    return li < b->head    ? "trunk"
           : li == b->head ? "head"
           : li == b->rgb  ? "rgb"
                           : "colour";
}

static inline void lb_compare(lb_result *res, const char *what,
                              const char *where, int li, size_t row, size_t col,
                              double got, double want, double bound)
{
    const double d = fabs(got - want);
    if (!(d <= bound)) {
        if (res->bad++ < 5) {
            FAILF("%s, %s layer %d at (%zu, %zu): %.9g, in double %.9g, "
                  "apart %.3g > bound %.3g",
                  what, where, li, row, col, got, want, d, bound);
        }
        return;
    }
    if (bound > 0.0 && d / bound > res->worst) {
        res->worst = d / bound;
    }
}

/*
 * Every layer of sample r (activations of a forward, rows from
 * lb_row_from_ws) against double from its own input; sigma, when not
 * NULL, the density output of that sample.
 */
static inline void lb_forward_row(lb_net *b, const lb_row *r, size_t row,
                                  const float *sigma, double eps,
                                  const char *what, lb_result *res)
{
    const nerf__network *net = b->net;
    const uint32_t W = net->width, V = net->view_width;
    double *x = b->tmp[0], *s = b->tmp[1], *e = b->tmp[2];
    for (int li = 0; li < b->n_layers; li++) {
        const nerf__linear *l = &b->layer[li];
        lb_input(b, li, r, x);
        lb_dense(b, li, x, NULL, eps, s, e);
        const double *y = li < b->head    ? r->trunk + li * W
                          : li == b->head ? r->head
                          : li == b->rgb  ? NULL
                                          : r->view + (li - b->view) * V;
        for (uint32_t o = 0; o < l->out; o++) {
            if (y == NULL) { /* rgb holds the sigmoid of the sum */
                lb_compare(res, what, "rgb", li, row, o, r->rgb[o],
                           1.0 / (1.0 + exp(-s[o])),
                           e[o] / 4 + FLOAT_SIGMOID_ABS);
                continue;
            }
            const bool relu = li != b->head;
            const double want = relu && s[o] < 0.0 ? 0.0 : s[o];
            lb_compare(res, what, lb_layer_name(b, li), li, row, o, y[o], want,
                       e[o]);
        }
    }
    if (!net->use_viewdirs) {
        /* rgb is the sigmoid of the head's first three columns. */
        for (int c = 0; c < 3; c++) {
            lb_compare(res, what, "rgb", b->head, row, (size_t)c, r->rgb[c],
                       1.0 / (1.0 + exp(-r->head[c])), FLOAT_SIGMOID_ABS);
        }
    }
    if (sigma) {
        const double logit = r->head[nerf__network_sigma_col(net)];
        double want = logit, bound = 0.0;
        if (net->exp_density) {
            want = exp(fmin(logit, NERF__EXP_DENSITY_MAX));
            bound = float_exp_bound(logit, 0.0, NERF__EXP_DENSITY_MAX);
        }
        if (r->outside) {
            want = bound = 0.0;
        }
        lb_compare(res, what, "density", b->head, row,
                   nerf__network_sigma_col(net), sigma[row], want, bound);
    }
}

/*
 * lb_forward_row() for every sample of a forward that kept its
 * activations in ws (reserved with keep), run with products of
 * per-term error eps (lb_eps()); positions as given to the forward,
 * sigma_out its densities or NULL.  Returns the worst ratio to a bound.
 */
static inline double lb_check_forward(lb_net *b, nerf__workspace *ws,
                                      const float *positions,
                                      const float *sigma_out, double eps,
                                      const char *what)
{
    lb_result res = {0.0, 0};
    if (!ws->keep) {
        FAILF("%s: the workspace kept no activations", what);
        return 0.0;
    }
    lb_row r;
    lb_row_alloc(b, &r);
    for (size_t i = 0; i < ws->n; i++) {
        lb_row_from_ws(b, ws, i, positions, &r);
        lb_forward_row(b, &r, i, sigma_out, eps, what, &res);
    }
    lb_row_free(&r);
    return res.worst;
}

/*
 * Densities of a density-only pass (nerf__model_density) against the
 * head's density column in double, from the trunk a forward over the same
 * samples kept in ws: the two passes make the same trunk products (same
 * samples, same shapes), so the trunk is the same bits, and only the one
 * column's product and the activation may round otherwise.
 */
static inline double lb_check_density(lb_net *b, nerf__workspace *ws,
                                      const float *positions,
                                      const float *density, double eps,
                                      const char *what)
{
    const nerf__network *net = b->net;
    const uint32_t W = net->width, col = nerf__network_sigma_col(net);
    const nerf__linear *h = &net->head;
    const float *top = nerf__trunk_buffer(net, ws, net->depth - 1);
    lb_result res = {0.0, 0};
    for (size_t i = 0; i < ws->n; i++) {
        double s = b->params[h->b + col], mag = 0.0;
        for (uint32_t k = 0; k < W; k++) {
            const double t =
                b->w[b->head][(size_t)col * W + k] * (double)top[i * W + k];
            s += t;
            mag += fabs(t);
        }
        double e = float_product_bound((double)W + 1, eps,
                                       fabs(b->params[h->b + col]), mag);
        double want = s;
        if (net->exp_density) {
            want = exp(fmin(s, NERF__EXP_DENSITY_MAX));
            e = float_exp_bound(s, e, NERF__EXP_DENSITY_MAX);
        }
        if (!nerf__space_contains(&net->space, positions + 3 * i)) {
            want = e = 0.0;
        }
        lb_compare(&res, what, "density", b->head, i, col, density[i], want, e);
    }
    return res.worst;
}

/*
 * The colour branch of one sample from a head row and an encoded
 * direction taken as exact: rgb in double, and in err the bound on any
 * float computation of it from the same two rows, carried through the
 * layers (ReLU passes the error on; the sigmoid's slope is at most 1/4).
 */
static inline void lb_colour_row(lb_net *b, const float *head_row,
                                 const float *enc_dir_row, double eps,
                                 double rgb[3], double err[3])
{
    const nerf__network *net = b->net;
    const uint32_t F = nerf__network_feature_width(net);
    double *x = b->tmp[0], *ex = b->tmp[3], *s = b->tmp[1], *e = b->tmp[2];
    lb_widen(head_row, F, x);
    lb_widen(enc_dir_row, net->dir_width, x + F);
    const double *carried = NULL;
    for (int li = b->view; li <= b->rgb; li++) {
        lb_dense(b, li, x, carried, eps, s, e);
        for (uint32_t o = 0; o < b->layer[li].out; o++) {
            x[o] = li < b->rgb && s[o] < 0.0 ? 0.0 : s[o];
            ex[o] = e[o];
        }
        carried = ex;
    }
    for (int c = 0; c < 3; c++) {
        rgb[c] = 1.0 / (1.0 + exp(-x[c]));
        err[c] = ex[c] / 4 + FLOAT_SIGMOID_ABS;
    }
}

/* ---- backward ------------------------------------------------------------ */

/*
 * The exact gradient of a network's parameters (offsets from
 * net->offset) and its bound, summed over samples.  A weight's gradient
 * sums n products dY x, each dY known within E: float_product_bound()
 * over sum (|dY| + E) |x|, plus sum E |x| carried, is the sum over
 * samples of (f |dY| + (1 + f) E) |x| with f = float_product_factor(),
 * which is what bound accumulates (f for biases without eps: they sum the
 * fp32 gradient itself, never rounded to bf16).
 */
typedef struct lb_grad {
    size_t n;              /* samples the library summed */
    double eps;            /* of the backward's products */
    double fw, fb;         /* f for weights and for biases */
    double *g;             /* the exact gradient */
    double *bound;         /* its bound, but for FLOAT_FLUSH's terms */
    double *d_enc, *e_enc; /* [n, Ep]: the encoding's gradient and bound,
                            * for an encoding with parameters */
} lb_grad;

/* For n samples and the backward's products' eps. */
static inline void lb_grad_alloc(const lb_net *b, size_t n, double eps,
                                 lb_grad *a)
{
    const nerf__network *net = b->net;
    a->n = n;
    a->eps = eps;
    /* One more term for the double sums' own rounding. */
    a->fw = float_product_factor((double)n + 1, eps);
    a->fb = float_product_factor((double)n + 1, 0.0);
    a->g = calloc(net->count, sizeof(double));
    a->bound = calloc(net->count, sizeof(double));
    a->d_enc = a->e_enc = NULL;
    if (nerf__encoding_params(&net->pos_enc)) {
        a->d_enc = calloc(n * net->pos_width + 1, sizeof(double));
        a->e_enc = calloc(n * net->pos_width + 1, sizeof(double));
    }
}

static inline void lb_grad_free(lb_grad *a)
{
    free(a->g);
    free(a->bound);
    free(a->d_enc);
    free(a->e_enc);
}

/*
 * Layer li's gradients for the output gradient dy (within ey) at input
 * x; then, when dx is not NULL, the gradient of input columns [c0, c1)
 * into dx [c1 - c0] and its bound into ex.
 */
static inline void lb_layer_back(lb_net *b, lb_grad *a, int li,
                                 const double *dy, const double *ey,
                                 const double *x, double *dx, double *ex,
                                 uint32_t c0, uint32_t c1)
{
    const nerf__linear *l = &b->layer[li];
    const size_t in = l->in, out = l->out, off = b->net->offset;
    for (size_t o = 0; o < out; o++) {
        if (dy[o] == 0.0 && ey[o] == 0.0) {
            continue;
        }
        const double d = dy[o];
        const double m = a->fw * fabs(d) + (1 + a->fw) * ey[o];
        const size_t bi = l->b - off + o, wi = l->w - off + o * in;
        a->g[bi] += d;
        a->bound[bi] += a->fb * fabs(d) + (1 + a->fb) * ey[o];
        double *g = a->g + wi, *gb = a->bound + wi;
        for (size_t k = 0; k < in; k++) {
            g[k] += d * x[k];
            gb[k] += m * fabs(x[k]);
        }
    }
    if (dx == NULL) {
        return;
    }
    const size_t cols = c1 - c0;
    const double f = float_product_factor((double)out + 1, a->eps);
    for (size_t k = 0; k < cols; k++) {
        dx[k] = 0.0;
        ex[k] = (out + 3) * FLOAT_FLUSH;
    }
    for (size_t o = 0; o < out; o++) {
        if (dy[o] == 0.0 && ey[o] == 0.0) {
            continue;
        }
        const double d = dy[o], m = f * fabs(d) + (1 + f) * ey[o];
        const double *w = b->w[li] + o * in + c0;
        for (size_t k = 0; k < cols; k++) {
            dx[k] += d * w[k];
            ex[k] += m * fabs(w[k]);
        }
    }
}

/* The ReLU's backward on a gradient and its bound: the mask of the
 * layer's float output y, the one the library applies. */
static inline void lb_mask(const double *y, size_t n, double *d, double *e)
{
    for (size_t k = 0; k < n; k++) {
        if (!(y[k] > 0.0)) {
            d[k] = e[k] = 0.0;
        }
    }
}

/*
 * One sample's backward in double, added to a: the loss gradient d_rgb
 * (NULL: zero) and d_sigma of sample `row`, whose activations are r.
 */
static inline void lb_backward_row(lb_net *b, lb_grad *a, const lb_row *r,
                                   size_t row, const float *d_rgb,
                                   double d_sigma)
{
    const nerf__network *net = b->net;
    const uint32_t W = net->width, V = net->view_width, Ep = net->pos_width;
    const uint32_t HW = nerf__network_head_width(net);
    const uint32_t sc = nerf__network_sigma_col(net);
    double *x = b->tmp[0], *d = b->tmp[1], *e = b->tmp[2];
    double *dn = b->tmp[3], *en = b->tmp[5];
    /* The sigmoid's backward, g y (1 - y) in float: three roundings. */
    double dz[3], ez[3];
    for (int c = 0; c < 3; c++) {
        const double g = d_rgb ? d_rgb[3 * row + c] : 0.0, y = r->rgb[c];
        dz[c] = g * y * (1.0 - y);
        ez[c] = float_gamma(4) * fabs(dz[c]);
    }
    if (net->use_viewdirs) {
        const uint32_t F = nerf__network_feature_width(net);
        lb_input(b, b->rgb, r, x);
        lb_layer_back(b, a, b->rgb, dz, ez, x, d, e, 0, V);
        for (int li = b->rgb - 1; li >= b->view; li--) {
            const int k = li - b->view;
            lb_mask(r->view + k * V, V, d, e);
            lb_input(b, li, r, x);
            if (li > b->view) {
                lb_layer_back(b, a, li, d, e, x, dn, en, 0, V);
            } else {
                lb_layer_back(b, a, li, d, e, x, dn, en, 0, F);
            }
            memcpy(d, dn, (li > b->view ? V : F) * sizeof(double));
            memcpy(e, en, (li > b->view ? V : F) * sizeof(double));
        }
        if (F < HW) { /* the reference head: sigma is a column apart */
            d[sc] = e[sc] = 0.0;
        }
    } else {
        for (int c = 0; c < 3; c++) {
            d[c] = dz[c];
            e[c] = ez[c];
        }
        d[sc] = e[sc] = 0.0;
    }
    /* The density's gradient: d_sigma times expf of the logit in float
     * (FLOAT_EXP_REL, one multiply), added to the colour's gradient in
     * the head's shared column (one more rounding). */
    double g = r->outside ? 0.0 : d_sigma, eg = 0.0;
    if (net->exp_density && g != 0.0) {
        g *= exp(fmin(r->head[sc], NERF__EXP_DENSITY_MAX));
        eg = (FLOAT_EXP_REL + float_gamma(3)) * fabs(g);
    }
    const double sum = d[sc] + g;
    const bool added = net->geo_features > 0; /* else set: exact */
    e[sc] += eg + (added ? float_gamma(2) * (fabs(sum) + e[sc] + eg) : 0.0);
    d[sc] = sum;
    /* The head, then the trunk down to the encoding. */
    lb_input(b, b->head, r, x);
    lb_layer_back(b, a, b->head, d, e, x, dn, en, 0, W);
    memcpy(d, dn, W * sizeof(double));
    memcpy(e, en, W * sizeof(double));
    for (int i = (int)net->depth - 1; i >= 0; i--) {
        lb_mask(r->trunk + i * W, W, d, e);
        lb_input(b, i, r, x);
        if (i == 0) {
            double *de = a->d_enc ? a->d_enc + row * Ep : NULL;
            double *ee = a->e_enc ? a->e_enc + row * Ep : NULL;
            lb_layer_back(b, a, 0, d, e, x, de, ee, 0, Ep);
            break;
        }
        /* At the skip the input was [gamma(x), h]: on through h only. */
        const uint32_t c0 = (uint32_t)i == net->skip ? Ep : 0;
        lb_layer_back(b, a, i, d, e, x, dn, en, c0, c0 + W);
        memcpy(d, dn, W * sizeof(double));
        memcpy(e, en, W * sizeof(double));
    }
}

/* A float at least v (>= 0). */
static inline float lb_float_up(double v)
{
    return (float)(v * (1.0 + 0x1p-22) + 0x1p-149);
}

/*
 * The parameters' gradient the library added into grads (the model's
 * array; zero before the backward), against a: every layer, and a hash
 * table through the library's scatter (positions as the forward had
 * them).  Returns the worst ratio to a bound.
 */
static inline double lb_compare_grad(lb_net *b, lb_grad *a,
                                     const float *positions, const float *grads,
                                     const char *what)
{
    const nerf__network *net = b->net;
    const double n = (double)a->n;
    lb_result res = {0.0, 0};
    for (int li = 0; li < b->n_layers; li++) {
        const nerf__linear *l = &b->layer[li];
        const size_t nw = (size_t)l->in * l->out;
        for (size_t j = 0; j < nw + l->out; j++) {
            const size_t p = l->w + j, q = p - net->offset;
            const double bound = a->bound[q] + (n + 3) * FLOAT_FLUSH;
            lb_compare(&res, what,
                       j < nw ? "gradient of W of" : "gradient of b of", li,
                       j < nw ? j / l->in : j - nw, j < nw ? j % l->in : 0,
                       grads[p], a->g[q], bound);
        }
    }
    const nerf__encoding *enc = &net->pos_enc;
    const size_t T = nerf__encoding_params(enc);
    if (T && a->d_enc) {
        /*
         * The scatter adds w d for each of at most 8 n (sample, corner)
         * pairs per entry, w >= 0 the same floats on both sides: against
         * the scatter of d rounded to float, the library's differs by at
         * most sum w (E + u |d|) + gamma(8n + 1) sum w (2 (1 + u) |d| + E),
         * and the scatter of that sum's terms rounded up, a sum of
         * nonnegative terms, is at least (1 - gamma(8n + 1)) of it.
         */
        const size_t Ep = net->pos_width, m = a->n * Ep;
        const double gm = float_gamma(8 * n + 1);
        float *dv = malloc((m + 1) * sizeof(float));
        float *bv = malloc((m + 1) * sizeof(float));
        float *t = calloc(T, sizeof(float)), *tb = calloc(T, sizeof(float));
        for (size_t k = 0; k < m; k++) {
            const double dk = a->d_enc[k], ek = a->e_enc[k];
            dv[k] = (float)dk;
            bv[k] = lb_float_up(ek + FLOAT_U * fabs(dk) +
                                gm * (2 * (1 + FLOAT_U) * fabs(dk) + ek));
        }
        nerf__encoding_backward(enc, a->n, positions, dv, Ep, t);
        nerf__encoding_backward(enc, a->n, positions, bv, Ep, tb);
        for (size_t j = 0; j < T; j++) {
            lb_compare(&res, what, "gradient of the table of", 0, j, 0,
                       grads[net->pos_params + j], t[j],
                       tb[j] / (1 - gm) + (8 * n + 2) * FLOAT_FLUSH);
        }
        free(dv);
        free(bv);
        free(t);
        free(tb);
    }
    return res.worst;
}

/*
 * The backward of the forward kept in ws, as the library ran it into
 * grads (zeroed before) with products of per-term error eps, for the loss
 * gradients d_rgb [n, 3] and d_sigma [n] (either NULL for zero): checked
 * against the exact gradient at the workspace's activations.  Returns
 * the worst ratio to a bound.
 */
static inline double lb_check_backward(lb_net *b, nerf__workspace *ws,
                                       const float *positions,
                                       const float *d_rgb, const float *d_sigma,
                                       const float *grads, double eps,
                                       const char *what)
{
    lb_grad a;
    lb_grad_alloc(b, ws->n, eps, &a);
    lb_row r;
    lb_row_alloc(b, &r);
    for (size_t i = 0; i < ws->n; i++) {
        lb_row_from_ws(b, ws, i, positions, &r);
        lb_backward_row(b, &a, &r, i, d_rgb, d_sigma ? d_sigma[i] : 0.0);
    }
    lb_row_free(&r);
    double worst = lb_compare_grad(b, &a, positions, grads, what);
    lb_grad_free(&a);
    return worst;
}

#endif
