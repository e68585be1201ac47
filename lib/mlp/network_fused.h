/*
 * The fused small-MLP path of network.h: for fp32 networks whose layers
 * are all at most NERF__FUSED_MAX_WIDTH wide (the fast preset's), a block
 * of NERF__FUSED_ROWS samples goes through every layer while its
 * activations stay in L1/L2, each product through smm.h's kernels instead
 * of one cblas_sgemm per layer over the whole batch.
 *
 * The workspace keeps its layout (network.h), so the two paths share the
 * encodings, the output passes and the backward's inputs.  The backward
 * sums the weight and bias gradients of fixed chunks of NERF__FUSED_CHUNK
 * samples, each into its own partial copy of the layers' gradients, and
 * adds the partials in chunk order: the result does not depend on the
 * thread count.
 */
#ifndef NERF_MLP_NETWORK_FUSED_H
#define NERF_MLP_NETWORK_FUSED_H

#include <stdbool.h>
#include <stddef.h>

#include "network.h"

#define NERF__FUSED_MAX_WIDTH 64
#define NERF__FUSED_ROWS 128
#define NERF__FUSED_CHUNK 2048

/* Whether the network's shape suits the fused path (fp32, narrow layers). */
bool nerf__fused_fits(const nerf__network *net);
/* Whether its passes take the fused path now: it fits and the kernels are
 * on (smm.h's variant is not NERF__SMM_OFF). */
bool nerf__fused_active(const nerf__network *net);

/* Floats of workspace scratch the fused path needs for n samples (packed
 * weights; with keep, the chunks' gradient partials); 0 if it does not fit. */
size_t nerf__fused_scratch(const nerf__network *net, size_t n, bool keep);

/* How much of a forward nerf__fused_forward() runs. */
typedef enum nerf__fused_part {
    /* Every layer. */
    NERF__FUSED_ALL,
    /* The trunk and the head's density column alone, into ws->head [n, 1]
     * without its bias. */
    NERF__FUSED_DENSITY,
    /* The trunk and the whole head, into ws->head [n, head width]. */
    NERF__FUSED_HEAD,
    /* The colour branch and rgb alone, from the rows a HEAD pass left in
     * ws->head (and from ws->enc_dir). */
    NERF__FUSED_COLOUR,
} nerf__fused_part;

/*
 * The layers of a forward, from ws->enc_pos and ws->enc_dir (already
 * encoded) to ws->trunk, ws->head, ws->view and ws->rgb (before the rgb
 * bias and sigmoid), as network.c's per-layer products leave them; or the
 * part of them that `part` names.  Every row is computed alone (smm.h),
 * so a HEAD pass followed by a COLOUR pass over some of its rows, moved
 * to the front, gives those rows' ALL results bit for bit.
 */
void nerf__fused_forward(const nerf__network *net, const float *params,
                         nerf__workspace *ws, size_t n, nerf__fused_part part);

/*
 * The layers' backward from d_rgb and d_sigma (either NULL for zero), with
 * the sigmoid and the density's activation: gradients added to grads.
 * Returns the gradient of the encoded positions ([n, *ld]) when the
 * position encoding has parameters, else NULL.
 */
const float *nerf__fused_backward(const nerf__network *net,
                                  const float *params, float *grads,
                                  nerf__workspace *ws, const float *d_rgb,
                                  const float *d_sigma, size_t *ld);

#endif
