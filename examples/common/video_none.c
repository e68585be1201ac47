/* video.h for a build without FFmpeg's libraries: nothing can be written. */
#include "video.h"

#include <stdio.h>

int video_supported(void)
{
    return 0;
}

video *video_open(const char *program, const char *path, uint32_t width,
                  uint32_t height, unsigned fps)
{
    fprintf(stderr, "%s: %s: this build has no video output\n", program,
            path);
    return NULL;
}

const char *video_codec(const video *v)
{
    return "none";
}

int video_write(video *v, const float *rgb)
{
    return -1;
}

int video_finish(video *v)
{
    return -1;
}

void video_discard(video *v)
{
}
