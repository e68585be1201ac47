#include "image_read.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "jpeg_io.h"
#include "png_io.h"

static const unsigned char png_magic[8] = {0x89, 'P', 'N', 'G',
                                           '\r', '\n', 0x1a, '\n'};
/* SOI and the first byte of the next marker. */
static const unsigned char jpeg_magic[3] = {0xff, 0xd8, 0xff};

int nerf__image_read_rgba(const nerf__env *env, const char *path,
                          uint32_t *width_out, uint32_t *height_out,
                          float **rgba_out)
{
    *rgba_out = NULL;
    *width_out = 0;
    *height_out = 0;
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        char text[128];
        if (strerror_r(errno, text, sizeof text) != 0) {
            snprintf(text, sizeof text, "error %d", errno);
        }
        return nerf__error(errno == ENOENT || errno == ENOTDIR ? NERF_ENOENT
                                                               : NERF_EIO,
                           "%s: cannot open: %s", path, text);
    }
    unsigned char head[8] = {0};
    size_t got = fread(head, 1, sizeof head, f);
    int read_failed = ferror(f);
    fclose(f);
    if (read_failed) {
        return nerf__error(NERF_EIO, "%s: read error", path);
    }
    if (got >= sizeof png_magic && memcmp(head, png_magic, 8) == 0) {
        return nerf__png_read_rgba(env, path, width_out, height_out,
                                   rgba_out);
    }
    if (got >= sizeof jpeg_magic &&
        memcmp(head, jpeg_magic, sizeof jpeg_magic) == 0) {
        return nerf__jpeg_read_rgba(env, path, width_out, height_out,
                                    rgba_out);
    }
    return nerf__error(NERF_EFORMAT, "%s: not a PNG or JPEG file%s", path,
                       got == 0 ? " (empty)" : "");
}
