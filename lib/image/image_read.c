#include "image_read.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "file_io.h"
#include "jpeg_io.h"
#include "png_io.h"

static const unsigned char png_magic[8] = {0x89, 'P', 'N', 'G',
                                           '\r', '\n', 0x1a, '\n'};
/* SOI and the first byte of the next marker. */
static const unsigned char jpeg_magic[3] = {0xff, 0xd8, 0xff};

typedef enum image_kind { KIND_PNG, KIND_JPEG } image_kind;

/*
 * Open the image at path (a regular file: nerf__file_open_read) and tell
 * its format from its first bytes, which are left unread (pread).
 */
static int open_image(const char *path, int *fd_out, uint64_t *size_out,
                      image_kind *kind)
{
    int rc = nerf__file_open_read(path, fd_out, size_out);
    if (rc != NERF_OK) {
        return rc;
    }
    unsigned char head[8] = {0};
    ssize_t got;
    do {
        got = pread(*fd_out, head, sizeof head, 0);
    } while (got < 0 && errno == EINTR);
    if (got < 0) {
        char text[128];
        if (strerror_r(errno, text, sizeof text) != 0) {
            snprintf(text, sizeof text, "error %d", errno);
        }
        rc = nerf__error(NERF_EIO, "%s: read error: %s", path, text);
    } else if ((size_t)got >= sizeof png_magic &&
               memcmp(head, png_magic, sizeof png_magic) == 0) {
        *kind = KIND_PNG;
    } else if ((size_t)got >= sizeof jpeg_magic &&
               memcmp(head, jpeg_magic, sizeof jpeg_magic) == 0) {
        *kind = KIND_JPEG;
    } else {
        rc = nerf__error(NERF_EFORMAT, "%s: not a PNG or JPEG file%s", path,
                         got == 0 ? " (empty)" : "");
    }
    if (rc != NERF_OK) {
        close(*fd_out);
        *fd_out = -1;
    }
    return rc;
}

/* fd as a stdio stream, which then owns it; closes fd on failure. */
static int stream_of(const char *path, int fd, FILE **f_out)
{
    *f_out = fdopen(fd, "rb");
    if (*f_out == NULL) {
        char text[128];
        if (strerror_r(errno, text, sizeof text) != 0) {
            snprintf(text, sizeof text, "error %d", errno);
        }
        close(fd);
        return nerf__error(NERF_EIO, "%s: cannot open: %s", path, text);
    }
    return NERF_OK;
}

int nerf__image_read_rgba(const nerf__env *env, const char *path,
                          uint32_t *width_out, uint32_t *height_out,
                          float **rgba_out)
{
    *rgba_out = NULL;
    *width_out = 0;
    *height_out = 0;
    int fd;
    uint64_t size;
    image_kind kind;
    int rc = open_image(path, &fd, &size, &kind);
    if (rc != NERF_OK) {
        return rc;
    }
    if (kind == KIND_PNG) {
        FILE *f;
        rc = stream_of(path, fd, &f);
        if (rc == NERF_OK) {
            rc = nerf__png_stream_read_rgba(env, path, f, size, width_out,
                                            height_out, rgba_out);
            fclose(f);
        }
        return rc;
    }
    unsigned char *data = NULL;
    size_t n = 0;
    rc = nerf__file_read_fd(env, path, fd, size, NERF__JPEG_MAX_FILE_SIZE,
                            &data, &n);
    close(fd);
    if (rc == NERF_OK) {
        rc = nerf__jpeg_decode_rgba(env, path, data, n, width_out,
                                    height_out, rgba_out);
    }
    nerf__free(env, data);
    return rc;
}

int nerf__image_read_size(const nerf__env *env, const char *path,
                          uint32_t *width_out, uint32_t *height_out)
{
    *width_out = 0;
    *height_out = 0;
    int fd;
    uint64_t size;
    image_kind kind;
    int rc = open_image(path, &fd, &size, &kind);
    FILE *f = NULL;
    if (rc == NERF_OK) {
        rc = stream_of(path, fd, &f);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    if (kind == KIND_PNG) {
        rc = nerf__png_stream_size(path, f, size, width_out, height_out);
    } else {
        rc = nerf__jpeg_stream_size(env, path, f, size, width_out,
                                    height_out);
    }
    fclose(f);
    return rc;
}
