/* Thread-local error messages and status strings. */
#ifndef NERF_COMMON_ERROR_H
#define NERF_COMMON_ERROR_H

#include "nerf.h"

#if defined(__GNUC__)
#  define NERF__PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#  define NERF__PRINTF(f, a)
#endif

/*
 * Record a formatted message as the calling thread's last error and return
 * status, so that failures read `return nerf__error(NERF_EIO, ...)`.
 */
int nerf__error(int status, const char *fmt, ...) NERF__PRINTF(2, 3);

/*
 * Prefix the current thread-local message with "prefix: ", keeping status.
 * Used when a lower layer failed without knowing which file it served.
 */
int nerf__error_prefix(int status, const char *prefix);

#endif
