#include "error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Long enough for two paths and a sentence; longer messages are cut. */
#define NERF_ERROR_MAX 1024

static _Thread_local char last_error[NERF_ERROR_MAX];

NERF_API const char *nerf_status_string(int status)
{
    switch (status) {
    case NERF_OK: return "success";
    case NERF_ERROR: return "internal error";
    case NERF_EINVAL: return "invalid argument";
    case NERF_ENOMEM: return "out of memory";
    case NERF_EIO: return "input/output error";
    case NERF_EFORMAT: return "malformed data";
    case NERF_ECANCELLED: return "cancelled";
    case NERF_EVERSION: return "unsupported version";
    case NERF_ENOENT: return "no such file or folder";
    case NERF_EUNRECOGNISED: return "not a recognised file or folder";
    default: return "unknown status";
    }
}

NERF_API const char *nerf_last_error(void)
{
    return last_error;
}

NERF_API void nerf_clear_error(void)
{
    last_error[0] = '\0';
}

int nerf__error(int status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(last_error, sizeof last_error, fmt, ap);
    va_end(ap);
    return status;
}

int nerf__error_prefix(int status, const char *prefix)
{
    char tmp[NERF_ERROR_MAX];
    size_t n = strlen(prefix);
    if (n > NERF_ERROR_MAX - 3) {
        n = NERF_ERROR_MAX - 3;
    }
    memcpy(tmp, prefix, n);
    tmp[n] = ':';
    tmp[n + 1] = ' ';
    size_t rest = strlen(last_error);
    if (rest > NERF_ERROR_MAX - n - 3) {
        rest = NERF_ERROR_MAX - n - 3;
    }
    memcpy(tmp + n + 2, last_error, rest);
    tmp[n + 2 + rest] = '\0';
    memcpy(last_error, tmp, sizeof last_error);
    return status;
}
