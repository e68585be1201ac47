/*
 * Point clouds from rendered views: one point per opaque enough ray at its
 * expected termination point, with colour and a normal from the
 * neighbouring rays' points.
 */
#include "points.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "camera.h"
#include "options.h"
#include "renderer.h"

#define MAX_STRIDE 1024u

static void points_defaults(nerf_points_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->opacity_threshold = NERF_POINTS_DEFAULT_OPACITY;
    o->max_points = NERF_POINTS_DEFAULT_MAX;
    o->stride = 1;
}

NERF_API int nerf_points_options_init(nerf_points_options *opts,
                                      size_t struct_size)
{
    nerf_points_options d;
    points_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_points_options");
}

static int check_options(const void *opts)
{
    const nerf_points_options *o = opts;
    const char *what = NULL;
    if (!(o->opacity_threshold >= 0.0f && o->opacity_threshold <= 1.0f)) {
        what = "opacity_threshold must be in [0, 1]";
    } else if (o->max_points < 1) {
        what = "max_points must be at least 1";
    } else if (o->stride < 1 || o->stride > MAX_STRIDE) {
        what = "stride must be 1..1024";
    } else if (o->reserved0 != 0) {
        what = "reserved0 must be 0";
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "nerf_points_options: %s", what);
    }
    return NERF_OK;
}

/* Progress of the whole call, from the renderer's per-view reports. */
typedef struct progress_relay {
    nerf_progress_cb cb;
    void *user;
    uint64_t done_before; /* rays of the views already rendered */
    uint64_t total;       /* rays of all views */
} progress_relay;

static int relay_progress(const nerf_progress *p, void *user)
{
    const progress_relay *relay = user;
    nerf_progress q = *p;
    q.struct_size = sizeof q;
    q.done = relay->done_before + p->done;
    q.total = relay->total;
    return relay->cb(&q, relay->user);
}

/* A view's camera at 1/stride of its resolution, same field of view. */
static nerf_camera strided(const nerf_camera *cam, uint32_t stride)
{
    nerf_camera c = *cam;
    c.width = (cam->width + stride - 1) / stride;
    c.height = (cam->height + stride - 1) / stride;
    c.fx = cam->fx / (float)stride;
    c.fy = cam->fy / (float)stride;
    c.cx = cam->cx / (float)stride;
    c.cy = cam->cy / (float)stride;
    return c;
}

/* Room for one more point, thinning the kept ones by half when they would
 * pass the bound (see nerf_points_from_views()). */
static int make_room(nerf_points *pts, uint64_t bound, uint64_t *keep_step)
{
    if (pts->count < pts->capacity) {
        return NERF_OK;
    }
    if (pts->capacity >= bound) {
        size_t half = 0;
        for (size_t i = 0; i < pts->count; i += 2, half++) {
            memmove(pts->positions + 3 * half, pts->positions + 3 * i,
                    3 * sizeof(float));
            memmove(pts->colours + 3 * half, pts->colours + 3 * i, 3);
            memmove(pts->normals + 3 * half, pts->normals + 3 * i,
                    3 * sizeof(float));
        }
        pts->count = half;
        *keep_step *= 2;
        return NERF_OK;
    }
    size_t cap = pts->capacity ? 2 * pts->capacity : 4096;
    cap = cap < bound ? cap : (size_t)bound;
    float *p = nerf__alloc(&pts->env, cap * 3 * sizeof(float));
    uint8_t *c = nerf__alloc(&pts->env, cap * 3);
    float *n = nerf__alloc(&pts->env, cap * 3 * sizeof(float));
    if (p == NULL || c == NULL || n == NULL) {
        nerf__free(&pts->env, p);
        nerf__free(&pts->env, c);
        nerf__free(&pts->env, n);
        return NERF_ENOMEM;
    }
    if (pts->count) {
        memcpy(p, pts->positions, pts->count * 3 * sizeof(float));
        memcpy(c, pts->colours, pts->count * 3);
        memcpy(n, pts->normals, pts->count * 3 * sizeof(float));
    }
    nerf__free(&pts->env, pts->positions);
    nerf__free(&pts->env, pts->colours);
    nerf__free(&pts->env, pts->normals);
    pts->positions = p;
    pts->colours = c;
    pts->normals = n;
    pts->capacity = cap;
    return NERF_OK;
}

static uint8_t to_byte(float c)
{
    if (!(c > 0.0f)) {
        return 0;
    }
    return c >= 1.0f ? 255 : (uint8_t)(c * 255.0f + 0.5f);
}

/* One view's buffers, width x height each (xyz and rgb three per pixel). */
typedef struct view_buf {
    float *rgb, *dist, *z, *opacity, *o, *d, *xyz;
} view_buf;

/*
 * The difference from pixel a to its neighbour b (a valid pixel), into
 * out, flipped when the neighbour is the one before it; false when b has
 * no point or lies across a depth discontinuity.
 */
static bool neighbour_step(const view_buf *v, const uint8_t *ok, size_t a,
                           size_t b, bool before, float jump, float *out)
{
    if (!ok[b] || fabsf(v->dist[b] - v->dist[a]) > jump * v->dist[a]) {
        return false;
    }
    for (int c = 0; c < 3; c++) {
        float step = v->xyz[3 * b + c] - v->xyz[3 * a + c];
        out[c] = before ? -step : step;
    }
    return true;
}

static void estimate_normal(const view_buf *v, const uint8_t *ok,
                            uint32_t w, uint32_t h, size_t i, size_t j,
                            float jump, float *n)
{
    n[0] = n[1] = n[2] = 0.0f;
    size_t a = j * w + i;
    float dx[3], dy[3];
    bool has_x = i + 1 < w ? neighbour_step(v, ok, a, a + 1, false, jump, dx)
                 : i > 0   ? neighbour_step(v, ok, a, a - 1, true, jump, dx)
                           : false;
    bool has_y = j + 1 < h ? neighbour_step(v, ok, a, a + w, false, jump, dy)
                 : j > 0   ? neighbour_step(v, ok, a, a - w, true, jump, dy)
                           : false;
    if (!has_x || !has_y) {
        return;
    }
    double c[3] = {(double)dx[1] * dy[2] - (double)dx[2] * dy[1],
                   (double)dx[2] * dy[0] - (double)dx[0] * dy[2],
                   (double)dx[0] * dy[1] - (double)dx[1] * dy[0]};
    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    if (!(len > 0.0) || !isfinite(len)) {
        return;
    }
    const float *p = v->xyz + 3 * a, *o = v->o + 3 * a;
    double facing = c[0] * (o[0] - p[0]) + c[1] * (o[1] - p[1]) +
                    c[2] * (o[2] - p[2]);
    double sign = facing < 0.0 ? -1.0 : 1.0;
    for (int k = 0; k < 3; k++) {
        n[k] = (float)(sign * c[k] / len);
    }
}

typedef struct collect_state {
    uint64_t seen;      /* points that passed the filter so far */
    uint64_t keep_step; /* keep every keep_step-th of them */
    uint64_t bound;     /* 2 max_points */
} collect_state;

static int collect_view(nerf_points *pts, const view_buf *v,
                        const nerf_camera *cam, float threshold,
                        uint32_t stride, uint8_t *ok, collect_state *st)
{
    const size_t n = (size_t)cam->width * cam->height;
    nerf__camera_rays(cam, 0, n, v->o, v->d);
    for (size_t k = 0; k < n; k++) {
        float a = v->opacity[k];
        ok[k] = a > 0.0f && a >= threshold && isfinite(v->z[k]) &&
                isfinite(v->dist[k]);
        for (int c = 0; c < 3; c++) {
            v->xyz[3 * k + c] = v->o[3 * k + c] + v->z[k] * v->d[3 * k + c];
        }
    }
    const float jump = 0.05f * (float)stride;
    for (uint32_t j = 0; j < cam->height; j++) {
        for (uint32_t i = 0; i < cam->width; i++) {
            size_t k = (size_t)j * cam->width + i;
            if (!ok[k]) {
                continue;
            }
            if (st->seen++ % st->keep_step != 0) {
                continue;
            }
            int rc = make_room(pts, st->bound, &st->keep_step);
            if (rc != NERF_OK) {
                return rc;
            }
            /* Thinning may have just doubled the step; the point stays
             * only if its index is still a multiple of it. */
            if ((st->seen - 1) % st->keep_step != 0) {
                continue;
            }
            size_t at = pts->count++;
            memcpy(pts->positions + 3 * at, v->xyz + 3 * k,
                   3 * sizeof(float));
            for (int c = 0; c < 3; c++) {
                pts->colours[3 * at + c] = to_byte(v->rgb[3 * k + c]);
            }
            estimate_normal(v, ok, cam->width, cam->height, i, j, jump,
                            pts->normals + 3 * at);
        }
    }
    return NERF_OK;
}

/* Keep the points of index floor(k n / max), k < max. */
static void thin_to(nerf_points *pts, uint64_t max)
{
    if (pts->count <= max) {
        return;
    }
    const uint64_t n = pts->count;
    for (uint64_t k = 0; k < max; k++) {
        size_t from = (size_t)(k * n / max);
        memmove(pts->positions + 3 * k, pts->positions + 3 * from,
                3 * sizeof(float));
        memmove(pts->colours + 3 * k, pts->colours + 3 * from, 3);
        memmove(pts->normals + 3 * k, pts->normals + 3 * from,
                3 * sizeof(float));
    }
    pts->count = (size_t)max;
}

static int render_views(nerf_points *pts, nerf_renderer *r,
                        const nerf_camera *cams, size_t n_cams,
                        const nerf_points_options *o,
                        progress_relay *relay)
{
    static const char fn[] = "nerf_points_from_views";
    /* Validate every camera first, so that a bad last one fails before
     * the work on the others. */
    size_t most = 0;
    relay->total = 0;
    for (size_t v = 0; v < n_cams; v++) {
        nerf_camera cam;
        char name[64];
        snprintf(name, sizeof name, "%s: camera %zu", fn, v);
        int rc = nerf__camera_read(&cam, &cams[v], name);
        if (rc != NERF_OK) {
            return rc;
        }
        nerf_camera s = strided(&cam, o->stride);
        size_t px = (size_t)s.width * s.height;
        most = px > most ? px : most;
        relay->total += px;
    }
    /* rgb, dist, z, opacity, o, d, xyz: 3 + 1 + 1 + 1 + 3 + 3 + 3 floats,
     * and the valid flags. */
    size_t floats;
    if (nerf__mul_size(most, 15, &floats) != 0) {
        return nerf__error(NERF_ENOMEM, "%s: views too large", fn);
    }
    float *block = nerf__alloc(&pts->env, floats * sizeof(float));
    uint8_t *ok = nerf__alloc(&pts->env, most);
    int rc = block && ok ? NERF_OK : NERF_ENOMEM;
    view_buf v = {block, block + 3 * most, block + 4 * most,
                  block + 5 * most, block + 6 * most, block + 9 * most,
                  block + 12 * most};
    /* A cap beyond what memory could hold never binds; keep 2 max from
     * overflowing. */
    const uint64_t huge = UINT64_MAX / 4;
    collect_state st = {0, 1, o->max_points < huge ? 2 * o->max_points
                                                   : 2 * huge};
    relay->done_before = 0;
    for (size_t k = 0; k < n_cams && rc == NERF_OK; k++) {
        nerf_camera cam;
        nerf__camera_read(&cam, &cams[k], fn);
        nerf_camera s = strided(&cam, o->stride);
        rc = nerf_renderer_render_depth(r, &s, v.rgb, v.dist, v.z, v.opacity,
                                        most);
        if (rc == NERF_OK) {
            rc = collect_view(pts, &v, &s, o->opacity_threshold, o->stride,
                              ok, &st);
        }
        relay->done_before += (uint64_t)s.width * s.height;
    }
    nerf__free(&pts->env, block);
    nerf__free(&pts->env, ok);
    if (rc == NERF_OK) {
        thin_to(pts, o->max_points);
    }
    return rc;
}

NERF_API int nerf_points_from_views(nerf_points **out,
                                    nerf_renderer *renderer,
                                    const nerf_camera *cameras,
                                    size_t n_cameras,
                                    const nerf_points_options *opts)
{
    static const char fn[] = "nerf_points_from_views";
    if (out == NULL) {
        return nerf__error(NERF_EINVAL, "%s: out is NULL", fn);
    }
    *out = NULL;
    if (renderer == NULL || cameras == NULL) {
        return nerf__error(NERF_EINVAL, "%s: renderer and cameras must not "
                           "be NULL", fn);
    }
    if (n_cameras == 0) {
        return nerf__error(NERF_EINVAL, "%s: no cameras", fn);
    }
    nerf_points_options o;
    points_defaults(&o);
    nerf__env env;
    int rc = nerf__options_open(&o, sizeof o, opts, "nerf_points_options",
                                check_options, &o.hooks, &env);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf_points *pts = nerf__calloc(&env, 1, sizeof *pts);
    if (pts == NULL) {
        return NERF_ENOMEM;
    }
    pts->env = env;
    /* The caller's callback stands in for the renderer's during the call,
     * reporting over all views. */
    nerf_progress_cb saved_cb = renderer->progress;
    void *saved_user = renderer->progress_user;
    progress_relay relay = {o.progress, o.progress_user, 0, 0};
    renderer->progress = o.progress ? relay_progress : NULL;
    renderer->progress_user = o.progress ? &relay : NULL;
    rc = render_views(pts, renderer, cameras, n_cameras, &o, &relay);
    renderer->progress = saved_cb;
    renderer->progress_user = saved_user;
    if (rc != NERF_OK) {
        nerf_points_destroy(pts);
        return rc;
    }
    *out = pts;
    return NERF_OK;
}

NERF_API size_t nerf_points_count(const nerf_points *points)
{
    return points ? points->count : 0;
}

NERF_API int nerf_points_arrays(const nerf_points *points,
                                const float **positions,
                                const uint8_t **colours,
                                const float **normals)
{
    if (points == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_points_arrays: points is "
                           "NULL");
    }
    const bool any = points->count > 0;
    if (positions) {
        *positions = any ? points->positions : NULL;
    }
    if (colours) {
        *colours = any ? points->colours : NULL;
    }
    if (normals) {
        *normals = any ? points->normals : NULL;
    }
    return NERF_OK;
}

NERF_API void nerf_points_destroy(nerf_points *points)
{
    if (points == NULL) {
        return;
    }
    nerf__env env = points->env;
    nerf__free(&env, points->positions);
    nerf__free(&env, points->colours);
    nerf__free(&env, points->normals);
    nerf__free(&env, points);
}
