/*
 * The element-wise passes around each sgemm, fused so that every
 * activation matrix is read and written once per pass: bias + ReLU going
 * forward, ReLU mask + bias gradient going backward.
 */
#ifndef NERF_MLP_FUSED_H
#define NERF_MLP_FUSED_H

#include <stddef.h>
#include <stdint.h>

/* y[i, :cols] = max(y[i, :cols] + b, 0) for n rows of stride ld. */
void nerf__bias_relu(size_t n, size_t cols, float *y, size_t ld,
                     const float *b);

/* y[i, :cols] += b. */
void nerf__bias_add(size_t n, size_t cols, float *y, size_t ld,
                    const float *b);

/*
 * dy[i, j] = 0 where y[i, j] <= 0 (ReLU backward, y being the ReLU output),
 * then db[j] += sum_i dy[i, j], summed by blocks of NERF__RELU_ROWS rows
 * whatever the thread count.  partial is scratch for
 * NERF__RELU_PARTIALS(n, cols) floats.
 */
#define NERF__RELU_ROWS 256
#define NERF__RELU_PARTIALS(n, cols)                                         \
    (((n) + NERF__RELU_ROWS - 1) / NERF__RELU_ROWS * (cols))
void nerf__relu_backward_bias(size_t n, size_t cols, const float *y,
                              size_t ldy, float *dy, size_t lddy, float *db,
                              float *partial);

/*
 * The same for a bf16 layer, whose products read only the rounded
 * gradient: the masked dy goes to dyb [n, cols] (contiguous) rounded to
 * bf16, and dy itself is left as it was.
 */
void nerf__relu_backward_bias_bf16(size_t n, size_t cols, const float *y,
                                   size_t ldy, const float *dy, size_t lddy,
                                   float *db, uint16_t *dyb, float *partial);

/* db[j] += sum_i dy[i, j]. */
void nerf__bias_backward(size_t n, size_t cols, const float *dy, size_t ld,
                         float *db);

#endif
