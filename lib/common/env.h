/*
 * The per-handle environment: allocator and log sink, copied from the
 * caller's nerf_hooks at creation so the caller's struct need not outlive
 * the handle.
 */
#ifndef NERF_COMMON_ENV_H
#define NERF_COMMON_ENV_H

#include <stddef.h>

#include "error.h"

typedef struct nerf__env {
    void *(*alloc)(size_t size, void *user);
    void (*free)(void *ptr, void *user);
    void *alloc_user;
    nerf_log_cb log_cb;   /* NULL: the process default */
    void *log_user;
    int log_level;
} nerf__env;

/* Fill env from hooks (NULL = defaults).  Validates the struct. */
int nerf__env_from_hooks(nerf__env *env, const nerf_hooks *hooks);

/* Process defaults: malloc/free and the default log handler. */
void nerf__env_default(nerf__env *env);

/*
 * 64-byte aligned allocation through the environment's allocator.  Sets the
 * thread's error and returns NULL on failure (including size overflow).
 */
void *nerf__alloc(const nerf__env *env, size_t size);
void *nerf__calloc(const nerf__env *env, size_t count, size_t size);
void nerf__free(const nerf__env *env, void *ptr);

/*
 * One allocation carved into arrays, each starting on a 64-byte line as
 * the block does: nerf__carve_size() is the block's size for `count`
 * arrays of bytes[i] bytes, and nerf__carve() hands out the next array
 * from the cursor *at (NULL for an empty one, which takes no room).
 * Callers bound the sizes so that the sum cannot wrap.
 */
size_t nerf__carve_size(const size_t *bytes, size_t count);
void *nerf__carve(unsigned char **at, size_t bytes);

/*
 * The growing scratch of a batch: replace *block with one allocation
 * carved into count float arrays of bytes[i] bytes, *slots[i] set to
 * each (NULL for an empty one).  On failure (NERF_ENOMEM) *block and the
 * slots are left as they were.
 */
int nerf__carve_floats(const nerf__env *env, void **block,
                       float **const *slots, const size_t *bytes,
                       size_t count);

/* Multiply sizes; returns 0 and sets *out on success, -1 on overflow. */
int nerf__mul_size(size_t a, size_t b, size_t *out);

void nerf__log(const nerf__env *env, int level, const char *fmt, ...)
    NERF__PRINTF(3, 4);

#endif
