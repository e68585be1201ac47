/*
 * Reading zip archives held in memory (what NumPy's .npz files are).  The
 * central directory is the only authority on member names and sizes: the
 * local headers are checked only for their signature and name, because
 * NumPy writes them in zip64 form (sizes 0xFFFFFFFF plus a zip64 extra
 * field) even for small members.  Archives that need zip64 in the central
 * directory, span disks or are encrypted are refused.
 *
 * Every offset and size is checked against the buffer, so a corrupt
 * archive gives NERF_EFORMAT, never an out-of-bounds read.  Messages do not
 * name the archive's file; callers add it with nerf__error_prefix().
 */
#ifndef NERF_IO_ZIP_READ_H
#define NERF_IO_ZIP_READ_H

#include <stddef.h>
#include <stdint.h>

#include "env.h"

typedef struct nerf__zip_entry {
    const char *name;   /* name_len bytes inside the archive, no NUL */
    size_t name_len;
    uint16_t method;    /* 0 stored, 8 deflate; others fail to extract */
    uint32_t crc;       /* CRC-32 of the uncompressed data */
    size_t comp_size;
    size_t size;        /* uncompressed */
    size_t data_offset; /* validated: data_offset + comp_size fits */
} nerf__zip_entry;

typedef struct nerf__zip {
    const unsigned char *buf; /* borrowed: must outlive the nerf__zip */
    size_t size;
    size_t count;
    nerf__zip_entry *entries;
} nerf__zip;

/*
 * Parse the end-of-central-directory record and the central directory of
 * buf[0, size), validating every entry and its local header.
 * Returns NERF_OK, NERF_EFORMAT or NERF_ENOMEM.
 */
int nerf__zip_open(nerf__zip *zip, const nerf__env *env, const void *buf,
                   size_t size);

/* Release what nerf__zip_open allocated; a zeroed zip is fine. */
void nerf__zip_close(nerf__zip *zip, const nerf__env *env);

/* The member called name (compared byte for byte), or NULL. */
const nerf__zip_entry *nerf__zip_find(const nerf__zip *zip, const char *name);

/*
 * Decompress a member into a buffer allocated through env (never NULL on
 * success; free with nerf__free), checking its size and CRC-32.  A member
 * declaring more than max_size bytes is refused before anything is
 * allocated.  Returns NERF_OK, NERF_EFORMAT or NERF_ENOMEM.
 */
int nerf__zip_extract(const nerf__zip *zip, const nerf__env *env,
                      const nerf__zip_entry *e, size_t max_size,
                      unsigned char **data_out);

#endif
