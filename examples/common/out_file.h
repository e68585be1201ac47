/*
 * The rule every example program follows before it writes a file: a file
 * that exists is replaced only when the user said so, and a run's input
 * never, whatever path names it.
 */
#ifndef NERF_EXAMPLES_OUT_FILE_H
#define NERF_EXAMPLES_OUT_FILE_H

#include <stddef.h>

/* A file or folder a run reads, as the user named it: role is how the
 * help calls it ("MODEL", "--poses"); a NULL path is one not given. */
typedef struct out_input {
    const char *role, *path;
} out_input;

/* How a program is told to replace what exists (its flag), for messages. */
#define OUT_OVERWRITE_HOW "--overwrite replaces it"

/*
 * Whether program may write the file path.  0 when nothing is there, or
 * when a regular file is there, overwrite is set and it is none of the
 * inputs (compared by device and inode, so that another path, a hard
 * link or a symbolic link to an input is found too).  Otherwise -1 after
 * one line on stderr naming path and the problem:
 *   "PROGRAM: PATH is the same file as ROLE INPUT, which this run reads:
 *    write to another file" (whatever overwrite says);
 *   "PROGRAM: PATH exists and is a folder (a FIFO, ...), not a file";
 *   "PROGRAM: PATH exists: HOW" (how: what replaces it, as
 *    OUT_OVERWRITE_HOW).
 * A symbolic link that leads nowhere counts as existing: writing would
 * replace it.
 */
int out_file_check(const char *program, const char *path, int overwrite,
                   const char *how, const out_input *inputs,
                   size_t n_inputs);

/*
 * Whether program may write a set of files it does not name itself (the
 * library does) into the folder dir: 0 when dir is missing, empty, or
 * overwrite is set; otherwise -1 after "PROGRAM: DIR holds files already:
 * HOW" on stderr.  What dir holds is not looked at further: a file of
 * the same name would be replaced.
 */
int out_folder_check(const char *program, const char *dir, int overwrite,
                     const char *how);

#endif
