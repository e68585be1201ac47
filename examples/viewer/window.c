/*
 * The interactive window.  Everything runs on the main thread: renders are
 * made here, and the renderer's progress callback, which libnerf calls on
 * this thread after every chunk of rays, looks at SDL's event queue and
 * cancels a full-resolution render as soon as the user moves the view.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SDL_MAIN_HANDLED
#include <SDL.h>

#include "../common/progress.h"
#include "fly.h"
#include "viewer.h"

/* Seconds without a change of view before the full render starts. */
#define SETTLE_SECONDS 0.15
/* What a preview may take; its resolution follows the model's speed. */
#define PREVIEW_SECONDS 0.1
#define PREVIEW_MIN_FACTOR 4
#define PREVIEW_MAX_FACTOR 32
/* A baked model's previews: what a frame may take, its drawing and the
 * rest of the loop included, so that it stays within 50 ms; the preview
 * is any size up to the window's. */
#define BAKED_FRAME_SECONDS 0.045
#define BAKED_PREVIEW_MIN_FACTOR 1
/* The least a baked preview's render is given, whatever the rest takes. */
#define BAKED_RENDER_MIN_SECONDS 0.01
/* Previews closer together than this, with nothing else in between, are
 * one movement: the time between them, less the render, is what a frame
 * costs besides the render. */
#define MOVING_GAP_SECONDS 0.25
/* Radians turned per pixel dragged, and distance kept per wheel notch. */
#define ORBIT_PER_PIXEL 0.01
#define ZOOM_PER_NOTCH 0.9
/* Progress bar height in pixels, and its redraw interval in seconds. */
#define BAR_HEIGHT 3
#define BAR_INTERVAL 0.1
/* Queued events of one type looked at between two chunks of rays. */
#define PEEK_MAX 256

typedef struct window {
    viewer *v;
    SDL_Window *win;
    SDL_Renderer *ren;
    SDL_Texture *tex;
    uint32_t tex_w, tex_h;
    uint8_t *pixels; /* 8-bit copy of the shown frame */
    size_t pixels_cap;
    frame preview, full;
    frame *shown;           /* NULL before the first render */
    fly *fly;               /* --fly's path; NULL without */
    double rays_per_second; /* previews' speed; 0 before the first */
    double preview_began;   /* when the last preview's render began */
    double frame_extra;     /* a moving frame's seconds besides its render:
                             * drawing, events (a running mean) */
    int paused;             /* the loop waited or did other work since
                             * the last preview */
    double deadline;        /* 0: none */
    double last_change;     /* when the view last moved */
    double last_bar;
    int moved;     /* the view changed: render a preview */
    int need_full; /* the shown frame is a preview */
    int refining;  /* inside the full render */
    int quit;
    unsigned n_previews, n_full, n_cancelled;
} window;

static int past_deadline(const window *w)
{
    return w->deadline > 0.0 && progress_now() >= w->deadline;
}

static void set_title(window *w, const char *state)
{
    char title[160];
    snprintf(title, sizeof title, "nerf-viewer: %s %ux%u %s",
             view_mode_name(w->v->mode), w->v->width, w->v->height, state);
    SDL_SetWindowTitle(w->win, title);
}

static void present(window *w, double bar)
{
    SDL_SetRenderDrawColor(w->ren, 0, 0, 0, 255);
    SDL_RenderClear(w->ren);
    if (w->tex) {
        SDL_RenderCopy(w->ren, w->tex, NULL, NULL);
    }
    if (bar > 0.0) {
        int ww, wh;
        SDL_GetRendererOutputSize(w->ren, &ww, &wh);
        SDL_Rect r = {0, wh - BAR_HEIGHT, (int)(bar * ww), BAR_HEIGHT};
        SDL_SetRenderDrawColor(w->ren, 255, 160, 0, 255);
        SDL_RenderFillRect(w->ren, &r);
    }
    SDL_RenderPresent(w->ren);
}

/* Upload the shown frame in the current view mode and draw it. */
static int show(window *w)
{
    frame *f = w->shown;
    if (f == NULL) {
        present(w, 0.0);
        return 0;
    }
    size_t bytes = (size_t)f->width * f->height * 3;
    if (bytes > w->pixels_cap) {
        free(w->pixels);
        w->pixels = malloc(bytes);
        w->pixels_cap = w->pixels ? bytes : 0;
        if (w->pixels == NULL) {
            fprintf(stderr, "nerf-viewer: out of memory\n");
            return -1;
        }
    }
    if (w->tex == NULL || w->tex_w != f->width || w->tex_h != f->height) {
        if (w->tex) {
            SDL_DestroyTexture(w->tex);
        }
        w->tex = SDL_CreateTexture(w->ren, SDL_PIXELFORMAT_RGB24,
                                   SDL_TEXTUREACCESS_STREAMING, (int)f->width,
                                   (int)f->height);
        if (w->tex == NULL) {
            fprintf(stderr, "nerf-viewer: SDL: %s\n", SDL_GetError());
            return -1;
        }
        w->tex_w = f->width;
        w->tex_h = f->height;
    }
    frame_to_rgb8(f, w->v->mode, w->v->near, w->v->far, w->pixels);
    SDL_UpdateTexture(w->tex, NULL, w->pixels, (int)f->width * 3);
    present(w, 0.0);
    return 0;
}

/* Would this event change what is shown?  Such events stop a refinement. */
static int event_matters(const SDL_Event *ev)
{
    switch (ev->type) {
    case SDL_QUIT:
    case SDL_MOUSEWHEEL: return 1;
    case SDL_MOUSEMOTION: return ev->motion.state != 0;
    case SDL_WINDOWEVENT:
        return ev->window.event == SDL_WINDOWEVENT_SIZE_CHANGED;
    case SDL_KEYDOWN:
        switch (ev->key.keysym.sym) {
        case SDLK_1:
        case SDLK_2:
        case SDLK_3:
        case SDLK_KP_1:
        case SDLK_KP_2:
        case SDLK_KP_3:
        case SDLK_r:
        case SDLK_q:
        case SDLK_ESCAPE: return 1;
        default: return 0;
        }
    default: return 0;
    }
}

/* Whether queued events of one type would change what is shown; also 1
 * when there are too many to look at, to let the main loop sort them out. */
static int queued_matter(Uint32 type)
{
    SDL_Event evs[PEEK_MAX];
    int n = SDL_PeepEvents(evs, PEEK_MAX, SDL_PEEKEVENT, type, type);
    for (int i = 0; i < n; i++) {
        if (event_matters(&evs[i])) {
            return 1;
        }
    }
    return n == PEEK_MAX;
}

static int input_pending(void)
{
    SDL_PumpEvents();
    /* Type by type, so that a flood of one kind cannot hide another. */
    if (queued_matter(SDL_QUIT) || queued_matter(SDL_MOUSEWHEEL) ||
        queued_matter(SDL_KEYDOWN) || queued_matter(SDL_WINDOWEVENT) ||
        queued_matter(SDL_MOUSEMOTION)) {
        return 1;
    }
    /* None of the queued moves had a button down: drop them, or a mouse
     * merely passing over the window would fill the queue. */
    SDL_FlushEvent(SDL_MOUSEMOTION);
    return 0;
}

static int on_progress(const nerf_progress *p, void *user)
{
    window *w = user;
    if (!w->refining) {
        return 0;
    }
    if (past_deadline(w) || input_pending()) {
        return 1;
    }
    double t = progress_now();
    if (t - w->last_bar >= BAR_INTERVAL && p->total > 0) {
        double done = (double)p->done / (double)p->total;
        char state[48];
        snprintf(state, sizeof state, "refining %.0f%%", 100.0 * done);
        set_title(w, state);
        present(w, done);
        w->last_bar = t;
    }
    return 0;
}

static void handle_event(window *w, const SDL_Event *ev)
{
    viewer *v = w->v;
    switch (ev->type) {
    case SDL_QUIT: w->quit = 1; break;
    case SDL_KEYDOWN:
        switch (ev->key.keysym.sym) {
        case SDLK_1:
        case SDLK_KP_1: v->mode = VIEW_RGB; break;
        case SDLK_2:
        case SDLK_KP_2: v->mode = VIEW_DEPTH; break;
        case SDLK_3:
        case SDLK_KP_3: v->mode = VIEW_OPACITY; break;
        case SDLK_r:
            v->view = v->home;
            w->moved = 1;
            break;
        case SDLK_q:
        case SDLK_ESCAPE: w->quit = 1; break;
        default: break;
        }
        break;
    case SDL_MOUSEMOTION: {
        const SDL_MouseMotionEvent *m = &ev->motion;
        int shift = (SDL_GetModState() & KMOD_SHIFT) != 0;
        int left = (m->state & SDL_BUTTON_LMASK) != 0;
        int other = (m->state & (SDL_BUTTON_RMASK | SDL_BUTTON_MMASK)) != 0;
        if (left && !shift) {
            /* The scene follows the hand: drag right, it turns right. */
            orbit_rotate(&v->view, -ORBIT_PER_PIXEL * m->xrel,
                         ORBIT_PER_PIXEL * m->yrel);
            w->moved = 1;
        } else if (left || other) {
            /* One pixel at the target's distance, in world units. */
            double unit = v->view.distance / (v->focal_ratio * v->width);
            orbit_pan(&v->view, -unit * m->xrel, unit * m->yrel);
            w->moved = 1;
        }
        break;
    }
    case SDL_MOUSEWHEEL: {
        int notches = ev->wheel.y;
        if (ev->wheel.direction == SDL_MOUSEWHEEL_FLIPPED) {
            notches = -notches;
        }
        if (notches != 0) {
            orbit_zoom(&v->view, pow(ZOOM_PER_NOTCH, notches));
            w->moved = 1;
        }
        break;
    }
    case SDL_WINDOWEVENT:
        if (ev->window.event == SDL_WINDOWEVENT_SIZE_CHANGED &&
            ev->window.data1 > 0 && ev->window.data2 > 0) {
            v->width = (uint32_t)ev->window.data1;
            v->height = (uint32_t)ev->window.data2;
            w->moved = 1;
        }
        break;
    default: break;
    }
}

static void measure(window *w, const frame *f)
{
    if (f->seconds > 0.0) {
        w->rays_per_second = (double)f->width * f->height / f->seconds;
    }
}

/* Render the view at a reduced size: PREVIEW_MIN_FACTOR smaller on each
 * side, or more if the model is too slow for that to be quick.  Sized by
 * the previews' own speed: they may march coarser than the full view.  A
 * baked model's previews may be any size up to the full one, so that
 * they are as sharp as the time allows. */
static int render_preview(window *w)
{
    viewer *v = w->v;
    double began = progress_now();
    if (w->preview_began > 0.0 && !w->paused &&
        began - w->preview_began < MOVING_GAP_SECONDS) {
        double extra = fmax(0.0, began - w->preview_began -
                                     w->preview.seconds);
        w->frame_extra = w->frame_extra > 0.0
                             ? 0.8 * w->frame_extra + 0.2 * extra
                             : extra;
    }
    w->preview_began = began;
    w->paused = 0;
    double factor = PREVIEW_MAX_FACTOR;
    if (w->rays_per_second > 0.0) {
        double pixels = (double)v->width * v->height;
        double budget =
            v->bake ? fmax(BAKED_FRAME_SECONDS - w->frame_extra,
                           BAKED_RENDER_MIN_SECONDS)
                    : PREVIEW_SECONDS;
        factor = sqrt(pixels / (w->rays_per_second * budget));
        factor = v->bake ? factor : ceil(factor);
        factor = fmin(fmax(factor, v->bake ? BAKED_PREVIEW_MIN_FACTOR
                                           : PREVIEW_MIN_FACTOR),
                      PREVIEW_MAX_FACTOR);
    }
    uint32_t pw = (uint32_t)fmax(1.0, floor(v->width / factor));
    uint32_t ph = (uint32_t)fmax(1.0, floor(v->height / factor));
    nerf_camera cam;
    int rc = viewer_camera(v, pw, ph, &cam);
    if (rc == NERF_OK) {
        rc = frame_render(&w->preview, v->preview_renderer
                                           ? v->preview_renderer
                                           : v->renderer,
                          v->bake, &cam);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    w->n_previews++;
    measure(w, &w->preview);
    w->shown = &w->preview;
    char state[48];
    snprintf(state, sizeof state, "(preview %ux%u)", pw, ph);
    set_title(w, state);
    return show(w) == 0 ? NERF_OK : NERF_ERROR;
}

static int render_full(window *w)
{
    viewer *v = w->v;
    nerf_camera cam;
    int rc = viewer_camera(v, v->width, v->height, &cam);
    if (rc != NERF_OK) {
        return rc;
    }
    w->refining = 1;
    w->last_bar = progress_now();
    rc = frame_render(&w->full, v->renderer, NULL, &cam);
    w->refining = 0;
    if (rc == NERF_ECANCELLED) {
        w->n_cancelled++;
        return rc;
    }
    if (rc != NERF_OK) {
        return rc;
    }
    w->n_full++;
    w->need_full = 0;
    w->shown = &w->full;
    char state[48];
    snprintf(state, sizeof state, "(%.2f s)", w->full.seconds);
    set_title(w, state);
    return show(w) == 0 ? NERF_OK : NERF_ERROR;
}

/* Sleep until an event arrives or there is work: the settle delay before
 * a refinement, or the deadline. */
static void wait_for_input(window *w)
{
    double now = progress_now();
    double wait = 0.25;
    if (w->need_full) {
        wait = fmax(0.0, w->last_change + SETTLE_SECONDS - now);
    }
    if (w->deadline > 0.0) {
        wait = fmin(wait, fmax(0.0, w->deadline - now));
    }
    SDL_WaitEventTimeout(NULL, (int)ceil(wait * 1000.0));
}

static int run(window *w)
{
    view_mode shown_mode = w->v->mode;
    w->moved = 1;
    while (!w->quit && !past_deadline(w)) {
        SDL_Event ev;
        while (SDL_PollEvent(&ev)) {
            handle_event(w, &ev);
        }
        if (w->quit) {
            break;
        }
        if (w->fly != NULL && fly_place(w->fly, w->v, progress_now())) {
            w->moved = 1;
        }
        int rc = NERF_OK;
        if (w->moved) {
            w->moved = 0;
            rc = render_preview(w);
            if (rc == NERF_OK && w->fly != NULL && w->fly->full_at == 0.0) {
                rc = fly_record(w->fly, &w->preview, progress_now());
            }
            shown_mode = w->v->mode;
            w->need_full = 1;
            w->last_change = progress_now();
        } else if (shown_mode != w->v->mode) {
            w->paused = 1;
            shown_mode = w->v->mode;
            set_title(w, w->need_full ? "(preview)" : "");
            rc = show(w) == 0 ? NERF_OK : NERF_ERROR;
        } else if (w->need_full &&
                   progress_now() - w->last_change >= SETTLE_SECONDS) {
            w->paused = 1;
            rc = render_full(w);
            if (rc == NERF_OK && w->fly != NULL && w->fly->stopped_at > 0.0) {
                /* The path is over and its end is drawn in full. */
                w->fly->full_at = progress_now();
                w->quit = 1;
            }
        } else {
            w->paused = 1;
            wait_for_input(w);
        }
        if (rc != NERF_OK && rc != NERF_ECANCELLED) {
            if (rc != NERF_ERROR) {
                fprintf(stderr, "nerf-viewer: %s: %s\n", nerf_status_string(rc),
                        nerf_last_error());
            }
            return 1;
        }
    }
    return 0;
}

int viewer_run_window(viewer *v)
{
    window w;
    memset(&w, 0, sizeof w);
    w.v = v;
    fly path;
    if (v->fly_seconds > 0.0) {
        fly_init(&path, v, v->fly_seconds);
        w.fly = &path;
    }
    SDL_SetMainReady();
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        fprintf(stderr, "nerf-viewer: cannot start SDL: %s\n", SDL_GetError());
        return 1;
    }
    int status = 1;
    SDL_SetHint(SDL_HINT_RENDER_SCALE_QUALITY, "linear");
    w.win = SDL_CreateWindow("nerf-viewer", SDL_WINDOWPOS_UNDEFINED,
                             SDL_WINDOWPOS_UNDEFINED, (int)v->width,
                             (int)v->height, SDL_WINDOW_RESIZABLE);
    if (w.win) {
        w.ren = SDL_CreateRenderer(w.win, -1, 0);
    }
    if (w.win == NULL || w.ren == NULL) {
        fprintf(stderr, "nerf-viewer: cannot open a window: %s\n",
                SDL_GetError());
        goto done;
    }
    /* Typing would otherwise queue text events nobody reads. */
    SDL_StopTextInput();
    nerf_renderer_set_progress(v->renderer, on_progress, &w);
    double start = progress_now();
    w.deadline = v->quit_after > 0.0 ? start + v->quit_after : 0.0;
    status = run(&w);
    nerf_renderer_set_progress(v->renderer, NULL, NULL);
    if (v->quit_after > 0.0) {
        fprintf(stderr,
                "nerf-viewer: %.1f s: %u previews, %u full frames, "
                "%u refinements interrupted\n",
                progress_now() - start, w.n_previews, w.n_full, w.n_cancelled);
    }
done:
    frame_free(&w.preview);
    frame_free(&w.full);
    free(w.pixels);
    if (w.tex) {
        SDL_DestroyTexture(w.tex);
    }
    if (w.ren) {
        SDL_DestroyRenderer(w.ren);
    }
    if (w.win) {
        SDL_DestroyWindow(w.win);
    }
    SDL_Quit();
    if (w.fly != NULL) {
        /* Scored after the window closed: the full renders it takes are
         * no part of what the path measured. */
        int rc = status == 0 ? fly_report(w.fly, v) : NERF_OK;
        if (rc != NERF_OK) {
            fprintf(stderr, "nerf-viewer: %s: %s\n", nerf_status_string(rc),
                    nerf_last_error());
            status = 1;
        } else if (status == 0 && w.fly->full_at == 0.0) {
            status = 1; /* the summary said the path did not finish */
        }
        fly_free(w.fly);
    }
    return status;
}
