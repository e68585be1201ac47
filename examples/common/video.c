/* MP4 videos through FFmpeg's libraries (see video.h). */
#include "video.h"

#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct video {
    const char *program;
    char *path, *tmp;
    const char *codec_name;
    AVFormatContext *fmt;
    AVCodecContext *enc;
    AVStream *stream;
    struct SwsContext *sws;
    AVFrame *frame;
    AVPacket *pkt;
    uint8_t *rgb8; /* one frame as 8-bit RGB, the input of the conversion */
    uint32_t width, height;
    int64_t next_pts;
    int created; /* the temporary file exists */
};

int video_supported(void)
{
    return 1;
}

static void report(const video *v, const char *what, int err)
{
    char msg[AV_ERROR_MAX_STRING_SIZE] = "";
    if (err < 0) {
        av_strerror(err, msg, sizeof msg);
    }
    fprintf(stderr, "%s: %s: %s%s%s\n", v->program, v->path, what,
            err < 0 ? ": " : "", msg);
}

/* H.264 plays everywhere; Debian's libavcodec encodes it through libx264.
 * A libavcodec built without it still has its own MPEG-4 part 2. */
static const AVCodec *pick_encoder(const char **name)
{
    const AVCodec *c = avcodec_find_encoder_by_name("libx264");
    if (c != NULL) {
        *name = "H.264 (libx264)";
        return c;
    }
    *name = "MPEG-4 part 2";
    return avcodec_find_encoder(AV_CODEC_ID_MPEG4);
}

static void free_video(video *v)
{
    if (v->fmt != NULL) {
        avio_closep(&v->fmt->pb);
        avformat_free_context(v->fmt);
    }
    avcodec_free_context(&v->enc);
    sws_freeContext(v->sws);
    av_frame_free(&v->frame);
    av_packet_free(&v->pkt);
    free(v->rgb8);
    free(v->path);
    free(v->tmp);
    free(v);
}

void video_discard(video *v)
{
    if (v == NULL) {
        return;
    }
    if (v->fmt != NULL) {
        avio_closep(&v->fmt->pb);
    }
    if (v->created) {
        remove(v->tmp);
    }
    free_video(v);
}

static int configure_encoder(video *v, const AVCodec *codec, unsigned fps)
{
    AVCodecContext *e = v->enc;
    e->width = (int)v->width;
    e->height = (int)v->height;
    e->time_base = (AVRational){1, (int)fps};
    e->framerate = (AVRational){(int)fps, 1};
    e->pix_fmt = AV_PIX_FMT_YUV420P;
    /* What the conversion below produces from the renderer's sRGB
     * values, said in the file so that players need not guess. */
    e->color_range = AVCOL_RANGE_MPEG;
    e->colorspace = AVCOL_SPC_SMPTE170M;
    e->color_primaries = AVCOL_PRI_BT709;
    e->color_trc = AVCOL_TRC_IEC61966_2_1;
    if (codec->id == AV_CODEC_ID_H264) {
        /* Renders are smooth: near-transparent quality stays small. */
        av_opt_set(e->priv_data, "crf", "18", 0);
    } else {
        /* MPEG-4 part 2 defaults to a low bit rate that smears detail;
         * a fixed quantiser keeps it sharp at any size. */
        e->flags |= AV_CODEC_FLAG_QSCALE;
        e->global_quality = FF_QP2LAMBDA * 3;
    }
    if (v->fmt->oformat->flags & AVFMT_GLOBALHEADER) {
        e->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    }
    int rc = avcodec_open2(e, codec, NULL);
    if (rc < 0) {
        report(v, "cannot start the video encoder", rc);
        return -1;
    }
    rc = avcodec_parameters_from_context(v->stream->codecpar, e);
    if (rc < 0) {
        report(v, "cannot describe the video stream", rc);
        return -1;
    }
    v->stream->time_base = e->time_base;
    v->stream->avg_frame_rate = e->framerate;
    return 0;
}

static int open_file(video *v)
{
    int rc = avio_open(&v->fmt->pb, v->tmp, AVIO_FLAG_WRITE);
    if (rc < 0) {
        report(v, "cannot create the video file", rc);
        return -1;
    }
    v->created = 1;
    /* The index at the front, so that players can start before the end
     * of the file has arrived (the web's progressive download). */
    AVDictionary *opts = NULL;
    av_dict_set(&opts, "movflags", "+faststart", 0);
    rc = avformat_write_header(v->fmt, &opts);
    av_dict_free(&opts);
    if (rc < 0) {
        report(v, "cannot write the MP4 header", rc);
        return -1;
    }
    return 0;
}

static int alloc_buffers(video *v)
{
    v->frame = av_frame_alloc();
    v->pkt = av_packet_alloc();
    v->rgb8 = malloc((size_t)v->width * v->height * 3);
    if (v->frame == NULL || v->pkt == NULL || v->rgb8 == NULL) {
        report(v, "out of memory for the video's buffers", 0);
        return -1;
    }
    v->frame->format = AV_PIX_FMT_YUV420P;
    v->frame->width = (int)v->width;
    v->frame->height = (int)v->height;
    int rc = av_frame_get_buffer(v->frame, 0);
    if (rc < 0) {
        report(v, "cannot allocate a video frame", rc);
        return -1;
    }
    /* Same size in and out: only the colour model changes. */
    v->sws = sws_getContext((int)v->width, (int)v->height, AV_PIX_FMT_RGB24,
                            (int)v->width, (int)v->height,
                            AV_PIX_FMT_YUV420P,
                            SWS_BICUBIC | SWS_ACCURATE_RND, NULL, NULL, NULL);
    if (v->sws == NULL) {
        report(v, "cannot set up the RGB to YUV conversion", 0);
        return -1;
    }
    return 0;
}

video *video_open(const char *program, const char *path, uint32_t width,
                  uint32_t height, unsigned fps)
{
    video *v = calloc(1, sizeof *v);
    if (v == NULL) {
        fprintf(stderr, "%s: %s: out of memory\n", program, path);
        return NULL;
    }
    v->program = program;
    v->width = width;
    v->height = height;
    size_t n = strlen(path);
    v->path = malloc(n + 1);
    v->tmp = malloc(n + sizeof ".partial");
    if (v->path == NULL || v->tmp == NULL) {
        fprintf(stderr, "%s: %s: out of memory\n", program, path);
        free_video(v);
        return NULL;
    }
    memcpy(v->path, path, n + 1);
    memcpy(v->tmp, path, n);
    memcpy(v->tmp + n, ".partial", sizeof ".partial");
    if (width % 2 != 0 || height % 2 != 0) {
        fprintf(stderr, "%s: %s: cannot encode %ux%u frames: the width and "
                        "height must be even (the codecs keep colour at "
                        "half resolution)\n",
                program, path, (unsigned)width, (unsigned)height);
        free_video(v);
        return NULL;
    }
    /* FFmpeg's own notes (libx264's statistics, say) would interleave with
     * the program's progress; its errors still show. */
    av_log_set_level(AV_LOG_ERROR);
    const AVCodec *codec = pick_encoder(&v->codec_name);
    if (codec == NULL) {
        report(v, "FFmpeg's libavcodec has neither libx264 nor an MPEG-4 "
                  "part 2 encoder", 0);
        free_video(v);
        return NULL;
    }
    /* MP4 whatever the name ends with: the option promises one. */
    int rc = avformat_alloc_output_context2(&v->fmt, NULL, "mp4", v->tmp);
    if (rc < 0 || v->fmt == NULL) {
        report(v, "cannot set up an MP4 file", rc);
        free_video(v);
        return NULL;
    }
    v->stream = avformat_new_stream(v->fmt, NULL);
    v->enc = avcodec_alloc_context3(codec);
    if (v->stream == NULL || v->enc == NULL) {
        report(v, "out of memory for the video encoder", 0);
        free_video(v);
        return NULL;
    }
    if (configure_encoder(v, codec, fps) != 0 || alloc_buffers(v) != 0 ||
        open_file(v) != 0) {
        video_discard(v);
        return NULL;
    }
    return v;
}

const char *video_codec(const video *v)
{
    return v->codec_name;
}

/* Send a frame (NULL: the end) and write every packet that comes out. */
static int encode(video *v, const AVFrame *frame)
{
    int rc = avcodec_send_frame(v->enc, frame);
    if (rc < 0) {
        report(v, "cannot encode a frame", rc);
        return -1;
    }
    for (;;) {
        rc = avcodec_receive_packet(v->enc, v->pkt);
        if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) {
            return 0;
        }
        if (rc < 0) {
            report(v, "cannot encode a frame", rc);
            return -1;
        }
        /* The muxer may have chosen a finer time base than the codec's. */
        av_packet_rescale_ts(v->pkt, v->enc->time_base, v->stream->time_base);
        v->pkt->stream_index = v->stream->index;
        rc = av_interleaved_write_frame(v->fmt, v->pkt);
        if (rc < 0) {
            report(v, "cannot write to the video file", rc);
            return -1;
        }
    }
}

/* Round to the nearest 8-bit level as the PNG frames do; NaN is 0. */
static uint8_t quantize(float x)
{
    if (!(x > 0.0f)) {
        return 0;
    }
    if (x >= 1.0f) {
        return 255;
    }
    return (uint8_t)(x * 255.0f + 0.5f);
}

int video_write(video *v, const float *rgb)
{
    size_t n = (size_t)v->width * v->height * 3;
    for (size_t k = 0; k < n; k++) {
        v->rgb8[k] = quantize(rgb[k]);
    }
    /* The encoder may still hold the previous frame's buffer. */
    int rc = av_frame_make_writable(v->frame);
    if (rc < 0) {
        report(v, "cannot reuse the video frame", rc);
        return -1;
    }
    const uint8_t *src[1] = {v->rgb8};
    const int stride[1] = {(int)v->width * 3};
    sws_scale(v->sws, src, stride, 0, (int)v->height, v->frame->data,
              v->frame->linesize);
    v->frame->pts = v->next_pts++;
    return encode(v, v->frame);
}

int video_finish(video *v)
{
    int ok = encode(v, NULL) == 0;
    if (ok) {
        int rc = av_write_trailer(v->fmt);
        if (rc < 0) {
            report(v, "cannot finish the MP4 file", rc);
            ok = 0;
        }
    }
    if (ok) {
        int rc = avio_closep(&v->fmt->pb);
        if (rc < 0) {
            report(v, "cannot write the video file", rc);
            ok = 0;
        }
    }
    if (ok && rename(v->tmp, v->path) != 0) {
        fprintf(stderr, "%s: %s: cannot move %s onto it: %s\n", v->program,
                v->path, v->tmp, strerror(errno));
        ok = 0;
    }
    if (ok) {
        v->created = 0;
        free_video(v);
        return 0;
    }
    video_discard(v);
    return -1;
}
