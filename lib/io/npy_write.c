/* .npy output: the one array LLFF's poses_bounds.npy needs. */
#include <stdio.h>
#include <string.h>

#include "byteorder.h"
#include "error.h"
#include "file_io.h"
#include "npy.h"

int nerf__npy_write_f8(const nerf__env *env, const char *path,
                       const double *data, size_t rows, size_t cols)
{
    /*
     * NumPy pads the header with spaces and ends it with a newline so that
     * the data starts on a 64-byte boundary; readers (ours included) may
     * rely on that alignment, so write it the same way.
     */
    enum { PREFIX = 10, ALIGN = 64 };
    char dict[128];
    int len = snprintf(dict, sizeof dict, "{'descr': '<f8', 'fortran_order': "
                       "False, 'shape': (%zu, %zu), }", rows, cols);
    if (len < 0 || (size_t)len + 1 > sizeof dict) {
        return nerf__error(NERF_EINVAL, "%s: npy shape too large", path);
    }
    size_t total = ((size_t)PREFIX + (size_t)len + 1 + ALIGN - 1) / ALIGN *
                   ALIGN;
    unsigned char head[256];
    memcpy(head, "\x93NUMPY\x01\x00", 8);
    nerf__store_le16(head + 8, (uint16_t)(total - PREFIX));
    memset(head + PREFIX, ' ', total - PREFIX);
    memcpy(head + PREFIX, dict, (size_t)len);
    head[total - 1] = '\n';
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
