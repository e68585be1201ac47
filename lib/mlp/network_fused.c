#include "network_fused.h"

#include <assert.h>
#include <string.h>

#include "multiversion.h"
#include "parallel.h"
#include "smm.h"

/* Packed W^T rows are padded to whole 64-byte lines: the kernels then
 * load them without masks, and every packed matrix starts on a line. */
#define PAD 16

static uint32_t padded(uint32_t w)
{
    return (w + PAD - 1) / PAD * PAD;
}

/* Layers in order: the trunk, the head, the colour branch and rgb. */
static uint32_t n_layers(const nerf__network *net)
{
    return net->depth + 1 + (net->use_viewdirs ? net->view_depth + 1 : 0);
}

static const nerf__linear *layer_at(const nerf__network *net, uint32_t i)
{
    if (i < net->depth) {
        return &net->trunk[i];
    }
    i -= net->depth;
    if (i == 0) {
        return &net->head;
    }
    return i - 1 < net->view_depth ? &net->view[i - 1] : &net->rgb;
}

bool nerf__fused_fits(const nerf__network *net)
{
    /* Inputs are at most two parts, each one of these widths. */
    if (net->onednn != NULL || net->depth == 0 ||
        net->pos_width > NERF__FUSED_MAX_WIDTH ||
        net->dir_width > NERF__FUSED_MAX_WIDTH) {
        return false;
    }
    for (uint32_t i = 0; i < n_layers(net); i++) {
        if (layer_at(net, i)->out > NERF__FUSED_MAX_WIDTH) {
            return false;
        }
    }
    return true;
}

bool nerf__fused_active(const nerf__network *net)
{
    return nerf__smm_variant() != NERF__SMM_OFF && nerf__fused_fits(net);
}

static size_t packed_floats(const nerf__network *net)
{
    size_t f = 0;
    for (uint32_t i = 0; i < n_layers(net); i++) {
        const nerf__linear *l = layer_at(net, i);
        f += (size_t)l->in * padded(l->out);
    }
    return f;
}

/* The layers' parameters after the encoding's, which the partials mirror:
 * from the first trunk layer's weights to the end of the network. */
static size_t layer_params(const nerf__network *net)
{
    return net->offset + net->count - net->trunk[0].w;
}

static size_t n_chunks(size_t n)
{
    return (n + NERF__FUSED_CHUNK - 1) / NERF__FUSED_CHUNK;
}

size_t nerf__fused_scratch(const nerf__network *net, size_t n, bool keep)
{
    if (!nerf__fused_fits(net)) {
        return 0;
    }
    return packed_floats(net) +
           (keep ? n_chunks(n) * padded((uint32_t)layer_params(net)) : 0);
}

typedef struct fjob {
    const nerf__network *net;
    const float *params;
    nerf__workspace *ws;
    const float *wt[NERF__MAX_DEPTH + NERF__MAX_VIEW_DEPTH + 2];
    nerf__fused_part part;
    /* backward */
    const float *d_rgb, *d_sigma;
    float *partials;
    size_t stride; /* floats from one chunk's partials to the next */
    size_t count;  /* layer_params() */
    size_t base;   /* index in params of the partials' first float */
    size_t n, G;
    int last_buffer; /* which gradient buffer the last dX lands in */
    float *grads;
} fjob;

/* W^T of every layer the pass needs, rows padded, into ws->fused, unless
 * the caller vouches that the weights packed there last are current. */
static void pack(fjob *j, uint32_t layers)
{
    nerf__workspace *ws = j->ws;
    const bool current = ws->params_unchanged && ws->packed_layers >= layers;
    float *at = ws->fused;
    for (uint32_t i = 0; i < layers; i++) {
        const nerf__linear *l = layer_at(j->net, i);
        const float *w = j->params + l->w;
        const uint32_t P = padded(l->out);
        for (uint32_t k = 0; k < l->in && !current; k++) {
            for (uint32_t o = 0; o < P; o++) {
                at[(size_t)k * P + o] = o < l->out ? w[(size_t)o * l->in + k]
                                                   : 0.0f;
            }
        }
        j->wt[i] = at;
        at += (size_t)l->in * P;
    }
    if (!current) {
        ws->packed_layers = layers;
    }
}

static nerf__smm_seg rows_of(const float *x, size_t ld, uint32_t k)
{
    return (nerf__smm_seg){x, ld, 1, k};
}

/* Reading down the columns of dY: A(o, r) = dY[r, o], for dW = dY^T X. */
static nerf__smm_seg cols_of(const float *dy, size_t ld, size_t rows)
{
    return (nerf__smm_seg){dy, 1, ld, (uint32_t)rows};
}

/*
 * Where a block's hidden activations go: the workspace's rows when it
 * keeps them for the backward, else two block-sized slots on the stack
 * (local), which never leave the cache.
 */
#define SLOT (NERF__FUSED_ROWS * NERF__FUSED_MAX_WIDTH)

static float *trunk_out(const fjob *j, float *local, uint32_t i, size_t r0)
{
    return local ? local + (i % 2) * SLOT
                 : nerf__trunk_buffer(j->net, j->ws, i) + r0 * j->net->width;
}

static float *view_out(const fjob *j, float *local, uint32_t k, size_t r0)
{
    return local ? local + (k % 2) * SLOT
                 : nerf__view_buffer(j->net, j->ws, k) +
                       r0 * j->net->view_width;
}

/* The trunk and the head of a block (only the head's density column for
 * a DENSITY pass). */
static void block_head(const fjob *j, size_t r0, size_t rows, float *local)
{
    const nerf__network *net = j->net;
    const float *params = j->params;
    nerf__workspace *ws = j->ws;
    const uint32_t W = net->width, Ep = net->pos_width;
    const float *x = ws->enc_pos + r0 * Ep;
    size_t ldx = Ep;
    for (uint32_t i = 0; i < net->depth; i++) {
        const nerf__linear *l = &net->trunk[i];
        float *y = trunk_out(j, local, i, r0);
        /* At the skip the input is [gamma(x), h]. */
        const bool skip = i > 0 && i == net->skip;
        nerf__smm_seg seg[2];
        int ns = 0;
        if (skip) {
            seg[ns++] = rows_of(ws->enc_pos + r0 * Ep, Ep, Ep);
        }
        seg[ns++] = rows_of(x, ldx, skip ? W : l->in);
        nerf__smm(rows, W, seg, ns, j->wt[i], padded(W), params + l->b,
                  NERF__SMM_RELU, y, W);
        x = y;
        ldx = W;
    }
    const nerf__smm_seg top = rows_of(x, W, W);
    if (j->part == NERF__FUSED_DENSITY) {
        /* One column, read straight from the head's density row. */
        const float *row =
            params + net->head.w + (size_t)nerf__network_sigma_col(net) * W;
        nerf__smm(rows, 1, &top, 1, row, 1, NULL, 0, ws->head + r0, 1);
        return;
    }
    const uint32_t HW = nerf__network_head_width(net);
    nerf__smm(rows, HW, &top, 1, j->wt[net->depth], padded(HW),
              params + net->head.b, 0, ws->head + r0 * HW, HW);
}

/* The colour branch of a block, from its head rows. */
static void block_colour(const fjob *j, size_t r0, size_t rows, float *local)
{
    const nerf__network *net = j->net;
    const float *params = j->params;
    nerf__workspace *ws = j->ws;
    const uint32_t HW = nerf__network_head_width(net);
    const uint32_t V = net->view_width, Ed = net->dir_width;
    const uint32_t F = nerf__network_feature_width(net);
    const uint32_t first = net->depth + 1;
    const nerf__smm_seg in0[2] = {rows_of(ws->head + r0 * HW, HW, F),
                                  rows_of(ws->enc_dir + r0 * Ed, Ed, Ed)};
    float *h = view_out(j, local, 0, r0);
    nerf__smm(rows, V, in0, 2, j->wt[first], padded(V),
              params + net->view[0].b, NERF__SMM_RELU, h, V);
    for (uint32_t k = 1; k < net->view_depth; k++) {
        float *hk = view_out(j, local, k, r0);
        const nerf__smm_seg in = rows_of(h, V, V);
        nerf__smm(rows, V, &in, 1, j->wt[first + k], padded(V),
                  params + net->view[k].b, NERF__SMM_RELU, hk, V);
        h = hk;
    }
    /* The rgb bias is added by network.c's sigmoid pass. */
    const nerf__smm_seg in = rows_of(h, V, V);
    nerf__smm(rows, 3, &in, 1, j->wt[first + net->view_depth], padded(3),
              NULL, 0, ws->rgb + r0 * 3, 3);
}

static void forward_block(const fjob *j, size_t r0, size_t rows,
                          float *local)
{
    if (j->part != NERF__FUSED_COLOUR) {
        block_head(j, r0, rows, local);
    }
    const bool colour =
        j->part == NERF__FUSED_ALL || j->part == NERF__FUSED_COLOUR;
    if (colour && j->net->use_viewdirs) {
        block_colour(j, r0, rows, local);
    }
}

static void forward_range(void *ctx, size_t begin, size_t end)
{
    const fjob *j = ctx;
    float slots[2 * SLOT]; /* 64 KB */
    float *local = j->ws->keep ? NULL : slots;
    for (size_t r0 = begin; r0 < end; r0 += NERF__FUSED_ROWS) {
        const size_t rows =
            end - r0 < NERF__FUSED_ROWS ? end - r0 : NERF__FUSED_ROWS;
        forward_block(j, r0, rows, local);
    }
}

void nerf__fused_forward(const nerf__network *net, const float *params,
                         nerf__workspace *ws, size_t n, nerf__fused_part part)
{
    fjob j = {.net = net, .params = params, .ws = ws, .part = part};
    const uint32_t layers = part == NERF__FUSED_DENSITY ? net->depth
                            : part == NERF__FUSED_HEAD  ? net->depth + 1
                                                        : n_layers(net);
    pack(&j, layers);
    nerf__parallel_for(n, (size_t)nerf__network_flops_per_sample(net) /
                              NERF__FLOPS_PER_OP, forward_range, &j);
}

/* ---- backward ------------------------------------------------------------ */

/* ReLU backward in place (y the ReLU's output) and the bias gradient,
 * summed row after row: the same order in every clone. */
NERF__CLONED(relu_mask_sum,
             (size_t rows, uint32_t cols, const float *restrict y, size_t ldy,
              float *restrict d, size_t ldd, float *restrict db),
             (rows, cols, y, ldy, d, ldd, db))
{
    for (size_t r = 0; r < rows; r++) {
        for (uint32_t c = 0; c < cols; c++) {
            float g = y[r * ldy + c] > 0.0f ? d[r * ldd + c] : 0.0f;
            d[r * ldd + c] = g;
            db[c] += g;
        }
    }
}

NERF__CLONED(col_sum,
             (size_t rows, uint32_t cols, const float *restrict d, size_t ldd,
              float *restrict db),
             (rows, cols, d, ldd, db))
{
    for (size_t r = 0; r < rows; r++) {
        for (uint32_t c = 0; c < cols; c++) {
            db[c] += d[r * ldd + c];
        }
    }
}

/* dW += dY^T X over the block's rows, into the chunk's partials. */
static void weight_grad(size_t rows, const float *dy, size_t G, uint32_t out,
                        const float *x, size_t ldx, uint32_t in, float *dw,
                        size_t ldw)
{
    const nerf__smm_seg a = cols_of(dy, G, rows);
    nerf__smm(out, in, &a, 1, x, ldx, NULL, NERF__SMM_ADD, dw, ldw);
}

/* dX = dY W, W a column block of [out, ldw]. */
static void input_grad(size_t rows, const float *dy, size_t G, uint32_t out,
                       const float *w, size_t ldw, uint32_t in, float *dx)
{
    const nerf__smm_seg a = rows_of(dy, G, out);
    nerf__smm(rows, in, &a, 1, w, ldw, NULL, 0, dx, G);
}

/* The sigmoid's backward, d_rgb * rgb (1 - rgb), into rows of G. */
static void sigmoid_grad(const fjob *j, size_t r0, size_t rows, float *dz)
{
    const float *rgb = j->ws->rgb + r0 * 3;
    for (size_t r = 0; r < rows; r++) {
        for (int c = 0; c < 3; c++) {
            const float y = rgb[3 * r + c];
            const float g = j->d_rgb ? j->d_rgb[3 * (r0 + r) + c] : 0.0f;
            dz[r * j->G + c] = g * y * (1.0f - y);
        }
    }
}

/* The density logit's gradient into its head column: set, or added to
 * what the colour branch put there (network.c's sigma_grad_rows). */
static void sigma_grad(const fjob *j, size_t r0, size_t rows, float *d_head)
{
    const nerf__network *net = j->net;
    const nerf__workspace *ws = j->ws;
    const uint32_t HW = nerf__network_head_width(net);
    const uint32_t sc = nerf__network_sigma_col(net);
    const bool add = net->geo_features > 0;
    for (size_t r = 0; r < rows; r++) {
        const size_t i = r0 + r;
        float g = j->d_sigma ? j->d_sigma[i] : 0.0f;
        if (net->exp_density) {
            g *= nerf__exp_density(ws->head[i * HW + sc]);
        }
        if (net->space.kind != NERF__SPACE_WORLD &&
            !nerf__space_contains(&net->space, ws->pos + 3 * i)) {
            g = 0.0f;
        }
        float *at = d_head + r * j->G + sc;
        *at = add ? *at + g : g;
    }
}

/*
 * One block's backward: gradients flow between the block's rows of
 * grad_a and grad_b (stride G, so that blocks never overlap whatever the
 * layer's width); returns which of the two holds the last dX.
 */
static int backward_block(const fjob *j, size_t r0, size_t rows, float *part)
{
    const nerf__network *net = j->net;
    const float *params = j->params;
    nerf__workspace *ws = j->ws;
    const size_t G = j->G;
    float *buf[2] = {ws->grad_a + r0 * G, ws->grad_b + r0 * G};
    int cur = 0;
    /* The partial of parameter index i (as in params) is PARTIAL(i). */
#define PARTIAL(i) (part + ((i) - j->base))
    const uint32_t W = net->width, Ep = net->pos_width;
    const uint32_t HW = nerf__network_head_width(net);

    if (net->use_viewdirs) {
        const uint32_t V = net->view_width, Ed = net->dir_width;
        const uint32_t F = nerf__network_feature_width(net);
        const uint32_t vd = net->view_depth;
        const nerf__linear *rgb = &net->rgb;
        float *dz = buf[0];
        sigmoid_grad(j, r0, rows, dz);
        col_sum(rows, 3, dz, G, PARTIAL(rgb->b));
        weight_grad(rows, dz, G, 3,
                    nerf__view_buffer(net, ws, vd - 1) + r0 * V, V, V,
                    PARTIAL(rgb->w), V);
        input_grad(rows, dz, G, 3, params + rgb->w, V, V, buf[1]);
        cur = 1;
        for (uint32_t k = vd; k-- > 1;) {
            const nerf__linear *v = &net->view[k];
            float *d = buf[cur];
            relu_mask_sum(rows, V, nerf__view_buffer(net, ws, k) + r0 * V, V,
                          d, G, PARTIAL(v->b));
            weight_grad(rows, d, G, V,
                        nerf__view_buffer(net, ws, k - 1) + r0 * V, V, V,
                        PARTIAL(v->w), V);
            input_grad(rows, d, G, V, params + v->w, V, V, buf[1 - cur]);
            cur = 1 - cur;
        }
        const nerf__linear *v0 = &net->view[0];
        float *d = buf[cur];
        relu_mask_sum(rows, V, nerf__view_buffer(net, ws, 0) + r0 * V, V, d,
                      G, PARTIAL(v0->b));
        weight_grad(rows, d, G, V, ws->head + r0 * HW, HW, F, PARTIAL(v0->w),
                    v0->in);
        weight_grad(rows, d, G, V, ws->enc_dir + r0 * Ed, Ed, Ed,
                    PARTIAL(v0->w + F), v0->in);
        /* The gradient goes on only through the head's part. */
        input_grad(rows, d, G, V, params + v0->w, v0->in, F, buf[1 - cur]);
        cur = 1 - cur;
    } else {
        sigmoid_grad(j, r0, rows, buf[0]);
    }
    float *d_head = buf[cur];
    sigma_grad(j, r0, rows, d_head);

    const nerf__linear *head = &net->head;
    col_sum(rows, HW, d_head, G, PARTIAL(head->b));
    weight_grad(rows, d_head, G, HW,
                nerf__trunk_buffer(net, ws, net->depth - 1) + r0 * W, W, W,
                PARTIAL(head->w), W);
    input_grad(rows, d_head, G, HW, params + head->w, W, W, buf[1 - cur]);
    cur = 1 - cur;

    for (uint32_t i = net->depth; i-- > 0;) {
        const nerf__linear *l = &net->trunk[i];
        float *d = buf[cur];
        relu_mask_sum(rows, W, nerf__trunk_buffer(net, ws, i) + r0 * W, W, d,
                      G, PARTIAL(l->b));
        if (i == 0) {
            weight_grad(rows, d, G, W, ws->enc_pos + r0 * Ep, Ep, Ep,
                        PARTIAL(l->w), l->in);
            if (nerf__encoding_params(&net->pos_enc)) {
                input_grad(rows, d, G, W, params + l->w, l->in, Ep,
                           buf[1 - cur]);
                cur = 1 - cur;
            }
            break;
        }
        /* At the skip the input was [gamma(x), h]: the gradient goes on
         * only through h. */
        const size_t col = i == net->skip ? Ep : 0;
        if (col) {
            weight_grad(rows, d, G, W, ws->enc_pos + r0 * Ep, Ep, Ep,
                        PARTIAL(l->w), l->in);
        }
        weight_grad(rows, d, G, W,
                    nerf__trunk_buffer(net, ws, i - 1) + r0 * W, W, W,
                    PARTIAL(l->w + col), l->in);
        input_grad(rows, d, G, W, params + l->w + col, l->in, W,
                   buf[1 - cur]);
        cur = 1 - cur;
    }
    return cur;
#undef PARTIAL
}

/* Which buffer backward_block() leaves the last dX in: one swap per
 * input gradient it computes. */
static int last_buffer(const nerf__network *net)
{
    uint32_t swaps = 1 + (net->depth - 1); /* the head, trunk layers > 0 */
    if (net->use_viewdirs) {
        swaps += 1 + (net->view_depth - 1) + 1; /* rgb, view k > 0, view 0 */
    }
    if (nerf__encoding_params(&net->pos_enc)) {
        swaps++;
    }
    return (int)(swaps % 2);
}

static void backward_chunk(void *ctx, size_t c)
{
    const fjob *j = ctx;
    float *part = j->partials + c * j->stride;
    memset(part, 0, j->count * sizeof(float));
    const size_t begin = c * NERF__FUSED_CHUNK;
    const size_t end =
        j->n - begin < NERF__FUSED_CHUNK ? j->n : begin + NERF__FUSED_CHUNK;
    for (size_t r0 = begin; r0 < end; r0 += NERF__FUSED_ROWS) {
        const size_t rows =
            end - r0 < NERF__FUSED_ROWS ? end - r0 : NERF__FUSED_ROWS;
        int last = backward_block(j, r0, rows, part);
        assert(last == j->last_buffer);
        (void)last;
    }
}

#define SPAN 256

/* grads += the chunks' partials, summed in chunk order. */
NERF__CLONED(reduce_range, (void *ctx, size_t begin, size_t end),
             (ctx, begin, end))
{
    const fjob *j = ctx;
    const size_t chunks = n_chunks(j->n);
    float s[SPAN];
    for (size_t i0 = begin * SPAN; i0 < end * SPAN && i0 < j->count;
         i0 += SPAN) {
        const size_t m = j->count - i0 < SPAN ? j->count - i0 : SPAN;
        for (size_t i = 0; i < m; i++) {
            s[i] = j->partials[i0 + i];
        }
        for (size_t c = 1; c < chunks; c++) {
            const float *p = j->partials + c * j->stride + i0;
            for (size_t i = 0; i < m; i++) {
                s[i] += p[i];
            }
        }
        float *g = j->grads + j->base + i0;
        for (size_t i = 0; i < m; i++) {
            g[i] += s[i];
        }
    }
}

const float *nerf__fused_backward(const nerf__network *net,
                                  const float *params, float *grads,
                                  nerf__workspace *ws, const float *d_rgb,
                                  const float *d_sigma, size_t *ld)
{
    const size_t n = ws->n;
    fjob j = {.net = net, .params = params, .ws = ws, .d_rgb = d_rgb,
              .d_sigma = d_sigma, .grads = grads, .n = n,
              .G = nerf__network_grad_width(net),
              .partials = ws->fused + packed_floats(net),
              .count = layer_params(net), .base = net->trunk[0].w,
              .last_buffer = last_buffer(net)};
    j.stride = padded((uint32_t)j.count);
    if (n > 0) {
        const size_t flops = (size_t)nerf__network_flops_per_sample(net);
        nerf__parallel_blocks(n_chunks(n), 2 * flops * NERF__FUSED_CHUNK /
                                               NERF__FLOPS_PER_OP,
                              backward_chunk, &j);
        nerf__parallel_for((j.count + SPAN - 1) / SPAN, SPAN * n_chunks(n),
                           reduce_range, &j);
    }
    if (!nerf__encoding_params(&net->pos_enc)) {
        return NULL;
    }
    *ld = j.G;
    return j.last_buffer ? ws->grad_b : ws->grad_a;
}
