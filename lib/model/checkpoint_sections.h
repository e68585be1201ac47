/*
 * The sections of a checkpoint's payload (docs/formats.md), as one table:
 * each section's tag, name, when a file has it, how its body is written,
 * and how it is read back.  checkpoint.c walks the table to write a
 * payload, to split one it reads, and to build the model from it; nothing
 * else lists the sections.
 */
#ifndef NERF_MODEL_CHECKPOINT_SECTIONS_H
#define NERF_MODEL_CHECKPOINT_SECTIONS_H

#include <stdbool.h>
#include <stdint.h>

#include "byte_buf.h"
#include "model.h"

/* Bit 31 of a tag: a reader that does not know the section must refuse the
 * file; without it, unknown sections are skipped. */
#define NERF__CKPT_TAG_REQUIRED 0x80000000u
/* u32 tag, u64 length, before each body. */
#define NERF__CKPT_SECTION_HEAD 12u

/* A section's place in the table, which is the order a payload is written
 * in (not the order of the tags). */
enum {
    NERF__CKPT_OPTIONS,
    NERF__CKPT_TRAINING,
    NERF__CKPT_PARAMS,
    NERF__CKPT_ADAM_M,
    NERF__CKPT_ADAM_V,
    NERF__CKPT_OPTIONS2,
    NERF__CKPT_TRAINING2,
    NERF__CKPT_OCCUPANCY,
    NERF__CKPT_MATMUL,
    NERF__CKPT_SPACE,
    NERF__CKPT_RENDER,
    NERF__CKPT_WEIGHTS_ONLY,
    NERF__CKPT_DATA,
    NERF__CKPT_SCHEDULE,
    NERF__CKPT_BATCH,
    NERF__CKPT_AVERAGE,
    NERF__CKPT_CORRECTIONS,
    NERF__CKPT_APPEARANCE,
    NERF__CKPT_APPEARANCE_0_13,
    NERF__CKPT_N_SECTIONS
};

/* Flags of a section kind. */
enum {
    /* Every file has it (a weights-only file too, unless OPTIMISER). */
    NERF__CKPT_CORE = 1,
    /* Optimiser state: a weights-only file does not have it. */
    NERF__CKPT_OPTIMISER = 2,
    /* Noisy floats, which zlib copies rather than compresses. */
    NERF__CKPT_STORED = 4,
    /* Its body is always size bytes long. */
    NERF__CKPT_FIXED = 8,
    /* Its body is one float per parameter of the model. */
    NERF__CKPT_PER_PARAM = 16
};

/* What a save writes: the model, whole or as weights only. */
typedef struct nerf__ckpt_save {
    const nerf_model *m;
    bool weights_only;
} nerf__ckpt_save;

/* A payload being read: its known sections' bodies by table index (NULL:
 * not in the file). */
typedef struct nerf__ckpt_view {
    const unsigned char *body[NERF__CKPT_N_SECTIONS];
    uint64_t len[NERF__CKPT_N_SECTIONS];
} nerf__ckpt_view;

typedef struct nerf__ckpt_section nerf__ckpt_section;

struct nerf__ckpt_section {
    uint32_t tag;
    /* For messages: "no %s section", "two %s sections". */
    const char *name;
    unsigned flags;
    uint64_t size; /* with NERF__CKPT_FIXED */
    /* Whether a file of s has the section, beyond what the flags say
     * (NULL: it has). */
    bool (*wanted)(const nerf__ckpt_save *s);
    /* Appends the body to b (a failed allocation sticks in b). */
    void (*write)(nerf__buf *b, const nerf__ckpt_save *s);
    /* Before the model exists: the options the body holds, into o.  Called
     * only when the file has the section; NERF_OK or an error naming
     * path. */
    int (*read_options)(const char *path, const nerf__ckpt_section *k,
                        const unsigned char *b, nerf_model_options *o);
    /* Into the model made of those options.  Called for every section not
     * CORE, with b NULL when the file lacks it, so that what a file
     * without the section means is said here too. */
    int (*read)(const char *path, nerf_model *m, const unsigned char *b,
                uint64_t len, const nerf__ckpt_view *v);
    /* For the one-word sections: where the option is, the value a file
     * without the section implies, the largest known value. */
    size_t option;
    uint32_t implied, max;
};

extern const nerf__ckpt_section nerf__ckpt_sections[NERF__CKPT_N_SECTIONS];

/* Whether a file of s has section k. */
bool nerf__ckpt_written(const nerf__ckpt_section *k, const nerf__ckpt_save *s);

#endif
