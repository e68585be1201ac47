#include "fused.h"

void nerf__bias_relu(size_t n, size_t cols, float *y, size_t ld,
                     const float *b)
{
    for (size_t i = 0; i < n; i++) {
        float *row = y + i * ld;
        for (size_t j = 0; j < cols; j++) {
            float v = row[j] + b[j];
            row[j] = v > 0.0f ? v : 0.0f;
        }
    }
}

void nerf__bias_add(size_t n, size_t cols, float *y, size_t ld,
                    const float *b)
{
    for (size_t i = 0; i < n; i++) {
        float *row = y + i * ld;
        for (size_t j = 0; j < cols; j++) {
            row[j] += b[j];
        }
    }
}

void nerf__relu_backward_bias(size_t n, size_t cols, const float *y,
                              size_t ldy, float *dy, size_t lddy, float *db)
{
    for (size_t i = 0; i < n; i++) {
        const float *yr = y + i * ldy;
        float *dr = dy + i * lddy;
        for (size_t j = 0; j < cols; j++) {
            float g = yr[j] > 0.0f ? dr[j] : 0.0f;
            dr[j] = g;
            db[j] += g;
        }
    }
}

void nerf__bias_backward(size_t n, size_t cols, const float *dy, size_t ld,
                         float *db)
{
    for (size_t i = 0; i < n; i++) {
        const float *dr = dy + i * ld;
        for (size_t j = 0; j < cols; j++) {
            db[j] += dr[j];
        }
    }
}
