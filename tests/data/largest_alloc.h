/*
 * An allocator for nerf_hooks that remembers the largest block it was
 * asked for: a reader that judges a file before believing it never asks
 * for more than the file can hold.
 */
#ifndef NERF_TEST_LARGEST_ALLOC_H
#define NERF_TEST_LARGEST_ALLOC_H

#include <stdlib.h>

#include "env.h"
#include "nerf.h"

static size_t largest_alloc;

static void *largest_alloc_alloc(size_t size, void *user)
{
    (void)user;
    largest_alloc = size > largest_alloc ? size : largest_alloc;
    return malloc(size);
}

static void largest_alloc_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

/* An environment whose allocations go through the above; resets the
 * record. */
static inline void largest_alloc_env(nerf__env *env)
{
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.alloc = largest_alloc_alloc;
    hooks.free = largest_alloc_free;
    if (nerf__env_from_hooks(env, &hooks) != NERF_OK) {
        abort();
    }
    largest_alloc = 0;
}

#endif
