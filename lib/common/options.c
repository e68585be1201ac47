#include "options.h"

#include <stdint.h>
#include <string.h>

#include "error.h"

/* Sanity bound so that a garbage struct_size does not make us scan memory. */
#define STRUCT_SIZE_MAX 65536u

int nerf__options_init(void *opts, size_t struct_size, const void *defaults,
                       size_t own_size, const char *name)
{
    if (opts == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL options struct", name);
    }
    if (struct_size < sizeof(uint32_t) || struct_size > STRUCT_SIZE_MAX) {
        return nerf__error(NERF_EINVAL, "%s: struct_size %zu is invalid",
                           name, struct_size);
    }
    size_t n = struct_size < own_size ? struct_size : own_size;
    if (struct_size > own_size) {
        memset((char *)opts + own_size, 0, struct_size - own_size);
    }
    memcpy(opts, defaults, n);
    uint32_t size32 = (uint32_t)struct_size;
    memcpy(opts, &size32, sizeof size32);
    return NERF_OK;
}

int nerf__options_read(void *dst, size_t own_size, const void *src,
                       const char *name)
{
    if (src == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL options struct", name);
    }
    uint32_t size;
    memcpy(&size, src, sizeof size);
    if (size < sizeof(uint32_t) || size > STRUCT_SIZE_MAX) {
        return nerf__error(NERF_EINVAL,
                           "%s: struct_size %u is invalid (was the struct "
                           "initialised with its *_init function?)",
                           name, (unsigned)size);
    }
    if (size > own_size) {
        const unsigned char *extra = (const unsigned char *)src + own_size;
        for (size_t i = 0; i < size - own_size; i++) {
            if (extra[i] != 0) {
                return nerf__error(NERF_EVERSION,
                                   "%s: struct_size %u is from a newer libnerf "
                                   "(this one knows %zu bytes) and sets fields "
                                   "it does not know",
                                   name, (unsigned)size, own_size);
            }
        }
    }
    size_t n = size < own_size ? size : own_size;
    memcpy((char *)dst + sizeof size, (const char *)src + sizeof size,
           n - sizeof size);
    uint32_t own32 = (uint32_t)own_size;
    memcpy(dst, &own32, sizeof own32);
    return NERF_OK;
}

void nerf__options_write(void *dst, const void *src, size_t own_size)
{
    uint32_t size;
    memcpy(&size, dst, sizeof size);
    size_t n = size < own_size ? size : own_size;
    memcpy((char *)dst + sizeof size, (const char *)src + sizeof size,
           n - sizeof size);
}

int nerf__options_open(void *dst, size_t own_size, const void *src,
                       const char *name, int (*check)(const void *opts),
                       const nerf_hooks *const *hooks, nerf__env *env)
{
    int rc = src ? nerf__options_read(dst, own_size, src, name) : NERF_OK;
    if (rc == NERF_OK && check) {
        rc = check(dst);
    }
    if (rc == NERF_OK) {
        rc = nerf__env_from_hooks(env, *hooks);
    }
    return rc;
}
