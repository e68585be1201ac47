#include "file_io.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
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

/* A file to read that is not there is not an input/output failure. */
static int open_error(const char *path, int err)
{
    if (err == ENOENT || err == ENOTDIR) {
        char text[128];
        return nerf__error(NERF_ENOENT, "%s: cannot open: %s", path,
                           describe(err, text, sizeof text));
    }
    return io_error(path, "cannot open", err);
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

const char *nerf__file_kind(unsigned mode)
{
    return S_ISREG(mode)    ? "a file"
           : S_ISDIR(mode)  ? "a folder"
           : S_ISFIFO(mode) ? "a FIFO (named pipe)"
           : S_ISCHR(mode)  ? "a character device"
           : S_ISBLK(mode)  ? "a block device"
           : S_ISSOCK(mode) ? "a socket"
                            : "a special file";
}

/* The refusal of what st says is not a regular file, naming its kind. */
static int not_regular(const char *path, const struct stat *st)
{
    if (S_ISDIR(st->st_mode)) {
        return nerf__error(NERF_EUNRECOGNISED, "%s: a folder, not a file",
                           path);
    }
    return nerf__error(NERF_EUNRECOGNISED, "%s: %s, not a regular file",
                       path, nerf__file_kind(st->st_mode));
}

int nerf__file_check_regular(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        return open_error(path, errno);
    }
    return S_ISREG(st.st_mode) ? NERF_OK : not_regular(path, &st);
}

/*
 * The stat before the open keeps devices from being opened at all (opening
 * some has effects); O_NONBLOCK keeps a FIFO swapped in after the stat from
 * blocking the open until a writer comes, and fstat then refuses it.  On a
 * regular file O_NONBLOCK changes nothing, but it is cleared all the same.
 */
int nerf__file_open_read(const char *path, int *fd_out, uint64_t *size_out)
{
    *fd_out = -1;
    *size_out = 0;
    int rc = nerf__file_check_regular(path);
    if (rc != NERF_OK) {
        return rc;
    }
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
    if (fd < 0) {
        return open_error(path, errno);
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        rc = io_error(path, "cannot stat", errno);
    } else if (!S_ISREG(st.st_mode)) {
        rc = not_regular(path, &st);
    } else {
        int flags = fcntl(fd, F_GETFL);
        if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
            rc = io_error(path, "cannot open", errno);
        }
    }
    if (rc != NERF_OK) {
        close(fd);
        return rc;
    }
    *fd_out = fd;
    *size_out = (uint64_t)st.st_size;
    return NERF_OK;
}

int nerf__file_fopen_read(const char *path, FILE **f_out, uint64_t *size_out)
{
    *f_out = NULL;
    int fd;
    int rc = nerf__file_open_read(path, &fd, size_out);
    if (rc != NERF_OK) {
        return rc;
    }
    FILE *f = fdopen(fd, "rb");
    if (f == NULL) {
        rc = io_error(path, "cannot open", errno);
        close(fd);
        return rc;
    }
    *f_out = f;
    return NERF_OK;
}

int nerf__file_read_fd(const nerf__env *env, const char *path, int fd,
                       uint64_t size, uint64_t max_size,
                       unsigned char **data_out, size_t *size_out)
{
    *data_out = NULL;
    *size_out = 0;
    if (size > max_size || size > SIZE_MAX - 1) {
        return nerf__error(NERF_EFORMAT, "%s: file is too large (%llu bytes; "
                           "the limit is %llu)", path,
                           (unsigned long long)size,
                           (unsigned long long)max_size);
    }
    /* One spare byte: an empty file still yields a non-NULL buffer. */
    unsigned char *buf = nerf__alloc(env, (size_t)size + 1);
    if (buf == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    int rc = read_all(fd, path, buf, (size_t)size);
    if (rc != NERF_OK) {
        nerf__free(env, buf);
        return rc;
    }
    *data_out = buf;
    *size_out = (size_t)size;
    return NERF_OK;
}

int nerf__file_read(const nerf__env *env, const char *path, uint64_t max_size,
                    unsigned char **data_out, size_t *size_out)
{
    *data_out = NULL;
    *size_out = 0;
    int fd;
    uint64_t size;
    int rc = nerf__file_open_read(path, &fd, &size);
    if (rc == NERF_OK) {
        rc = nerf__file_read_fd(env, path, fd, size, max_size, data_out,
                                size_out);
        close(fd);
    }
    return rc;
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

/* A new temporary name beside path, "path.tmp.<pid>.<n>"; NULL if out of
 * memory.  nerf__file_remove_stale_temps() knows this pattern. */
static char *temp_name(const nerf__env *env, const char *path)
{
    size_t size = strlen(path) + 64;
    char *temp = nerf__alloc(env, size);
    if (temp != NULL) {
        unsigned n = atomic_fetch_add(&temp_counter, 1u);
        snprintf(temp, size, "%s.tmp.%ld.%u", path, (long)getpid(), n);
    }
    return temp;
}

/* Create a new temporary file beside path; on failure, the error names
 * path with `what` and the reason, and *temp is NULL. */
static int open_temp(const nerf__env *env, const char *path,
                     const char *what, char **temp, int *fd)
{
    *temp = temp_name(env, path);
    if (*temp == NULL) {
        return NERF_ENOMEM;
    }
    *fd = open(*temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (*fd < 0) {
        int rc = io_error(path, what, errno);
        nerf__free(env, *temp);
        *temp = NULL;
        return rc;
    }
    return NERF_OK;
}

int nerf__file_check_writable(const nerf__env *env, const char *path)
{
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        return nerf__error(NERF_EIO, "%s: cannot be written: it is a folder",
                           path);
    }
    char *temp;
    int fd;
    int rc = open_temp(env, path, "cannot be written: cannot create a "
                       "temporary file beside it", &temp, &fd);
    if (rc == NERF_OK) {
        close(fd);
        unlink(temp);
        nerf__free(env, temp);
    }
    return rc;
}

/* The folder of path into scratch (as large as path), and its last part. */
static const char *split_path(const char *path, char *scratch,
                              const char **base)
{
    strcpy(scratch, path);
    char *slash = strrchr(scratch, '/');
    if (slash == NULL) {
        *base = path;
        return ".";
    }
    *base = path + (slash - scratch) + 1;
    if (slash == scratch) {
        return "/";
    }
    *slash = '\0';
    return scratch;
}

/* Digits only, at least one; the value, or -1 when not or too large. */
static long parse_digits(const char *s, size_t n)
{
    if (n == 0 || n > 9) {
        return -1;
    }
    long v = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') {
            return -1;
        }
        v = 10 * v + (s[i] - '0');
    }
    return v;
}

/* The pid of name if it is base.tmp.<pid>.<n>, else -1. */
static long temp_owner(const char *name, const char *base)
{
    size_t bn = strlen(base);
    if (strncmp(name, base, bn) != 0 || strncmp(name + bn, ".tmp.", 5) != 0) {
        return -1;
    }
    const char *pid = name + bn + 5;
    const char *dot = strchr(pid, '.');
    if (dot == NULL || parse_digits(dot + 1, strlen(dot + 1)) < 0) {
        return -1;
    }
    return parse_digits(pid, (size_t)(dot - pid));
}

unsigned nerf__file_remove_stale_temps(const nerf__env *env, const char *path)
{
    char *scratch = nerf__alloc(env, strlen(path) + 1);
    if (scratch == NULL) {
        return 0; /* best effort: the save itself does not need this */
    }
    const char *base;
    const char *dir = split_path(path, scratch, &base);
    unsigned removed = 0;
    DIR *d = base[0] ? opendir(dir) : NULL;
    for (struct dirent *e = d ? readdir(d) : NULL; e; e = readdir(d)) {
        long pid = temp_owner(e->d_name, base);
        /* Only a writer that no longer runs: kill(pid, 0) fails with
         * ESRCH.  A pid reused since keeps its file, which is safe. */
        if (pid > 0 && pid != (long)getpid() && kill((pid_t)pid, 0) != 0 &&
            errno == ESRCH && unlinkat(dirfd(d), e->d_name, 0) == 0) {
            removed++;
        }
    }
    if (d) {
        closedir(d);
    }
    nerf__free(env, scratch);
    return removed;
}

int nerf__file_write_atomic(const nerf__env *env, const char *path,
                            const nerf__span *parts, size_t n_parts)
{
    char *temp;
    int fd;
    int rc = open_temp(env, path, "cannot create a temporary file beside it",
                       &temp, &fd);
    if (rc != NERF_OK) {
        return rc;
    }
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
    nerf__free(env, temp);
    return rc;
}
