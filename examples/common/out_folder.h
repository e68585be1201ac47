/*
 * Output folders of the example programs: made when missing (as mkdir -p
 * does), so that a run is not refused, or lost, for want of a folder.
 */
#ifndef NERF_EXAMPLES_OUT_FOLDER_H
#define NERF_EXAMPLES_OUT_FOLDER_H

#include <stddef.h>

/*
 * Make the folder dir and any missing parents.  0 when dir is a folder
 * now (*created: 1 if this call made it); otherwise an errno value, and
 * failed holds the part of dir that could not be made (ENOTDIR: a part
 * that exists as a file).
 */
int out_make_folder(const char *dir, int *created, char *failed,
                    size_t failed_size);

/*
 * The folder that file lies in ("." for a bare name), made when missing,
 * saying so on stderr as program; 0 on success, else -1 after printing
 * "program: file: cannot be written: PART: REASON".
 */
int out_make_parent(const char *file, const char *program);

/*
 * The output folder dir, made when missing (saying so on stderr as
 * program) and found writable, before anything is computed for it; 0, or
 * -1 after printing "program: dir: cannot be written: REASON".
 */
int out_ready_folder(const char *dir, const char *program);

#endif
