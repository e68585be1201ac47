#include "fly.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "viewer.h"

#define TWO_PI 6.283185307179586
/* A forward-facing capture covers a few degrees of view: the loop sways
 * the view by about as much as its cameras differ (radians about the
 * focus point the home view circles). */
#define SWAY_YAW 0.10
#define SWAY_PITCH 0.05
/* Frames scored against a full render at most, evenly spread over the
 * path: a full render of a slow model takes seconds. */
#define MAX_SCORED 60

void fly_init(fly *f, const viewer *v, double seconds)
{
    memset(f, 0, sizeof *f);
    f->seconds = seconds;
    f->start = v->view;
    f->forward_facing =
        v->dataset != NULL &&
        nerf_dataset_get_format(v->dataset) == NERF_DATASET_LLFF;
}

/* The view at u of the path (0 to 1): a whole turn, or a loop that
 * rises above the start and comes back to it. */
static void path_view(const fly *f, double u, orbit *out)
{
    *out = f->start;
    double a = TWO_PI * u;
    if (f->forward_facing) {
        out->yaw += SWAY_YAW * sin(a);
        out->pitch += SWAY_PITCH * (1.0 - cos(a));
    } else {
        out->yaw += a;
    }
}

int fly_place(fly *f, viewer *v, double now)
{
    if (f->stopped_at > 0.0) {
        return 0;
    }
    if (f->t0 == 0.0) {
        f->t0 = now;
        f->last_shown = now;
    }
    double u = (now - f->t0) / f->seconds;
    if (u >= 1.0) {
        /* The hand stopped when the path ended, whenever the loop looks:
         * a late look counts against the time to full quality. */
        u = 1.0;
        f->stopped_at = f->t0 + f->seconds;
    }
    f->u = u;
    path_view(f, u, &v->view);
    return 1;
}

int fly_record(fly *f, const frame *shown, double now)
{
    if (f->n == f->cap) {
        size_t cap = f->cap ? 2 * f->cap : 64;
        fly_frame *grown = realloc(f->frames, cap * sizeof *grown);
        if (grown == NULL) {
            return NERF_ENOMEM;
        }
        f->frames = grown;
        f->cap = cap;
    }
    size_t floats = (size_t)shown->width * shown->height * 3;
    fly_frame *fr = &f->frames[f->n];
    fr->rgb = malloc(floats * sizeof(float));
    if (fr->rgb == NULL) {
        return NERF_ENOMEM;
    }
    memcpy(fr->rgb, shown->rgb, floats * sizeof(float));
    fr->u = f->u;
    fr->seconds = now - f->last_shown;
    fr->w = shown->width;
    fr->h = shown->height;
    f->last_shown = now;
    f->n++;
    return NERF_OK;
}

/* Where output pixel i of n samples a source row or column of m pixels,
 * pixel centres aligned, as a display's linear scaling does: the lower
 * source pixel and the weight of the upper one. */
static void source_of(uint32_t i, uint32_t n, uint32_t m, uint32_t *lo,
                      float *wt)
{
    double s = ((double)i + 0.5) * m / n - 0.5;
    if (s < 0.0) {
        s = 0.0;
    }
    if (s > (double)(m - 1)) {
        s = (double)(m - 1);
    }
    *lo = (uint32_t)s;
    if (*lo >= m - 1) {
        *lo = m > 1 ? m - 2 : 0;
    }
    *wt = m > 1 ? (float)(s - *lo) : 0.0f;
}

/* The frame as the window shows it: scaled to W x H with linear
 * interpolation. */
static void scale_up(const fly_frame *fr, uint32_t W, uint32_t H, float *out)
{
    for (uint32_t y = 0; y < H; y++) {
        uint32_t y0;
        float ty;
        source_of(y, H, fr->h, &y0, &ty);
        uint32_t y1 = fr->h > 1 ? y0 + 1 : y0;
        for (uint32_t x = 0; x < W; x++) {
            uint32_t x0;
            float tx;
            source_of(x, W, fr->w, &x0, &tx);
            uint32_t x1 = fr->w > 1 ? x0 + 1 : x0;
            const float *a = fr->rgb + 3 * ((size_t)y0 * fr->w + x0);
            const float *b = fr->rgb + 3 * ((size_t)y0 * fr->w + x1);
            const float *c = fr->rgb + 3 * ((size_t)y1 * fr->w + x0);
            const float *d = fr->rgb + 3 * ((size_t)y1 * fr->w + x1);
            float *o = out + 3 * ((size_t)y * W + x);
            for (int k = 0; k < 3; k++) {
                float top = a[k] + tx * (b[k] - a[k]);
                float bottom = c[k] + tx * (d[k] - c[k]);
                o[k] = top + ty * (bottom - top);
            }
        }
    }
}

static int by_value(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

/* The nearest-rank percentile p (0 to 100) of n sorted values. */
static double rank(const double *sorted, size_t n, double p)
{
    /* p n first: exact for whole p, as the test's awk computes it. */
    size_t k = (size_t)ceil(p * (double)n / 100.0);
    return sorted[k > 0 ? k - 1 : 0];
}

/* Whether frame i of n is scored when at most MAX_SCORED are. */
static int scored(size_t i, size_t n)
{
    return n <= MAX_SCORED ||
           (i + 1) * MAX_SCORED / n > i * MAX_SCORED / n;
}

static void summarise(const fly *f, const viewer *v, double *ms,
                      double *psnr, size_t n_psnr)
{
    size_t n = f->n;
    qsort(ms, n, sizeof *ms, by_value);
    qsort(psnr, n_psnr, sizeof *psnr, by_value);
    printf("fly: %zu frames shown while moving, a %.1f s %s at %ux%u\n", n,
           f->seconds, f->forward_facing ? "loop" : "turn", v->width,
           v->height);
    printf("fly: frame time median %.1f ms, 95th percentile %.1f ms "
           "(nearest rank)\n",
           rank(ms, n, 50.0), rank(ms, n, 95.0));
    printf("fly: shown frames against the full render (%zu of %zu, evenly "
           "spread): median PSNR %.2f dB, lowest %.2f dB\n",
           n_psnr, n, rank(psnr, n_psnr, 50.0), psnr[0]);
    if (f->full_at > 0.0) {
        printf("fly: full quality %.2f s after the path stopped\n",
               f->full_at - f->stopped_at);
    } else {
        printf("fly: full quality not reached before the window closed\n");
    }
}

int fly_report(fly *f, viewer *v)
{
    if (f->n == 0) {
        printf("fly: no frame was shown\n");
        return NERF_OK;
    }
    size_t pixels = (size_t)v->width * v->height;
    float *scaled = malloc(pixels * 3 * sizeof(float));
    double *ms = malloc(f->n * sizeof *ms);
    double *psnr = malloc(f->n * sizeof *psnr);
    frame full;
    memset(&full, 0, sizeof full);
    int rc = scaled && ms && psnr ? NERF_OK : NERF_ENOMEM;
    orbit kept = v->view;
    size_t n_psnr = 0;
    for (size_t i = 0; i < f->n && rc == NERF_OK; i++) {
        const fly_frame *fr = &f->frames[i];
        ms[i] = 1e3 * fr->seconds;
        if (!scored(i, f->n)) {
            printf("frame %4zu  %8.1f ms  %4ux%-4u  psnr      -\n", i + 1,
                   ms[i], fr->w, fr->h);
            continue;
        }
        nerf_camera cam;
        path_view(f, fr->u, &v->view);
        rc = viewer_camera(v, v->width, v->height, &cam);
        if (rc == NERF_OK) {
            rc = frame_render(&full, v->renderer, NULL, &cam);
        }
        if (rc == NERF_OK) {
            scale_up(fr, v->width, v->height, scaled);
            rc = nerf_psnr(scaled, full.rgb, pixels * 3, &psnr[n_psnr]);
        }
        if (rc == NERF_OK) {
            printf("frame %4zu  %8.1f ms  %4ux%-4u  psnr %6.2f dB\n", i + 1,
                   ms[i], fr->w, fr->h, psnr[n_psnr]);
            n_psnr++;
        }
    }
    v->view = kept;
    if (rc == NERF_OK) {
        summarise(f, v, ms, psnr, n_psnr);
    }
    frame_free(&full);
    free(scaled);
    free(ms);
    free(psnr);
    return rc;
}

void fly_free(fly *f)
{
    for (size_t i = 0; i < f->n; i++) {
        free(f->frames[i].rgb);
    }
    free(f->frames);
    f->frames = NULL;
    f->n = f->cap = 0;
}
