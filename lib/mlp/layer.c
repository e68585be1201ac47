#include "layer.h"

#include <assert.h>

#include "fused.h"
#include "gemm.h"
#include "gemm_onednn.h"

int nerf__layer_forward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                        const nerf__layer_part *parts, int n_parts,
                        const float *w, size_t ldw, const float *b, bool relu,
                        float *y, size_t ldy, uint16_t *kept)
{
    assert(n_parts >= 1 && n_parts <= NERF__LAYER_MAX_PARTS);
    assert(b != NULL || !relu);
    if (c->onednn) {
        return nerf__onednn_forward(c, n, out, parts, n_parts, w, ldw, b,
                                    relu, y, ldy, kept);
    }
    size_t col = 0;
    for (int p = 0; p < n_parts; p++) {
        nerf__gemm_forward(n, out, parts[p].in, parts[p].x, parts[p].ldx,
                           w + col, ldw, p == 0 ? 0.0f : 1.0f, y, ldy);
        col += parts[p].in;
    }
    if (b && relu) {
        nerf__bias_relu(n, out, y, ldy, b);
    } else if (b) {
        nerf__bias_add(n, out, y, ldy, b);
    }
    return NERF_OK;
}

int nerf__layer_backward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                         const float *dy, size_t lddy, const uint16_t *dyb,
                         const nerf__layer_part *parts, int n_parts,
                         const uint16_t *kept, const float *w, size_t ldw,
                         float *dw, int dx_part, float *dx, size_t lddx)
{
    assert(n_parts >= 1 && n_parts <= NERF__LAYER_MAX_PARTS);
    assert(dx == NULL || (dx_part >= 0 && dx_part < n_parts));
    if (c->onednn) {
        return nerf__onednn_backward(c, n, out, dy, lddy, dyb, parts,
                                     n_parts, kept, w, ldw, dw, dx_part, dx,
                                     lddx);
    }
    assert(dyb == NULL && kept == NULL);
    size_t col = 0, dx_col = 0;
    for (int p = 0; p < n_parts; p++) {
        nerf__gemm_weight_grad(n, out, parts[p].in, dy, lddy, parts[p].x,
                               parts[p].ldx, dw + col, ldw);
        if (p == dx_part) {
            dx_col = col;
        }
        col += parts[p].in;
    }
    if (dx) {
        nerf__gemm_input_grad(n, out, parts[dx_part].in, dy, lddy, w + dx_col,
                              ldw, dx, lddx);
    }
    return NERF_OK;
}

void nerf__layer_scratch_free(struct nerf__onednn_scratch *s)
{
    nerf__onednn_scratch_free(s);
}
