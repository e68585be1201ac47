/* COLMAP sparse models, text and binary: see colmap.h and docs/formats.md. */
#include "colmap.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "byteorder.h"
#include "distortion.h"
#include "transforms.h"

/* Longer image names than this are refused (COLMAP stores relative paths). */
#define MAX_NAME 4096
/* The most 2D points or track entries one record may claim in text form
 * is bounded by the line; in binary form, by the bytes left. */

static const struct {
    const char *name;
    int n_params;
} models[NERF__COLMAP_N_MODELS] = {
    {"SIMPLE_PINHOLE", 3}, {"PINHOLE", 4},    {"SIMPLE_RADIAL", 4},
    {"RADIAL", 5},         {"OPENCV", 8},     {"OPENCV_FISHEYE", 8},
    {"FULL_OPENCV", 12},   {"FOV", 5},        {"SIMPLE_RADIAL_FISHEYE", 4},
    {"RADIAL_FISHEYE", 5}, {"THIN_PRISM_FISHEYE", 12},
};

const char *nerf__colmap_model_name(int model)
{
    return model >= 0 && model < NERF__COLMAP_N_MODELS ? models[model].name
                                                       : NULL;
}

int nerf__colmap_model_param_count(int model)
{
    return model >= 0 && model < NERF__COLMAP_N_MODELS
               ? models[model].n_params
               : -1;
}

void nerf__colmap_free(const nerf__env *env, nerf__colmap_model *m)
{
    for (size_t i = 0; i < m->n_images; i++) {
        nerf__free(env, m->images[i].name);
    }
    nerf__free(env, m->cameras);
    nerf__free(env, m->images);
    nerf__free(env, m->points);
    nerf__free(env, m->track);
    memset(m, 0, sizeof *m);
}

const nerf__colmap_camera *nerf__colmap_find_camera(
    const nerf__colmap_model *m, uint32_t id)
{
    size_t lo = 0, hi = m->n_cameras;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (m->cameras[mid].id == id) {
            return &m->cameras[mid];
        }
        if (m->cameras[mid].id < id) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return NULL;
}

/* ---- shared checks ------------------------------------------------------ */

/*
 * A camera from its model id and parameters, or an error naming the file,
 * the camera and what is wrong with it.
 */
static int make_camera(const char *path, uint32_t id, int model,
                       uint64_t width, uint64_t height, const double *p,
                       nerf__colmap_camera *out)
{
    if (model > NERF__COLMAP_OPENCV) {
        return nerf__error(NERF_EFORMAT, "%s: camera %u: camera model %s is "
                           "not supported (SIMPLE_PINHOLE, PINHOLE, "
                           "SIMPLE_RADIAL, RADIAL and OPENCV are)", path,
                           (unsigned)id, nerf__colmap_model_name(model));
    }
    if (width < 1 || height < 1 || width > 65536 || height > 65536) {
        return nerf__error(NERF_EFORMAT, "%s: camera %u: image size %llux%llu "
                           "is outside 1..65536", path, (unsigned)id,
                           (unsigned long long)width,
                           (unsigned long long)height);
    }
    int n = models[model].n_params;
    for (int k = 0; k < n; k++) {
        if (!isfinite(p[k]) || !(fabs(p[k]) <= NERF__CAMERA_MAX_ABS)) {
            return nerf__error(NERF_EFORMAT, "%s: camera %u: parameter %d is "
                               "%g (must be finite and at most %g in size)",
                               path, (unsigned)id, k, p[k],
                               NERF__CAMERA_MAX_ABS);
        }
    }
    memset(out, 0, sizeof *out);
    out->id = id;
    out->model = model;
    out->width = (uint32_t)width;
    out->height = (uint32_t)height;
    bool one_focal = model == NERF__COLMAP_SIMPLE_PINHOLE ||
                     model == NERF__COLMAP_SIMPLE_RADIAL ||
                     model == NERF__COLMAP_RADIAL;
    const double *pp = one_focal ? p + 1 : p + 2;
    out->fx = p[0];
    out->fy = one_focal ? p[0] : p[1];
    out->cx = pp[0];
    out->cy = pp[1];
    const double *dist = pp + 2;
    if (model == NERF__COLMAP_SIMPLE_RADIAL) {
        out->k1 = dist[0];
    } else if (model == NERF__COLMAP_RADIAL) {
        out->k1 = dist[0];
        out->k2 = dist[1];
    } else if (model == NERF__COLMAP_OPENCV) {
        out->k1 = dist[0];
        out->k2 = dist[1];
        out->p1 = dist[2];
        out->p2 = dist[3];
    }
    if (!(out->fx >= NERF__FOCAL_MIN && out->fy >= NERF__FOCAL_MIN)) {
        return nerf__error(NERF_EFORMAT, "%s: camera %u: focal %g, %g (must "
                           "be at least %g)", path, (unsigned)id, out->fx,
                           out->fy, NERF__FOCAL_MIN);
    }
    /* The lens every call that takes a camera accepts, judged by the same
     * function, so that the model is refused here, naming the camera. */
    const double lens[5] = {out->k1, out->k2, out->p1, out->p2, out->k3};
    char why[96];
    if (nerf__lens_problem(lens, why, sizeof why) != NULL) {
        return nerf__error(NERF_EFORMAT, "%s: camera %u: %s", path,
                           (unsigned)id, why);
    }
    return NERF_OK;
}

static int compare_camera(const void *a, const void *b)
{
    uint32_t x = ((const nerf__colmap_camera *)a)->id;
    uint32_t y = ((const nerf__colmap_camera *)b)->id;
    return (x > y) - (x < y);
}

static int sort_cameras(const char *path, nerf__colmap_model *m)
{
    if (m->n_cameras == 0) {
        return nerf__error(NERF_EFORMAT, "%s: no cameras", path);
    }
    qsort(m->cameras, m->n_cameras, sizeof *m->cameras, compare_camera);
    for (size_t i = 1; i < m->n_cameras; i++) {
        if (m->cameras[i].id == m->cameras[i - 1].id) {
            return nerf__error(NERF_EFORMAT, "%s: camera %u appears twice",
                               path, (unsigned)m->cameras[i].id);
        }
    }
    return NERF_OK;
}

/*
 * An image's pose and camera; name is checked so that joining it to the
 * images folder cannot leave that folder.
 */
static int check_image(const char *path, const nerf__colmap_model *m,
                       nerf__colmap_image *im)
{
    const char *name = im->name;
    if (name[0] == '\0' || name[0] == '/' || strstr(name, "..") != NULL) {
        return nerf__error(NERF_EFORMAT, "%s: image %u: name '%.256s' must be "
                           "a relative path inside the images folder", path,
                           (unsigned)im->id, name);
    }
    for (const char *c = name; *c; c++) {
        if ((unsigned char)*c < 0x20) {
            return nerf__error(NERF_EFORMAT, "%s: image %u: name holds a "
                               "control character", path, (unsigned)im->id);
        }
    }
    double n2 = 0.0;
    for (int k = 0; k < 4; k++) {
        n2 += im->q[k] * im->q[k];
    }
    for (int k = 0; k < 7; k++) {
        double v = k < 4 ? im->q[k] : im->t[k - 4];
        if (!isfinite(v) || !(fabs(v) <= NERF__CAMERA_MAX_ABS)) {
            return nerf__error(NERF_EFORMAT, "%s: image %u (%.256s): pose "
                               "value %g is not finite or beyond %g", path,
                               (unsigned)im->id, name, v,
                               NERF__CAMERA_MAX_ABS);
        }
    }
    if (!(n2 > 1e-12)) {
        return nerf__error(NERF_EFORMAT, "%s: image %u (%.256s): the "
                           "quaternion has zero length", path,
                           (unsigned)im->id, name);
    }
    double inv = 1.0 / sqrt(n2);
    for (int k = 0; k < 4; k++) {
        im->q[k] *= inv;
    }
    if (nerf__colmap_find_camera(m, im->camera_id) == NULL) {
        return nerf__error(NERF_EFORMAT, "%s: image %u (%.256s): camera %u "
                           "is not in the cameras file", path,
                           (unsigned)im->id, name, (unsigned)im->camera_id);
    }
    return NERF_OK;
}

static int check_point(const char *path, uint64_t id, const double xyz[3])
{
    for (int k = 0; k < 3; k++) {
        if (!isfinite(xyz[k]) || !(fabs(xyz[k]) <= NERF__CAMERA_MAX_ABS)) {
            return nerf__error(NERF_EFORMAT, "%s: point %llu: coordinate %g "
                               "is not finite or beyond %g", path,
                               (unsigned long long)id, xyz[k],
                               NERF__CAMERA_MAX_ABS);
        }
    }
    return NERF_OK;
}

/* Grow *arr (of *cap elements of size elem) to hold at least need. */
static int grow(const nerf__env *env, void **arr, size_t *cap, size_t need,
                size_t elem)
{
    if (need <= *cap) {
        return NERF_OK;
    }
    size_t n = *cap ? *cap : 16;
    while (n < need) {
        if (n > SIZE_MAX / 2 / elem) {
            return NERF_ENOMEM;
        }
        n *= 2;
    }
    void *p = nerf__calloc(env, n, elem);
    if (p == NULL) {
        return NERF_ENOMEM;
    }
    if (*arr) {
        memcpy(p, *arr, *cap * elem);
    }
    nerf__free(env, *arr);
    *arr = p;
    *cap = n;
    return NERF_OK;
}

static char *copy_name(const nerf__env *env, const char *s, size_t n)
{
    char *out = nerf__alloc(env, n + 1);
    if (out) {
        memcpy(out, s, n);
        out[n] = '\0';
    }
    return out;
}

/* ---- binary ------------------------------------------------------------- */

typedef struct reader {
    const unsigned char *p;
    size_t left;
} reader;

static bool take(reader *r, size_t n, const unsigned char **out)
{
    if (r->left < n) {
        return false;
    }
    *out = r->p;
    r->p += n;
    r->left -= n;
    return true;
}

/* A file that ends inside the record of `what` whose id was read. */
static int truncated(const char *path, const char *what, uint64_t id)
{
    return nerf__error(NERF_EFORMAT, "%s: truncated in %s %llu", path, what,
                       (unsigned long long)id);
}

/* A file that ends before the id of its record index (from 0) of n. */
static int truncated_before(const char *path, const char *what,
                            uint64_t index, uint64_t n)
{
    return nerf__error(NERF_EFORMAT, "%s: truncated after %llu of the %llu "
                       "%s it claims", path, (unsigned long long)index,
                       (unsigned long long)n, what);
}

/* The leading record count, checked against the bytes that follow. */
static int read_count(const char *path, reader *r, size_t min_record,
                      const char *what, uint64_t *out)
{
    const unsigned char *b = NULL;
    if (!take(r, 8, &b)) {
        return nerf__error(NERF_EFORMAT, "%s: truncated: no %s count", path,
                           what);
    }
    *out = nerf__load_le64(b);
    if (*out > r->left / min_record) {
        return nerf__error(NERF_EFORMAT, "%s: truncated or corrupt: claims "
                           "%llu %s, more than its %zu bytes can hold", path,
                           (unsigned long long)*out, what, r->left);
    }
    return NERF_OK;
}

static int cameras_bin(const nerf__env *env, const char *path, reader *r,
                       nerf__colmap_model *m)
{
    uint64_t n = 0;
    int rc = read_count(path, r, 24, "cameras", &n);
    if (rc != NERF_OK) {
        return rc;
    }
    m->cameras = nerf__calloc(env, n ? n : 1, sizeof *m->cameras);
    if (m->cameras == NULL) {
        return NERF_ENOMEM;
    }
    for (uint64_t i = 0; i < n; i++) {
        const unsigned char *b = NULL;
        if (!take(r, 24, &b)) {
            return r->left >= 4 ? truncated(path, "camera",
                                            nerf__load_le32(r->p))
                                : truncated_before(path, "cameras", i, n);
        }
        uint32_t id = nerf__load_le32(b);
        int32_t model = (int32_t)nerf__load_le32(b + 4);
        int np = nerf__colmap_model_param_count(model);
        if (np < 0) {
            return nerf__error(NERF_EFORMAT, "%s: camera %u: unknown camera "
                               "model id %d", path, (unsigned)id, (int)model);
        }
        double p[12] = {0};
        if (model > NERF__COLMAP_OPENCV) {
            /* Refused by name before its parameters are read. */
            return make_camera(path, id, model, 1, 1, p, &m->cameras[i]);
        }
        const unsigned char *pb = NULL;
        if (!take(r, 8 * (size_t)np, &pb)) {
            return truncated(path, "camera", id);
        }
        for (int k = 0; k < np; k++) {
            p[k] = nerf__load_lef64(pb + 8 * k);
        }
        rc = make_camera(path, id, model, nerf__load_le64(b + 8),
                         nerf__load_le64(b + 16), p, &m->cameras[i]);
        if (rc != NERF_OK) {
            return rc;
        }
        m->n_cameras++;
    }
    return NERF_OK;
}

static int images_bin(const nerf__env *env, const char *path, reader *r,
                      nerf__colmap_model *m)
{
    uint64_t n = 0;
    /* id, q, t, camera id, the name's NUL, the 2D point count */
    int rc = read_count(path, r, 64 + 1 + 8, "images", &n);
    if (rc != NERF_OK) {
        return rc;
    }
    m->images = nerf__calloc(env, n ? n : 1, sizeof *m->images);
    if (m->images == NULL) {
        return NERF_ENOMEM;
    }
    for (uint64_t i = 0; i < n; i++) {
        const unsigned char *b = NULL;
        if (!take(r, 64, &b)) {
            return r->left >= 4 ? truncated(path, "image",
                                            nerf__load_le32(r->p))
                                : truncated_before(path, "images", i, n);
        }
        nerf__colmap_image *im = &m->images[i];
        im->id = nerf__load_le32(b);
        for (int k = 0; k < 4; k++) {
            im->q[k] = nerf__load_lef64(b + 4 + 8 * k);
        }
        for (int k = 0; k < 3; k++) {
            im->t[k] = nerf__load_lef64(b + 36 + 8 * k);
        }
        im->camera_id = nerf__load_le32(b + 60);
        size_t limit = r->left < MAX_NAME ? r->left : MAX_NAME;
        const unsigned char *end = memchr(r->p, '\0', limit);
        if (end == NULL) {
            return r->left < MAX_NAME
                       ? truncated(path, "the name of image", im->id)
                       : nerf__error(NERF_EFORMAT, "%s: image %u: name "
                                     "longer than %d bytes", path,
                                     (unsigned)im->id, MAX_NAME);
        }
        size_t len = (size_t)(end - r->p);
        im->name = copy_name(env, (const char *)r->p, len);
        if (im->name == NULL) {
            return NERF_ENOMEM;
        }
        m->n_images++;
        r->p += len + 1;
        r->left -= len + 1;
        if (!take(r, 8, &b)) {
            return truncated(path, "image", im->id);
        }
        uint64_t n2d = nerf__load_le64(b);
        if (n2d > r->left / 24) {
            return nerf__error(NERF_EFORMAT, "%s: truncated or corrupt: image %u "
                               "(%.256s) claims %llu 2D points, more than "
                               "the %zu bytes left can hold", path, (unsigned)im->id,
                               im->name, (unsigned long long)n2d, r->left);
        }
        take(r, 24 * (size_t)n2d, &b);
        rc = check_image(path, m, im);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    return NERF_OK;
}

static int points_bin(const nerf__env *env, const char *path, reader *r,
                      nerf__colmap_model *m)
{
    enum { HEAD = 8 + 24 + 3 + 8 + 8 };
    uint64_t n = 0;
    int rc = read_count(path, r, HEAD, "points", &n);
    if (rc != NERF_OK) {
        return rc;
    }
    /* A first pass sizes the track store and finds any truncation. */
    reader scan = *r;
    uint64_t total = 0;
    for (uint64_t i = 0; i < n; i++) {
        const unsigned char *b = NULL;
        if (!take(&scan, HEAD, &b)) {
            return scan.left >= 8 ? truncated(path, "point",
                                              nerf__load_le64(scan.p))
                                  : truncated_before(path, "points", i, n);
        }
        uint64_t len = nerf__load_le64(b + HEAD - 8);
        if (len > scan.left / 8) {
            return nerf__error(NERF_EFORMAT, "%s: truncated or corrupt: point %llu "
                               "claims a track of %llu images, more than the "
                               "%zu bytes left can hold", path,
                               (unsigned long long)nerf__load_le64(b),
                               (unsigned long long)len, scan.left);
        }
        take(&scan, 8 * (size_t)len, &b);
        total += len;
    }
    m->points = nerf__calloc(env, n ? n : 1, sizeof *m->points);
    m->track = nerf__calloc(env, total ? total : 1, sizeof *m->track);
    if (m->points == NULL || m->track == NULL) {
        return NERF_ENOMEM;
    }
    for (uint64_t i = 0; i < n; i++) {
        const unsigned char *b = NULL;
        take(r, HEAD, &b);
        nerf__colmap_point *pt = &m->points[i];
        for (int k = 0; k < 3; k++) {
            pt->xyz[k] = nerf__load_lef64(b + 8 + 8 * k);
        }
        rc = check_point(path, nerf__load_le64(b), pt->xyz);
        if (rc != NERF_OK) {
            return rc;
        }
        pt->track_first = m->n_track;
        pt->track_len = (size_t)nerf__load_le64(b + HEAD - 8);
        take(r, 8 * pt->track_len, &b);
        for (size_t k = 0; k < pt->track_len; k++) {
            m->track[m->n_track++] = nerf__load_le32(b + 8 * k);
        }
        m->n_points++;
    }
    return NERF_OK;
}

/* ---- text --------------------------------------------------------------- */

/*
 * A line of a text file, NUL-terminated in place, with a cursor over its
 * whitespace-separated tokens.
 */
typedef struct line {
    char *cur;
    size_t number; /* 1-based, for messages */
} line;

static bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r';
}

/* The next token, NUL-terminated in place; NULL at the end of the line. */
static char *token(line *l)
{
    while (is_space(*l->cur)) {
        l->cur++;
    }
    if (*l->cur == '\0') {
        return NULL;
    }
    char *start = l->cur;
    while (*l->cur && !is_space(*l->cur)) {
        l->cur++;
    }
    if (*l->cur) {
        *l->cur++ = '\0';
    }
    return start;
}

static bool tok_double(line *l, double *out)
{
    char *t = token(l), *end;
    if (t == NULL) {
        return false;
    }
    errno = 0;
    *out = strtod(t, &end);
    return *end == '\0' && end != t && isfinite(*out);
}

static bool tok_u64(line *l, uint64_t max, uint64_t *out)
{
    char *t = token(l), *end;
    if (t == NULL || !(*t >= '0' && *t <= '9')) {
        return false;
    }
    errno = 0;
    unsigned long long v = strtoull(t, &end, 10);
    if (*end != '\0' || errno == ERANGE || v > max) {
        return false;
    }
    *out = v;
    return true;
}

/*
 * A writable, NUL-terminated copy of the file with every line ending
 * replaced by NUL; lines are walked with next_line().
 */
typedef struct text {
    char *buf;
    char *next;
    char *end;
    size_t number;
} text;

static int text_open(const nerf__env *env, const unsigned char *data,
                     size_t size, text *t)
{
    t->buf = nerf__alloc(env, size + 1);
    if (t->buf == NULL) {
        return NERF_ENOMEM;
    }
    memcpy(t->buf, data, size);
    t->buf[size] = '\0';
    t->next = t->buf;
    t->end = t->buf + size;
    t->number = 0;
    return NERF_OK;
}

/* The next line (comments and blank lines included); false at the end. */
static bool next_line(text *t, line *l)
{
    if (t->next >= t->end) {
        return false;
    }
    char *start = t->next;
    char *nl = memchr(start, '\n', (size_t)(t->end - start));
    if (nl) {
        *nl = '\0';
        t->next = nl + 1;
    } else {
        t->next = t->end;
    }
    l->cur = start;
    l->number = ++t->number;
    return true;
}

/* Whether a line holds nothing but a comment or whitespace. */
static bool skippable(const line *l)
{
    const char *c = l->cur;
    while (is_space(*c)) {
        c++;
    }
    return *c == '\0' || *c == '#';
}

/* A NUL byte inside a text file would end lines early: refuse it. */
static int text_check(const char *path, const unsigned char *data, size_t size)
{
    if (memchr(data, '\0', size) != NULL) {
        return nerf__error(NERF_EFORMAT, "%s: holds a NUL byte: not a text "
                           "file (binary models are .bin)", path);
    }
    return NERF_OK;
}

static int bad_line(const char *path, size_t number, const char *what)
{
    return nerf__error(NERF_EFORMAT, "%s:%zu: %s", path, number, what);
}

static int cameras_txt(const nerf__env *env, const char *path, text *t,
                       nerf__colmap_model *m)
{
    size_t cap = 0;
    line l;
    while (next_line(t, &l)) {
        if (skippable(&l)) {
            continue;
        }
        uint64_t id, w, h;
        if (!tok_u64(&l, UINT32_MAX, &id)) {
            return bad_line(path, l.number, "expected CAMERA_ID MODEL WIDTH "
                            "HEIGHT PARAMS...: bad camera id");
        }
        const char *model_name = token(&l);
        int model = -1;
        for (int k = 0; model_name && k < NERF__COLMAP_N_MODELS; k++) {
            if (strcmp(model_name, models[k].name) == 0) {
                model = k;
            }
        }
        if (model < 0) {
            return nerf__error(NERF_EFORMAT, "%s:%zu: camera %u: unknown "
                               "camera model '%.64s'", path, l.number,
                               (unsigned)id, model_name ? model_name : "");
        }
        if (!tok_u64(&l, UINT64_MAX, &w) || !tok_u64(&l, UINT64_MAX, &h)) {
            return bad_line(path, l.number, "bad image width or height");
        }
        double p[12] = {0};
        if (model <= NERF__COLMAP_OPENCV) {
            for (int k = 0; k < models[model].n_params; k++) {
                if (!tok_double(&l, &p[k])) {
                    return nerf__error(NERF_EFORMAT, "%s:%zu: camera %u: %s "
                                       "needs %d finite parameters", path,
                                       l.number, (unsigned)id,
                                       models[model].name,
                                       models[model].n_params);
                }
            }
            if (token(&l) != NULL) {
                return nerf__error(NERF_EFORMAT, "%s:%zu: camera %u: more "
                                   "than the %d parameters of %s", path,
                                   l.number, (unsigned)id,
                                   models[model].n_params,
                                   models[model].name);
            }
        }
        int rc = grow(env, (void **)&m->cameras, &cap, m->n_cameras + 1,
                      sizeof *m->cameras);
        if (rc == NERF_OK) {
            rc = make_camera(path, (uint32_t)id, model, w, h, p,
                             &m->cameras[m->n_cameras]);
        }
        if (rc != NERF_OK) {
            return rc;
        }
        m->n_cameras++;
    }
    return NERF_OK;
}

/*
 * Each image is two lines: the pose line and the line of its 2D points,
 * which may be empty (and is then not a blank line to skip).
 */
static int images_txt(const nerf__env *env, const char *path, text *t,
                      nerf__colmap_model *m)
{
    size_t cap = 0;
    line l;
    while (next_line(t, &l)) {
        if (skippable(&l)) {
            continue;
        }
        int rc = grow(env, (void **)&m->images, &cap, m->n_images + 1,
                      sizeof *m->images);
        if (rc != NERF_OK) {
            return rc;
        }
        nerf__colmap_image *im = &m->images[m->n_images];
        uint64_t id, cam;
        bool ok = tok_u64(&l, UINT32_MAX, &id);
        for (int k = 0; ok && k < 4; k++) {
            ok = tok_double(&l, &im->q[k]);
        }
        for (int k = 0; ok && k < 3; k++) {
            ok = tok_double(&l, &im->t[k]);
        }
        ok = ok && tok_u64(&l, UINT32_MAX, &cam);
        const char *name = ok ? token(&l) : NULL;
        if (name == NULL) {
            return bad_line(path, l.number, "expected IMAGE_ID QW QX QY QZ "
                            "TX TY TZ CAMERA_ID NAME");
        }
        size_t len = strlen(name);
        if (len > MAX_NAME) {
            return bad_line(path, l.number, "image name too long");
        }
        im->id = (uint32_t)id;
        im->camera_id = (uint32_t)cam;
        im->name = copy_name(env, name, len);
        if (im->name == NULL) {
            return NERF_ENOMEM;
        }
        m->n_images++;
        rc = check_image(path, m, im);
        if (rc != NERF_OK) {
            return rc;
        }
        /* The 2D points: triples X Y POINT3D_ID, not kept. */
        if (next_line(t, &l)) {
            size_t n = 0;
            while (token(&l) != NULL) {
                n++;
            }
            if (n % 3 != 0) {
                return nerf__error(NERF_EFORMAT, "%s:%zu: image %u: the 2D "
                                   "points line holds %zu values, not "
                                   "triples X Y POINT3D_ID", path, l.number,
                                   (unsigned)im->id, n);
            }
        }
    }
    return NERF_OK;
}

static int points_txt(const nerf__env *env, const char *path, text *t,
                      nerf__colmap_model *m)
{
    size_t cap = 0, track_cap = 0;
    line l;
    while (next_line(t, &l)) {
        if (skippable(&l)) {
            continue;
        }
        uint64_t id, rgb, image, idx;
        nerf__colmap_point pt;
        double err;
        bool ok = tok_u64(&l, UINT64_MAX, &id);
        for (int k = 0; ok && k < 3; k++) {
            ok = tok_double(&l, &pt.xyz[k]);
        }
        for (int k = 0; ok && k < 3; k++) {
            ok = tok_u64(&l, 255, &rgb);
        }
        ok = ok && tok_double(&l, &err);
        if (!ok) {
            return bad_line(path, l.number, "expected POINT3D_ID X Y Z R G B "
                            "ERROR TRACK...");
        }
        int rc = check_point(path, id, pt.xyz);
        if (rc != NERF_OK) {
            return rc;
        }
        pt.track_first = m->n_track;
        pt.track_len = 0;
        for (;;) {
            while (is_space(*l.cur)) {
                l.cur++;
            }
            if (*l.cur == '\0') {
                break;
            }
            if (!tok_u64(&l, UINT32_MAX, &image) ||
                !tok_u64(&l, UINT32_MAX, &idx)) {
                return nerf__error(NERF_EFORMAT, "%s:%zu: point %llu: the "
                                   "track must be pairs IMAGE_ID POINT2D_IDX",
                                   path, l.number, (unsigned long long)id);
            }
            rc = grow(env, (void **)&m->track, &track_cap, m->n_track + 1,
                      sizeof *m->track);
            if (rc != NERF_OK) {
                return rc;
            }
            m->track[m->n_track++] = (uint32_t)image;
            pt.track_len++;
        }
        rc = grow(env, (void **)&m->points, &cap, m->n_points + 1,
                  sizeof *m->points);
        if (rc != NERF_OK) {
            return rc;
        }
        m->points[m->n_points++] = pt;
    }
    return NERF_OK;
}

/* ---- entry points ------------------------------------------------------- */

typedef int (*bin_fn)(const nerf__env *, const char *, reader *,
                      nerf__colmap_model *);
typedef int (*txt_fn)(const nerf__env *, const char *, text *,
                      nerf__colmap_model *);

static int parse(const nerf__env *env, const char *path,
                 const unsigned char *data, size_t size, int binary,
                 nerf__colmap_model *m, bin_fn bin, txt_fn txt)
{
    if (binary) {
        reader r = {data, size};
        int rc = bin(env, path, &r, m);
        if (rc == NERF_OK && r.left != 0) {
            rc = nerf__error(NERF_EFORMAT, "%s: %zu bytes after the last "
                             "record", path, r.left);
        }
        return rc;
    }
    int rc = text_check(path, data, size);
    if (rc != NERF_OK) {
        return rc;
    }
    text t;
    rc = text_open(env, data, size, &t);
    if (rc == NERF_OK) {
        rc = txt(env, path, &t, m);
        nerf__free(env, t.buf);
    }
    return rc;
}

int nerf__colmap_parse_cameras(const nerf__env *env, const char *path,
                               const unsigned char *data, size_t size,
                               int binary, nerf__colmap_model *m)
{
    int rc = parse(env, path, data, size, binary, m, cameras_bin,
                   cameras_txt);
    return rc == NERF_OK ? sort_cameras(path, m) : rc;
}

int nerf__colmap_parse_images(const nerf__env *env, const char *path,
                              const unsigned char *data, size_t size,
                              int binary, nerf__colmap_model *m)
{
    int rc = parse(env, path, data, size, binary, m, images_bin, images_txt);
    if (rc == NERF_OK && m->n_images == 0) {
        rc = nerf__error(NERF_EFORMAT, "%s: no images (COLMAP registered "
                         "none)", path);
    }
    return rc;
}

int nerf__colmap_parse_points(const nerf__env *env, const char *path,
                              const unsigned char *data, size_t size,
                              int binary, nerf__colmap_model *m)
{
    return parse(env, path, data, size, binary, m, points_bin, points_txt);
}
