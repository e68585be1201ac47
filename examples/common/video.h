/*
 * MP4 output for the example programs, through FFmpeg's libraries.  They
 * are optional at build time (meson option 'video'): without them
 * video_none.c stands in and video_supported() says 0, so a program can
 * explain that and carry on with its PNG frames.  Only the programs link
 * FFmpeg, never libnerf.
 */
#ifndef NERF_EXAMPLES_VIDEO_H
#define NERF_EXAMPLES_VIDEO_H

#include <stdint.h>

typedef struct video video;

/* 1 when this build can write videos, 0 when FFmpeg was not found. */
int video_supported(void);

/*
 * Start an MP4 video of width x height pixels (both even: the codecs store
 * colour at half resolution) at fps frames a second, written to a
 * temporary file beside path and moved onto path by video_finish.  NULL on
 * failure, after a line on stderr that starts with program and names path.
 */
video *video_open(const char *program, const char *path, uint32_t width,
                  uint32_t height, unsigned fps);

/* The codec chosen, for messages: "H.264 (libx264)" or "MPEG-4 part 2". */
const char *video_codec(const video *v);

/* Append a frame of width x height RGB floats in [0, 1], top row first.
 * 0, or -1 after a line on stderr. */
int video_write(video *v, const float *rgb);

/* Flush the encoder, finish the file and move it onto its path; frees v.
 * 0, or -1 after a line on stderr (the temporary file is removed). */
int video_finish(video *v);

/* Give up: remove the temporary file and free v.  NULL is ignored. */
void video_discard(video *v);

#endif
