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
#include <stddef.h>

/* Unit roundoff of float (round to nearest). */
#define FLOAT_U 0x1p-24

/* gamma(n) for float; n well below 2^24 in every use. */
static inline double float_gamma(double n)
{
    return n * FLOAT_U / (1.0 - n * FLOAT_U);
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
 * libm's expf in float, relative to the exact exponential of its float
 * argument: 2 ulps, 4 u (glibc documents at most 1 ulp for expf; musl's
 * and Apple's are within 1 as well).
 */
#define FLOAT_EXPF_REL (4 * FLOAT_U)

/*
 * The library's float sigmoid, 1 / (1 + expf(-z)), against the exact
 * sigmoid of the same float z: expf within FLOAT_EXPF_REL, then an add
 * and a divide within u each, so within (4 + 1 + 1) u (1 + O(u)) of
 * sigma(z) <= 1 relatively, hence absolutely: 8 u.  A z within E of the
 * exact argument adds E / 4, the sigmoid's largest slope.
 */
#define FLOAT_SIGMOID_ABS (8 * FLOAT_U)

/*
 * |expf(z^) - exp(z)| for a float z^ within E of z, the exponent truncated
 * at zmax as the library's exponential density truncates it: the exact
 * exponential moves by at most exp(z) (exp(E) - 1), and expf errs by
 * FLOAT_EXPF_REL of exp(z^) <= exp(z + E).
 */
static inline double float_exp_bound(double z, double E, double zmax)
{
    z = z < zmax ? z : zmax;
    return exp(z) * expm1(E) + FLOAT_EXPF_REL * exp(z + E);
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
