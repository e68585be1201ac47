/*
 * The per-ray marches behind march.c, shared by its count and fill passes
 * so that they agree.  From lattice index k0 each returns the number of
 * samples and, when t_out is not NULL, writes them (t and dt); *resume
 * gets the lattice index to continue from, or NERF__MARCH_DONE.  u is the
 * ray's jitter in [0, 1).
 */
#ifndef NERF_SAMPLING_MARCH_RAY_H
#define NERF_SAMPLING_MARCH_RAY_H

#include "march.h"

/* World space (march.c): lattice t = t0' + (k + u) step / |d|, with t0'
 * = max(t0, entry into the grid's bound). */
uint32_t nerf__march_ray_linear(const nerf__occupancy *g,
                                const nerf__march_options *mo,
                                const float o[3], const float d[3], float t0,
                                float t1, float u, uint32_t k0, float *t_out,
                                float *dt_out, uint32_t *resume);

/* Contracted space (march_contract.c; mo->contract > 0). */
uint32_t nerf__march_ray_contract(const nerf__occupancy *g,
                                  const nerf__march_options *mo,
                                  const float o[3], const float d[3],
                                  float t0, float t1, float u, uint32_t k0,
                                  float *t_out, float *dt_out,
                                  uint32_t *resume);

#endif
