#include "out_folder.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int is_folder(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* One part of the path: made, already a folder, or why not. */
static int make_one(const char *part, int *made)
{
    if (mkdir(part, 0777) == 0) {
        *made = 1;
        return 0;
    }
    int err = errno;
    if (is_folder(part)) {
        return 0; /* EEXIST, or EACCES on a folder that exists */
    }
    struct stat st;
    if (err == EEXIST || stat(part, &st) == 0) {
        return ENOTDIR;
    }
    return err;
}

int out_make_folder(const char *dir, int *created, char *failed,
                    size_t failed_size)
{
    *created = 0;
    size_t n = strlen(dir);
    char *part = malloc(n + 1);
    if (part == NULL) {
        return ENOMEM;
    }
    memcpy(part, dir, n + 1);
    int err = 0;
    /* Each prefix ending before a slash, then the whole path; the root
     * and repeated slashes make empty or existing parts, which pass. */
    for (size_t i = 1; i <= n && err == 0; i++) {
        if (i < n && part[i] != '/') {
            continue;
        }
        char saved = part[i];
        part[i] = '\0';
        int made = 0;
        err = make_one(part, &made);
        *created |= made;
        if (err != 0) {
            snprintf(failed, failed_size, "%s", part);
        }
        part[i] = saved;
    }
    free(part);
    return err;
}

int out_make_parent(const char *file, const char *program)
{
    const char *slash = strrchr(file, '/');
    if (slash == NULL || slash == file) {
        return 0; /* the current folder or the root */
    }
    size_t n = (size_t)(slash - file);
    char *dir = malloc(n + 1);
    if (dir == NULL) {
        fprintf(stderr, "%s: out of memory\n", program);
        return -1;
    }
    memcpy(dir, file, n);
    dir[n] = '\0';
    char failed[4200];
    int created = 0;
    int err = out_make_folder(dir, &created, failed, sizeof failed);
    if (err != 0) {
        fprintf(stderr, "%s: %s: cannot be written: %s: %s\n", program, file,
                failed, strerror(err));
    } else if (created) {
        fprintf(stderr, "%s: created the folder %s\n", program, dir);
    }
    free(dir);
    return err != 0 ? -1 : 0;
}

int out_ready_folder(const char *dir, const char *program)
{
    char failed[4200];
    int created = 0;
    int err = out_make_folder(dir, &created, failed, sizeof failed);
    if (err == ENOTDIR && strcmp(failed, dir) == 0) {
        fprintf(stderr, "%s: %s: cannot be written: it is not a folder\n",
                program, dir);
        return -1;
    }
    if (err != 0) {
        fprintf(stderr, "%s: %s: cannot be written: %s: %s\n", program, dir,
                failed, strerror(err));
        return -1;
    }
    if (created) {
        fprintf(stderr, "%s: created the folder %s\n", program, dir);
    }
    if (access(dir, W_OK | X_OK) != 0) {
        fprintf(stderr, "%s: %s: cannot be written: %s\n", program, dir,
                strerror(errno));
        return -1;
    }
    return 0;
}
