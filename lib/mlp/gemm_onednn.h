/*
 * The oneDNN backend of the layer products (built when meson finds oneDNN:
 * -Dbf16).  A model created with NERF_MATMUL_BF16 or
 * NERF_MATMUL_FP32_ONEDNN owns one nerf__onednn, which holds the oneDNN
 * primitives its products have needed, one per shape, and for bf16 a
 * bfloat16 copy of its layer weights.
 *
 * Semantics, bf16: every product rounds both operands to bfloat16 (round
 * to nearest even) and accumulates in fp32 into an fp32 result; the
 * master weights, the gradients and the optimiser stay fp32.  The weight
 * copy is refreshed on the first product after
 * nerf__onednn_weights_changed(), which the model calls whenever it
 * writes its parameters (an optimiser step, a load, an import): never per
 * product.
 *
 * Semantics, fp32: the products of the cblas path, with the bias and ReLU
 * fused into them, computed by oneDNN's own kernels; operands are read in
 * place.  Results differ from cblas's by the order of the sums only.
 *
 * Threads: oneDNN always runs on the calling thread (its OpenMP thread
 * count is set to 1 around each call and restored); products are cut into
 * row blocks over libnerf's workers (common/parallel.h) as gemm.c does
 * for a one-thread OpenBLAS.  So neither OpenMP's threads nor
 * OMP_NUM_THREADS ever compete with libnerf's pool or with renderers'
 * workers.  A row of a forward or input-gradient product is computed the
 * same way whichever block it falls in, so those results do not depend on
 * the thread count; a weight gradient is cut by the thread count and is
 * deterministic for a given one.
 *
 * Primitives are shared by every thread that uses the model (they run
 * with the caller's scratchpad), so a model may still be queried from
 * several threads at once.
 */
#ifndef NERF_MLP_GEMM_ONEDNN_H
#define NERF_MLP_GEMM_ONEDNN_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"
#include "layer.h"
#include "nerf_config.h"

typedef struct nerf__onednn nerf__onednn;
typedef struct nerf__onednn_scratch nerf__onednn_scratch;

/* A range of the model's parameter array that products read as weights. */
typedef struct nerf__onednn_region {
    size_t offset, count;
} nerf__onednn_region;

#define NERF__ONEDNN_MAX_REGIONS 2

#if NERF_HAVE_BF16

/*
 * 1 if models of nerf_matmul `matmul` (NERF_MATMUL_BF16 or
 * NERF_MATMUL_FP32_ONEDNN) can run here, else 0 with the reason in *why
 * (a static string).  bf16 needs oneDNN to report an ISA with AVX512-BF16
 * or better and to create an optimised bf16 matmul for it; fp32 needs an
 * optimised fp32 matmul.  The answers are computed once per process.
 * Thread-safe.
 */
int nerf__onednn_supported(uint32_t matmul, const char **why);

/*
 * A backend of nerf_matmul `matmul` for weights in params[regions].
 * params must stay where it is for the backend's life.  Fails with
 * NERF_EINVAL when that kind is not supported here.
 */
int nerf__onednn_create(const nerf__env *env, uint32_t matmul,
                        const float *params,
                        const nerf__onednn_region *regions, int n_regions,
                        nerf__onednn **out);
void nerf__onednn_destroy(nerf__onednn *b);

/* 1 if b rounds its operands to bf16 (layer.h's kept and dyb apply). */
int nerf__onednn_rounds(const nerf__onednn *b);

/* The parameters were written: the next product refreshes the copy. */
void nerf__onednn_weights_changed(nerf__onednn *b);

/* oneDNN primitives created so far (for benchmarks). */
size_t nerf__onednn_primitives(nerf__onednn *b);

/*
 * 1 while every primitive b has created is one of oneDNN's brgemm
 * kernels, which compute a row the same way whatever rows share its
 * product (the pieces' promise above rests on it); 0 once one is not.
 * Primitives are made as shapes first come, so this speaks of the products
 * run so far: ask after the work whose results it vouches for.
 */
int nerf__onednn_rows_alone(nerf__onednn *b);

/* The layer products (layer.h) for a context whose backend is set. */
int nerf__onednn_forward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                         const nerf__layer_part *parts, int n_parts,
                         const float *w, size_t ldw, const float *b, int relu,
                         float *y, size_t ldy, uint16_t *kept);
int nerf__onednn_backward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                          const float *dy, size_t lddy, const uint16_t *dyb,
                          const nerf__layer_part *parts, int n_parts,
                          const uint16_t *kept, const float *w, size_t ldw,
                          float *dw, int dx_part, float *dx, size_t lddx);

void nerf__onednn_scratch_free(nerf__onednn_scratch *s);

/* Round n floats to bfloat16, nearest even (NaN stays NaN). */
void nerf__bf16_round(const float *x, size_t n, uint16_t *out);

#else /* !NERF_HAVE_BF16: the same calls, for a build without oneDNN */

static inline int nerf__onednn_supported(uint32_t matmul, const char **why)
{
    (void)matmul;
    if (why) {
        *why = "this libnerf was built without oneDNN (-Dbf16)";
    }
    return 0;
}

static inline int nerf__onednn_create(const nerf__env *env, uint32_t matmul,
                                      const float *params,
                                      const nerf__onednn_region *regions,
                                      int n_regions, nerf__onednn **out)
{
    (void)env;
    (void)matmul;
    (void)params;
    (void)regions;
    (void)n_regions;
    *out = NULL;
    return nerf__error(NERF_EINVAL, "oneDNN products: this libnerf was "
                       "built without oneDNN (-Dbf16)");
}

static inline void nerf__onednn_destroy(nerf__onednn *b)
{
    (void)b;
}

static inline int nerf__onednn_rounds(const nerf__onednn *b)
{
    (void)b;
    return 0;
}

static inline void nerf__onednn_weights_changed(nerf__onednn *b)
{
    (void)b;
}

static inline size_t nerf__onednn_primitives(nerf__onednn *b)
{
    (void)b;
    return 0;
}

static inline int nerf__onednn_rows_alone(nerf__onednn *b)
{
    (void)b;
    return 1;
}

/* Unreachable: no context can name a backend that cannot be created. */
static inline int nerf__onednn_forward(const nerf__layer_ctx *c, size_t n,
                                       uint32_t out,
                                       const nerf__layer_part *parts,
                                       int n_parts, const float *w,
                                       size_t ldw, const float *b, int relu,
                                       float *y, size_t ldy, uint16_t *kept)
{
    (void)c, (void)n, (void)out, (void)parts, (void)n_parts, (void)w;
    (void)ldw, (void)b, (void)relu, (void)y, (void)ldy, (void)kept;
    return nerf__error(NERF_ERROR, "oneDNN products: not built");
}

static inline int nerf__onednn_backward(const nerf__layer_ctx *c, size_t n,
                                        uint32_t out, const float *dy,
                                        size_t lddy, const uint16_t *dyb,
                                        const nerf__layer_part *parts,
                                        int n_parts, const uint16_t *kept,
                                        const float *w, size_t ldw, float *dw,
                                        int dx_part, float *dx, size_t lddx)
{
    (void)c, (void)n, (void)out, (void)dy, (void)lddy, (void)dyb;
    (void)parts, (void)n_parts, (void)kept, (void)w, (void)ldw, (void)dw;
    (void)dx_part, (void)dx, (void)lddx;
    return nerf__error(NERF_ERROR, "oneDNN products: not built");
}

static inline void nerf__onednn_scratch_free(nerf__onednn_scratch *s)
{
    (void)s;
}

#endif

#endif
