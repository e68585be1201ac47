/*
 * Bounds on float rounding that tests compare against, derived rather than
 * observed (issue 53): a comparison of two computations that may round
 * differently (another kernel, summation order, thread split, processor)
 * must hold on every machine, so its tolerance comes from the arithmetic.
 *
 * The basic fact (Higham, Accuracy and Stability of Numerical Algorithms,
 * 2002, sections 2.2 and 3.1): a sum of n float terms, or a dot product of
 * length n, computed in any order, blocked or not, with or without fused
 * multiply-adds, is within gamma(n) * (sum of the terms' magnitudes) of
 * its exact value, where u = 2^-24 and gamma(n) = n u / (1 - n u).
 */
#ifndef NERF_TESTS_FLOAT_BOUNDS_H
#define NERF_TESTS_FLOAT_BOUNDS_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Unit roundoff of float (round to nearest). */
#define FLOAT_U 0x1p-24

/* gamma(n) for float; n well below 2^24 in every use. */
static inline double float_gamma(double n)
{
    return n * FLOAT_U / (1.0 - n * FLOAT_U);
}

/* ---- Rendering: compositing bounds and running error bounds ----------
 * (tests/render).  Compositing (lib/render/composite.c, composite_packed.c)
 * in float against exact arithmetic on the same float inputs.
 */

/*
 * Relative error of libm's expf and expm1f (and of exp and expm1 in
 * double), as a multiple of the result.  glibc's manual ("Known Maximum
 * Errors in Math Functions") lists at most 1 ulp for these in float and
 * double on x86-64 and aarch64 (every third float in [-112, 0], the range
 * compositing uses, gave at most 0.502 and 0.771 ulp with glibc 2.36's
 * x86-64 variants); an ulp of y is at most 2u |y|, and we allow 2 ulps.
 */
#define FLOAT_EXP_REL (4.0 * FLOAT_U)
#define DOUBLE_U 0x1p-53
#define DOUBLE_EXP_REL (4.0 * DOUBLE_U)

/*
 * The largest opacity (sum of weights) compositing n samples in float can
 * give; exactly it is at most 1, or 1 + n 1e-10 with composite.h's 1e-10
 * terms.  With a_i the float alphas in [0, 1], q_i = fl(1 - a_i) (+
 * 1e-10) >= (1 - a_i)(1 - u) and T_(i+1) = fl(T_i q_i), each
 *   T_i a_i = T_i - T_i (1 - a_i) <= T_i - T_(i+1) / (1 + u)^3
 * (three roundings: 1 - a, + 1e-10, the product), and the 1e-10 adds
 * T_i 1e-10 <= 1e-10; summed, sum T_i a_i <= (1 + 3 n u)(1 + n 1e-10)
 * (T_i <= 1).  Each weight's product and the n - 1 additions round once
 * more: (1 + gamma(n)).  So (1 + gamma(4n))(1 + n 1e-10) bounds it with
 * the higher-order terms (Higham's lemma 3.3: (1 + gamma(a))(1 +
 * gamma(b)) <= 1 + gamma(a + b)).
 */
static inline double float_opacity_max(double n)
{
    return (1.0 + float_gamma(4.0 * n)) * (1.0 + n * 1e-10);
}

/*
 * Early termination (composite_packed.h): a ray of n samples that stops
 * after m, its float transmittance T_m < eps, against the same ray
 * composited to the end.  The first m samples are the same operations in
 * both, so the sums agree there bit for bit.  The rest adds weights whose
 * sum, telescoped as in float_opacity_max() from T_m instead of 1 (two
 * roundings a step: no 1e-10 here), is at most T_m (1 + gamma(2(n - m) +
 * 1)), each times a colour in [0, 1] (one more rounding): the opacity and
 * each colour's sum move by at most that, and rgb = sum w c + (1 - sum
 * w) bg moves by a difference of two such amounts, no more than either.
 * Each of the n - m additions rounds by at most u |partial sum| <= u (1 +
 * gamma(4n + 1)); at the end each side rounds (1 - opacity) bg by at most
 * u |1 - opacity| <= u (T_m + gamma(4n)) and adds it, once more u (1 +
 * gamma(4n + 1)).
 */
static inline double float_early_stop_bound(double n, double m, double T_m)
{
    return T_m * (1.0 + float_gamma(2.0 * (n - m) + 4.0)) +
           (n - m + 2.0) * FLOAT_U * (1.0 + float_gamma(4.0 * n + 1.0)) +
           2.0 * FLOAT_U * float_gamma(4.0 * n);
}

/*
 * Running error bounds.  A float computation is mirrored operation by
 * operation in double on the same float inputs; each value carries
 *   v   its double evaluation,
 *   e   a bound on |float result - exact result|,
 *   ed  a bound on |v - exact result|,
 * where "exact" is the same operations in real arithmetic.  Each rounding
 * of a result r adds at most u |r| (+ half the smallest subnormal for a
 * product), each operand's error propagates through the operation's
 * derivative, and magnitudes are bounded by |v| + e + ed, which holds for
 * the float, the double and the exact value alike.  The float program
 * must be the C the library compiles (round to nearest, no contraction:
 * the build says -ffp-contract=off).  A float result then lies within
 * e + ed of v; fb_holds() allows 2^-30 of that for the rounding of the
 * bound's own computation in double (at most some 2^-40 relative over the
 * thousands of operations of one ray).
 */
typedef struct fb {
    double v, e, ed;
} fb;

/* A float input: exact in both. */
static inline fb fb_in(double x)
{
    return (fb){x, 0.0, 0.0};
}

static inline double fb_mag(fb a)
{
    return fabs(a.v) + a.e + a.ed;
}

static inline fb fb_neg(fb a)
{
    return (fb){-a.v, a.e, a.ed};
}

static inline fb fb_add(fb a, fb b)
{
    const double r = fabs(a.v + b.v) + a.e + a.ed + b.e + b.ed;
    return (fb){a.v + b.v, a.e + b.e + FLOAT_U * r, a.ed + b.ed + DOUBLE_U * r};
}

static inline fb fb_sub(fb a, fb b)
{
    return fb_add(a, fb_neg(b));
}

static inline fb fb_mul(fb a, fb b)
{
    const double ma = fb_mag(a), mb = fb_mag(b);
    return (fb){a.v * b.v, ma * b.e + mb * a.e + FLOAT_U * ma * mb + 0x1p-150,
                ma * b.ed + mb * a.ed + DOUBLE_U * ma * mb + 0x1p-1074};
}

/* a / b, b bounded away from 0 (|b| > its errors). */
static inline fb fb_div(fb a, fb b)
{
    const double lo = fabs(b.v) - b.e - b.ed, q = fb_mag(a) / lo;
    return (fb){a.v / b.v, (a.e + q * b.e) / lo + FLOAT_U * q + 0x1p-150,
                (a.ed + q * b.ed) / lo + DOUBLE_U * q + 0x1p-1074};
}

/* expf (exp in the mirror): exp(x) - exp(y) <= exp(max) |x - y|; a
 * subnormal result's 2 ulps are 2^-148 at most (2^-1073 in double). */
static inline fb fb_expf(fb a)
{
    const double y = exp(a.v), top = exp(a.v + a.e + a.ed);
    return (fb){y, top * a.e + FLOAT_EXP_REL * top + 0x1p-148,
                top * a.ed + DOUBLE_EXP_REL * top + 0x1p-1073};
}

/* expm1f (expm1 in the mirror). */
static inline fb fb_expm1f(fb a)
{
    const double y = expm1(a.v), top = exp(a.v + a.e + a.ed);
    const double m = fabs(y) + top * (a.e + a.ed);
    return (fb){y, top * a.e + FLOAT_EXP_REL * m + 0x1p-148,
                top * a.ed + DOUBLE_EXP_REL * m + 0x1p-1073};
}

/* Whether a float result of the mirrored computation can be `got`. */
static inline bool fb_holds(double got, fb a)
{
    return fabs(got - a.v) <= (a.e + a.ed) * (1.0 + 0x1p-30);
}

/* max(s, 0); where the float and the exact value may fall on either side
 * of 0, both lie in [0, |v| + e + ed]. */
static inline fb fb_relu(fb a)
{
    if (a.v - a.e - a.ed > 0.0) {
        return a;
    }
    if (a.v + a.e + a.ed <= 0.0) {
        return fb_in(0.0);
    }
    return (fb){a.v > 0.0 ? a.v : 0.0, fb_mag(a), fb_mag(a)};
}

/* Whether the float and the exact value of a are on the same side of 0
 * (a branch on a's sign takes the same way in both). */
static inline bool fb_sign_known(fb a)
{
    return fabs(a.v) > a.e + a.ed;
}

/* A value whose error is not bounded (a branch that may go either way). */
static inline fb fb_unknown(double v)
{
    return (fb){v, INFINITY, INFINITY};
}

/*
 * Forward-mode derivatives in the same mirror: x a value, dx its
 * derivative along one direction of the inputs, both fb.  dx.v is the
 * derivative computed in double and dx.ed bounds its distance from the
 * exact derivative of the exact computation (dx.e means nothing: no
 * float computes it).  This differentiates a forward formula without a
 * step: nothing is truncated.
 */
typedef struct fbd {
    fb x, dx;
} fbd;

/* An input held fixed, and one that moves: x + h dx. */
static inline fbd fbd_in(double x)
{
    return (fbd){fb_in(x), fb_in(0.0)};
}

static inline fbd fbd_var(double x, double dx)
{
    return (fbd){fb_in(x), fb_in(dx)};
}

static inline fbd fbd_neg(fbd a)
{
    return (fbd){fb_neg(a.x), fb_neg(a.dx)};
}

static inline fbd fbd_add(fbd a, fbd b)
{
    return (fbd){fb_add(a.x, b.x), fb_add(a.dx, b.dx)};
}

static inline fbd fbd_sub(fbd a, fbd b)
{
    return fbd_add(a, fbd_neg(b));
}

static inline fbd fbd_mul(fbd a, fbd b)
{
    return (fbd){fb_mul(a.x, b.x),
                 fb_add(fb_mul(a.x, b.dx), fb_mul(a.dx, b.x))};
}

static inline fbd fbd_div(fbd a, fbd b)
{
    const fb q = fb_div(a.x, b.x);
    return (fbd){q, fb_div(fb_sub(a.dx, fb_mul(q, b.dx)), b.x)};
}

static inline fbd fbd_expf(fbd a)
{
    const fb e = fb_expf(a.x);
    return (fbd){e, fb_mul(e, a.dx)};
}

/* d expm1(x) = exp(x) dx; the exp's bound as fb_expf() gives it. */
static inline fbd fbd_expm1f(fbd a)
{
    return (fbd){fb_expm1f(a.x), fb_mul(fb_expf(a.x), a.dx)};
}

static inline fbd fbd_relu(fbd a)
{
    if (a.x.v - a.x.e - a.x.ed > 0.0) {
        return a;
    }
    if (a.x.v + a.x.e + a.x.ed <= 0.0) {
        return fbd_in(0.0);
    }
    return (fbd){fb_relu(a.x), fb_unknown(0.0)};
}

/*
 * Mirrors of the compositing of one ray, operation by operation as the
 * library's C evaluates them, on float inputs t (and dt or dir_norm, bg,
 * the gradients of the outputs) and on colours rgb[3n] and densities
 * sigma[n] given as fb (exact where they are the library's own inputs,
 * with bounds where they come from a network).  bg NULL: black.
 */

/* The longest ray the backward mirrors take (they leave longer ones'
 * outputs unwritten: callers check). */
#define FB_RAY_MAX 1024

/* What composite_packed.c accumulates: colour sums, depth, opacity and the
 * transmittance in front of the next sample. */
typedef struct fb_ray {
    fbd rgb[3], depth, opacity, trans;
} fb_ray;

static inline void fb_ray_init(fb_ray *r)
{
    r->rgb[0] = r->rgb[1] = r->rgb[2] = fbd_in(0.0);
    r->depth = r->opacity = fbd_in(0.0);
    r->trans = fbd_in(1.0);
}

/* One sample of nerf__composite_packed_ray() (alpha = -expm1f(-sigma
 * dt)); its weight into *w if not NULL. */
static inline void fb_packed_step(fb_ray *r, double t, double dt,
                                  const fbd *rgb, fbd sigma, fbd *w)
{
    const fbd alpha = fbd_neg(fbd_expm1f(fbd_mul(fbd_neg(sigma), fbd_in(dt))));
    const fbd wi = fbd_mul(r->trans, alpha);
    for (int c = 0; c < 3; c++) {
        r->rgb[c] = fbd_add(r->rgb[c], fbd_mul(wi, rgb[c]));
    }
    r->depth = fbd_add(r->depth, fbd_mul(wi, fbd_in(t)));
    r->opacity = fbd_add(r->opacity, wi);
    r->trans = fbd_mul(r->trans, fbd_sub(fbd_in(1.0), alpha));
    if (w) {
        *w = wi;
    }
}

/* nerf__composite_state_rgb(): sum w c + (1 - opacity) bg. */
static inline void fb_packed_rgb(const fb_ray *r, const float *bg, fbd *rgb)
{
    const fbd rest = fbd_sub(fbd_in(1.0), r->opacity);
    for (int c = 0; c < 3; c++) {
        rgb[c] =
            bg ? fbd_add(r->rgb[c], fbd_mul(rest, fbd_in(bg[c]))) : r->rgb[c];
    }
}

/* The per-weight gradient g_i of both backward passes:
 * dc . rgb_i - dc . bg + d_depth t_i + d_opacity, left to right. */
static inline fb fb_weight_grad(const double *dc, fb dbg, const fb *rgb,
                                double t, double d_depth, double d_opacity)
{
    fb g = fb_add(fb_mul(fb_in(dc[0]), rgb[0]), fb_mul(fb_in(dc[1]), rgb[1]));
    g = fb_add(g, fb_mul(fb_in(dc[2]), rgb[2]));
    g = fb_sub(g, dbg);
    g = fb_add(g, fb_mul(fb_in(d_depth), fb_in(t)));
    return fb_add(g, fb_in(d_opacity));
}

static inline fb fb_bg_grad(const double *dc, const float *bg)
{
    if (bg == NULL) {
        return fb_in(0.0);
    }
    fb d = fb_add(fb_mul(fb_in(dc[0]), fb_in(bg[0])),
                  fb_mul(fb_in(dc[1]), fb_in(bg[1])));
    return fb_add(d, fb_mul(fb_in(dc[2]), fb_in(bg[2])));
}

/* alpha_of() of composite_packed.c: -expm1f(-sigma dt). */
static inline fb fb_packed_alpha(fb sigma, double dt)
{
    return fb_neg(fb_expm1f(fb_mul(fb_neg(sigma), fb_in(dt))));
}

/*
 * nerf__composite_packed_ray_backward() on the m samples it uses (m <=
 * FB_RAY_MAX): d_rgb[3m] and d_sigma[m].  dc: dL/d(rgb) (3 values).
 */
static inline void fb_packed_backward(uint32_t m, const float *t,
                                      const float *dt, const fb *rgb,
                                      const fb *sigma, const float *bg,
                                      const double *dc, double d_depth,
                                      double d_opacity, fb *d_rgb, fb *d_sigma)
{
    fb trans[FB_RAY_MAX];
    fb T = fb_in(1.0);
    if (m > FB_RAY_MAX) {
        return;
    }
    for (uint32_t i = 0; i < m; i++) {
        trans[i] = T;
        T = fb_mul(T, fb_sub(fb_in(1.0), fb_packed_alpha(sigma[i], dt[i])));
    }
    const fb dbg = fb_bg_grad(dc, bg);
    fb rest = fb_in(0.0);
    for (uint32_t i = m; i-- > 0;) {
        const fb alpha = fb_packed_alpha(sigma[i], dt[i]);
        const fb q = fb_sub(fb_in(1.0), alpha);
        const fb w = fb_mul(trans[i], alpha);
        const fb g =
            fb_weight_grad(dc, dbg, rgb + 3 * i, t[i], d_depth, d_opacity);
        for (int c = 0; c < 3; c++) {
            d_rgb[3 * i + c] = fb_mul(w, fb_in(dc[c]));
        }
        d_sigma[i] =
            fb_mul(fb_mul(fb_mul(trans[i], fb_sub(g, rest)), fb_in(dt[i])), q);
        rest = fb_add(fb_mul(g, alpha), fb_mul(q, rest));
    }
}

/* composite.c's delta_i: (t_(i+1) - t_i) |d|, the last 1e10 |d|. */
static inline fb fb_composite_delta(uint32_t n, const float *t, uint32_t i,
                                    double dir_norm)
{
    const fb dt =
        i + 1 < n ? fb_sub(fb_in(t[i + 1]), fb_in(t[i])) : fb_in((double)1e10f);
    return fb_mul(dt, fb_in(dir_norm));
}

/* composite.c's alpha_i = 1 - expf(-relu(s_i) delta_i), with the exp
 * into *e (the backward's factor). */
static inline fb fb_composite_alpha(fb sigma, fb delta, fb *e)
{
    const fb ex = fb_expf(fb_mul(fb_neg(fb_relu(sigma)), delta));
    if (e) {
        *e = ex;
    }
    return fb_sub(fb_in(1.0), ex);
}

/* composite.c's T_(i+1) = T_i (1 - alpha_i + 1e-10). */
static inline fb fb_composite_q(fb alpha)
{
    return fb_add(fb_sub(fb_in(1.0), alpha), fb_in((double)1e-10f));
}

/*
 * nerf__composite_ray_bg(): rgb[3], depth, opacity; weights[n] if not
 * NULL.
 */
static inline void fb_composite_forward(uint32_t n, const float *t,
                                        double dir_norm, const fbd *rgb,
                                        const fbd *sigma, const float *bg,
                                        fbd *out_rgb, fbd *depth, fbd *opacity,
                                        fbd *weights)
{
    fbd T = fbd_in(1.0), r[3] = {fbd_in(0.0), fbd_in(0.0), fbd_in(0.0)};
    fbd dep = fbd_in(0.0), acc = fbd_in(0.0);
    for (uint32_t i = 0; i < n; i++) {
        const fbd delta = {fb_composite_delta(n, t, i, dir_norm), fb_in(0.0)};
        const fbd alpha = fbd_sub(
            fbd_in(1.0), fbd_expf(fbd_mul(fbd_neg(fbd_relu(sigma[i])), delta)));
        const fbd w = fbd_mul(alpha, T);
        T = fbd_mul(
            T, fbd_add(fbd_sub(fbd_in(1.0), alpha), fbd_in((double)1e-10f)));
        if (weights) {
            weights[i] = w;
        }
        for (int c = 0; c < 3; c++) {
            r[c] = fbd_add(r[c], fbd_mul(w, rgb[3 * i + c]));
        }
        dep = fbd_add(dep, fbd_mul(w, fbd_in(t[i])));
        acc = fbd_add(acc, w);
    }
    for (int c = 0; c < 3; c++) {
        out_rgb[c] = bg ? fbd_add(r[c], fbd_mul(fbd_sub(fbd_in(1.0), acc),
                                                fbd_in(bg[c])))
                        : r[c];
    }
    *depth = dep;
    *opacity = acc;
}

/*
 * nerf__composite_ray_backward_bg() (n <= FB_RAY_MAX): d_rgb[3n],
 * d_sigma[n].
 */
static inline void fb_composite_backward(uint32_t n, const float *t,
                                         double dir_norm, const fb *rgb,
                                         const fb *sigma, const float *bg,
                                         const double *dc, double d_depth,
                                         double d_opacity, fb *d_rgb,
                                         fb *d_sigma)
{
    fb trans[FB_RAY_MAX];
    fb T = fb_in(1.0);
    if (n > FB_RAY_MAX) {
        return;
    }
    for (uint32_t i = 0; i < n; i++) {
        trans[i] = T;
        T = fb_mul(T,
                   fb_composite_q(fb_composite_alpha(
                       sigma[i], fb_composite_delta(n, t, i, dir_norm), NULL)));
    }
    const fb dbg = fb_bg_grad(dc, bg);
    fb rest = fb_in(0.0);
    for (uint32_t i = n; i-- > 0;) {
        const fb dist = fb_composite_delta(n, t, i, dir_norm);
        fb e;
        const fb alpha = fb_composite_alpha(sigma[i], dist, &e);
        const fb w = fb_mul(alpha, trans[i]);
        const fb g =
            fb_weight_grad(dc, dbg, rgb + 3 * i, t[i], d_depth, d_opacity);
        for (int c = 0; c < 3; c++) {
            d_rgb[3 * i + c] = fb_mul(w, fb_in(dc[c]));
        }
        const fb d_alpha = fb_mul(trans[i], fb_sub(g, rest));
        if (!fb_sign_known(sigma[i])) {
            d_sigma[i] = fb_unknown(0.0);
        } else if (sigma[i].v > 0.0) {
            d_sigma[i] = fb_mul(fb_mul(d_alpha, dist), e);
        } else {
            d_sigma[i] = fb_in(0.0);
        }
        rest = fb_add(fb_mul(g, alpha), fb_mul(fb_composite_q(alpha), rest));
    }
}

/* ---- Dense layers' products (tests/model/layer_bounds.h) -------------- */

/*
 * Relative error of one product term whose two operands were each rounded
 * to bfloat16 first, as oneDNN's bf16 products round them: 8 significant
 * bits, so each operand within 2^-8 of itself (half its spacing of 2^-7
 * relative to its leading bit), and the product within
 * (1 + 2^-8)^2 - 1.
 */
#define FLOAT_BF16_PRODUCT (0x1p-7 + 0x1p-16)

/*
 * An absolute allowance per operation for a subnormal operand or result
 * flushed to zero (oneDNN's bf16 kernels run with DAZ and FTZ) and for
 * underflow: flushing a factor below 2^-126 moves a product by at most
 * 2^-126 times the other factor, taken below 2^26 (every operand in these
 * tests is), plus 2^-126 for a flushed result: at most 2^-99.  Negligible
 * beside any other term, but it keeps the bounds true at zero.
 */
#define FLOAT_FLUSH 0x1p-99

/*
 * |computed - exact| for c = init + sum_{k<K} a_k b_k computed in float by
 * any kernel (any order, blocking, thread split, with or without fused
 * multiply-adds), where mag = sum_k |a_k b_k| and each term's operands may
 * first be rounded with relative error eps per product (0 for fp32,
 * FLOAT_BF16_PRODUCT for bf16).  The rounded operands move the sum by at
 * most eps mag; summing K + 1 terms of magnitude at most |init| and
 * (1 + eps) |a_k b_k| errs by at most gamma(K + 1) times their sum
 * (Higham, 3.1); one more rounding is allowed for a bias added apart from
 * the product, as the library's rgb and density passes do.
 * float_product_factor() is the bound's factor of mag alone, for sums of
 * bounds accumulated term by term.
 */
static inline double float_product_factor(double K, double eps)
{
    return eps + float_gamma(K + 2) * (1 + eps);
}

static inline double float_product_bound(double K, double eps, double init,
                                         double mag)
{
    return float_product_factor(K, eps) * mag + float_gamma(K + 2) * init +
           (K + 2) * FLOAT_FLUSH;
}

/*
 * The library's float sigmoid, 1 / (1 + expf(-z)), against the exact
 * sigmoid of the same float z: expf within FLOAT_EXP_REL, then an add
 * and a divide within u each, so within (4 + 1 + 1) u (1 + O(u)) of
 * sigma(z) <= 1 relatively, hence absolutely: 8 u.  A z within E of the
 * exact argument adds E / 4, the sigmoid's largest slope.
 */
#define FLOAT_SIGMOID_ABS (8 * FLOAT_U)

/*
 * |expf(z^) - exp(z)| for a float z^ within E of z, the exponent truncated
 * at zmax as the library's exponential density truncates it: the exact
 * exponential moves by at most exp(z) (exp(E) - 1), and expf errs by
 * FLOAT_EXP_REL of exp(z^) <= exp(z + E).
 */
static inline double float_exp_bound(double z, double E, double zmax)
{
    z = z < zmax ? z : zmax;
    return exp(z) * expm1(E) + FLOAT_EXP_REL * exp(z + E);
}

/*
 * The library's frequency encoding (lib/encoding/frequency.c), a sine or
 * cosine of 2^k a, against its exact value v: the double-angle recurrence
 * errs by at most about 3 2^k 2^-52 (the error at most doubles each step,
 * plus a few roundings in double), below 2^-31 for k < 16, before the
 * value rounds to float, within u of itself; a reference's own sine in
 * double errs by 2^-52.
 */
static inline double float_frequency_bound(double v)
{
    return FLOAT_U * fabs(v) + 0x1p-31;
}

#endif
