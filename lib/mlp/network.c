#include "network.h"

#include <math.h>
#include <string.h>

#include "fused.h"
#include "gemm_onednn.h"
#include "layer.h"
#include "network_fused.h"
#include "parallel.h"
#include "rng.h"

static nerf__linear place(uint32_t in, uint32_t out, size_t *offset)
{
    nerf__linear l = {in, out, *offset, *offset + (size_t)in * out};
    *offset += (size_t)in * out + out;
    return l;
}

void nerf__network_layout(nerf__network *net, size_t offset)
{
    net->dir_width =
        net->use_viewdirs ? nerf__encoding_width(&net->dir_enc) : 0;
    net->pos_width = nerf__encoding_width(&net->pos_enc);
    net->offset = offset;
    size_t at = offset;
    /* The encoding's parameters come first: the layers after them are
     * what weight decay applies to. */
    const size_t enc = nerf__encoding_params(&net->pos_enc);
    net->pos_params = enc ? at : 0;
    at += enc;
    if (net->view_depth < 1) {
        net->view_depth = 1;
    }
    for (uint32_t i = 0; i < net->depth; i++) {
        uint32_t in = i == 0 ? net->pos_width : net->width;
        if (i > 0 && i == net->skip) {
            in += net->pos_width;
        }
        net->trunk[i] = place(in, net->width, &at);
    }
    memset(net->view, 0, sizeof net->view);
    memset(&net->rgb, 0, sizeof net->rgb);
    if (net->use_viewdirs) {
        const uint32_t V = net->view_width;
        net->head = place(net->width, nerf__network_head_width(net), &at);
        net->view[0] = place(nerf__network_feature_width(net) + net->dir_width,
                             V, &at);
        for (uint32_t k = 1; k < net->view_depth; k++) {
            net->view[k] = place(V, V, &at);
        }
        net->rgb = place(V, 3, &at);
    } else {
        net->head = place(net->width, 4, &at);
    }
    net->count = at - offset;
}

static void init_linear(const nerf__linear *l, float *params, uint64_t seed,
                        uint64_t stream)
{
    nerf__rng rng = nerf__rng_make(seed, stream);
    float bound = 1.0f / sqrtf((float)l->in);
    size_t total = (size_t)l->in * l->out + l->out; /* W then b, contiguous */
    for (size_t k = 0; k < total; k++) {
        params[l->w + k] = (2.0f * nerf__rng_uniform(&rng) - 1.0f) * bound;
    }
}

void nerf__network_init(const nerf__network *net, float *params,
                        uint64_t seed, uint64_t stream_base)
{
    for (uint32_t i = 0; i < net->depth; i++) {
        init_linear(&net->trunk[i], params, seed, stream_base + i);
    }
    /* The fused head initialises its two parts as the reference's two
     * separate layers would be: same fan-in, so the same bound. */
    init_linear(&net->head, params, seed, stream_base + NERF__MAX_DEPTH);
    if (net->use_viewdirs) {
        /* Streams as the reference network had them, extra colour layers
         * and the table after. */
        init_linear(&net->view[0], params, seed,
                    stream_base + NERF__MAX_DEPTH + 1);
        init_linear(&net->rgb, params, seed, stream_base + NERF__MAX_DEPTH + 2);
        for (uint32_t k = 1; k < net->view_depth; k++) {
            init_linear(&net->view[k], params, seed,
                        stream_base + NERF__MAX_DEPTH + 2 + k);
        }
    }
    if (nerf__encoding_params(&net->pos_enc)) {
        nerf__encoding_init(&net->pos_enc, params + net->pos_params, seed,
                            stream_base + 2 * NERF__MAX_DEPTH);
    }
}

/* ---- workspace ---------------------------------------------------------- */

size_t nerf__network_grad_width(const nerf__network *net)
{
    size_t g = net->width + 1;
    if (net->view_width > g) {
        g = net->view_width;
    }
    if (nerf__network_head_width(net) > g) {
        g = nerf__network_head_width(net);
    }
    if (nerf__encoding_params(&net->pos_enc) && net->pos_width > g) {
        g = net->pos_width; /* the encoding's gradient input */
    }
    return g;
}

/* Layers in order: the trunk, the head, the colour branch and rgb. */
static uint32_t layer_count(const nerf__network *net)
{
    return net->depth + 1 + (net->use_viewdirs ? net->view_depth + 1 : 0);
}

static const nerf__linear *layer_at(const nerf__network *net, uint32_t index)
{
    if (index < net->depth) {
        return &net->trunk[index];
    }
    index -= net->depth;
    if (index == 0) {
        return &net->head;
    }
    return index - 1 < net->view_depth ? &net->view[index - 1] : &net->rgb;
}

/* Inputs of the layers before `index`, side by side. */
static size_t input_columns(const nerf__network *net, uint32_t index)
{
    size_t k = 0;
    for (uint32_t i = 0; i < index; i++) {
        k += layer_at(net, i)->in;
    }
    return k;
}

/*
 * A bf16 network that keeps its activations also keeps each layer's input
 * as its forward product rounded it ([n, in], layer after layer), so that
 * the weight gradient need not round it again: NULL otherwise.
 */
static uint16_t *kept_input(const nerf__network *net, nerf__workspace *ws,
                            uint32_t index)
{
    return nerf__onednn_rounds(net->onednn) && ws->kept
               ? ws->kept + ws->n * input_columns(net, index)
               : NULL;
}

static int reserve(const nerf__env *env, nerf__workspace *ws,
                   const nerf__network *net, size_t n, bool keep,
                   bool density_only)
{
    /* cblas takes int dimensions: refuse batches whose matrices it cannot
     * address. */
    if (n > (size_t)1 << 24) {
        return nerf__error(NERF_EINVAL, "batch of %zu samples is too large "
                           "(at most %d per call)", n, 1 << 24);
    }
    size_t layers = keep ? net->depth : 2;
    size_t view_layers = density_only ? 0 : keep ? net->view_depth : 2;
    /* bf16 storage, in floats (two values each). */
    const bool bf16 = keep && nerf__onednn_rounds(net->onednn);
    size_t kept = bf16 ? (n * input_columns(net, layer_count(net)) + 1) / 2 : 0;
    size_t grad16 = bf16 ? (n * nerf__network_grad_width(net) + 1) / 2 : 0;
    size_t partials =
        keep ? NERF__RELU_PARTIALS(n, nerf__network_grad_width(net)) : 0;
    enum { SLOTS = 13 };
    size_t bytes[SLOTS] = { /* in floats, made bytes below */
        n * net->pos_width,
        density_only ? 0 : n * net->dir_width,
        keep && nerf__encoding_params(&net->pos_enc) ? n * 3 : 0,
        layers * n * net->width,
        n * nerf__network_head_width(net),
        view_layers * n * net->view_width,
        density_only ? 0 : n * 3,
        keep ? n * nerf__network_grad_width(net) : 0,
        keep ? n * nerf__network_grad_width(net) : 0,
        kept,
        grad16,
        partials,
        net->onednn ? 0 : nerf__fused_scratch(net, n, keep),
    };
    for (int i = 0; i < SLOTS; i++) {
        bytes[i] *= sizeof(float);
    }
    unsigned char *block = nerf__alloc(env, nerf__carve_size(bytes, SLOTS));
    if (block == NULL) {
        return NERF_ENOMEM;
    }
    nerf__workspace_release(env, ws);
    float *kept_at = NULL, *grad16_at = NULL;
    float **slots[SLOTS] = {&ws->enc_pos, &ws->enc_dir, &ws->pos, &ws->trunk,
                            &ws->head, &ws->view, &ws->rgb, &ws->grad_a,
                            &ws->grad_b, &kept_at, &grad16_at,
                            &ws->partials, &ws->fused};
    unsigned char *at = block;
    for (int i = 0; i < SLOTS; i++) {
        *slots[i] = nerf__carve(&at, bytes[i]);
    }
    ws->kept = (uint16_t *)kept_at;
    ws->grad_bf16 = (uint16_t *)grad16_at;
    ws->enc_pos = (float *)block; /* first slot: also the block to free */
    ws->env = *env;
    ws->cap = n;
    ws->n = n;
    ws->keep = keep;
    ws->density_only = density_only;
    ws->encoded = 0;
    return NERF_OK;
}

int nerf__workspace_reserve(const nerf__env *env, nerf__workspace *ws,
                            const nerf__network *net, size_t n, bool keep)
{
    if (n <= ws->cap && (ws->keep || !keep) && !ws->density_only) {
        ws->n = n;
        return NERF_OK;
    }
    return reserve(env, ws, net, n, keep, false);
}

int nerf__workspace_reserve_density(const nerf__env *env, nerf__workspace *ws,
                                    const nerf__network *net, size_t n)
{
    if (n <= ws->cap) {
        ws->n = n;
        return NERF_OK;
    }
    return reserve(env, ws, net, n, false, true);
}

void nerf__workspace_release(const nerf__env *env, nerf__workspace *ws)
{
    nerf__free(env, ws->enc_pos);
    nerf__layer_scratch_free(ws->onednn);
    memset(ws, 0, sizeof *ws);
}

static float sigmoid(float z)
{
    return 1.0f / (1.0f + expf(-z));
}

/*
 * The loops between products, over the thread pool in ranges of samples.
 * One job type serves them all: each range function reads what it needs.
 */
typedef struct rows_job {
    const nerf__network *net;
    const float *params;
    nerf__workspace *ws;
    float *rgb_out, *sigma_out;
    const float *d_rgb, *d_sigma;
    const float *pos; /* positions, for the space's domain */
    float *dz;
    size_t ld;
} rows_job;

static void encode_positions(const nerf__network *net, const float *params,
                             nerf__workspace *ws, size_t n,
                             const float *positions)
{
    const size_t encoded = ws->encoded;
    ws->encoded = 0;
    if (encoded == n) {
        return;
    }
    const nerf__encoding *e = &net->pos_enc;
    const bool trained = nerf__encoding_params(e) > 0;
    nerf__encoding_forward(e, trained ? params + net->pos_params : NULL, n,
                           positions, ws->enc_pos, net->pos_width);
    if (trained && ws->pos) {
        memcpy(ws->pos, positions, n * 3 * sizeof(float));
    }
}

static void encode_directions(const nerf__network *net, nerf__workspace *ws,
                              size_t n, const float *directions)
{
    nerf__encoding_forward(&net->dir_enc, NULL, n, directions, ws->enc_dir,
                           net->dir_width);
}

static float *trunk_buffer(const nerf__network *net, nerf__workspace *ws,
                           uint32_t layer)
{
    return nerf__trunk_buffer(net, ws, layer);
}

static float *view_buffer(const nerf__network *net, nerf__workspace *ws,
                          uint32_t layer)
{
    return nerf__view_buffer(net, ws, layer);
}

static float exp_density(float x)
{
    return nerf__exp_density(x);
}

/* Outside the space's domain there is nothing (space.h): density 0, and
 * no gradient reaches the logit. */
static bool outside(const nerf__network *net, const float *pos, size_t i)
{
    return !nerf__space_contains(&net->space, pos + 3 * i);
}

/* The sigmoid on rgb, and the colours copied out of the workspace. */
static void colour_rows(void *ctx, size_t begin, size_t end)
{
    const rows_job *j = ctx;
    const nerf__network *net = j->net;
    nerf__workspace *ws = j->ws;
    if (net->use_viewdirs) {
        const float *b = j->params + net->rgb.b;
        for (size_t i = begin; i < end; i++) {
            for (int c = 0; c < 3; c++) {
                ws->rgb[3 * i + c] = sigmoid(ws->rgb[3 * i + c] + b[c]);
            }
        }
    } else {
        for (size_t i = begin; i < end; i++) {
            for (int c = 0; c < 3; c++) {
                ws->rgb[3 * i + c] = sigmoid(ws->head[4 * i + c]);
            }
        }
    }
    if (j->rgb_out) {
        memcpy(j->rgb_out + 3 * begin, ws->rgb + 3 * begin,
               (end - begin) * 3 * sizeof(float));
    }
}

/* The densities, from the head's rows. */
static void sigma_rows(void *ctx, size_t begin, size_t end)
{
    const rows_job *j = ctx;
    const nerf__network *net = j->net;
    const uint32_t HW = nerf__network_head_width(net);
    const float *s = j->ws->head + nerf__network_sigma_col(net);
    for (size_t i = begin; i < end; i++) {
        float x = s[i * HW];
        float sigma = net->exp_density ? exp_density(x) : x;
        j->sigma_out[i] = outside(net, j->pos, i) ? 0.0f : sigma;
    }
}

static void output_rows(void *ctx, size_t begin, size_t end)
{
    const rows_job *j = ctx;
    colour_rows(ctx, begin, end);
    if (j->sigma_out) {
        sigma_rows(ctx, begin, end);
    }
}

/* The fused small-MLP path (network_fused.h) where the network fits it and
 * the workspace was reserved for it. */
static bool use_fused(const nerf__network *net, const nerf__workspace *ws)
{
    return ws->fused != NULL && nerf__fused_active(net);
}

static nerf__layer_ctx layer_ctx(const nerf__network *net, nerf__workspace *ws)
{
    return (nerf__layer_ctx){net->onednn, &ws->onednn, &ws->env};
}

/* The trunk, from the encoded positions in ws->enc_pos; returns its last
 * activation, [n, width]. */
static int trunk_forward(const nerf__network *net, const float *params,
                         nerf__workspace *ws, size_t n, const float **top)
{
    const nerf__layer_ctx c = layer_ctx(net, ws);
    const uint32_t W = net->width, Ep = net->pos_width;
    const float *x = ws->enc_pos;
    size_t ldx = Ep;
    for (uint32_t i = 0; i < net->depth; i++) {
        const nerf__linear *l = &net->trunk[i];
        float *y = trunk_buffer(net, ws, i);
        /* At the skip the input is [gamma(x), h]. */
        const bool skip = i > 0 && i == net->skip;
        const nerf__layer_part parts[2] = {
            {skip ? ws->enc_pos : x, skip ? Ep : ldx, skip ? Ep : l->in},
            {x, ldx, W},
        };
        int rc = nerf__layer_forward(&c, n, W, parts, skip ? 2 : 1,
                                     params + l->w, l->in, params + l->b,
                                     true, y, W, kept_input(net, ws, i));
        if (rc != NERF_OK) {
            return rc;
        }
        x = y;
        ldx = W;
    }
    *top = x;
    return NERF_OK;
}

/* The trunk and the head, from ws->enc_pos to ws->head. */
static int head_forward(const nerf__network *net, const float *params,
                        nerf__workspace *ws, size_t n)
{
    const float *x;
    int rc = trunk_forward(net, params, ws, n, &x);
    if (rc != NERF_OK) {
        return rc;
    }
    const nerf__layer_ctx c = layer_ctx(net, ws);
    const uint32_t W = net->width, HW = nerf__network_head_width(net);
    const nerf__layer_part top = {x, W, W};
    return nerf__layer_forward(&c, n, HW, &top, 1, params + net->head.w, W,
                               params + net->head.b, false, ws->head, HW,
                               kept_input(net, ws, net->depth));
}

/* The colour branch, from ws->head and ws->enc_dir to ws->rgb (before the
 * rgb bias, which the sigmoid pass adds). */
static int colour_forward(const nerf__network *net, const float *params,
                          nerf__workspace *ws, size_t n)
{
    if (!net->use_viewdirs) {
        return NERF_OK;
    }
    const nerf__layer_ctx c = layer_ctx(net, ws);
    const nerf__linear *v0 = &net->view[0], *r = &net->rgb;
    const uint32_t Ed = net->dir_width, V = net->view_width;
    const uint32_t HW = nerf__network_head_width(net);
    const uint32_t F = nerf__network_feature_width(net);
    float *h = view_buffer(net, ws, 0);
    const nerf__layer_part in0[2] = {{ws->head, HW, F},
                                     {ws->enc_dir, Ed, Ed}};
    const uint32_t first = net->depth + 1; /* view[0]'s index */
    int rc = nerf__layer_forward(&c, n, V, in0, 2, params + v0->w, v0->in,
                                 params + v0->b, true, h, V,
                                 kept_input(net, ws, first));
    for (uint32_t k = 1; k < net->view_depth && rc == NERF_OK; k++) {
        float *hk = view_buffer(net, ws, k);
        const nerf__layer_part in = {h, V, V};
        rc = nerf__layer_forward(&c, n, V, &in, 1, params + net->view[k].w,
                                 V, params + net->view[k].b, true, hk, V,
                                 kept_input(net, ws, first + k));
        h = hk;
    }
    const nerf__layer_part in = {h, V, V};
    if (rc == NERF_OK) {
        rc = nerf__layer_forward(&c, n, 3, &in, 1, params + r->w, V, NULL,
                                 false, ws->rgb, 3,
                                 kept_input(net, ws, first + net->view_depth));
    }
    return rc;
}

/* The layers of `part` (ALL, HEAD or COLOUR) on the network's path. */
static int run_layers(const nerf__network *net, const float *params,
                      nerf__workspace *ws, size_t n, nerf__fused_part part)
{
    if (use_fused(net, ws)) {
        nerf__fused_forward(net, params, ws, n, part);
        return NERF_OK;
    }
    int rc = NERF_OK;
    if (part != NERF__FUSED_COLOUR) {
        rc = head_forward(net, params, ws, n);
    }
    if (rc == NERF_OK && part != NERF__FUSED_HEAD) {
        rc = colour_forward(net, params, ws, n);
    }
    return rc;
}

int nerf__network_forward(const nerf__network *net, const float *params,
                          nerf__workspace *ws, size_t n,
                          const float *positions, const float *directions,
                          float *rgb_out, float *sigma_out)
{
    ws->n = n;
    encode_positions(net, params, ws, n, positions);
    if (net->use_viewdirs) {
        encode_directions(net, ws, n, directions);
    }
    int rc = run_layers(net, params, ws, n, NERF__FUSED_ALL);
    if (rc != NERF_OK) {
        return rc;
    }
    rows_job j = {.net = net, .params = params, .ws = ws, .rgb_out = rgb_out,
                  .sigma_out = sigma_out, .pos = positions};
    nerf__parallel_for(n, 60, output_rows, &j);
    return NERF_OK;
}

int nerf__network_head(const nerf__network *net, const float *params,
                       nerf__workspace *ws, size_t n, const float *positions,
                       float *sigma_out)
{
    ws->n = n;
    encode_positions(net, params, ws, n, positions);
    int rc = run_layers(net, params, ws, n, NERF__FUSED_HEAD);
    if (rc != NERF_OK) {
        return rc;
    }
    rows_job j = {.net = net, .params = params, .ws = ws,
                  .sigma_out = sigma_out, .pos = positions};
    nerf__parallel_for(n, 30, sigma_rows, &j);
    return NERF_OK;
}

int nerf__network_colour(const nerf__network *net, const float *params,
                         nerf__workspace *ws, size_t n_colour,
                         const float *directions, float *rgb_out)
{
    ws->n = n_colour;
    if (net->use_viewdirs) {
        encode_directions(net, ws, n_colour, directions);
    }
    int rc = run_layers(net, params, ws, n_colour, NERF__FUSED_COLOUR);
    if (rc != NERF_OK) {
        return rc;
    }
    rows_job j = {.net = net, .params = params, .ws = ws, .rgb_out = rgb_out};
    nerf__parallel_for(n_colour, 60, colour_rows, &j);
    return NERF_OK;
}

/* Density from the head's one column, ws->head [n, 1]. */
static void density_rows(void *ctx, size_t begin, size_t end)
{
    const rows_job *j = ctx;
    const nerf__network *net = j->net;
    const float b = j->params[net->head.b + nerf__network_sigma_col(net)];
    for (size_t i = begin; i < end; i++) {
        float x = j->ws->head[i] + b;
        float sigma = net->exp_density ? exp_density(x) : x;
        j->sigma_out[i] = outside(net, j->pos, i) ? 0.0f : sigma;
    }
}

int nerf__network_density(const nerf__network *net, const float *params,
                          nerf__workspace *ws, size_t n,
                          const float *positions, float *sigma_out)
{
    const nerf__layer_ctx c = layer_ctx(net, ws);
    const uint32_t W = net->width;
    ws->n = n;
    encode_positions(net, params, ws, n, positions);
    rows_job j = {.net = net, .params = params, .ws = ws,
                  .sigma_out = sigma_out, .pos = positions};
    if (use_fused(net, ws)) {
        nerf__fused_forward(net, params, ws, n, NERF__FUSED_DENSITY);
        nerf__parallel_for(n, 30, density_rows, &j);
        return NERF_OK;
    }
    const float *x;
    int rc = trunk_forward(net, params, ws, n, &x);
    /* Only the density row of the head's weights; its bias is added by
     * density_rows. */
    const size_t row = (size_t)nerf__network_sigma_col(net) * W;
    const nerf__layer_part top = {x, W, W};
    if (rc == NERF_OK) {
        rc = nerf__layer_forward(&c, n, 1, &top, 1, params + net->head.w + row,
                                 W, NULL, false, ws->head, 1, NULL);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__parallel_for(n, 30, density_rows, &j);
    return NERF_OK;
}

/* dz = d_rgb * rgb (1 - rgb): the sigmoid's backward, into rows of ld. */
static void sigmoid_backward_rows(void *ctx, size_t begin, size_t end)
{
    const rows_job *j = ctx;
    const float *rgb = j->ws->rgb;
    for (size_t i = begin; i < end; i++) {
        for (int c = 0; c < 3; c++) {
            float y = rgb[3 * i + c];
            float g = j->d_rgb ? j->d_rgb[3 * i + c] : 0.0f;
            j->dz[i * j->ld + c] = g * y * (1.0f - y);
        }
    }
}

static void sigmoid_backward(nerf__workspace *ws, const float *d_rgb,
                             float *dz, size_t ld)
{
    rows_job j = {.ws = ws, .d_rgb = d_rgb, .dz = dz, .ld = ld};
    nerf__parallel_for(ws->n, 12, sigmoid_backward_rows, &j);
}

/*
 * The density logit's gradient into its head column (rows of ld, one
 * float each): set, or added where the colour branch has already put
 * the column's other gradient there.
 */
static void sigma_grad_rows(void *ctx, size_t begin, size_t end)
{
    const rows_job *j = ctx;
    const nerf__network *net = j->net;
    const size_t HW = nerf__network_head_width(net);
    const float *logit = j->ws->head + nerf__network_sigma_col(net);
    const bool add = net->geo_features > 0;
    for (size_t i = begin; i < end; i++) {
        float g = j->d_sigma ? j->d_sigma[i] : 0.0f;
        if (net->exp_density) {
            g *= exp_density(logit[i * HW]);
        }
        if (outside(net, j->ws->pos, i)) {
            g = 0.0f;
        }
        j->dz[i * j->ld] = add ? j->dz[i * j->ld] + g : g;
    }
}

static void sigma_grad(const nerf__network *net, nerf__workspace *ws,
                       const float *d_sigma, float *d_head)
{
    const uint32_t HW = nerf__network_head_width(net);
    rows_job j = {.net = net, .ws = ws, .d_sigma = d_sigma,
                  .dz = d_head + nerf__network_sigma_col(net), .ld = HW};
    nerf__parallel_for(ws->n, 64, sigma_grad_rows, &j);
}

/* The buffer of the two gradient scratch buffers that p is not. */
static float *spare_grad(nerf__workspace *ws, const float *p)
{
    return p == ws->grad_a ? ws->grad_b : ws->grad_a;
}

/*
 * The ReLU backward and bias gradient of a layer whose output was y, on
 * its output gradient dy.  A bf16 network's products read the masked
 * gradient only rounded: it comes back rounded (dy is then left as it
 * was); fp32 networks get NULL and the masked gradient in dy.
 */
static const uint16_t *relu_backward(const nerf__network *net,
                                     nerf__workspace *ws, size_t cols,
                                     const float *y, float *dy, float *db)
{
    if (nerf__onednn_rounds(net->onednn) && ws->grad_bf16) {
        nerf__relu_backward_bias_bf16(ws->n, cols, y, cols, dy, cols, db,
                                      ws->grad_bf16, ws->partials);
        return ws->grad_bf16;
    }
    nerf__relu_backward_bias(ws->n, cols, y, cols, dy, cols, db,
                             ws->partials);
    return NULL;
}

int nerf__network_backward(const nerf__network *net, const float *params,
                           float *grads, nerf__workspace *ws,
                           const float *d_rgb, const float *d_sigma)
{
    const nerf__layer_ctx c = layer_ctx(net, ws);
    const size_t n = ws->n;
    const uint32_t W = net->width, Ep = net->pos_width;
    const uint32_t HW = nerf__network_head_width(net);
    float *d_head = ws->grad_a;
    int rc = NERF_OK;
    if (use_fused(net, ws) && ws->keep) {
        size_t ld = 0;
        const float *d_enc = nerf__fused_backward(net, params, grads, ws,
                                                  d_rgb, d_sigma, &ld);
        if (d_enc) {
            nerf__encoding_backward(&net->pos_enc, n, ws->pos, d_enc, ld,
                                    grads + net->pos_params);
        }
        return NERF_OK;
    }

    if (net->use_viewdirs) {
        const nerf__linear *r = &net->rgb;
        const uint32_t Ed = net->dir_width, V = net->view_width;
        const uint32_t F = nerf__network_feature_width(net);
        const uint32_t first = net->depth + 1; /* view[0]'s index */
        float *dz = ws->grad_b; /* [n, 3] */
        sigmoid_backward(ws, d_rgb, dz, 3);
        const nerf__layer_part h_top = {
            view_buffer(net, ws, net->view_depth - 1), V, V};
        nerf__bias_backward(n, 3, dz, 3, grads + r->b);
        float *d_view = ws->grad_a; /* [n, V] */
        rc = nerf__layer_backward(&c, n, 3, dz, 3, NULL, &h_top, 1,
                                  kept_input(net, ws, first + net->view_depth),
                                  params + r->w, V, grads + r->w, 0, d_view,
                                  V);
        for (uint32_t k = net->view_depth; k-- > 1 && rc == NERF_OK;) {
            const nerf__linear *v = &net->view[k];
            const nerf__layer_part h_in = {view_buffer(net, ws, k - 1), V, V};
            const uint16_t *g16 = relu_backward(net, ws, V,
                                                view_buffer(net, ws, k),
                                                d_view, grads + v->b);
            float *d_in = spare_grad(ws, d_view);
            rc = nerf__layer_backward(&c, n, V, d_view, V, g16, &h_in, 1,
                                      kept_input(net, ws, first + k),
                                      params + v->w, V, grads + v->w, 0, d_in,
                                      V);
            d_view = d_in;
        }
        if (rc != NERF_OK) {
            return rc;
        }
        const nerf__linear *v0 = &net->view[0];
        const uint16_t *g16 = relu_backward(net, ws, V, view_buffer(net, ws, 0),
                                            d_view, grads + v0->b);
        const nerf__layer_part in0[2] = {{ws->head, HW, F},
                                         {ws->enc_dir, Ed, Ed}};
        d_head = spare_grad(ws, d_view);
        rc = nerf__layer_backward(&c, n, V, d_view, V, g16, in0, 2,
                                  kept_input(net, ws, first), params + v0->w,
                                  v0->in, grads + v0->w, 0, d_head, HW);
        if (rc != NERF_OK) {
            return rc;
        }
        sigma_grad(net, ws, d_sigma, d_head);
    } else {
        sigmoid_backward(ws, d_rgb, d_head, 4);
        sigma_grad(net, ws, d_sigma, d_head);
    }

    const nerf__layer_part h_last = {trunk_buffer(net, ws, net->depth - 1), W,
                                     W};
    nerf__bias_backward(n, HW, d_head, HW, grads + net->head.b);
    float *dh = spare_grad(ws, d_head);
    rc = nerf__layer_backward(&c, n, HW, d_head, HW, NULL, &h_last, 1,
                              kept_input(net, ws, net->depth),
                              params + net->head.w, W, grads + net->head.w, 0,
                              dh, W);

    for (uint32_t i = net->depth; i-- > 0 && rc == NERF_OK;) {
        const nerf__linear *l = &net->trunk[i];
        const uint16_t *g16 = relu_backward(net, ws, W,
                                            trunk_buffer(net, ws, i), dh,
                                            grads + l->b);
        uint16_t *kept = kept_input(net, ws, i);
        if (i == 0) {
            const nerf__layer_part enc = {ws->enc_pos, Ep, Ep};
            const nerf__encoding *e = &net->pos_enc;
            if (nerf__encoding_params(e) == 0) {
                rc = nerf__layer_backward(&c, n, W, dh, W, g16, &enc, 1, kept,
                                          params + l->w, l->in, grads + l->w,
                                          -1, NULL, 0);
                break;
            }
            float *d_enc = spare_grad(ws, dh);
            rc = nerf__layer_backward(&c, n, W, dh, W, g16, &enc, 1, kept,
                                      params + l->w, l->in, grads + l->w, 0,
                                      d_enc, Ep);
            if (rc == NERF_OK) {
                nerf__encoding_backward(e, n, ws->pos, d_enc, Ep,
                                        grads + net->pos_params);
            }
            break;
        }
        /* At the skip the input was [gamma(x), h]: the gradient goes on
         * only through h, part 1. */
        const bool skip = i == net->skip;
        const nerf__layer_part x = {trunk_buffer(net, ws, i - 1), W, W};
        const nerf__layer_part parts[2] = {{ws->enc_pos, Ep, Ep}, x};
        float *dx = spare_grad(ws, dh);
        rc = nerf__layer_backward(&c, n, W, dh, W, g16, skip ? parts : &x,
                                  skip ? 2 : 1, kept, params + l->w, l->in,
                                  grads + l->w, skip ? 1 : 0, dx, W);
        dh = dx;
    }
    return rc;
}

double nerf__network_flops_per_sample(const nerf__network *net)
{
    double f = 0.0;
    for (uint32_t i = 0; i < net->depth; i++) {
        f += 2.0 * net->trunk[i].in * net->trunk[i].out;
    }
    f += 2.0 * net->head.in * net->head.out;
    if (net->use_viewdirs) {
        for (uint32_t k = 0; k < net->view_depth; k++) {
            f += 2.0 * net->view[k].in * net->view[k].out;
        }
        f += 2.0 * net->rgb.in * net->rgb.out;
    }
    return f;
}
