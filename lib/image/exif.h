/*
 * The one Exif field libnerf needs: Orientation (tag 0x0112), which says
 * how a camera's stored pixels must be turned to stand upright.  A photo
 * read without it comes out rotated or mirrored, and its pose with it.
 */
#ifndef NERF_IMAGE_EXIF_H
#define NERF_IMAGE_EXIF_H

#include <stddef.h>
#include <stdint.h>

/*
 * Find the Orientation in the body of an APP1 marker (data[0..n), which
 * starts "Exif\0\0" and then a TIFF header).  On success *orientation is
 * 1..8, or 1 when IFD0 has no Orientation entry.  On failure returns
 * non-zero and writes a sentence saying what is wrong (the header, an
 * offset past the end, a bad entry type, a value outside 1..8) into why.
 * Only the TIFF header, IFD0's entry count and its entries are read; every
 * offset is checked against n.
 */
int nerf__exif_orientation(const uint8_t *data, size_t n,
                           uint32_t *orientation, char *why,
                           size_t why_size);

/* Whether an APP1 body is an Exif block (as opposed to XMP and others). */
int nerf__exif_is_exif(const uint8_t *data, size_t n);

#endif
