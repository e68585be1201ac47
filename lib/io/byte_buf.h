/*
 * A growing byte buffer for files built whole in memory and then written
 * through nerf__file_write_atomic: a failed allocation sticks and drops
 * every later write, so that a writer checks once, when it saves.
 */
#ifndef NERF_IO_BYTE_BUF_H
#define NERF_IO_BYTE_BUF_H

#include <stdbool.h>
#include <stddef.h>

#include "env.h"
#include "error.h"

typedef struct nerf__buf {
    const nerf__env *env;
    unsigned char *data;
    size_t size, cap;
    bool failed;
} nerf__buf;

/* n new bytes at the end of the buffer, or NULL after a failure. */
unsigned char *nerf__buf_grow(nerf__buf *b, size_t n);

void nerf__buf_put(nerf__buf *b, const void *data, size_t n);

/* Room for n more bytes in one allocation, for a writer that knows roughly
 * how much it will write: a hint, past which the buffer still grows. */
void nerf__buf_reserve(nerf__buf *b, size_t n);

/* Formatted text, without its terminating NUL. */
void nerf__buf_printf(nerf__buf *b, const char *fmt, ...) NERF__PRINTF(2, 3);

/* Write the buffer to path atomically and free it.  NERF_OK; NERF_ENOMEM
 * (named path) when a write was dropped; NERF_EIO (named path). */
int nerf__buf_save(nerf__buf *b, const char *path);

#endif
