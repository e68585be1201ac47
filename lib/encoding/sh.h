/*
 * Spherical-harmonics encoding of view directions, the direction input of
 * the hash-grid model's colour network.  It has no parameters and
 * directions are not trained, so it has no backward.
 */
#ifndef NERF_ENCODING_SH_H
#define NERF_ENCODING_SH_H

#include <stddef.h>
#include <stdint.h>

#define NERF__SH_MAX_DEGREE 4

/* Floats per sample: degree^2 (degree clamped to 1..4 as below). */
uint32_t nerf__sh_width(uint32_t degree);

/*
 * Real spherical harmonics of the given degree (the number of bands l = 0
 * .. degree - 1, so degree^2 values; 4 gives instant-ngp's 16), ordered by
 * band l and then m = -l..l, the m < 0 ones built on sin(|m| phi) and the
 * m > 0 ones on cos(m phi).
 *
 * Normalisation: orthonormal on the unit sphere (the integral of Y_i Y_j
 * over the sphere is delta_ij), so Y_0 = 1 / (2 sqrt(pi)).  Sign: the
 * Condon-Shortley phase (-1)^m is kept, as instant-ngp keeps it, so the
 * values equal instant-ngp's: the l = 1 band is c (-y, z, -x) with
 * c = sqrt(3 / (4 pi)).
 *
 * Each direction (rows of `in`, stride in_stride floats, 3 used) is used
 * as given, not mapped from [0, 1], after normalising it to unit length; a
 * zero vector encodes as the polynomials at the origin (only Y_0 and the
 * constant part of Y_6 are non-zero).  Rows of `out` have stride
 * out_stride >= degree^2; the gap is not touched.  Degrees outside 1..4
 * are clamped to that range.
 */
void nerf__sh_forward(uint32_t degree, size_t n, const float *in,
                      size_t in_stride, float *out, size_t out_stride);

#endif
