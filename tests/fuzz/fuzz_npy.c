/*
 * libFuzzer target for the .npy parser: any buffer must parse or fail
 * cleanly, and a buffer that parses must be safe to read in full.
 */
#include <stdint.h>
#include <stdlib.h>

#include "npy.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    nerf__npy a;
    if (nerf__npy_parse(data, size, &a) != 0) {
        return 0;
    }
    /* count * elem_size equals the bytes after the header, so the
     * conversions below touch exactly the data the parser vouched for. */
    float *f = malloc((a.count ? a.count : 1) * sizeof *f);
    double *d = malloc((a.count ? a.count : 1) * sizeof *d);
    if (f && d) {
        nerf__npy_to_float(&a, f, a.count);
        nerf__npy_to_double(&a, d, a.count);
    }
    free(f);
    free(d);
    char shape[64];
    nerf__npy_format_shape(a.shape, a.ndim, shape, sizeof shape);
    return 0;
}
