/*
 * Whole-file reads and crash-safe writes.  Every error message starts with
 * the path, so callers can return the status unchanged.
 */
#ifndef NERF_IO_FILE_IO_H
#define NERF_IO_FILE_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "env.h"

/*
 * Whether path (through symbolic links) is a regular file, found with
 * stat alone: nothing is opened, so nothing can block.  This is the one
 * check every reader of the library makes before it reads a file.
 * Returns NERF_OK; NERF_ENOENT ("PATH: cannot open: No such file or
 * directory"); NERF_EUNRECOGNISED naming what path is instead: "PATH: a
 * folder, not a file", "PATH: a FIFO (named pipe), not a regular file",
 * a character or block device, a socket; NERF_EIO (cannot stat).
 */
int nerf__file_check_regular(const char *path);

/* What a file of this st_mode is, for messages: "a file", "a folder", "a
 * FIFO (named pipe)", "a character device", "a block device", "a socket". */
const char *nerf__file_kind(unsigned mode);

/*
 * Open the regular file at path for reading, without ever blocking on
 * something else: path is checked as by nerf__file_check_regular(), then
 * opened with O_NONBLOCK and checked again through the descriptor, so that
 * a FIFO put in its place in between is refused too.  On success *fd_out
 * (close it) reads normally and *size_out is the file's size.
 * Returns as nerf__file_check_regular(), and NERF_EIO when it cannot be
 * opened.
 */
int nerf__file_open_read(const char *path, int *fd_out, uint64_t *size_out);

/* The same as a stdio stream (fclose it). */
int nerf__file_fopen_read(const char *path, FILE **f_out, uint64_t *size_out);

/*
 * Read the regular file at path (nerf__file_open_read) into a buffer
 * allocated through env (free it with nerf__free).  A file larger than
 * max_size is refused, so that a stray multi-gigabyte file cannot exhaust
 * memory.  *data_out is never NULL on success, even for an empty file.
 * Returns NERF_OK; NERF_ENOENT (no such file); NERF_EUNRECOGNISED (a
 * folder, a FIFO, a device: anything but a regular file); NERF_EIO
 * (cannot open or read); NERF_EFORMAT (larger than max_size); NERF_ENOMEM.
 */
int nerf__file_read(const nerf__env *env, const char *path, uint64_t max_size,
                    unsigned char **data_out, size_t *size_out);

/*
 * The same for a file already open as fd (nerf__file_open_read, which
 * gave its size), read from its current offset; fd stays open.
 */
int nerf__file_read_fd(const nerf__env *env, const char *path, int fd,
                       uint64_t size, uint64_t max_size,
                       unsigned char **data_out, size_t *size_out);

/* A piece of the data written by nerf__file_write_atomic(). */
typedef struct nerf__span {
    const void *data;
    size_t size;
} nerf__span;

/*
 * Write the concatenation of parts to path so that path holds either its
 * old content or the complete new content, never a mix: the data goes to a
 * new file beside path ("path.tmp.<pid>.<n>"), is flushed to disk and then
 * renamed over path.  On failure the temporary file is removed and an
 * existing file at path is left untouched.
 * Returns NERF_OK; NERF_EIO; NERF_ENOMEM.
 */
int nerf__file_write_atomic(const nerf__env *env, const char *path,
                            const nerf__span *parts, size_t n_parts);

/*
 * Whether nerf__file_write_atomic(path) can create its temporary file:
 * creates one and removes it again, so that a path through a missing
 * folder, a regular file or a folder without write permission is found
 * before work that ends in a save, not by the save.  (A full disk or a
 * quota can still make the save fail.)
 * Returns NERF_OK; NERF_EIO naming path and the reason; NERF_ENOMEM.
 */
int nerf__file_check_writable(const nerf__env *env, const char *path);

/*
 * Remove the temporary files that writers of path killed before they
 * could clean up (kill -9, a crash) left beside it: names
 * "path.tmp.<pid>.<n>" exactly, whose pid is not a live process (kill(pid,
 * 0) reports ESRCH), never this process's own.  Best effort; returns how
 * many it removed.  The pid test assumes writers on this machine: on a
 * folder shared over the network, another host's live writer would look
 * dead, so call this only where one writer owns path (checkpoints).
 */
unsigned nerf__file_remove_stale_temps(const nerf__env *env, const char *path);

#endif
