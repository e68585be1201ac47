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

#include <stddef.h>

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

#include <math.h>
#include <stdbool.h>

/*
 * Relative error of libm's expf and expm1f (and of exp and expm1 in
 * double), as a multiple of the result.  glibc's manual ("Known Maximum
 * Errors in Math Functions") lists at most 1 ulp for these in float and
 * double on x86-64 and aarch64; an ulp of y is at most 2u |y|, and we
 * allow 2 ulps.
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
    return (fb){a.v + b.v, a.e + b.e + FLOAT_U * r,
                a.ed + b.ed + DOUBLE_U * r};
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

/* expf (exp in the mirror): exp(x) - exp(y) <= exp(max) |x - y|. */
static inline fb fb_expf(fb a)
{
    const double y = exp(a.v), top = exp(a.v + a.e + a.ed);
    return (fb){y, top * a.e + FLOAT_EXP_REL * top + 0x1p-149,
                top * a.ed + DOUBLE_EXP_REL * top + 0x1p-1074};
}

/* expm1f (expm1 in the mirror). */
static inline fb fb_expm1f(fb a)
{
    const double y = expm1(a.v), top = exp(a.v + a.e + a.ed);
    const double m = fabs(y) + top * (a.e + a.ed);
    return (fb){y, top * a.e + FLOAT_EXP_REL * m + 0x1p-149,
                top * a.ed + DOUBLE_EXP_REL * m + 0x1p-1074};
}

/* Whether a float result of the mirrored computation can be `got`. */
static inline bool fb_holds(double got, fb a)
{
    return fabs(got - a.v) <= (a.e + a.ed) * (1.0 + 0x1p-30);
}

#endif
