/*
 * Blender / "Realistic Synthetic 360" scenes, and instant-ngp style
 * transforms.json files, which extend the same layout with explicit
 * intrinsics.
 */
#include <cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "dataset.h"
#include "file_io.h"

/* Generous: a transforms file lists one small object per frame. */
#define JSON_MAX_BYTES (64u << 20)
#define PI_D 3.14159265358979323846

/* Intrinsics fields, at top level or per frame; NAN when absent. */
typedef struct intrinsics {
    double angle_x, angle_y, fl_x, fl_y, cx, cy, w, h;
} intrinsics;

typedef struct frame {
    uint32_t index;  /* position in the file's frames list */
    char *path;
    double c2w[12];
    intrinsics in;
} frame;

/* Everything one load needs, so that the helpers take one pointer. */
typedef struct blender_ctx {
    nerf_dataset *ds;
    const char *dir;
    const char *json_path;
    frame *frames;
    uint32_t n_frames;
} blender_ctx;

/* Read key as a finite number into *out when present. */
static int get_number(const blender_ctx *b, const cJSON *obj, const char *key,
                      const char *where, double *out)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (item == NULL) {
        return NERF_OK;
    }
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble)) {
        return nerf__error(NERF_EFORMAT, "%s: %sfield '%s' is not a finite "
                           "number", b->json_path, where, key);
    }
    *out = item->valuedouble;
    return NERF_OK;
}

static int read_intrinsics(const blender_ctx *b, const cJSON *obj,
                           const char *where, intrinsics *in)
{
    static const char *const keys[] = {"camera_angle_x", "camera_angle_y",
                                       "fl_x", "fl_y", "cx", "cy", "w", "h"};
    double *fields[] = {&in->angle_x, &in->angle_y, &in->fl_x, &in->fl_y,
                        &in->cx, &in->cy, &in->w, &in->h};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        int rc = get_number(b, obj, keys[i], where, fields[i]);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    return NERF_OK;
}

static double det3(const double *m, size_t stride)
{
    const double *r0 = m, *r1 = m + stride, *r2 = m + 2 * stride;
    return r0[0] * (r1[1] * r2[2] - r1[2] * r2[1]) -
           r0[1] * (r1[0] * r2[2] - r1[2] * r2[0]) +
           r0[2] * (r1[0] * r2[1] - r1[1] * r2[0]);
}

/* transform_matrix: 4 rows (or the top 3) of 4 finite numbers. */
static int read_matrix(const blender_ctx *b, const cJSON *fr, uint32_t idx,
                       double *c2w)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(fr, "transform_matrix");
    if (m == NULL) {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: missing field "
                           "'transform_matrix'", b->json_path, (unsigned)idx);
    }
    int rows = cJSON_IsArray(m) ? cJSON_GetArraySize(m) : -1;
    if (rows != 3 && rows != 4) {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: transform_matrix "
                           "must be a list of 4 rows of 4 numbers",
                           b->json_path, (unsigned)idx);
    }
    double last[4] = {0.0, 0.0, 0.0, 1.0};
    for (int r = 0; r < rows; r++) {
        const cJSON *row = cJSON_GetArrayItem(m, r);
        if (!cJSON_IsArray(row) || cJSON_GetArraySize(row) != 4) {
            return nerf__error(NERF_EFORMAT, "%s: frame %u: transform_matrix "
                               "row %d is not a list of 4 numbers",
                               b->json_path, (unsigned)idx, r);
        }
        for (int c = 0; c < 4; c++) {
            const cJSON *v = cJSON_GetArrayItem(row, c);
            if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) {
                return nerf__error(NERF_EFORMAT, "%s: frame %u: "
                                   "transform_matrix[%d][%d] is not a finite "
                                   "number", b->json_path, (unsigned)idx, r, c);
            }
            double *dst = r < 3 ? &c2w[r * 4 + c] : &last[c];
            *dst = v->valuedouble;
        }
    }
    static const double homogeneous[4] = {0.0, 0.0, 0.0, 1.0};
    for (int c = 0; c < 4; c++) {
        if (fabs(last[c] - homogeneous[c]) > 1e-4) {
            return nerf__error(NERF_EFORMAT, "%s: frame %u: the last row of "
                               "transform_matrix must be [0, 0, 0, 1]",
                               b->json_path, (unsigned)idx);
        }
    }
    if (fabs(det3(c2w, 4)) < 1e-9) {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: transform_matrix has "
                           "a degenerate rotation", b->json_path,
                           (unsigned)idx);
    }
    return NERF_OK;
}

/* The image path of a frame: relative to the json, ".png" when bare. */
static int frame_path(const blender_ctx *b, const cJSON *fr, uint32_t idx,
                      char **out)
{
    const cJSON *fp = cJSON_GetObjectItemCaseSensitive(fr, "file_path");
    if (!cJSON_IsString(fp) || fp->valuestring[0] == '\0') {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: %s 'file_path'",
                           b->json_path, (unsigned)idx,
                           fp == NULL ? "missing field" : "bad string in");
    }
    const char *name = fp->valuestring;
    while (name[0] == '.' && name[1] == '/') {
        name += 2;
    }
    const char *base = strrchr(name, '/');
    base = base ? base + 1 : name;
    bool has_ext = strchr(base + (base[0] != '\0'), '.') != NULL;
    char *rel = nerf__alloc(&b->ds->env, strlen(name) + 5);
    if (rel == NULL) {
        return NERF_ENOMEM;
    }
    strcpy(rel, name);
    if (!has_ext) {
        strcat(rel, ".png");
    }
    *out = nerf__path_join(&b->ds->env, b->dir, rel);
    nerf__free(&b->ds->env, rel);
    return *out ? NERF_OK : NERF_ENOMEM;
}

/* Collect the frames the skip setting keeps, in file order. */
static int parse_frames(blender_ctx *b, const cJSON *root,
                        const nerf__dataset_config *cfg)
{
    if (!cJSON_IsObject(root)) {
        return nerf__error(NERF_EFORMAT, "%s: the top level is not a JSON "
                           "object", b->json_path);
    }
    intrinsics top = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
    int rc = read_intrinsics(b, root, "", &top);
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    if (rc == NERF_OK && !cJSON_IsArray(frames)) {
        rc = nerf__error(NERF_EFORMAT, "%s: %s 'frames'", b->json_path,
                         frames ? "not a list:" : "missing field");
    }
    if (rc != NERF_OK) {
        return rc;
    }
    int total = cJSON_GetArraySize(frames);
    b->frames = nerf__calloc(&b->ds->env, (size_t)total / cfg->skip + 1,
                             sizeof *b->frames);
    if (b->frames == NULL) {
        return NERF_ENOMEM;
    }
    uint32_t idx = 0;
    for (const cJSON *fr = frames->child; fr; fr = fr->next, idx++) {
        if (idx % cfg->skip != 0) {
            continue;
        }
        frame *f = &b->frames[b->n_frames];
        char where[32];
        snprintf(where, sizeof where, "frame %u: ", (unsigned)idx);
        f->index = idx;
        f->in = top;
        rc = cJSON_IsObject(fr) ? NERF_OK
             : nerf__error(NERF_EFORMAT, "%s: %snot a JSON object",
                           b->json_path, where);
        if (rc == NERF_OK) {
            rc = read_intrinsics(b, fr, where, &f->in);
        }
        if (rc == NERF_OK) {
            rc = read_matrix(b, fr, idx, f->c2w);
        }
        if (rc == NERF_OK) {
            rc = frame_path(b, fr, idx, &f->path);
        }
        if (rc != NERF_OK) {
            return rc;
        }
        b->n_frames++;
    }
    return NERF_OK;
}

/* Fill a view from a frame, in the units of the file's image size. */
static int resolve_intrinsics(const blender_ctx *b, const frame *f,
                              uint32_t w, uint32_t h, nerf__view *v)
{
    const intrinsics *in = &f->in;
    if ((!isnan(in->w) && in->w != w) || (!isnan(in->h) && in->h != h)) {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: w x h is %gx%g but "
                           "%s is %ux%u", b->json_path, (unsigned)f->index,
                           in->w, in->h, f->path, (unsigned)w, (unsigned)h);
    }
    double angles[2] = {in->angle_x, in->angle_y};
    for (int i = 0; i < 2; i++) {
        if (!isnan(angles[i]) && !(angles[i] > 0.0 && angles[i] < PI_D)) {
            return nerf__error(NERF_EFORMAT, "%s: frame %u: camera_angle_%c "
                               "%g is not in (0, pi)", b->json_path,
                               (unsigned)f->index, i ? 'y' : 'x', angles[i]);
        }
    }
    if (!isnan(in->fl_x)) {
        v->fx = in->fl_x;
    } else if (!isnan(in->angle_x)) {
        v->fx = 0.5 * w / tan(0.5 * in->angle_x);
    } else {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: missing field "
                           "'camera_angle_x' (or 'fl_x')", b->json_path,
                           (unsigned)f->index);
    }
    if (!isnan(in->fl_y)) {
        v->fy = in->fl_y;
    } else if (!isnan(in->angle_y)) {
        v->fy = 0.5 * h / tan(0.5 * in->angle_y);
    } else {
        v->fy = v->fx;
    }
    v->cx = isnan(in->cx) ? 0.5 * w : in->cx;
    v->cy = isnan(in->cy) ? 0.5 * h : in->cy;
    if (!(v->fx > 0.0) || !(v->fy > 0.0)) {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: focal length must be "
                           "positive (fx %g, fy %g)", b->json_path,
                           (unsigned)f->index, v->fx, v->fy);
    }
    memcpy(v->c2w, f->c2w, sizeof v->c2w);
    return NERF_OK;
}

static bool file_missing(const char *path)
{
    struct stat st;
    return stat(path, &st) != 0 && errno == ENOENT;
}

/* Load the images of the kept frames and set up their cameras. */
static int load_frames(blender_ctx *b, const nerf__dataset_config *cfg)
{
    nerf_dataset *ds = b->ds;
    uint32_t kept = 0, missing = 0;
    for (uint32_t i = 0; i < b->n_frames; i++) {
        frame f = b->frames[i];
        b->frames[i].path = NULL;
        if (cfg->skip_missing && file_missing(f.path)) {
            nerf__free(&ds->env, f.path);
            missing++;
            continue;
        }
        b->frames[kept++] = f;
    }
    b->n_frames = kept;
    if (missing > 0) {
        nerf__log(&ds->env, NERF_LOG_WARN, "%s: skipped %u frame(s) whose "
                  "image is missing", b->json_path, (unsigned)missing);
    }
    if (kept == 0) {
        return nerf__error(NERF_EFORMAT, "%s: no frames to load", b->json_path);
    }
    int rc = nerf__dataset_reserve(ds, kept);
    double k = cfg->downscale;
    for (uint32_t i = 0; i < kept && rc == NERF_OK; i++) {
        rc = nerf__dataset_load_image(ds, i, b->frames[i].path, cfg->downscale,
                                      cfg->white_background);
        nerf__view *v = &ds->views[i];
        if (rc == NERF_OK) {
            rc = resolve_intrinsics(b, &b->frames[i], ds->src_width,
                                    ds->src_height, v);
        }
        if (rc != NERF_OK) {
            break;
        }
        v->fx /= k;
        v->fy /= k;
        v->cx /= k;
        v->cy /= k;
        double r = sqrt(v->c2w[3] * v->c2w[3] + v->c2w[7] * v->c2w[7] +
                        v->c2w[11] * v->c2w[11]);
        ds->scene_radius = r > ds->scene_radius ? r : ds->scene_radius;
    }
    return rc;
}

static int parse_file(blender_ctx *b, const nerf__dataset_config *cfg)
{
    unsigned char *text;
    size_t size;
    int rc = nerf__file_read(&b->ds->env, b->json_path, JSON_MAX_BYTES, &text,
                             &size);
    if (rc != NERF_OK) {
        return rc;
    }
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts((const char *)text, size, &end, 0);
    if (root == NULL) {
        size_t pos = end ? (size_t)(end - (const char *)text) : 0;
        size_t line = 1;
        for (size_t i = 0; i < pos && i < size; i++) {
            line += text[i] == '\n';
        }
        rc = nerf__error(NERF_EFORMAT, "%s: invalid JSON at line %zu (byte "
                         "%zu)", b->json_path, line, pos);
    } else {
        rc = parse_frames(b, root, cfg);
    }
    cJSON_Delete(root);
    nerf__free(&b->ds->env, text);
    return rc;
}

int nerf__blender_load(nerf_dataset *ds, const char *dir, const char *name,
                       const nerf__dataset_config *cfg)
{
    blender_ctx b = {ds, dir, NULL, NULL, 0};
    char *json_path = nerf__path_join(&ds->env, dir, name);
    if (json_path == NULL) {
        return NERF_ENOMEM;
    }
    b.json_path = json_path;
    int rc = parse_file(&b, cfg);
    if (rc == NERF_OK) {
        rc = load_frames(&b, cfg);
    }
    if (rc == NERF_OK) {
        ds->kind = NERF__DATASET_BLENDER;
        ds->near_bound = 2.0f;
        ds->far_bound = 6.0f;
        ds->scene_scale = 1.0;
        nerf__log(&ds->env, NERF_LOG_INFO,
                  "%s: Blender scene, %u images of %ux%u (downscale %u from "
                  "%ux%u), focal %.3f x %.3f, near %g far %g, cameras up to "
                  "%.3f from the origin", json_path, (unsigned)ds->count,
                  (unsigned)ds->width, (unsigned)ds->height,
                  (unsigned)cfg->downscale, (unsigned)ds->src_width,
                  (unsigned)ds->src_height, ds->views[0].fx, ds->views[0].fy,
                  ds->near_bound, ds->far_bound, ds->scene_radius);
    }
    for (uint32_t i = 0; i < b.n_frames; i++) {
        nerf__free(&ds->env, b.frames[i].path);
    }
    nerf__free(&ds->env, b.frames);
    nerf__free(&ds->env, json_path);
    return rc;
}
