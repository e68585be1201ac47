/* What the encodings share: running a row encoder over the thread pool. */
#include "encoding.h"

#include "parallel.h"

typedef struct rows_job {
    const nerf__encoding *e;
    nerf__encode_rows_fn fn;
    const float *in;
    float *out;
    size_t out_stride;
} rows_job;

static void rows(void *ctx, size_t begin, size_t end)
{
    const rows_job *j = ctx;
    j->fn(j->e, end - begin, j->in + 3 * begin, j->out + begin * j->out_stride,
          j->out_stride);
}

void nerf__encoding_by_rows(const nerf__encoding *e, nerf__encode_rows_fn fn,
                            size_t grain, size_t n, const float *in,
                            float *out, size_t out_stride)
{
    rows_job j = {e, fn, in, out, out_stride};
    nerf__parallel_for(n, grain, rows, &j);
}

size_t nerf__encoding_no_params(const nerf__encoding *e)
{
    (void)e;
    return 0;
}
