/*
 * The NeRF network: a ReLU trunk with a skip connection, a head giving the
 * 256-wide feature and sigma, and a view branch giving rgb.  The same code
 * runs the hash-grid model of Mueller et al. (2022): a hash-grid position
 * encoding whose table is trained with the layers, a one-layer trunk, a
 * 16-wide head whose first output is log-density (exp activation) and whose
 * whole output feeds a two-layer colour branch with spherical-harmonics
 * directions.  Samples are
 * rows of row-major matrices and every layer is one cblas_sgemm per pass
 * (two where the input is a concatenation: the concatenation is never
 * copied, each part multiplies its own column block of the weights).
 *
 * Weights are stored as PyTorch stores nn.Linear: W is [out, in] row-major,
 * followed by the bias [out].  All parameters of a network are one slice of
 * the model's parameter array, so the optimiser and the checkpoint see one
 * flat vector.
 */
#ifndef NERF_MLP_NETWORK_H
#define NERF_MLP_NETWORK_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "encoding.h"
#include "env.h"
#include "layer.h"
#include "space.h"

#define NERF__MAX_DEPTH 32
#define NERF__MAX_VIEW_DEPTH 8
/* Truncated exponential: log-densities above this give exp(this), and
 * their gradient uses the same value, so a large logit cannot overflow. */
#define NERF__EXP_DENSITY_MAX 15.0f

typedef struct nerf__linear {
    uint32_t in, out;
    size_t w; /* offset of W [out, in] in the parameter array */
    size_t b; /* offset of the bias [out] */
} nerf__linear;

typedef struct nerf__network {
    /* The encodings of positions and directions, run through their ops
     * (encoding.h); the network never asks which kinds they are. */
    nerf__encoding pos_enc, dir_enc;
    /* Where positions must lie to hold density (space.h): samples outside
     * the domain get density 0 and no density gradient. */
    nerf__space space;
    uint32_t pos_width, dir_width; /* encoded widths */
    uint32_t depth, width, skip, view_width, view_depth;
    /* 0: the reference head, a width-wide feature plus sigma.  G > 0: a
     * G-wide head whose column 0 is also the density, all of it feeding
     * the colour branch. */
    uint32_t geo_features;
    bool use_viewdirs;
    bool exp_density; /* sigma = exp(x) rather than raw x (ReLU later) */
    /* Offset of the position encoding's parameters (a hash grid's table)
     * in the parameter array; 0 if it has none. */
    size_t pos_params;
    nerf__linear trunk[NERF__MAX_DEPTH];
    /* With view directions and no geo_features: rows [0, width) are the
     * feature layer, row width is sigma (the reference's feature_linear
     * and alpha_linear, fused so that one sgemm serves both).  Without
     * view directions: the 4-wide output_linear, [r, g, b, sigma]. */
    nerf__linear head;
    /* view[0]: [feature, encoded d] -> view_width; the rest view_width ->
     * view_width; all ReLU. */
    nerf__linear view[NERF__MAX_VIEW_DEPTH];
    nerf__linear rgb;  /* view_width -> 3, sigmoid */
    size_t offset;     /* first parameter in the model's array */
    size_t count;      /* number of parameters, table included */
    /* The model's oneDNN backend (gemm_onednn.h), or NULL: products in
     * fp32 through cblas.  Set by the model after the layout. */
    struct nerf__onednn *onednn;
} nerf__network;

/*
 * Lay the network's layers out from parameter offset `offset`.  The caller
 * has filled the encodings and the shape fields.
 */
void nerf__network_layout(nerf__network *net, size_t offset);

/* Floats per sample in the head's output. */
static inline uint32_t nerf__network_head_width(const nerf__network *net)
{
    if (!net->use_viewdirs) {
        return 4;
    }
    return net->geo_features ? net->geo_features : net->width + 1;
}

/* Head columns [0, this) feed the colour branch. */
static inline uint32_t nerf__network_feature_width(const nerf__network *net)
{
    return net->geo_features ? net->geo_features : net->width;
}

/* The head column holding the density logit. */
static inline uint32_t nerf__network_sigma_col(const nerf__network *net)
{
    if (!net->use_viewdirs) {
        return 3;
    }
    return net->geo_features ? 0 : net->width;
}

/*
 * PyTorch's default nn.Linear initialisation (uniform in +-1/sqrt(in) for
 * weights and biases), the one the reference port trains with.  Each layer
 * draws from its own counter-based stream keyed by (seed, stream_base +
 * layer), so results do not depend on the order layers are visited.
 */
void nerf__network_init(const nerf__network *net, float *params,
                        uint64_t seed, uint64_t stream_base);

/*
 * Activation and gradient buffers for batches of up to `cap` samples.
 * `keep` stores every trunk activation, which backward needs; without it
 * the trunk alternates between two buffers.  Buffers grow on demand and are
 * reused, so a training loop allocates only on its first step.
 */
typedef struct nerf__workspace {
    size_t cap;
    size_t n;      /* samples in the last forward */
    bool keep;
    bool density_only; /* no direction, colour branch or rgb buffers */
    float *enc_pos; /* [n, pos_width] */
    float *enc_dir; /* [n, dir_width] */
    float *pos;     /* [n, 3], the positions, kept for the backward of an
                     * encoding with parameters */
    float *trunk;   /* [depth or 2][n, width], after ReLU */
    float *head;    /* [n, head_width] */
    float *view;    /* [view_depth][n, view_width], after ReLU */
    float *rgb;     /* [n, 3], after the sigmoid */
    float *grad_a;  /* [n, width + 1], gradient scratch */
    float *grad_b;  /* [n, width + 1] */
    /* bf16 networks with keep: every layer's input as its forward product
     * rounded it, and a rounded gradient ([n, width + 1]). */
    uint16_t *kept;
    uint16_t *grad_bf16;
    float *partials;  /* the ReLU backward's bias sums by row block */
    nerf__env env;  /* what reserved it, for the oneDNN scratch */
    /* The rounded operands and streams of a oneDNN network's products,
     * created by its first product (layer.h). */
    struct nerf__onednn_scratch *onednn;
    /* The fused path's packed weights and gradient partials
     * (network_fused.h), or NULL where the network does not fit it. */
    float *fused;
    /* Set by a caller whose parameters have not changed since this
     * workspace's last forward (a renderer between the rounds of one
     * block): the fused path then keeps the weights it packed for that
     * forward instead of packing them again. */
    bool params_unchanged;
    uint32_t packed_layers; /* layers ws->fused holds, 0 after a reserve */
    /* Set by a caller who left in enc_pos (and pos, where kept) the
     * position encodings of the next forward's `encoded` samples, as a
     * density pass over more samples computed them: that forward then
     * does not encode the positions again.  The forward resets it. */
    size_t encoded;
} nerf__workspace;

/* Floats per sample in each of grad_a and grad_b. */
size_t nerf__network_grad_width(const nerf__network *net);

/* Where trunk layer `layer`'s activations are ([n, width]): its own slot
 * when the workspace keeps them, else one of two alternating slots. */
static inline float *nerf__trunk_buffer(const nerf__network *net,
                                        nerf__workspace *ws, uint32_t layer)
{
    size_t slot = ws->keep ? layer : layer % 2;
    return ws->trunk + slot * ws->n * net->width;
}

/* The same for the colour branch ([n, view_width]). */
static inline float *nerf__view_buffer(const nerf__network *net,
                                       nerf__workspace *ws, uint32_t layer)
{
    size_t slot = ws->keep ? layer : layer % 2;
    return ws->view + slot * ws->n * net->view_width;
}

/* The exponential density activation, truncated. */
static inline float nerf__exp_density(float x)
{
    return expf(x < NERF__EXP_DENSITY_MAX ? x : NERF__EXP_DENSITY_MAX);
}

int nerf__workspace_reserve(const nerf__env *env, nerf__workspace *ws,
                            const nerf__network *net, size_t n, bool keep);
/* A workspace for nerf__network_density() only: about a third of the
 * memory of a full one (no colour branch).  A full workspace serves too. */
int nerf__workspace_reserve_density(const nerf__env *env, nerf__workspace *ws,
                                    const nerf__network *net, size_t n);
void nerf__workspace_release(const nerf__env *env, nerf__workspace *ws);

/*
 * Forward n samples.  positions and directions are [n, 3]; directions may
 * be NULL when the network ignores them.  rgb_out [n, 3] receives the
 * sigmoid colours and sigma_out [n] the raw density (either may be NULL).
 * The workspace must have been reserved for n samples.
 *
 * These calls fail only for a bf16 network (NERF_ENOMEM, or NERF_ERROR if
 * oneDNN fails), with a message; an fp32 network always gives NERF_OK.
 */
int nerf__network_forward(const nerf__network *net, const float *params,
                           nerf__workspace *ws, size_t n,
                           const float *positions, const float *directions,
                           float *rgb_out, float *sigma_out);

/*
 * Density only, for occupancy-grid updates: the position encoding, the
 * trunk and the head's density column, without the colour branch.
 * sigma_out[n] receives what nerf__network_forward() gives as sigma (up
 * to rounding: the head is one column here).  ws must have been reserved
 * for n samples by either reserve call; the activations of its last
 * forward are overwritten.
 */
int nerf__network_density(const nerf__network *net, const float *params,
                           nerf__workspace *ws, size_t n,
                           const float *positions, float *sigma_out);

/*
 * A forward in two halves, for a renderer that needs the colour of only
 * some samples: nerf__network_head() gives the density of n samples as
 * nerf__network_forward() would and leaves in ws->head [n, head_width]
 * the rows the colour branch reads; the caller may then move some of
 * those rows to the front (each row alone, in order) and
 * nerf__network_colour() gives the colours of the first n_colour rows as
 * nerf__network_forward() would for their samples (bit for bit on the
 * fused path, whose rows are computed alone).  ws must be a full
 * workspace (not a density one) reserved for n samples; n_colour <= n.
 */
int nerf__network_head(const nerf__network *net, const float *params,
                       nerf__workspace *ws, size_t n, const float *positions,
                       float *sigma_out);
int nerf__network_colour(const nerf__network *net, const float *params,
                         nerf__workspace *ws, size_t n_colour,
                         const float *directions, float *rgb_out);

/*
 * Backward the last forward (which must have kept its activations), given
 * the loss gradient with respect to rgb [n, 3] (after the sigmoid) and raw
 * sigma [n]; either may be NULL for zero.  Gradients are added to grads
 * (same layout as params).
 */
int nerf__network_backward(const nerf__network *net, const float *params,
                            float *grads, nerf__workspace *ws,
                            const float *d_rgb, const float *d_sigma);

/* Multiply-adds per sample of one forward pass. */
double nerf__network_flops_per_sample(const nerf__network *net);

#endif
