/*
 * Input encodings behind one interface.  The network holds an encoding for
 * positions and one for view directions and runs them through their ops
 * (width, parameters, initialisation, forward, backward) without knowing
 * which kind it has; a new encoding adds a constructor and an ops table
 * here and nothing in the network changes.
 *
 * The kinds: the frequency (positional) encoding of the paper, in both its
 * forms (frequency.c); the multiresolution hash grid of Mueller et al.,
 * whose table is trained (hashgrid.h, hashgrid_encoding.c); spherical
 * harmonics for directions (sh.h).
 *
 * An encoding with parameters owns a slice of the model's flat parameter
 * array: the network lays it out (nerf__encoding_params floats), the ops
 * read it in forward and add to its gradient in backward.  Forward and
 * backward run over the thread pool (parallel.h) and give the same result
 * for every thread count.
 */
#ifndef NERF_ENCODING_H
#define NERF_ENCODING_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "hashgrid.h"

/* The paper's positional encoding, gamma(p), of `dims` coordinates. */
typedef struct nerf__frequency {
    uint32_t dims;        /* input coordinates per sample (3) */
    uint32_t frequencies; /* L */
    bool include_input;   /* prepend the raw coordinates */
    bool scale_pi;        /* frequencies 2^k pi rather than 2^k */
} nerf__frequency;

typedef struct nerf__encoding nerf__encoding;

typedef struct nerf__encoding_ops {
    /* Floats per sample that forward writes. */
    uint32_t (*width)(const nerf__encoding *e);
    /* Trainable floats; 0 for an encoding without parameters. */
    size_t (*params)(const nerf__encoding *e);
    /* Fill the parameters from the counter-based streams (seed,
     * stream_base + k); NULL without parameters. */
    void (*init)(const nerf__encoding *e, float *params, uint64_t seed,
                 uint64_t stream_base);
    /* Encode n samples (rows of 3 floats) into rows of out, stride
     * out_stride >= width (the gap is not touched).  params is the
     * encoding's slice (NULL without parameters). */
    void (*forward)(const nerf__encoding *e, const float *params, size_t n,
                    const float *in, float *out, size_t out_stride);
    /* Add dL/dparams for the same n inputs, given dL/dout (rows of
     * d_stride), into grad (the slice's gradient); NULL without
     * parameters. */
    void (*backward)(const nerf__encoding *e, size_t n, const float *in,
                     const float *d_out, size_t d_stride, float *grad);
} nerf__encoding_ops;

struct nerf__encoding {
    uint32_t kind; /* nerf_encoding_kind, for messages and reports */
    const nerf__encoding_ops *ops;
    union {
        nerf__frequency freq; /* NERF_ENCODING_FREQUENCY */
        nerf__hashgrid hash;  /* NERF_ENCODING_HASHGRID */
        uint32_t sh_degree;   /* NERF_ENCODING_SPHERICAL_HARMONICS */
    } u;
};

/* Constructors: the settings, checked by the caller (the model). */
void nerf__encoding_frequency(nerf__encoding *e, uint32_t frequencies,
                              bool include_input, bool scale_pi);
void nerf__encoding_sh(nerf__encoding *e, uint32_t degree);
/* hg is laid out already (nerf__hashgrid_layout). */
void nerf__encoding_hashgrid(nerf__encoding *e, const nerf__hashgrid *hg);

static inline uint32_t nerf__encoding_width(const nerf__encoding *e)
{
    return e->ops->width(e);
}

static inline size_t nerf__encoding_params(const nerf__encoding *e)
{
    return e->ops->params(e);
}

static inline void nerf__encoding_init(const nerf__encoding *e, float *params,
                                       uint64_t seed, uint64_t stream_base)
{
    if (e->ops->init) {
        e->ops->init(e, params, seed, stream_base);
    }
}

static inline void nerf__encoding_forward(const nerf__encoding *e,
                                          const float *params, size_t n,
                                          const float *in, float *out,
                                          size_t out_stride)
{
    e->ops->forward(e, params, n, in, out, out_stride);
}

static inline void nerf__encoding_backward(const nerf__encoding *e, size_t n,
                                           const float *in,
                                           const float *d_out,
                                           size_t d_stride, float *grad)
{
    if (e->ops->backward) {
        e->ops->backward(e, n, in, d_out, d_stride, grad);
    }
}

/*
 * Ops without parameters are built from a function that encodes rows on
 * the calling thread: this runs it over the thread pool by ranges of
 * samples (grain: rough operations per sample, for the pool's decision to
 * wake its threads).
 */
typedef void (*nerf__encode_rows_fn)(const nerf__encoding *e, size_t n,
                                     const float *in, float *out,
                                     size_t out_stride);
void nerf__encoding_by_rows(const nerf__encoding *e, nerf__encode_rows_fn fn,
                            size_t grain, size_t n, const float *in,
                            float *out, size_t out_stride);
size_t nerf__encoding_no_params(const nerf__encoding *e);

/*
 * The frequency encoding of n samples of f->dims floats each (rows of in,
 * stride in_stride) into rows of out (stride out_stride), on the calling
 * thread.  The order is the reference implementation's: the raw input if
 * included, then for each frequency k the dims sines followed by the dims
 * cosines.
 */
uint32_t nerf__frequency_width(const nerf__frequency *f);
void nerf__frequency_encode(const nerf__frequency *f, size_t n,
                            const float *in, size_t in_stride, float *out,
                            size_t out_stride);

#endif
