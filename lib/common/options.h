/*
 * Versioned options structs.  Each public options struct starts with a
 * uint32_t struct_size; the library reads min(struct_size, own size) bytes
 * and keeps its defaults for the rest, so binaries built against an older,
 * smaller struct keep working.  A caller's larger struct (from a newer
 * header) is accepted only if the bytes this library does not know are zero.
 */
#ifndef NERF_COMMON_OPTIONS_H
#define NERF_COMMON_OPTIONS_H

#include <stddef.h>

#include "env.h"

/*
 * Write defaults (own_size bytes) into the caller's struct, truncated to
 * struct_size, and set its struct_size.  name is used in error messages.
 */
int nerf__options_init(void *opts, size_t struct_size, const void *defaults,
                       size_t own_size, const char *name);

/*
 * Overlay the caller's struct src onto dst (which holds own_size bytes of
 * defaults).  Returns NERF_EINVAL for a NULL or impossibly small struct and
 * NERF_EVERSION for unknown non-zero trailing bytes.
 */
int nerf__options_read(void *dst, size_t own_size, const void *src,
                       const char *name);

/*
 * The other way, after nerf__options_read(): copy src (own_size bytes)
 * back into the caller's struct dst, only as many bytes as its
 * struct_size covers, which stays as it was.  For the calls that fill a
 * caller's options (presets and the like).
 */
void nerf__options_write(void *dst, const void *src, size_t own_size);

/*
 * What every nerf_*_create() does first with its options, in this order:
 * overlay the caller's struct src (NULL: keep the defaults in dst), check
 * the result (check may be NULL), and take the environment from the hooks
 * the result names (*hooks, a field of dst).  Returns the first failure.
 */
int nerf__options_open(void *dst, size_t own_size, const void *src,
                       const char *name, int (*check)(const void *opts),
                       const nerf_hooks *const *hooks, nerf__env *env);

#endif
