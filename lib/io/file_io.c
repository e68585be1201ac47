#include "file_io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Distinguishes temporary files of concurrent saves within one process;
 * the pid distinguishes processes. */
static atomic_uint temp_counter;

/* The error text for errno value err, without strerror's shared buffer. */
static const char *describe(int err, char *buf, size_t size)
{
    if (strerror_r(err, buf, size) != 0) {
        snprintf(buf, size, "error %d", err);
    }
    return buf;
}

static int io_error(const char *path, const char *what, int err)
{
    char text[128];
    return nerf__error(NERF_EIO, "%s: %s: %s", path, what,
                       describe(err, text, sizeof text));
}

/* Read exactly size bytes; a short file is an error. */
static int read_all(int fd, const char *path, unsigned char *buf, size_t size)
{
    size_t done = 0;
    while (done < size) {
        ssize_t got = read(fd, buf + done, size - done);
        if (got < 0 && errno == EINTR) {
            continue;
        }
        if (got < 0) {
            return io_error(path, "read error", errno);
        }
        if (got == 0) {
            return nerf__error(NERF_EIO, "%s: file shrank while being read "
                               "(%zu of %zu bytes)", path, done, size);
        }
        done += (size_t)got;
    }
    return NERF_OK;
}

static int check_size(const char *path, const struct stat *st,
                      uint64_t max_size, size_t *size_out)
{
    if (!S_ISREG(st->st_mode)) {
        return nerf__error(NERF_EIO, "%s: not a regular file", path);
    }
    uint64_t size = (uint64_t)st->st_size;
    if (size > max_size || size > SIZE_MAX - 1) {
        return nerf__error(NERF_EFORMAT, "%s: file is too large (%llu bytes; "
                           "the limit is %llu)", path,
                           (unsigned long long)size,
                           (unsigned long long)max_size);
    }
    *size_out = (size_t)size;
    return NERF_OK;
}

int nerf__file_read(const nerf__env *env, const char *path, uint64_t max_size,
                    unsigned char **data_out, size_t *size_out)
{
    *data_out = NULL;
    *size_out = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        return io_error(path, "cannot open", errno);
    }
    struct stat st;
    size_t size = 0;
    int rc = NERF_OK;
    if (fstat(fd, &st) != 0) {
        rc = io_error(path, "cannot stat", errno);
    }
    if (rc == NERF_OK) {
        rc = check_size(path, &st, max_size, &size);
    }
    unsigned char *buf = NULL;
    if (rc == NERF_OK) {
        /* One spare byte: an empty file still yields a non-NULL buffer. */
        buf = nerf__alloc(env, size + 1);
        rc = buf ? read_all(fd, path, buf, size)
                 : nerf__error_prefix(NERF_ENOMEM, path);
    }
    close(fd);
    if (rc != NERF_OK) {
        nerf__free(env, buf);
        return rc;
    }
    *data_out = buf;
    *size_out = size;
    return NERF_OK;
}

static int write_all(int fd, const unsigned char *data, size_t size)
{
    while (size > 0) {
        ssize_t put = write(fd, data, size);
        if (put < 0 && errno == EINTR) {
            continue;
        }
        if (put <= 0) {
            return put < 0 ? errno : EIO;
        }
        data += put;
        size -= (size_t)put;
    }
    return 0;
}

/* Write, flush and close the temporary file; returns 0 or an errno. */
static int fill_temp(int fd, const nerf__span *parts, size_t n_parts,
                     const char **what)
{
    int err = 0;
    *what = "cannot write";
    for (size_t i = 0; i < n_parts && err == 0; i++) {
        err = write_all(fd, parts[i].data, parts[i].size);
    }
    if (err == 0 && fsync(fd) != 0) {
        *what = "cannot flush to disk";
        err = errno;
    }
    /* close() can report a deferred write error (NFS, quotas). */
    if (close(fd) != 0 && err == 0) {
        *what = "cannot close";
        err = errno;
    }
    return err;
}

/*
 * Make the rename itself durable.  Best effort: some file systems refuse
 * fsync on directories, and the new file is complete either way.
 */
static void sync_parent(const char *path, char *scratch)
{
    strcpy(scratch, path);
    char *slash = strrchr(scratch, '/');
    const char *dir = ".";
    if (slash == scratch) {
        dir = "/";
    } else if (slash) {
        *slash = '\0';
        dir = scratch;
    }
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
}

int nerf__file_write_atomic(const nerf__env *env, const char *path,
                            const nerf__span *parts, size_t n_parts)
{
    size_t len = strlen(path);
    char *temp = nerf__alloc(env, len + 64);
    if (temp == NULL) {
        return NERF_ENOMEM;
    }
    unsigned n = atomic_fetch_add(&temp_counter, 1u);
    snprintf(temp, len + 64, "%s.tmp.%ld.%u", path, (long)getpid(), n);
    int rc = NERF_OK;
    int fd = open(temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) {
        rc = io_error(path, "cannot create a temporary file beside it", errno);
    } else {
        const char *what;
        int err = fill_temp(fd, parts, n_parts, &what);
        if (err == 0 && rename(temp, path) != 0) {
            what = "cannot rename the temporary file over it";
            err = errno;
        }
        if (err != 0) {
            rc = io_error(path, what, err);
            unlink(temp);
        } else {
            sync_parent(path, temp);
        }
    }
    nerf__free(env, temp);
    return rc;
}
