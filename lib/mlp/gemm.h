/*
 * The three products of a dense layer, through cblas_sgemm.
 *
 * When the BLAS runs on one thread (OpenBLAS with OPENBLAS_NUM_THREADS=1,
 * or after openblas_set_num_threads(1)), each product is cut into blocks
 * at fixed places, spread over libnerf's own workers (common/parallel.h).
 * That is how the small layers of the fast preset use every core:
 * OpenBLAS's own threading of a 64-wide product spends much of its time
 * handing work between its threads (docs/perf-log/
 * early-first-measurements.md).  Each element of a result comes
 * from one sgemm call over the whole reduction.  Forward and input-
 * gradient calls are the same for any number of workers, so their results
 * do not depend on the thread count; a weight gradient is cut into one
 * call per thread of the pool, and is deterministic for a given thread
 * count, however busy the pool.  Results may depend, in the last bits,
 * on the rows a product holds: the BLAS can round a row by the size of
 * its call and the row's place in it (gemm.c), so a sample's values can
 * differ with the samples beside it, unlike on the fused path
 * (network_fused.h).
 */
#ifndef NERF_MLP_GEMM_H
#define NERF_MLP_GEMM_H

#include <stddef.h>
#include <stdint.h>

/* Y[n, out] = beta Y + X[n, in] W^T, W a column block of a [out, ldw]. */
void nerf__gemm_forward(size_t n, uint32_t out, uint32_t in, const float *x,
                        size_t ldx, const float *w, size_t ldw, float beta,
                        float *y, size_t ldy);

/* dW[out, in] += dY[n, out]^T X[n, in]. */
void nerf__gemm_weight_grad(size_t n, uint32_t out, uint32_t in,
                            const float *dy, size_t lddy, const float *x,
                            size_t ldx, float *dw, size_t lddw);

/* dX[n, in] = dY[n, out] W, W a column block of a [out, ldw]. */
void nerf__gemm_input_grad(size_t n, uint32_t out, uint32_t in, const float *dy,
                           size_t lddy, const float *w, size_t ldw, float *dx,
                           size_t lddx);

/*
 * The BLAS's own thread count: OpenBLAS's when the BLAS is OpenBLAS, else
 * 0 (unknown).  Only read, never changed: it belongs to the application.
 */
int nerf__blas_threads(void);

#endif
