/*
 * The machine nerf-bench runs on: a monotonic clock, the load average,
 * this process's resident memory, and the BLAS build and its thread
 * count (through OpenBLAS's own calls where meson found them).
 */
#include <cblas.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "nerf-bench.h"

double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The 1, 5 and 15 minute load averages, or -1s off Linux: the figures are
 * only comparable between runs on an otherwise idle machine. */
void load_average(double out[3])
{
    out[0] = out[1] = out[2] = -1.0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf %lf %lf", &out[0], &out[1], &out[2]) != 3) {
            out[0] = out[1] = out[2] = -1.0;
        }
        fclose(f);
    }
}

/* A Vm* figure of this process ("VmHWM", "VmRSS") in MB, or -1 where
 * /proc is missing. */
double vm_mb(const char *field)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (f == NULL) {
        return -1.0;
    }
    char line[256];
    double mb = -1.0;
    size_t len = strlen(field);
    while (fgets(line, sizeof line, f)) {
        long kb;
        if (strncmp(line, field, len) == 0 && line[len] == ':' &&
            sscanf(line + len + 1, "%ld", &kb) == 1) {
            mb = kb / 1024.0;
            break;
        }
    }
    fclose(f);
    return mb;
}

int blas_threads(void)
{
#ifdef HAVE_OPENBLAS_GET_NUM_THREADS
    return openblas_get_num_threads();
#else
    return -1;
#endif
}

void set_blas_threads(int n)
{
#ifdef HAVE_OPENBLAS_SET_NUM_THREADS
    if (n > 0) {
        openblas_set_num_threads(n);
    }
#else
    (void)n;
#endif
}

const char *blas_config(void)
{
#ifdef HAVE_OPENBLAS_GET_CONFIG
    return openblas_get_config();
#else
    return NULL;
#endif
}

const char *blas_corename(void)
{
#ifdef HAVE_OPENBLAS_GET_CORENAME
    return openblas_get_corename();
#else
    return NULL;
#endif
}
