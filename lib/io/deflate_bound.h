/*
 * How far deflate (zlib streams, zip members, PNG image data) can expand
 * its input, which every reader of deflated data uses to judge a declared
 * size before believing it with an allocation.
 */
#ifndef NERF_IO_DEFLATE_BOUND_H
#define NERF_IO_DEFLATE_BOUND_H

/*
 * Deflate's longest match is 258 bytes, and it costs at least 2 bits (a
 * 1-bit length code and a 1-bit distance code in a dynamic block), so no
 * stream inflates to more than 258 / (2 / 8) = 1032 times its size.  A
 * header that claims more is corrupt or forged.
 */
#define NERF__DEFLATE_MAX_RATIO 1032u

#endif
