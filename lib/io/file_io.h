/*
 * Whole-file reads and crash-safe writes.  Every error message starts with
 * the path, so callers can return the status unchanged.
 */
#ifndef NERF_IO_FILE_IO_H
#define NERF_IO_FILE_IO_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"

/*
 * Read the regular file at path into a buffer allocated through env (free
 * it with nerf__free).  A file larger than max_size is refused, so that a
 * stray multi-gigabyte file cannot exhaust memory.  *data_out is never
 * NULL on success, even for an empty file.
 * Returns NERF_OK; NERF_EIO (cannot open or read, not a regular file);
 * NERF_EFORMAT (larger than max_size); NERF_ENOMEM.
 */
int nerf__file_read(const nerf__env *env, const char *path, uint64_t max_size,
                    unsigned char **data_out, size_t *size_out);

/* A piece of the data written by nerf__file_write_atomic(). */
typedef struct nerf__span {
    const void *data;
    size_t size;
} nerf__span;

/*
 * Write the concatenation of parts to path so that path holds either its
 * old content or the complete new content, never a mix: the data goes to a
 * new file beside path ("path.tmp.<pid>.<n>"), is flushed to disk and then
 * renamed over path.  On failure the temporary file is removed and an
 * existing file at path is left untouched.
 * Returns NERF_OK; NERF_EIO; NERF_ENOMEM.
 */
int nerf__file_write_atomic(const nerf__env *env, const char *path,
                            const nerf__span *parts, size_t n_parts);

#endif
