/* Small helpers shared by the example programs' command lines. */
#ifndef NERF_EXAMPLES_CLI_H
#define NERF_EXAMPLES_CLI_H

#include <stdint.h>

/* A macro's value as a string literal, for help texts: CLI_STR(256) is
 * "256". */
#define CLI_STR_(x) #x
#define CLI_STR(x) CLI_STR_(x)

/* Parse a whole decimal number in [min, max]; 0 on success, -1 if not. */
int cli_uint(const char *text, uint64_t min, uint64_t max, uint64_t *out);

/* Parse a finite floating-point number; 0 on success, -1 if not. */
int cli_double(const char *text, double *out);

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
