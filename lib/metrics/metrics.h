/*
 * Image quality metrics.  The public entry points are nerf_psnr() and
 * nerf_ssim(); the constants are here so tests and tools can reproduce the
 * exact definition.
 */
#ifndef NERF_METRICS_METRICS_H
#define NERF_METRICS_METRICS_H

#include "nerf.h"

/* SSIM as in Wang et al. 2004 and the reference NeRF evaluation. */
#define NERF__SSIM_WINDOW 11     /* taps of the Gaussian, per axis */
#define NERF__SSIM_SIGMA 1.5
#define NERF__SSIM_K1 0.01
#define NERF__SSIM_K2 0.03

/* The normalised 11-tap Gaussian the SSIM filter uses. */
void nerf__ssim_window(double taps[NERF__SSIM_WINDOW]);

#endif
