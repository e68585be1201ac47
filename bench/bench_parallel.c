/*
 * bench_parallel: what handing a loop to the thread pool costs against
 * running it on the calling thread, for loops of growing size.  The
 * pool's split threshold (MIN_WORK_PER_PART in lib/common/parallel.c)
 * should sit near the size where the two meet.  Prints figures; asserts
 * nothing.
 *
 *   bench_parallel [--calls N]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nerf_internal.h"

/* Items per loop, as in the renderer's blocks (64 rays). */
#define ITEMS 64
/* The pool sees each item as this many operations, so that it always
 * splits: the bench measures the split itself, not the threshold. */
#define FORCE_SPLIT ((size_t)1 << 24)

typedef struct job {
    size_t adds; /* dependent additions per item */
    float out[ITEMS];
} job;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void items(void *ctx, size_t begin, size_t end)
{
    job *j = ctx;
    for (size_t i = begin; i < end; i++) {
        float s = (float)i;
        for (size_t k = 0; k < j->adds; k++) {
            s = s * 0.999f + 1.0f; /* a chain the compiler cannot fold */
        }
        j->out[i] = s;
    }
}

static double per_call(job *j, int calls, int split)
{
    double t0 = now();
    for (int c = 0; c < calls; c++) {
        if (split) {
            nerf__parallel_for(ITEMS, FORCE_SPLIT, items, j);
        } else {
            items(j, 0, ITEMS);
        }
    }
    return (now() - t0) / calls;
}

int main(int argc, char **argv)
{
    int calls = 4000;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--calls") == 0 && i + 1 < argc) {
            calls = atoi(argv[++i]);
        } else {
            fprintf(stderr, "usage: bench_parallel [--calls N]\n");
            return 2;
        }
    }
    if (calls < 1) {
        calls = 1;
    }
    printf("thread pool of %u threads; %d calls a size, %d items a call\n",
           nerf__parallel_threads(), calls, ITEMS);
    /* The pool's unit, a simple operation, is about a quarter of a
     * nanosecond; the first column puts each loop's time in that unit. */
    printf("%14s %12s %12s %8s\n", "operations", "inline (us)",
           "split (us)", "gain");
    job j;
    memset(&j, 0, sizeof j);
    for (size_t adds = 1; adds <= ((size_t)1 << 14); adds *= 4) {
        j.adds = adds;
        per_call(&j, calls / 10 + 1, 1); /* wake the workers first */
        double in = per_call(&j, calls, 0);
        double sp = per_call(&j, calls, 1);
        printf("%14.0f %12.2f %12.2f %7.2fx\n", in * 4e9, in * 1e6, sp * 1e6,
               in / sp);
        if (in * calls > 20.0) {
            break; /* the large sizes say nothing new */
        }
    }
    return 0;
}
