/*
 * NumPy .npy arrays (format versions 1.0 and 2.0) parsed from memory.  The
 * header is read strictly: exactly the keys 'descr', 'fortran_order' and
 * 'shape', in any order, written as NumPy writes them; anything else is
 * refused rather than guessed at.  The data is not copied and not assumed
 * to be aligned: read it with nerf__npy_to_float/_double.
 */
#ifndef NERF_IO_NPY_H
#define NERF_IO_NPY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "env.h"

#define NERF__NPY_MAX_DIMS 4

typedef enum nerf__npy_dtype {
    NERF__NPY_F4 = 1, /* '<f4' */
    NERF__NPY_F8 = 2  /* '<f8' */
} nerf__npy_dtype;

typedef struct nerf__npy {
    nerf__npy_dtype dtype;
    size_t elem_size;   /* bytes per element */
    bool fortran_order; /* true: column-major data */
    uint32_t ndim;      /* 0 for a scalar */
    size_t shape[NERF__NPY_MAX_DIMS];
    size_t count;       /* product of shape (1 for a scalar) */
    const unsigned char *data; /* inside the parsed buffer */
    size_t data_size;   /* count * elem_size */
} nerf__npy;

/*
 * Parse the .npy image buf[0, size).  The buffer must hold exactly the
 * header and count * elem_size bytes of data.  On failure returns
 * NERF_EFORMAT with a message that does not name the file (callers add
 * it with nerf__error_prefix).
 */
int nerf__npy_parse(const void *buf, size_t size, nerf__npy *out);

/* Convert the first n elements (n <= count), in storage order, into dst. */
void nerf__npy_to_float(const nerf__npy *a, float *dst, size_t n);
void nerf__npy_to_double(const nerf__npy *a, double *dst, size_t n);

/* The dtype as NumPy spells it ("<f4"). */
const char *nerf__npy_dtype_name(nerf__npy_dtype dtype);

/*
 * Format a shape as Python prints it: "()", "(3,)", "(64, 63)".  Always
 * NUL-terminates (truncating if buf is short).
 */
void nerf__npy_format_shape(const size_t *shape, uint32_t ndim, char *buf,
                            size_t size);

/*
 * Write rows x cols doubles (row-major) to path as a version 1.0 .npy
 * array, '<f8' in C order, with the header NumPy itself writes, through
 * nerf__file_write_atomic.  Returns NERF_OK; NERF_EIO (named path);
 * NERF_ENOMEM.
 */
int nerf__npy_write_f8(const nerf__env *env, const char *path,
                       const double *data, size_t rows, size_t cols);

/*
 * Write the float32 array data (C order, shape[0..ndim)) to path as a
 * version 1.0 .npy, '<f4', through nerf__file_write_atomic.  Returns
 * NERF_OK; NERF_EINVAL (ndim > NERF__NPY_MAX_DIMS); NERF_EIO (named
 * path); NERF_ENOMEM.
 */
int nerf__npy_write_f4(const nerf__env *env, const char *path,
                       const float *data, const size_t *shape, uint32_t ndim);

#endif
