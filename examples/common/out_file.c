#include "out_file.h"

#include <dirent.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

static const char *kind_of(mode_t mode)
{
    return S_ISDIR(mode)    ? "a folder"
           : S_ISFIFO(mode) ? "a FIFO"
           : S_ISCHR(mode)  ? "a character device"
           : S_ISBLK(mode)  ? "a block device"
           : S_ISSOCK(mode) ? "a socket"
                            : "not a regular file";
}

/* The input that is the file st describes, or NULL. */
static const out_input *same_as_input(const struct stat *st,
                                      const out_input *inputs, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        struct stat in;
        if (inputs[i].path != NULL && stat(inputs[i].path, &in) == 0 &&
            in.st_dev == st->st_dev && in.st_ino == st->st_ino) {
            return &inputs[i];
        }
    }
    return NULL;
}

int out_file_check(const char *program, const char *path, int overwrite,
                   const char *how, const out_input *inputs,
                   size_t n_inputs)
{
    struct stat st;
    if (lstat(path, &st) != 0) {
        /* Nothing there, or a path that cannot be looked at (a part of
         * it missing or not a folder): the writer, which makes the
         * folders, says what stops it. */
        return 0;
    }
    int dangling = S_ISLNK(st.st_mode) && stat(path, &st) != 0;
    if (!dangling) {
        const out_input *in = same_as_input(&st, inputs, n_inputs);
        if (in != NULL) {
            fprintf(stderr, "%s: %s is the same file as %s %s, which this "
                    "run reads: write to another file\n", program, path,
                    in->role, in->path);
            return -1;
        }
        if (!S_ISREG(st.st_mode)) {
            fprintf(stderr, "%s: %s exists and is %s, not a file\n", program,
                    path, kind_of(st.st_mode));
            return -1;
        }
    }
    if (!overwrite) {
        fprintf(stderr, "%s: %s exists: %s\n", program, path,
                how != NULL ? how : OUT_OVERWRITE_HOW);
        return -1;
    }
    return 0;
}

/* Whether the folder dir holds anything; 0 when it cannot be read (the
 * writer then says why it cannot write there). */
static int holds_anything(const char *dir)
{
    DIR *d = opendir(dir);
    if (d == NULL) {
        return 0;
    }
    int found = 0;
    struct dirent *e;
    while (!found && (e = readdir(d)) != NULL) {
        found = strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    }
    closedir(d);
    return found;
}

int out_folder_check(const char *program, const char *dir, int overwrite,
                     const char *how)
{
    struct stat st;
    if (overwrite || stat(dir, &st) != 0 || !S_ISDIR(st.st_mode) ||
        !holds_anything(dir)) {
        return 0;
    }
    fprintf(stderr, "%s: %s holds files already: %s\n", program, dir,
            how != NULL ? how : OUT_OVERWRITE_HOW);
    return -1;
}
