#include "progress.h"

#include <string.h>
#include <time.h>

double nerf__seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int nerf__progress_report(nerf_progress_cb cb, void *user, uint32_t kind,
                          uint64_t done, uint64_t total, double start)
{
    if (cb == NULL) {
        return 0;
    }
    nerf_progress p;
    memset(&p, 0, sizeof p);
    p.struct_size = sizeof p;
    p.kind = kind;
    p.done = done;
    p.total = total;
    p.elapsed = nerf__seconds() - start;
    return cb(&p, user);
}
