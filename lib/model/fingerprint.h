/*
 * What data a model was trained on, in brief: enough to tell, when a
 * checkpoint is resumed, that the dataset is not the one it was trained
 * on (lego's model on fern, another downscale, another scene of the same
 * size).  The trainer records it in the model; checkpoints carry it in an
 * optional section (docs/formats.md, "data").
 */
#ifndef NERF_MODEL_FINGERPRINT_H
#define NERF_MODEL_FINGERPRINT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Kinds of scene, as the dataset layer numbers them (nerf__dataset_kind). */
#define NERF__FINGERPRINT_BLENDER 1u
#define NERF__FINGERPRINT_LLFF 2u
#define NERF__FINGERPRINT_COLMAP 3u

/* Flags. */
#define NERF__FINGERPRINT_NDC 1u

typedef struct nerf__fingerprint {
    bool known;              /* false: no record (a model never trained
                                by a trainer, or an older checkpoint) */
    uint32_t count;          /* training images */
    uint32_t width, height;  /* of the stored images */
    uint32_t src_width, src_height; /* of the files, before downscaling */
    uint32_t kind;           /* NERF__FINGERPRINT_BLENDER, ... */
    uint32_t flags;          /* NERF__FINGERPRINT_NDC */
    float mean_rgb[3];       /* mean colour over all pixels */
    float near_bound, far_bound;
} nerf__fingerprint;

/* Bytes of the checkpoint section's body (a later writer may append). */
#define NERF__FINGERPRINT_SIZE 48u

void nerf__fingerprint_store(unsigned char *p, const nerf__fingerprint *f);

/* From a section body of len bytes; false when it is too short or holds
 * values no dataset has (the checkpoint is then corrupt). */
bool nerf__fingerprint_parse(const unsigned char *p, uint64_t len,
                             nerf__fingerprint *f);

/*
 * Whether b (the data at hand) differs from a (the recorded) enough to
 * say so: the aspects that differ, comma-separated, into what ("" when
 * none); the return value is their number.
 */
int nerf__fingerprint_compare(const nerf__fingerprint *a,
                              const nerf__fingerprint *b, char *what,
                              size_t what_size);

/* "100 images of 800x800 (blender, mean colour ..., near 2 far 6)";
 * with_word 0 leaves out the word "images" ("17 of 504x378 (...)"). */
void nerf__fingerprint_describe(const nerf__fingerprint *f, int with_word,
                                char *out, size_t out_size);

#endif
