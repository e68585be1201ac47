/*
 * The products of one dense layer, in the precision its network computes
 * in.  network.c describes each layer once (its input parts, weights,
 * bias and activation) and this interface picks the backend:
 *
 *  - fp32: one cblas_sgemm per input part (gemm.h), then the fused bias
 *    and ReLU pass (fused.h), exactly as the network always ran;
 *  - oneDNN (gemm_onednn.h, built with oneDNN): bias and ReLU fused into
 *    the product, in fp32, or with the operands rounded to bfloat16 and
 *    the products accumulated in fp32.
 *
 * A layer whose input is a concatenation ([gamma(x), h] at the skip,
 * [feature, gamma(d)] in the view branch) takes it as parts: part p
 * multiplies the column block of W that follows the blocks of the parts
 * before it, so the concatenation is never built in fp32.
 */
#ifndef NERF_MLP_LAYER_H
#define NERF_MLP_LAYER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "env.h"

struct nerf__onednn;
struct nerf__onednn_scratch;

/* One input part: rows of x, stride ldx, `in` columns. */
typedef struct nerf__layer_part {
    const float *x;
    size_t ldx;
    uint32_t in;
} nerf__layer_part;

#define NERF__LAYER_MAX_PARTS 2

/*
 * Where a call's products run.  onednn NULL: fp32 through cblas, and the
 * other fields are unused.  Otherwise the model's oneDNN backend, and the
 * caller's scratch (created on first use with env, freed with
 * nerf__layer_scratch_free()), which holds the rounded operands and the
 * per-thread streams: one per workspace, since workspaces are never
 * shared between threads.
 */
typedef struct nerf__layer_ctx {
    struct nerf__onednn *onednn;
    struct nerf__onednn_scratch **scratch;
    const nerf__env *env;
} nerf__layer_ctx;

/*
 * Y[n, out] = act(sum_p X_p W_p^T + b).  W is [out, ldw] from w, the
 * parts' column blocks side by side from column 0.  b [out] may be NULL
 * (no bias); relu needs a bias.
 *
 * bf16 only (nerf__onednn_rounds()): `kept`, when not NULL, receives the
 * rounded input (the parts side by side, [n, sum of their widths]) for
 * the backward to reuse, which spares rounding it again; the fp32 paths
 * ignore it.
 * @return NERF_OK, or (oneDNN only) NERF_ENOMEM or NERF_ERROR with a
 * message.
 */
int nerf__layer_forward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                        const nerf__layer_part *parts, int n_parts,
                        const float *w, size_t ldw, const float *b, bool relu,
                        float *y, size_t ldy, uint16_t *kept);

/*
 * The products of the layer's backward, given dY [n, out] (the gradient
 * of its output before the activation, stride lddy):
 * dW_p += dY^T X_p for every part (dw has w's layout), then, when dx is
 * not NULL, dX = dY W_q for q = dx_part.
 *
 * bf16 only (NULL otherwise): dyb is dY already rounded ([n, out],
 * contiguous; dy is then not read) and kept what the forward kept.
 * @return as nerf__layer_forward().
 */
int nerf__layer_backward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                         const float *dy, size_t lddy, const uint16_t *dyb,
                         const nerf__layer_part *parts, int n_parts,
                         const uint16_t *kept, const float *w, size_t ldw,
                         float *dw, int dx_part, float *dx, size_t lddx);

void nerf__layer_scratch_free(struct nerf__onednn_scratch *s);

#endif
