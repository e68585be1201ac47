#include "env.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/*
 * Every block is over-allocated by ALIGN bytes: the caller's pointer sits on
 * the next 64-byte boundary (cache line and AVX-512 width) and the raw
 * pointer is stored just below it, so nerf__free() can hand the original
 * back to the user's free().
 */
#define ALIGN 64

static void *default_alloc(size_t size, void *user)
{
    (void)user;
    return malloc(size);
}

static void default_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

int nerf__mul_size(size_t a, size_t b, size_t *out)
{
    if (b != 0 && a > SIZE_MAX / b) {
        return -1;
    }
    *out = a * b;
    return 0;
}

void *nerf__alloc(const nerf__env *env, size_t size)
{
    if (size > SIZE_MAX - ALIGN) {
        nerf__error(NERF_ENOMEM, "allocation of %zu bytes is too large", size);
        return NULL;
    }
    void *(*fn)(size_t, void *) = env && env->alloc ? env->alloc : default_alloc;
    unsigned char *raw = fn(size + ALIGN, env ? env->alloc_user : NULL);
    if (raw == NULL) {
        nerf__error(NERF_ENOMEM, "out of memory allocating %zu bytes", size);
        return NULL;
    }
    uintptr_t p = ((uintptr_t)raw + sizeof(void *) + ALIGN - 1) & ~(uintptr_t)(ALIGN - 1);
    ((void **)p)[-1] = raw;
    return (void *)p;
}

void *nerf__calloc(const nerf__env *env, size_t count, size_t size)
{
    size_t total;
    if (nerf__mul_size(count, size, &total) != 0) {
        nerf__error(NERF_ENOMEM, "allocation of %zu x %zu bytes overflows",
                    count, size);
        return NULL;
    }
    void *p = nerf__alloc(env, total);
    if (p) {
        memset(p, 0, total);
    }
    return p;
}

void nerf__free(const nerf__env *env, void *ptr)
{
    if (ptr == NULL) {
        return;
    }
    void (*fn)(void *, void *) = env && env->free ? env->free : default_free;
    fn(((void **)ptr)[-1], env ? env->alloc_user : NULL);
}

static size_t line_round(size_t bytes)
{
    return (bytes + 63) & ~(size_t)63;
}

size_t nerf__carve_size(const size_t *bytes, size_t count)
{
    size_t total = 0;
    for (size_t i = 0; i < count; i++) {
        total += line_round(bytes[i]);
    }
    return total;
}

void *nerf__carve(unsigned char **at, size_t bytes)
{
    if (bytes == 0) {
        return NULL;
    }
    void *p = *at;
    *at += line_round(bytes);
    return p;
}

int nerf__carve_floats(const nerf__env *env, void **block,
                       float **const *slots, const size_t *bytes,
                       size_t count)
{
    unsigned char *at = nerf__alloc(env, nerf__carve_size(bytes, count));
    if (at == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(env, *block);
    *block = at;
    for (size_t i = 0; i < count; i++) {
        *slots[i] = nerf__carve(&at, bytes[i]);
    }
    return NERF_OK;
}
