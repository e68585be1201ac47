/* The growing byte buffer of the writers that build a file in memory. */
#include "byte_buf.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "file_io.h"

static bool set_cap(nerf__buf *b, size_t cap)
{
    unsigned char *p = nerf__alloc(b->env, cap);
    if (p == NULL) {
        b->failed = true;
        return false;
    }
    if (b->data) {
        memcpy(p, b->data, b->size);
    }
    nerf__free(b->env, b->data);
    b->data = p;
    b->cap = cap;
    return true;
}

void nerf__buf_reserve(nerf__buf *b, size_t n)
{
    if (!b->failed && b->size + n > b->cap) {
        set_cap(b, b->size + n);
    }
}

unsigned char *nerf__buf_grow(nerf__buf *b, size_t n)
{
    if (b->failed) {
        return NULL;
    }
    if (b->size + n > b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 4096;
        while (cap < b->size + n) {
            cap *= 2;
        }
        if (!set_cap(b, cap)) {
            return NULL;
        }
    }
    unsigned char *at = b->data + b->size;
    b->size += n;
    return at;
}

void nerf__buf_put(nerf__buf *b, const void *data, size_t n)
{
    unsigned char *p = nerf__buf_grow(b, n);
    if (p) {
        memcpy(p, data, n);
    }
}

void nerf__buf_printf(nerf__buf *b, const char *fmt, ...)
{
    va_list ap, again;
    va_start(ap, fmt);
    va_copy(again, ap);
    const int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    /* vsnprintf writes a NUL after the text: room for it, then the size
     * taken back, so that the next write overwrites it. */
    unsigned char *p = n > 0 ? nerf__buf_grow(b, (size_t)n + 1) : NULL;
    if (p) {
        vsnprintf((char *)p, (size_t)n + 1, fmt, again);
        b->size--;
    }
    va_end(again);
}

int nerf__buf_save(nerf__buf *b, const char *path)
{
    int rc;
    if (b->failed) {
        rc = nerf__error(NERF_ENOMEM, "%s: out of memory", path);
    } else {
        nerf__span part = {b->data, b->size};
        rc = nerf__file_write_atomic(b->env, path, &part, 1);
    }
    nerf__free(b->env, b->data);
    b->data = NULL;
    b->size = b->cap = 0;
    return rc;
}
