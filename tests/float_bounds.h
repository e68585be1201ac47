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

#endif
