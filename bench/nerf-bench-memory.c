/*
 * Peak resident memory of an 800x800 render (--render-size), what a
 * caller rendering a whole view must have.  Each preset renders in a
 * child forked at the start, so that the figure is the render's alone.
 * Without --full the reference and fast presets stop after the first rows
 * (--rss-rows): scratch is allocated on each worker's first block and does
 * not grow, and a whole image would take long.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "nerf-bench.h"

typedef struct rss_stop {
    uint64_t limit; /* 0: never stop */
    uint64_t done;
} rss_stop;

static int rss_progress(const nerf_progress *p, void *user)
{
    rss_stop *s = user;
    s->done = p->done;
    return s->limit && p->done >= s->limit;
}

static void rss_measure(int preset, bool full, const run_info *ri,
                        rss_result *res)
{
    const uint32_t side = ri->render_side, rows = ri->rss_rows;
    preset_setup p;
    memset(res, 0, sizeof *res);
    if (preset_make(&p, preset, ri->matmul, NULL) != 0) {
        fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        return;
    }
    res->model_mb = vm_mb("VmRSS");
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = ri->workers_requested;
    ro.white_background = 1;
    nerf_renderer *r = NULL;
    size_t pixels = (size_t)side * side;
    /* A caller of a full render holds full-size outputs: touch them all
     * up front so that a stopped render counts them too. */
    float *rgb = malloc(pixels * 3 * sizeof(float));
    float *depth = malloc(pixels * sizeof(float));
    float *opacity = malloc(pixels * sizeof(float));
    if (rgb && depth && opacity &&
        nerf_renderer_create(&r, p.model, p.eval_sampler, &ro) == NERF_OK) {
        memset(rgb, 0, pixels * 3 * sizeof(float));
        memset(depth, 0, pixels * sizeof(float));
        memset(opacity, 0, pixels * sizeof(float));
        rss_stop stop = {full ? 0 : (uint64_t)rows * side, 0};
        nerf_renderer_set_progress(r, rss_progress, &stop);
        nerf_camera cam;
        view_camera(&cam, side);
        double t0 = now();
        int rc =
            nerf_renderer_render_image(r, &cam, rgb, depth, opacity, pixels);
        res->seconds = now() - t0;
        if (rc == NERF_OK || (rc == NERF_ECANCELLED && !full)) {
            struct rusage ru;
            getrusage(RUSAGE_SELF, &ru);
            res->ok = 1;
            res->full = rc == NERF_OK;
            res->workers = r->threads;
            res->hwm_mb = vm_mb("VmHWM");
            res->maxrss_mb = ru.ru_maxrss / 1024.0;
            res->outputs_mb = pixels * 5 * sizeof(float) / 1048576.0;
            res->rays_done = rc == NERF_OK ? pixels : stop.done;
            res->rays_total = pixels;
        } else {
            fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        }
    } else {
        fprintf(stderr, "nerf-bench: cannot set up the %ux%u render\n", side,
                side);
    }
    nerf_renderer_destroy(r);
    free(rgb);
    free(depth);
    free(opacity);
    preset_release(&p);
}

/*
 * Forked while this process is still small, so the figure is the render's
 * own and not inflated by the training buffers measured later.
 */
void rss_in_child(int preset, bool full, const run_info *ri, rss_result *res)
{
    memset(res, 0, sizeof *res);
    int fd[2];
    if (pipe(fd) != 0) {
        return;
    }
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        rss_result r;
        rss_measure(preset, full, ri, &r);
        ssize_t w = write(fd[1], &r, sizeof r);
        _exit(w == (ssize_t)sizeof r ? 0 : 1);
    }
    close(fd[1]);
    if (pid > 0) {
        size_t got = 0;
        while (got < sizeof *res) {
            ssize_t n = read(fd[0], (char *)res + got, sizeof *res - got);
            if (n < 0 && errno == EINTR) {
                continue;
            }
            if (n <= 0) {
                break;
            }
            got += (size_t)n;
        }
        int status = 0;
        waitpid(pid, &status, 0);
        if (got != sizeof *res || !WIFEXITED(status) ||
            WEXITSTATUS(status) != 0) {
            memset(res, 0, sizeof *res);
        }
    }
    close(fd[0]);
}

/* How the figure was taken, in words, for both reports. */
const char *rss_method(const rss_result *r, char *buf, size_t size)
{
    if (r->full) {
        snprintf(buf, size,
                 "whole %ux%u nerf_renderer_render_image in a "
                 "forked child, %u worker(s); VmHWM at the end",
                 (unsigned)sqrt((double)r->rays_total),
                 (unsigned)sqrt((double)r->rays_total), r->workers);
    } else {
        snprintf(buf, size,
                 "%ux%u nerf_renderer_render_image in a forked "
                 "child, %u worker(s), full-size outputs touched up front, "
                 "cancelled by its progress callback after %llu of %llu rays "
                 "(the first rows); VmHWM at that point (scratch is allocated "
                 "on each worker's first block and does not grow)",
                 (unsigned)sqrt((double)r->rays_total),
                 (unsigned)sqrt((double)r->rays_total), r->workers,
                 (unsigned long long)r->rays_done,
                 (unsigned long long)r->rays_total);
    }
    return buf;
}
