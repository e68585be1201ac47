/*
 * libFuzzer target for the zip reader: open the archive, look every member
 * up by name, extract it and, since .npz members are .npy arrays, parse
 * what comes out.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "env.h"
#include "npy.h"
#include "zip_read.h"

/* Far above what a fuzz input can declare (deflate expands at most about
 * 1032 times), so the size check never hides the extraction path. */
#define MAX_MEMBER (64u << 20)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    nerf__env env;
    nerf__env_default(&env);
    nerf__zip zip;
    if (nerf__zip_open(&zip, &env, data, size) != NERF_OK) {
        return 0;
    }
    for (size_t i = 0; i < zip.count; i++) {
        const nerf__zip_entry *e = &zip.entries[i];
        char name[256];
        if (e->name_len < sizeof name &&
            memchr(e->name, '\0', e->name_len) == NULL) {
            memcpy(name, e->name, e->name_len);
            name[e->name_len] = '\0';
            /* An earlier member of the same name may win; either is fine. */
            if (nerf__zip_find(&zip, name) == NULL) {
                abort();
            }
        }
        unsigned char *out = NULL;
        if (nerf__zip_extract(&zip, &env, e, MAX_MEMBER, &out) == NERF_OK) {
            nerf__npy a;
            (void)nerf__npy_parse(out, e->size, &a);
            nerf__free(&env, out);
        }
    }
    nerf__zip_close(&zip, &env);
    return 0;
}
