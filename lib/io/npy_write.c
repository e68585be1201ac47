/* .npy output: LLFF's poses_bounds.npy, and float32 arrays of any shape
 * (depth maps, point data). */
#include <stdio.h>
#include <string.h>

#include "byteorder.h"
#include "error.h"
#include "file_io.h"
#include "npy.h"

/*
 * The header NumPy writes for a C-order array of dtype descr: returns its
 * length in head (a multiple of 64), or 0 after setting the error.
 */
static size_t npy_header(unsigned char head[512], const char *path,
                         const char *descr, const size_t *shape,
                         uint32_t ndim)
{
    /*
     * NumPy pads the header with spaces and ends it with a newline so that
     * the data starts on a 64-byte boundary; readers (ours included) may
     * rely on that alignment, so write it the same way.
     */
    enum { PREFIX = 10, ALIGN = 64 };
    char shape_text[NERF__NPY_MAX_DIMS * 24 + 4];
    nerf__npy_format_shape(shape, ndim, shape_text, sizeof shape_text);
    char dict[256];
    int len = snprintf(dict, sizeof dict, "{'descr': '%s', 'fortran_order': "
                       "False, 'shape': %s, }", descr, shape_text);
    if (len < 0 || (size_t)len + 1 > sizeof dict) {
        nerf__error(NERF_EINVAL, "%s: npy shape too large", path);
        return 0;
    }
    size_t total = ((size_t)PREFIX + (size_t)len + 1 + ALIGN - 1) / ALIGN *
                   ALIGN;
    memcpy(head, "\x93NUMPY\x01\x00", 8);
    nerf__store_le16(head + 8, (uint16_t)(total - PREFIX));
    memset(head + PREFIX, ' ', total - PREFIX);
    memcpy(head + PREFIX, dict, (size_t)len);
    head[total - 1] = '\n';
    return total;
}

int nerf__npy_write_f8(const nerf__env *env, const char *path,
                       const double *data, size_t rows, size_t cols)
{
    unsigned char head[512];
    const size_t shape[2] = {rows, cols};
    size_t total = npy_header(head, path, "<f8", shape, 2);
    if (total == 0) {
        return NERF_EINVAL;
    }
    size_t n = rows * cols;
    unsigned char *body = nerf__alloc(env, n * 8 > 0 ? n * 8 : 1);
    if (body == NULL) {
        return NERF_ENOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        nerf__store_lef64(body + 8 * i, data[i]);
    }
    nerf__span parts[2] = {{head, total}, {body, n * 8}};
    int rc = nerf__file_write_atomic(env, path, parts, 2);
    nerf__free(env, body);
    return rc;
}

int nerf__npy_write_f4(const nerf__env *env, const char *path,
                       const float *data, const size_t *shape, uint32_t ndim)
{
    unsigned char head[512];
    size_t total = npy_header(head, path, "<f4", shape, ndim);
    if (total == 0) {
        return NERF_EINVAL;
    }
    size_t n = 1;
    for (uint32_t i = 0; i < ndim; i++) {
        size_t bytes;
        if (nerf__mul_size(n, shape[i], &n) != 0 ||
            nerf__mul_size(n, 4, &bytes) != 0) {
            return nerf__error(NERF_EINVAL, "%s: npy shape too large", path);
        }
    }
    unsigned char *body = nerf__alloc(env, n * 4 > 0 ? n * 4 : 1);
    if (body == NULL) {
        return NERF_ENOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        nerf__store_lef32(body + 4 * i, data[i]);
    }
    nerf__span parts[2] = {{head, total}, {body, n * 4}};
    int rc = nerf__file_write_atomic(env, path, parts, 2);
    nerf__free(env, body);
    return rc;
}

NERF_API int nerf_npy_write_float(const char *path, const float *data,
                                  const size_t *shape, uint32_t ndim)
{
    static const char fn[] = "nerf_npy_write_float";
    if (path == NULL || shape == NULL) {
        return nerf__error(NERF_EINVAL, "%s: path and shape must not be "
                           "NULL", fn);
    }
    if (ndim < 1 || ndim > NERF__NPY_MAX_DIMS) {
        return nerf__error(NERF_EINVAL, "%s: %s: ndim must be 1..%d, not %u",
                           fn, path, NERF__NPY_MAX_DIMS, ndim);
    }
    size_t n = 1;
    for (uint32_t i = 0; i < ndim; i++) {
        n *= shape[i];
    }
    if (data == NULL && n > 0) {
        return nerf__error(NERF_EINVAL, "%s: %s: data is NULL", fn, path);
    }
    nerf__env env;
    nerf__env_default(&env);
    return nerf__npy_write_f4(&env, path, data, shape, ndim);
}
