/*
 * The built-in scene as a COLMAP model: images/ of opaque PNGs and
 * sparse/0/ cameras, images and points3D in COLMAP's text or binary form,
 * so that the COLMAP loader is tested on every machine.
 */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "byte_buf.h"
#include "byteorder.h"
#include "camera.h"
#include "colmap.h"
#include "colmap_poses.h"
#include "field.h"
#include "scene_image.h"
#include "scene_internal.h"

/* Views that seed points, and pixels a side of their grid. */
#define SEED_VIEWS 8u
#define SEED_GRID 10u
/* A seed ray must be this opaque for its end to count as a surface. */
#define SEED_OPACITY 0.95f
/* Another view sees a point when its ray there ends within this distance
 * of it (world units; the solids' edges are some 0.02 wide). */
#define SEE_TOLERANCE 0.05

static void put_u32(nerf__buf *b, uint32_t v)
{
    unsigned char *p = nerf__buf_grow(b, 4);
    if (p) {
        nerf__store_le32(p, v);
    }
}

static void put_u64(nerf__buf *b, uint64_t v)
{
    unsigned char *p = nerf__buf_grow(b, 8);
    if (p) {
        nerf__store_le64(p, v);
    }
}

static void put_f64(nerf__buf *b, double v)
{
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    put_u64(b, bits);
}

typedef struct point {
    double xyz[3];
    uint8_t rgb[3];
} point;

/* Where view k sees point p: pixel (u, v), or idx < 0 for not at all. */
typedef struct sighting {
    float u, v;
    int32_t idx; /* position in the view's list of 2D points */
} sighting;

typedef struct colmap_writer {
    const nerf_scene_options *o;
    nerf__scene_look look; /* the capture's */
    const nerf__env *env;
    const char *dir;
    uint32_t n;        /* views */
    nerf_camera *cams; /* n */
    point *points;
    uint32_t n_points;
    sighting *seen;   /* n_points x n */
    uint32_t *n_seen; /* 2D points per view */
} colmap_writer;

static uint8_t to8(double v)
{
    return (uint8_t)lrint((v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v) * 255.0);
}

/* Cameras of all views, train then val then test, and their photos. */
static int write_views(colmap_writer *w, uint8_t *rgba)
{
    const nerf_scene_options *o = w->o;
    const uint32_t counts[3] = {o->n_train, o->n_val, o->n_test};
    char path[4096];
    snprintf(path, sizeof path, "%s/images", w->dir);
    int rc = nerf__scene_make_dir(path);
    uint8_t *mask = NULL;
    if (rc == NERF_OK && o->occluders) {
        /* Every photo gets its mask: the loader asks for one per photo
         * once a masks/ folder is there. */
        snprintf(path, sizeof path, "%s/masks", w->dir);
        rc = nerf__scene_make_dir(path);
        mask = nerf__alloc(w->env, (size_t)o->width * o->height);
        rc = rc == NERF_OK && mask == NULL ? NERF_ENOMEM : rc;
    }
    uint32_t k = 0;
    for (int split = 0; split < 3; split++) {
        for (uint32_t i = 0; i < counts[split] && rc == NERF_OK; i++, k++) {
            nerf_camera *cam = &w->cams[k];
            nerf__scene_capture_camera(o, split, i, counts[split], cam);
            nerf__scene_render_view(cam, &w->look, o->threads, rgba, NULL);
            /* A photograph has no alpha: composite onto white (the
             * opaque captures are RGB already). */
            size_t px = (size_t)o->width * o->height;
            for (size_t j = 0; j < px && w->look.channels == 4; j++) {
                double a = rgba[4 * j + 3] / 255.0;
                for (int c = 0; c < 3; c++) {
                    rgba[3 * j + c] =
                        to8(rgba[4 * j + c] / 255.0 * a + (1.0 - a));
                }
            }
            if (mask != NULL) {
                memset(mask, 255, px);
                if (nerf__scene_occluded(o, split, i)) {
                    nerf__scene_paint_occluder(o, i, 3, rgba, mask);
                }
            }
            snprintf(path, sizeof path, "%s/images/%05u", w->dir, (unsigned)k);
            rc = nerf__scene_image_write(w->env, path, o, 3, rgba);
            if (rc == NERF_OK && mask != NULL) {
                /* COLMAP's name for the mask of images/<name>. */
                snprintf(path, sizeof path, "%s/masks/%05u%s.png", w->dir,
                         (unsigned)k, nerf__scene_image_extension(o));
                rc = nerf__scene_mask_write(w->env, path, o, mask);
            }
        }
    }
    nerf__free(w->env, mask);
    return rc;
}

/* Pixel of cam where x projects, false when behind it or outside. */
static bool project(const nerf_camera *cam, const double x[3], float *u,
                    float *v)
{
    double d[3], c[3];
    for (int a = 0; a < 3; a++) {
        d[a] = x[a] - cam->c2w[4 * a + 3];
    }
    for (int a = 0; a < 3; a++) {
        c[a] = cam->c2w[a] * d[0] + cam->c2w[4 + a] * d[1] +
               cam->c2w[8 + a] * d[2];
    }
    if (!(c[2] < -1e-6)) {
        return false;
    }
    double uu = cam->cx + cam->fx * c[0] / -c[2];
    double vv = cam->cy - cam->fy * c[1] / -c[2];
    if (!(uu >= 0.0 && vv >= 0.0 && uu < cam->width && vv < cam->height)) {
        return false;
    }
    *u = (float)uu;
    *v = (float)vv;
    return true;
}

/* Whether the ray from cam's centre through x ends at x. */
static bool sees(const colmap_writer *w, const nerf_camera *cam,
                 const double x[3])
{
    float o[3], d[3], rgb[3], depth;
    double len2 = 0.0;
    for (int a = 0; a < 3; a++) {
        o[a] = cam->c2w[4 * a + 3];
        d[a] = (float)(x[a] - o[a]);
        len2 += (double)d[a] * d[a];
    }
    /* t = 1 at x: anything beyond t = 2 is behind it. */
    float alpha =
        nerf__scene_render_ray_in(w->look.world, o, d, 0.0f, 2.0f, rgb, &depth);
    if (!(alpha > 0.5f)) {
        return false;
    }
    /* The far backdrop's soft edge blurs depth in proportion. */
    const double len = sqrt(len2);
    return fabs(depth / alpha - 1.0) * len < fmax(SEE_TOLERANCE, 0.01 * len);
}

/*
 * Surface points from a grid of pixels of a few views, then which views
 * see each of them.
 */
static int make_points(colmap_writer *w)
{
    const nerf_scene_options *o = w->o;
    uint32_t step = w->n > SEED_VIEWS ? w->n / SEED_VIEWS : 1;
    uint32_t cap = SEED_VIEWS * SEED_GRID * SEED_GRID + SEED_GRID * SEED_GRID;
    w->points = nerf__calloc(w->env, cap, sizeof *w->points);
    if (w->points == NULL) {
        return NERF_ENOMEM;
    }
    for (uint32_t k = 0; k < w->n; k += step) {
        const nerf_camera *cam = &w->cams[k];
        for (uint32_t gy = 0; gy < SEED_GRID; gy++) {
            for (uint32_t gx = 0; gx < SEED_GRID && w->n_points < cap; gx++) {
                size_t col = (size_t)((gx + 0.5) * o->width / SEED_GRID);
                size_t row = (size_t)((gy + 0.5) * o->height / SEED_GRID);
                float ro[3], rd[3], rgb[3], depth;
                nerf__camera_rays(cam, row * o->width + col, 1, ro, rd);
                float a = nerf__scene_render_ray_in(w->look.world, ro, rd,
                                                    w->look.near, w->look.far,
                                                    rgb, &depth);
                if (!(a > SEED_OPACITY)) {
                    continue;
                }
                point *p = &w->points[w->n_points++];
                for (int c = 0; c < 3; c++) {
                    p->xyz[c] = ro[c] + (double)rd[c] * depth / a;
                    p->rgb[c] = to8(rgb[c] / a);
                }
            }
        }
    }
    size_t cells;
    if (nerf__mul_size(w->n_points ? w->n_points : 1, w->n, &cells) != 0) {
        return NERF_ENOMEM;
    }
    w->seen = nerf__calloc(w->env, cells, sizeof *w->seen);
    w->n_seen = nerf__calloc(w->env, w->n, sizeof *w->n_seen);
    if (w->seen == NULL || w->n_seen == NULL) {
        return NERF_ENOMEM;
    }
    for (uint32_t p = 0; p < w->n_points; p++) {
        for (uint32_t k = 0; k < w->n; k++) {
            sighting *s = &w->seen[(size_t)p * w->n + k];
            s->idx = -1;
            if (project(&w->cams[k], w->points[p].xyz, &s->u, &s->v) &&
                sees(w, &w->cams[k], w->points[p].xyz)) {
                s->idx = (int32_t)w->n_seen[k]++;
            }
        }
    }
    return NERF_OK;
}

/* One camera: PINHOLE, or OPENCV when the views have a lens (k3 is
 * refused beforehand: OPENCV has none). */
static void camera_record(const colmap_writer *w, bool bin, nerf__buf *b)
{
    const nerf_camera *c = &w->cams[0];
    const bool lens =
        c->k1 != 0.0f || c->k2 != 0.0f || c->p1 != 0.0f || c->p2 != 0.0f;
    const double p[8] = {c->fx, c->fy, c->cx, c->cy,
                         c->k1, c->k2, c->p1, c->p2};
    const int n = lens ? 8 : 4;
    if (bin) {
        put_u64(b, 1);
        put_u32(b, 1);
        put_u32(b, lens ? NERF__COLMAP_OPENCV : NERF__COLMAP_PINHOLE);
        put_u64(b, c->width);
        put_u64(b, c->height);
        for (int i = 0; i < n; i++) {
            put_f64(b, p[i]);
        }
        return;
    }
    nerf__buf_printf(b, "# Camera list with one line of data per camera:\n"
                        "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
                        "# Number of cameras: 1\n");
    nerf__buf_printf(b, "1 %s %u %u", lens ? "OPENCV" : "PINHOLE",
                     (unsigned)c->width, (unsigned)c->height);
    for (int i = 0; i < n; i++) {
        nerf__buf_printf(b, " %.17g", p[i]);
    }
    nerf__buf_printf(b, "\n");
}

static void image_records(const colmap_writer *w, bool bin, nerf__buf *b)
{
    if (bin) {
        put_u64(b, w->n);
    } else {
        nerf__buf_printf(b,
                         "# Image list with two lines of data per image:\n"
                         "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, "
                         "NAME\n"
                         "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
                         "# Number of images: %u\n",
                         (unsigned)w->n);
    }
    for (uint32_t k = 0; k < w->n; k++) {
        double c2w[12], q[4], t[3];
        for (int i = 0; i < 12; i++) {
            c2w[i] = w->cams[k].c2w[i];
        }
        nerf__c2w_to_colmap(c2w, q, t);
        char name[32];
        snprintf(name, sizeof name, "%05u%s", (unsigned)k,
                 nerf__scene_image_extension(w->o));
        if (bin) {
            put_u32(b, k + 1);
            for (int i = 0; i < 4; i++) {
                put_f64(b, q[i]);
            }
            for (int i = 0; i < 3; i++) {
                put_f64(b, t[i]);
            }
            put_u32(b, 1);
            nerf__buf_put(b, name, strlen(name) + 1);
            put_u64(b, w->n_seen[k]);
        } else {
            nerf__buf_printf(
                b, "%u %.17g %.17g %.17g %.17g %.17g %.17g %.17g 1 %s\n",
                (unsigned)(k + 1), q[0], q[1], q[2], q[3], t[0], t[1], t[2],
                name);
        }
        /* The point ids in the order the sightings were numbered. */
        const char *sep = "";
        for (uint32_t p = 0; p < w->n_points; p++) {
            const sighting *s = &w->seen[(size_t)p * w->n + k];
            if (s->idx < 0) {
                continue;
            }
            if (bin) {
                put_f64(b, s->u);
                put_f64(b, s->v);
                put_u64(b, (uint64_t)p + 1);
            } else {
                nerf__buf_printf(b, "%s%.6f %.6f %u", sep, (double)s->u,
                                 (double)s->v, (unsigned)(p + 1));
                sep = " ";
            }
        }
        if (!bin) {
            nerf__buf_printf(b, "\n");
        }
    }
}

static void point_records(const colmap_writer *w, bool bin, nerf__buf *b)
{
    if (bin) {
        put_u64(b, w->n_points);
    } else {
        nerf__buf_printf(b,
                         "# 3D point list with one line of data per point:\n"
                         "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, "
                         "TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
                         "# Number of points: %u\n",
                         (unsigned)w->n_points);
    }
    for (uint32_t p = 0; p < w->n_points; p++) {
        const point *pt = &w->points[p];
        const sighting *row = &w->seen[(size_t)p * w->n];
        uint64_t len = 0;
        for (uint32_t k = 0; k < w->n; k++) {
            len += row[k].idx >= 0;
        }
        if (bin) {
            put_u64(b, (uint64_t)p + 1);
            for (int c = 0; c < 3; c++) {
                put_f64(b, pt->xyz[c]);
            }
            nerf__buf_put(b, pt->rgb, 3);
            put_f64(b, 0.0);
            put_u64(b, len);
        } else {
            nerf__buf_printf(b, "%u %.17g %.17g %.17g %u %u %u 0",
                             (unsigned)(p + 1), pt->xyz[0], pt->xyz[1],
                             pt->xyz[2], pt->rgb[0], pt->rgb[1], pt->rgb[2]);
        }
        for (uint32_t k = 0; k < w->n; k++) {
            if (row[k].idx < 0) {
                continue;
            }
            if (bin) {
                put_u32(b, k + 1);
                put_u32(b, (uint32_t)row[k].idx);
            } else {
                nerf__buf_printf(b, " %u %d", (unsigned)(k + 1),
                                 (int)row[k].idx);
            }
        }
        if (!bin) {
            nerf__buf_printf(b, "\n");
        }
    }
}

static int write_model(const colmap_writer *w, bool bin)
{
    typedef void (*record_fn)(const colmap_writer *, bool, nerf__buf *);
    static const record_fn records[3] = {camera_record, image_records,
                                         point_records};
    static const char *const names[3] = {"cameras", "images", "points3D"};
    char path[4096];
    snprintf(path, sizeof path, "%s/sparse/0", w->dir);
    int rc = nerf__scene_make_dir(path);
    for (int f = 0; f < 3 && rc == NERF_OK; f++) {
        nerf__buf b = {w->env, NULL, 0, 0, false};
        records[f](w, bin, &b);
        snprintf(path, sizeof path, "%s/sparse/0/%s.%s", w->dir, names[f],
                 bin ? "bin" : "txt");
        rc = nerf__buf_save(&b, path);
    }
    return rc;
}

int nerf__scene_write_colmap(const char *dir, const nerf_scene_options *o,
                             const nerf__env *env, uint8_t *rgba)
{
    colmap_writer w;
    memset(&w, 0, sizeof w);
    w.o = o;
    w.env = env;
    w.dir = dir;
    w.look = nerf__scene_look_of(o);
    w.n = o->n_train + o->n_val + o->n_test;
    w.cams = nerf__calloc(env, w.n, sizeof *w.cams);
    int rc = w.cams ? write_views(&w, rgba) : NERF_ENOMEM;
    if (rc == NERF_OK) {
        rc = make_points(&w);
    }
    if (rc == NERF_OK) {
        rc = write_model(&w, o->layout == NERF_SCENE_LAYOUT_COLMAP_BINARY);
    }
    if (rc == NERF_OK) {
        nerf__log(env, NERF_LOG_INFO,
                  "scene: wrote %u views of %ux%u and "
                  "%u sparse points as a COLMAP %s model to %s",
                  (unsigned)w.n, (unsigned)o->width, (unsigned)o->height,
                  (unsigned)w.n_points,
                  o->layout == NERF_SCENE_LAYOUT_COLMAP_BINARY ? "binary"
                                                               : "text",
                  dir);
    }
    nerf__free(env, w.cams);
    nerf__free(env, w.points);
    nerf__free(env, w.seen);
    nerf__free(env, w.n_seen);
    return rc;
}
