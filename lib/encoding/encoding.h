/*
 * Input encodings.  The network sees only what an encoding produces, so a
 * new kind (the hash grid of a later issue) slots in here without touching
 * the MLP: it adds a kind, its width and its forward (and, for encodings
 * with trainable tables, a backward).
 */
#ifndef NERF_ENCODING_H
#define NERF_ENCODING_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct nerf__encoding {
    uint32_t kind;        /* nerf_encoding_kind */
    uint32_t dims;        /* input coordinates per sample (3) */
    uint32_t frequencies; /* L */
    bool include_input;   /* prepend the raw coordinates */
    bool scale_pi;        /* frequencies 2^k pi rather than 2^k */
} nerf__encoding;

/* Floats per sample that the encoding writes. */
uint32_t nerf__encoding_width(const nerf__encoding *enc);

/*
 * Encode n samples of enc->dims floats each (rows of in, stride in_stride
 * floats) into rows of out (stride out_stride floats).  The order is the
 * reference implementation's: the raw input if included, then for each
 * frequency k the dims sines followed by the dims cosines.
 */
void nerf__encoding_forward(const nerf__encoding *enc, size_t n,
                            const float *in, size_t in_stride, float *out,
                            size_t out_stride);

#endif
