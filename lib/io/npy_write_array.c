/* .npy output of float32 arrays of any shape (density grids). */
#include <stdio.h>
#include <string.h>

#include "byteorder.h"
#include "error.h"
#include "file_io.h"
#include "npy.h"

int nerf__npy_write_f4(const nerf__env *env, const char *path,
                       const float *data, const size_t *shape, uint32_t ndim)
{
    enum { PREFIX = 10, ALIGN = 64 };
    if (ndim > NERF__NPY_MAX_DIMS) {
        return nerf__error(NERF_EINVAL, "%s: npy arrays of %u dimensions "
                           "are not supported", path, (unsigned)ndim);
    }
    char shape_text[96];
    nerf__npy_format_shape(shape, ndim, shape_text, sizeof shape_text);
    size_t n = 1;
    for (uint32_t i = 0; i < ndim; i++) {
        n *= shape[i];
    }
    char dict[160];
    int len = snprintf(dict, sizeof dict, "{'descr': '<f4', 'fortran_order': "
                       "False, 'shape': %s, }", shape_text);
    if (len < 0 || (size_t)len + 1 > sizeof dict) {
        return nerf__error(NERF_EINVAL, "%s: npy shape too large", path);
    }
    /* Padded with spaces to a 64-byte boundary and ended by a newline, as
     * NumPy writes it (see npy_write.c). */
    size_t total = ((size_t)PREFIX + (size_t)len + 1 + ALIGN - 1) / ALIGN *
                   ALIGN;
    unsigned char head[256];
    memcpy(head, "\x93NUMPY\x01\x00", 8);
    nerf__store_le16(head + 8, (uint16_t)(total - PREFIX));
    memset(head + PREFIX, ' ', total - PREFIX);
    memcpy(head + PREFIX, dict, (size_t)len);
    head[total - 1] = '\n';
    nerf__span parts[2] = {{head, total}, {data, n * 4}};
    unsigned char *body = NULL;
    const uint16_t probe = 1;
    unsigned char first;
    memcpy(&first, &probe, 1);
    if (first != 1) {
        /* A big-endian host: the file is little-endian. */
        body = nerf__alloc(env, n * 4 + 1);
        if (body == NULL) {
            return NERF_ENOMEM;
        }
        for (size_t i = 0; i < n; i++) {
            nerf__store_lef32(body + 4 * i, data[i]);
        }
        parts[1].data = body;
    }
    int rc = nerf__file_write_atomic(env, path, parts, 2);
    nerf__free(env, body);
    return rc;
}
