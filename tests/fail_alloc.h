/*
 * An allocator for nerf_hooks that fails its fail_at-th call and counts
 * the blocks still live, for allocation-failure injection: run an
 * operation with fail_at = 1, 2, ... until it succeeds, and check that
 * every failure reports NERF_ENOMEM and leaves no block behind.
 */
#ifndef NERF_TEST_FAIL_ALLOC_H
#define NERF_TEST_FAIL_ALLOC_H

#include <stdlib.h>

#include "nerf.h"

typedef struct fail_alloc {
    int calls, fail_at, live;
} fail_alloc;

static void *fail_alloc_alloc(size_t size, void *user)
{
    fail_alloc *f = user;
    if (++f->calls == f->fail_at) {
        return NULL;
    }
    f->live++;
    return malloc(size);
}

static void fail_alloc_free(void *ptr, void *user)
{
    fail_alloc *f = user;
    f->live--;
    free(ptr);
}

/* Hooks whose allocations go through f. */
static inline void fail_alloc_hooks(nerf_hooks *hooks, fail_alloc *f)
{
    NERF_HOOKS_INIT(hooks);
    hooks->alloc = fail_alloc_alloc;
    hooks->free = fail_alloc_free;
    hooks->alloc_user = f;
}

#endif
