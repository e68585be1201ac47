/* How far a render buffer grows past what a batch asked for. */
#ifndef NERF_RENDER_HEADROOM_H
#define NERF_RENDER_HEADROOM_H

#include <stddef.h>

/* Sample and ray counts vary from batch to batch; growing by an eighth
 * makes reallocations rare once they settle.  The batch's workspace and
 * the opacity cut's size theirs alike, so that a cut batch finds the room
 * its density pass took. */
static inline size_t nerf__with_headroom(size_t n)
{
    return n + n / 8 + 64;
}

#endif
