#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#include "options.h"

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

int cli_split(const char *text)
{
    static const char *const names[] = {"train", "val", "test"};
    static const int splits[] = {NERF_SPLIT_TRAIN, NERF_SPLIT_VAL,
                                 NERF_SPLIT_TEST};
    for (int i = 0; i < 3; i++) {
        if (strcmp(text, names[i]) == 0) {
            return splits[i];
        }
    }
    return -1;
}

int cli_march_steps(const char *program, const char *option, const char *text,
                    int64_t *out)
{
    uint64_t n = 0;
    if (cli_int_option(program, option, text, 1, CLI_MARCH_STEPS_MAX, &n) !=
        0) {
        return -1;
    }
    *out = (int64_t)n;
    return 0;
}

const char *cli_value(int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) {
        return NULL;
    }
    return argv[++*i];
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
