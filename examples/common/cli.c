#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <nerf.h>

int cli_uint(const char *text, uint64_t min, uint64_t max, uint64_t *out)
{
    if (text == NULL || *text < '0' || *text > '9') {
        return -1;
    }
    char *end;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 10);
    if (errno != 0 || *end != '\0' || v < min || v > max) {
        return -1;
    }
    *out = v;
    return 0;
}

int cli_double(const char *text, double *out)
{
    if (text == NULL || *text == '\0') {
        return -1;
    }
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (errno != 0 || *end != '\0' || !isfinite(v)) {
        return -1;
    }
    *out = v;
    return 0;
}

void cli_report(const char *program, int status)
{
    fprintf(stderr, "%s: %s: %s\n", program, nerf_status_string(status),
            nerf_last_error());
}

void cli_log(int level, const char *msg, void *user)
{
    const char *program = user;
    if (level <= NERF_LOG_INFO) {
        fprintf(stderr, "%s: %s\n", program ? program : "libnerf", msg);
    }
}

/* Weak: resolved from the OpenBLAS that libnerf loads, absent with
 * another BLAS. */
#if defined(__GNUC__)
extern void openblas_set_num_threads(int n) __attribute__((weak));
#endif

void cli_blas_single_thread(void)
{
#if defined(__GNUC__)
    if (openblas_set_num_threads && getenv("OPENBLAS_NUM_THREADS") == NULL) {
        openblas_set_num_threads(1);
    }
#endif
}
