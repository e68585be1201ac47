/* Small helpers shared by the example programs' command lines. */
#ifndef NERF_EXAMPLES_CLI_H
#define NERF_EXAMPLES_CLI_H

#include <stdint.h>

/* nerf_dataset_options.downscale's largest factor. */
#define CLI_DOWNSCALE_MAX 256

/* The largest --skip (every K-th view of a split). */
#define CLI_SKIP_MAX 100000

/* A macro's value as a string literal, for help texts: CLI_STR(256) is
 * "256". */
#define CLI_STR_(x) #x
#define CLI_STR(x) CLI_STR_(x)

/* Parse a whole decimal number in [min, max]; 0 on success, -1 if not. */
int cli_uint(const char *text, uint64_t min, uint64_t max, uint64_t *out);

/* Parse a finite floating-point number; 0 on success, -1 if not. */
int cli_double(const char *text, double *out);

/* A nerf_split from "train", "val" or "test"; -1 for anything else. */
int cli_split(const char *text);

/* The most steps a march takes across its grid's diagonal: the sampler's
 * range of march_steps. */
#define CLI_MARCH_STEPS_MAX 65536

/* --march-steps and the like: a march's steps, 1..CLI_MARCH_STEPS_MAX; 0
 * on success, -1 after saying why (cli_int_option()). */
int cli_march_steps(const char *program, const char *option, const char *text,
                    int64_t *out);

/* The value after option argv[*i], advancing *i; NULL if missing. */
const char *cli_value(int argc, char **argv, int *i);

/* Print "PROGRAM: libnerf error: STATUS: MESSAGE" to stderr. */
void cli_report(const char *program, int status);

/* A log callback writing info and above to stderr, prefixed. */
void cli_log(int level, const char *msg, void *user);

/*
 * Run OpenBLAS on one thread, unless OPENBLAS_NUM_THREADS says otherwise:
 * libnerf then spreads each product over its own workers, which is faster
 * for its small layers (see docs/performance.md).  A program's choice, not
 * the library's; nothing happens with another BLAS.
 */
void cli_blas_single_thread(void);

#endif
