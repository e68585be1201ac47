/*
 * nerf-viewer --fly: a camera path flown without a person, each frame the
 * window shows while moving kept, then scored against the full render of
 * the same view, so that the viewer's speed and what it shows while moving
 * are measured rather than claimed (docs/viewer.md, "Measuring").
 *
 * The path runs on the clock: at time t of S seconds the view is where a
 * hand moving at that pace would have put it, however long frames take, so
 * a slow frame shows as a jump, as it would to a person.  All-round scenes
 * (Blender-like, or none) turn once around the target; forward-facing
 * (LLFF) ones sway in a small loop about the first camera's view.  The
 * path ends where it started, and stops there.
 */
#ifndef NERF_VIEWER_FLY_H
#define NERF_VIEWER_FLY_H

#include <stddef.h>
#include <stdint.h>

#include "frame.h"
#include "orbit.h"

struct viewer;

typedef struct fly_frame {
    double u;         /* where on the path, 0 to 1 */
    double seconds;   /* from the frame before's showing to this one's */
    uint32_t w, h;    /* as rendered, before the window scales it */
    float *rgb;       /* w x h x 3, as rendered */
} fly_frame;

typedef struct fly {
    double seconds;      /* the path's length in time */
    int forward_facing;  /* sway in a loop rather than turn */
    orbit start;         /* the view the path starts and ends at */
    double t0;           /* when the path started; 0 before */
    double last_shown;   /* when the last frame was shown */
    double stopped_at;   /* when the path ended; 0 while moving */
    double full_at;      /* when the full render was shown after; 0 */
    double u;            /* where the view was last placed */
    fly_frame *frames;
    size_t n, cap;
} fly;

/* A path of `seconds` from the viewer's current view. */
void fly_init(fly *f, const struct viewer *v, double seconds);

/* Place the viewer's view where the path is at time now (starting the
 * path on the first call).  Returns 1 while moving; the call that finds
 * the path over puts the view at its end and returns 1 once more, so
 * that the view's last stretch is drawn; after that, 0. */
int fly_place(fly *f, struct viewer *v, double now);

/* The frame just shown at time now, drawn at the last placed view.
 * Returns a libnerf status (NERF_ENOMEM). */
int fly_record(fly *f, const frame *shown, double now);

/* Render the full view of every recorded frame, print each frame's time
 * and PSNR against it, then the summary, on stdout.  Returns a libnerf
 * status. */
int fly_report(fly *f, struct viewer *v);

void fly_free(fly *f);

#endif
