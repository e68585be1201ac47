/*
 * nerf-frames: the photos of a video, for COLMAP and nerf-train.  Decodes
 * through FFmpeg's libraries (built only where meson finds them), keeps
 * the sharpest frame of each of --frames equal stretches of the video's
 * time, and writes them as JPEGs through libjpeg, named in the video's
 * order.  A front end, as docs/DESIGN says: libnerf never links FFmpeg.
 */
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/display.h>
#include <libavutil/imgutils.h>
#include <libswscale/swscale.h>

#include <errno.h>
#include <jpeglib.h>
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/interrupt.h"
#include "common/opt_table.h"
#include "common/out_file.h"
#include "common/out_folder.h"
#include "common/progress.h"
#include "common/shared_opts.h"

#define PROG "nerf-frames"

/* Five digits in the names: frame_00000.jpg .. frame_99999.jpg. */
#define FRAMES_MAX 99999
#define FRAMES_DEFAULT 150

static const char about[] =
    "Write the photos of the video FILE to DIR (created if missing) as\n"
    "frame_NNNNN.jpg, NNNNN counting from 00000 in the video's order: the\n"
    "video's time is cut into --frames equal stretches and each gives its\n"
    "sharpest frame (the highest variance of the Laplacian of its\n"
    "brightness), so that motion blur is left out.  The photos for\n"
    "scripts/colmap-train.sh, which runs this program on a video.\n";

static const char after[] =
    "A video of fewer frames than --frames gives all its frames.  Ctrl-C\n"
    "(SIGINT) stops, says how many photos are written and exits with\n"
    "status 130 (SIGTERM: 143).\n"
    "Examples:\n"
    "  nerf-frames --video walk.mp4 --out walk-photos\n"
    "  nerf-frames --video walk.mp4 --out walk-photos --frames 60\n";

typedef struct args {
    const char *video, *out;
    uint64_t frames, quality;
    int overwrite, list;
} args;

static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    a->frames = FRAMES_DEFAULT;
    a->quality = 95;
    const opt opts[] = {
        {.name = "--video", OPT_TEXT_TO(&a->video), .flags = OPT_REQUIRED,
         .value = "FILE",
         .help = "the video: any container and codec FFmpeg's\n"
                 "libraries read (required)"},
        {.name = "--out", OPT_TEXT_TO(&a->out), .flags = OPT_REQUIRED,
         .value = "DIR", .help = "the folder to write (required)"},
        {.name = "--frames", OPT_INT_IN(&a->frames, 1, FRAMES_MAX),
         .value = "N",
         .help = "photos to take, {range} (default {default}): as\n"
                 "many stretches of the video's time"},
        {.name = "--quality", OPT_INT_IN(&a->quality, 1, 100), .value = "Q",
         .help = "JPEG quality, {range} (default {default})"},
        {.name = "--list", OPT_FLAG_SETS(&a->list, 1),
         .help = "print a line for each photo on stdout: its name,\n"
                 "the frame it is (counting from 0), its time in\n"
                 "seconds and its sharpness (default off)"},
        {OPT_OVERWRITE(&a->overwrite),
         .help = "write into DIR even if it holds files, replacing\n"
                 "photos of the same names (default off: a DIR\n"
                 "that holds anything is refused)"},
        {.name = NULL},
    };
    const opt_program p = {.name = PROG, .opts = opts, .column = 20,
                           .about = about, .after = after};
    return opt_parse(&p, argc, argv);
}

/* ---- the video -------------------------------------------------------- */

typedef struct input {
    const char *path;
    AVFormatContext *fmt;
    AVCodecContext *dec;
    int stream;
    int turn; /* degrees clockwise the frames are turned to be upright */
} input;

static void close_input(input *in)
{
    avcodec_free_context(&in->dec);
    avformat_close_input(&in->fmt);
}

/* "PROG: PATH: WHAT[: FFmpeg's reason]" on stderr. */
static void say(const char *path, const char *what, int err)
{
    char msg[AV_ERROR_MAX_STRING_SIZE] = "";
    if (err < 0) {
        av_strerror(err, msg, sizeof msg);
    }
    fprintf(stderr, PROG ": %s: %s%s%s\n", path, what, err < 0 ? ": " : "",
            msg);
}

/*
 * What is not a regular file is refused before FFmpeg opens it: opening
 * a FIFO would wait for a writer that may never come.
 */
static int check_file(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        fprintf(stderr, PROG ": %s: %s\n", path,
                errno == ENOENT ? "no such file or folder" : strerror(errno));
        return -1;
    }
    const char *kind = S_ISDIR(st.st_mode)    ? "a folder, not a file"
                       : S_ISFIFO(st.st_mode) ? "a FIFO (named pipe), not a "
                                                "regular file"
                       : S_ISCHR(st.st_mode)  ? "a character device, not a "
                                                "regular file"
                       : S_ISSOCK(st.st_mode) ? "a socket, not a regular file"
                       : !S_ISREG(st.st_mode) ? "not a regular file"
                                              : NULL;
    if (kind != NULL) {
        fprintf(stderr, PROG ": %s: %s\n", path, kind);
        return -1;
    }
    return 0;
}

/*
 * Phones store a portrait video as landscape frames and a display matrix
 * that says how to turn them (FFmpeg's players turn them by it): the
 * photos are turned the same way, so that they stand as the user saw
 * them.  Degrees clockwise, 0, 90, 180 or 270; mirroring is not undone.
 */
static int upright_turn(const AVStream *st)
{
    const uint8_t *m = NULL;
#if LIBAVCODEC_VERSION_INT >= AV_VERSION_INT(60, 31, 100)
    const AVPacketSideData *sd = av_packet_side_data_get(
        st->codecpar->coded_side_data, st->codecpar->nb_coded_side_data,
        AV_PKT_DATA_DISPLAYMATRIX);
    m = sd != NULL && sd->size >= 9 * sizeof(int32_t) ? sd->data : NULL;
#else
    size_t size = 0;
    m = av_stream_get_side_data(st, AV_PKT_DATA_DISPLAYMATRIX, &size);
    m = size >= 9 * sizeof(int32_t) ? m : NULL;
#endif
    if (m == NULL) {
        return 0;
    }
    /* The matrix turns counter-clockwise by the angle given. */
    double angle = -av_display_rotation_get((const int32_t *)(const void *)m);
    if (angle != angle) { /* NaN: a degenerate matrix */
        return 0;
    }
    long q = lround(angle / 90.0);
    return (int)(((q % 4) + 4) % 4) * 90;
}

/* src (w x h RGB) turned clockwise by turn degrees into dst. */
static void turn_rgb(const uint8_t *src, int w, int h, int turn,
                     uint8_t *dst)
{
    int ow = turn == 180 ? w : h;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            int ox, oy;
            if (turn == 90) {
                ox = h - 1 - y;
                oy = x;
            } else if (turn == 270) {
                ox = y;
                oy = w - 1 - x;
            } else {
                ox = w - 1 - x;
                oy = h - 1 - y;
            }
            memcpy(dst + 3 * ((size_t)oy * ow + ox),
                   src + 3 * ((size_t)y * w + x), 3);
        }
    }
}

/* Open path's best video stream and its decoder; 0, or -1 after a line
 * naming path. */
static int open_input(input *in, const char *path)
{
    memset(in, 0, sizeof *in);
    in->path = path;
    in->stream = -1;
    int rc = avformat_open_input(&in->fmt, path, NULL, NULL);
    if (rc < 0) {
        say(path, "not a video FFmpeg can read", rc);
        return -1;
    }
    rc = avformat_find_stream_info(in->fmt, NULL);
    if (rc < 0) {
        say(path, "not a video FFmpeg can read (no stream information)", rc);
        close_input(in);
        return -1;
    }
    const AVCodec *codec = NULL;
    rc = av_find_best_stream(in->fmt, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
    if (rc == AVERROR_STREAM_NOT_FOUND) {
        /* What it has instead, so that a user knows what they gave. */
        char kinds[160] = "";
        size_t used = 0;
        for (unsigned s = 0; s < in->fmt->nb_streams && used < 120; s++) {
            const char *k = av_get_media_type_string(
                in->fmt->streams[s]->codecpar->codec_type);
            int w = snprintf(kinds + used, sizeof kinds - used, "%s%s",
                             s ? ", " : "", k ? k : "unknown");
            used += w > 0 ? (size_t)w : 0;
        }
        fprintf(stderr, PROG ": %s: has no video stream (%s%s)\n", path,
                in->fmt->nb_streams ? "its streams: " : "no streams at all",
                kinds);
        close_input(in);
        return -1;
    }
    if (rc < 0 || codec == NULL) {
        say(path, "no decoder for its video stream's codec in this "
                  "FFmpeg", rc);
        close_input(in);
        return -1;
    }
    in->stream = rc;
    in->turn = upright_turn(in->fmt->streams[rc]);
    /* FFmpeg reads a lone photo as a video of one frame (its image2 and
     * *_pipe demuxers): a photo belongs in a folder of photos. */
    const char *demuxer = in->fmt->iformat->name;
    if (strcmp(demuxer, "image2") == 0 || strstr(demuxer, "_pipe") != NULL) {
        fprintf(stderr, PROG ": %s: a still image (%s), not a video: put "
                "photos in a folder instead\n", path, demuxer);
        close_input(in);
        return -1;
    }
    in->dec = avcodec_alloc_context3(codec);
    if (in->dec == NULL) {
        say(path, "out of memory for the decoder", 0);
        close_input(in);
        return -1;
    }
    AVStream *st = in->fmt->streams[in->stream];
    rc = avcodec_parameters_to_context(in->dec, st->codecpar);
    if (rc >= 0) {
        rc = avcodec_open2(in->dec, codec, NULL);
    }
    if (rc < 0) {
        say(path, "cannot start the video decoder", rc);
        close_input(in);
        return -1;
    }
    return 0;
}

/* The video stream's presentation times: the first, the last and how
 * many packets, read without decoding. */
typedef struct timeline {
    uint64_t count;
    int64_t first, last; /* in the stream's time base */
    int timed;           /* every packet had a time */
} timeline;

static int read_timeline(input *in, timeline *tl)
{
    memset(tl, 0, sizeof *tl);
    tl->timed = 1;
    AVPacket *pkt = av_packet_alloc();
    if (pkt == NULL) {
        say(in->path, "out of memory", 0);
        return -1;
    }
    int rc;
    while ((rc = av_read_frame(in->fmt, pkt)) >= 0) {
        if (pkt->stream_index == in->stream) {
            int64_t t = pkt->pts != AV_NOPTS_VALUE ? pkt->pts : pkt->dts;
            if (t == AV_NOPTS_VALUE) {
                tl->timed = 0;
            } else if (tl->count == 0 || tl->timed == 0) {
                tl->first = tl->last = t;
            } else {
                tl->first = t < tl->first ? t : tl->first;
                tl->last = t > tl->last ? t : tl->last;
            }
            tl->count++;
        }
        av_packet_unref(pkt);
    }
    av_packet_free(&pkt);
    if (rc != AVERROR_EOF) {
        say(in->path, "cannot read the video", rc);
        return -1;
    }
    return 0;
}

/* ---- choosing frames -------------------------------------------------- */

/*
 * Sharpness as the variance of the Laplacian of the brightness: blur from
 * a moving hand or a missed focus takes away the fine detail first, which
 * is where the Laplacian (the second difference across a pixel's four
 * neighbours) is large, so a blurred frame's Laplacian varies little.  It
 * needs no threshold, and it is only compared between frames of the same
 * short stretch, which show nearly the same things: what a frame shows
 * changes the measure as much as blur does, so comparing across the
 * whole video would favour busy views, not sharp ones.
 */
static double sharpness(const uint8_t *rgb, int w, int h)
{
    if (w < 3 || h < 3) {
        return 0.0;
    }
    /* Brightness as BT.601 weighs the channels, in 8-bit fixed point. */
    uint8_t *y = malloc((size_t)w * h);
    if (y == NULL) {
        return 0.0;
    }
    for (size_t p = 0; p < (size_t)w * h; p++) {
        const uint8_t *c = rgb + 3 * p;
        y[p] = (uint8_t)((77u * c[0] + 150u * c[1] + 29u * c[2] + 128u) >> 8);
    }
    double sum = 0.0, sum2 = 0.0;
    for (int r = 1; r < h - 1; r++) {
        const uint8_t *row = y + (size_t)r * w;
        for (int c = 1; c < w - 1; c++) {
            double lap = (double)row[c - 1] + row[c + 1] + row[c - w] +
                         row[c + w] - 4.0 * row[c];
            sum += lap;
            sum2 += lap * lap;
        }
    }
    free(y);
    double n = (double)(w - 2) * (h - 2);
    double mean = sum / n;
    return sum2 / n - mean * mean;
}

/* Write rgb (w x h, 3 bytes a pixel) as a JPEG; 0, or -1 after a line
 * naming path. */
typedef struct jpeg_fail {
    struct jpeg_error_mgr mgr;
    jmp_buf back;
} jpeg_fail;

static void jpeg_fail_exit(j_common_ptr cinfo)
{
    jpeg_fail *f = (jpeg_fail *)cinfo->err;
    longjmp(f->back, 1);
}

static int write_jpeg(const char *path, const uint8_t *rgb, int w, int h,
                      int quality)
{
    FILE *fp = fopen(path, "wb");
    if (fp == NULL) {
        fprintf(stderr, PROG ": %s: cannot be written: %s\n", path,
                strerror(errno));
        return -1;
    }
    struct jpeg_compress_struct cinfo;
    jpeg_fail fail;
    cinfo.err = jpeg_std_error(&fail.mgr);
    fail.mgr.error_exit = jpeg_fail_exit;
    if (setjmp(fail.back)) {
        char msg[JMSG_LENGTH_MAX];
        fail.mgr.format_message((j_common_ptr)&cinfo, msg);
        jpeg_destroy_compress(&cinfo);
        fclose(fp);
        remove(path);
        fprintf(stderr, PROG ": %s: cannot be written: %s\n", path, msg);
        return -1;
    }
    jpeg_create_compress(&cinfo);
    jpeg_stdio_dest(&cinfo, fp);
    cinfo.image_width = (JDIMENSION)w;
    cinfo.image_height = (JDIMENSION)h;
    cinfo.input_components = 3;
    cinfo.in_color_space = JCS_RGB;
    jpeg_set_defaults(&cinfo);
    jpeg_set_quality(&cinfo, quality, TRUE);
    jpeg_start_compress(&cinfo, TRUE);
    while (cinfo.next_scanline < cinfo.image_height) {
        JSAMPROW row = (JSAMPROW)(rgb + (size_t)cinfo.next_scanline * w * 3);
        jpeg_write_scanlines(&cinfo, &row, 1);
    }
    jpeg_finish_compress(&cinfo);
    jpeg_destroy_compress(&cinfo);
    if (fclose(fp) != 0) {
        fprintf(stderr, PROG ": %s: cannot be written: %s\n", path,
                strerror(errno));
        remove(path);
        return -1;
    }
    return 0;
}

/* The run: frames decoded so far, the stretch being looked at and its
 * sharpest frame. */
typedef struct picker {
    const args *a;
    uint64_t n;       /* stretches */
    uint64_t decoded; /* frames decoded */
    int64_t stretch;  /* the current one, -1 before the first frame */
    double best_score;
    uint64_t best_frame; /* its place in the video, counting from 0 */
    double best_time;    /* its time, seconds; NAN: none */
    uint8_t *cur, *best; /* RGB frames, w x h */
    int w, h;
    uint64_t written;
    struct SwsContext *sws;
    int turn;         /* input.turn */
    uint8_t *turned;  /* best, turned upright; NULL when turn is 0 */
} picker;

static int flush_stretch(picker *pk)
{
    if (pk->stretch < 0) {
        return 0;
    }
    char path[4096];
    int len = snprintf(path, sizeof path, "%s/frame_%05llu.jpg", pk->a->out,
                       (unsigned long long)pk->written);
    if (len < 0 || (size_t)len >= sizeof path) {
        fprintf(stderr, PROG ": %s: the path is too long\n", pk->a->out);
        return -1;
    }
    const uint8_t *px = pk->best;
    int w = pk->w, h = pk->h;
    if (pk->turn != 0) {
        turn_rgb(pk->best, pk->w, pk->h, pk->turn, pk->turned);
        px = pk->turned;
        if (pk->turn != 180) {
            w = pk->h;
            h = pk->w;
        }
    }
    if (write_jpeg(path, px, w, h, (int)pk->a->quality) != 0) {
        return -1;
    }
    if (pk->a->list) {
        printf("frame_%05llu.jpg %llu %.3f %.1f\n",
               (unsigned long long)pk->written,
               (unsigned long long)pk->best_frame, pk->best_time,
               pk->best_score);
        fflush(stdout);
    }
    pk->written++;
    pk->stretch = -1;
    return 0;
}

/* Look at one decoded frame, which falls in stretch k. */
static int take_frame(picker *pk, const AVFrame *f, int64_t k, double time,
                      const char *path)
{
    if (pk->cur == NULL) {
        pk->w = f->width;
        pk->h = f->height;
        pk->cur = malloc((size_t)pk->w * pk->h * 3);
        pk->best = malloc((size_t)pk->w * pk->h * 3);
        if (pk->turn != 0) {
            pk->turned = malloc((size_t)pk->w * pk->h * 3);
        }
        if (pk->cur == NULL || pk->best == NULL ||
            (pk->turn != 0 && pk->turned == NULL)) {
            say(path, "out of memory for its frames", 0);
            return -1;
        }
    }
    if (f->width != pk->w || f->height != pk->h) {
        fprintf(stderr, PROG ": %s: its frames change size (%dx%d, then "
                "%dx%d); COLMAP's one camera needs one size\n", path, pk->w,
                pk->h, f->width, f->height);
        return -1;
    }
    pk->sws = sws_getCachedContext(pk->sws, f->width, f->height,
                                   (enum AVPixelFormat)f->format, f->width,
                                   f->height, AV_PIX_FMT_RGB24,
                                   SWS_BICUBIC | SWS_ACCURATE_RND, NULL,
                                   NULL, NULL);
    if (pk->sws == NULL) {
        say(path, "cannot convert its frames to RGB", 0);
        return -1;
    }
    uint8_t *dst[1] = {pk->cur};
    const int stride[1] = {pk->w * 3};
    sws_scale(pk->sws, (const uint8_t *const *)f->data, f->linesize, 0,
              f->height, dst, stride);
    if (k != pk->stretch && flush_stretch(pk) != 0) {
        return -1;
    }
    double score = sharpness(pk->cur, pk->w, pk->h);
    if (pk->stretch < 0 || score > pk->best_score) {
        uint8_t *t = pk->best;
        pk->best = pk->cur;
        pk->cur = t;
        pk->best_score = score;
        pk->best_frame = pk->decoded;
        pk->best_time = time;
        pk->stretch = k;
    }
    return 0;
}

/* The stretch a frame falls in: by its time when every packet had one,
 * else by its place among the frames. */
static int64_t stretch_of(const picker *pk, const timeline *tl,
                          const AVFrame *f)
{
    uint64_t n = pk->n;
    int64_t t = f->best_effort_timestamp;
    if (tl->timed && t != AV_NOPTS_VALUE && tl->last > tl->first) {
        /* The span ends one frame's time after the last frame starts, so
         * that the last stretch is as long as the others. */
        double frame = (double)(tl->last - tl->first) / (double)(tl->count - 1);
        double span = (double)(tl->last - tl->first) + frame;
        double u = (double)(t - tl->first) / span;
        int64_t k = (int64_t)(u * (double)n);
        return k < 0 ? 0 : k >= (int64_t)n ? (int64_t)n - 1 : k;
    }
    uint64_t k = pk->decoded * n / tl->count;
    return (int64_t)(k >= n ? n - 1 : k);
}

enum { DONE = 0, FAILED = 1, INTERRUPTED = 2 };

static int decode_all(input *in, picker *pk, const timeline *tl,
                      progress *bar)
{
    AVPacket *pkt = av_packet_alloc();
    AVFrame *f = av_frame_alloc();
    int result = pkt && f ? DONE : FAILED;
    if (result == FAILED) {
        say(in->path, "out of memory", 0);
    }
    int eof = 0;
    while (result == DONE && !eof) {
        if (interrupted) {
            result = INTERRUPTED;
            break;
        }
        int rc = av_read_frame(in->fmt, pkt);
        if (rc == AVERROR_EOF) {
            eof = 1;
            rc = avcodec_send_packet(in->dec, NULL); /* drain */
        } else if (rc < 0) {
            say(in->path, "cannot read the video", rc);
            result = FAILED;
            break;
        } else if (pkt->stream_index != in->stream) {
            av_packet_unref(pkt);
            continue;
        } else {
            rc = avcodec_send_packet(in->dec, pkt);
            av_packet_unref(pkt);
        }
        if (rc < 0 && rc != AVERROR_EOF) {
            say(in->path, "cannot decode the video", rc);
            result = FAILED;
            break;
        }
        while (result == DONE) {
            rc = avcodec_receive_frame(in->dec, f);
            if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) {
                break;
            }
            if (rc < 0) {
                say(in->path, "cannot decode the video", rc);
                result = FAILED;
                break;
            }
            int64_t k = stretch_of(pk, tl, f);
            AVRational tb = in->fmt->streams[in->stream]->time_base;
            double time = f->best_effort_timestamp != AV_NOPTS_VALUE
                              ? (double)f->best_effort_timestamp * av_q2d(tb)
                              : NAN;
            if (take_frame(pk, f, k, time, in->path) != 0) {
                result = FAILED;
            }
            pk->decoded++;
            av_frame_unref(f);
            char note[64];
            snprintf(note, sizeof note, "frames, %llu photos written",
                     (unsigned long long)pk->written);
            progress_update(bar, pk->decoded < tl->count ? pk->decoded
                                                         : tl->count, note);
        }
    }
    av_packet_free(&pkt);
    av_frame_free(&f);
    return result;
}

int main(int argc, char **argv)
{
    args a;
    if (parse(argc, argv, &a) != 0) {
        return 2;
    }
    if (out_folder_check(PROG, a.out, a.overwrite, "--overwrite writes the "
                         "photos into it, replacing files of the same "
                         "names") != 0) {
        return 2;
    }
    if (check_file(a.video) != 0) {
        return 1;
    }
    /* FFmpeg's own notes would interleave with the progress; its errors
     * still show. */
    av_log_set_level(AV_LOG_ERROR);
    input in;
    timeline tl;
    if (open_input(&in, a.video) != 0) {
        return 1;
    }
    int rc = read_timeline(&in, &tl);
    close_input(&in);
    if (rc != 0) {
        return 1;
    }
    if (tl.count == 0) {
        fprintf(stderr, PROG ": %s: has no frames (its video stream is "
                "empty)\n", a.video);
        return 1;
    }
    /* Read again from the start: a rewind by seeking is not offered by
     * every container. */
    if (open_input(&in, a.video) != 0) {
        return 1;
    }
    if (out_ready_folder(a.out, PROG) != 0) {
        close_input(&in);
        return 1;
    }
    interrupt_catch(1);
    picker pk = {.a = &a, .n = a.frames < tl.count ? a.frames : tl.count,
                 .turn = in.turn,
                 .stretch = -1};
    if (tl.count < a.frames) {
        fprintf(stderr, PROG ": %s has %llu frames, fewer than --frames "
                "%llu: taking them all\n", a.video,
                (unsigned long long)tl.count, (unsigned long long)a.frames);
    }
    progress bar;
    progress_begin(&bar, PROG, tl.count);
    int result = decode_all(&in, &pk, &tl, &bar);
    if (result == DONE && flush_stretch(&pk) != 0) {
        result = FAILED;
    }
    if (result == DONE && pk.decoded == 0) {
        fprintf(stderr, PROG ": %s: has no frames (none of its %llu "
                "packets decoded to a picture)\n", a.video,
                (unsigned long long)tl.count);
        result = FAILED;
    }
    if (result == DONE) {
        char note[4400];
        int upright = pk.turn == 90 || pk.turn == 270;
        char turned[48] = "";
        if (pk.turn != 0) {
            snprintf(turned, sizeof turned, ", turned %d degrees as the "
                     "video says", pk.turn);
        }
        snprintf(note, sizeof note, "(%llu of %llu frames, %dx%d%s, to %s)",
                 (unsigned long long)pk.written,
                 (unsigned long long)pk.decoded, upright ? pk.h : pk.w,
                 upright ? pk.w : pk.h, turned, a.out);
        progress_end(&bar, note);
    } else if (bar.tty) {
        fputc('\n', stderr);
    }
    if (result == INTERRUPTED) {
        fprintf(stderr, PROG ": interrupted: %s holds the first %llu "
                "photos\n", a.out, (unsigned long long)pk.written);
    }
    sws_freeContext(pk.sws);
    free(pk.cur);
    free(pk.best);
    free(pk.turned);
    close_input(&in);
    return result == DONE          ? 0
           : result == INTERRUPTED ? 128 + (int)interrupted
                                   : 1;
}
