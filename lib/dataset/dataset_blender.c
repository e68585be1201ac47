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
#include "transforms.h"

/* An unbounded Blender-layout scene (aabb_scale > 1): the central cube's
 * half side (the Blender scenes' bound), and its rays' bounds in units of
 * it. */
#define BLENDER_INNER 1.5
#define UNBOUNDED_NEAR 0.05
#define UNBOUNDED_FAR 1e4

typedef struct frame {
    uint32_t index;  /* position in the file's frames list */
    char name[224];  /* for messages: index and file_path */
    char *path;
    double c2w[12];
    nerf__intrinsics in;
} frame;

/* Everything one load needs, so that the helpers take one pointer. */
typedef struct blender_ctx {
    nerf_dataset *ds;
    const char *dir;
    const char *json_path;
    frame *frames;
    uint32_t n_frames;
    bool whole;        /* one transforms.json for every split */
} blender_ctx;

/*
 * A bare file_path (the Blender scenes write "./train/r_0") names the PNG
 * beside it, as it always has, or failing that a JPEG: the first of these
 * that exists.  With none of them the .png path is kept, so that the error
 * (or skip_missing) names what the format expects.
 */
static const char *const bare_exts[] = {".png", ".jpg", ".jpeg", ".JPG",
                                        ".JPEG"};
#define BARE_EXT_MAX 5

static void add_extension(const char *dir, char *rel, size_t stem)
{
    for (size_t k = 0; k < sizeof bare_exts / sizeof *bare_exts; k++) {
        strcpy(rel + stem, bare_exts[k]);
        char full[4096];
        struct stat st;
        if (snprintf(full, sizeof full, "%s/%s", dir, rel) <
                (int)sizeof full &&
            stat(full, &st) == 0) {
            return;
        }
    }
    strcpy(rel + stem, bare_exts[0]);
}

/* The image path of a frame: relative to the json, an extension added
 * when bare (add_extension). */
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
    size_t stem = strlen(name);
    char *rel = nerf__alloc(&b->ds->env, stem + BARE_EXT_MAX + 1);
    if (rel == NULL) {
        return NERF_ENOMEM;
    }
    strcpy(rel, name);
    if (!has_ext) {
        add_extension(b->dir, rel, stem);
    }
    *out = nerf__path_join(&b->ds->env, b->dir, rel);
    nerf__free(&b->ds->env, rel);
    return *out ? NERF_OK : NERF_ENOMEM;
}

/*
 * Whether frame idx belongs to the split: a file of one split holds only
 * its own frames; one transforms.json for all splits is split as LLFF
 * scenes are, every llff_holdout-th frame (from the first) held out for
 * test and val, or with a hold-out of 0 serves every frame to every split.
 */
static bool in_split(const blender_ctx *b, uint32_t idx,
                     const nerf__dataset_config *cfg)
{
    if (!b->whole || cfg->llff_holdout == 0) {
        return true;
    }
    bool held = idx % cfg->llff_holdout == 0;
    return cfg->split == NERF_SPLIT_TRAIN ? !held : held;
}

/* Collect the frames of the split that the skip setting keeps, in file
 * order. */
static int parse_frames(blender_ctx *b, const cJSON *root,
                        const nerf__dataset_config *cfg)
{
    nerf__intrinsics top;
    const cJSON *frames = NULL;
    int rc = nerf__transforms_top(b->json_path, root, &top, &frames,
                                  &b->ds->aabb_scale);
    if (rc != NERF_OK) {
        return rc;
    }
    int total = cJSON_GetArraySize(frames);
    b->frames = nerf__calloc(&b->ds->env, (size_t)total / cfg->skip + 1,
                             sizeof *b->frames);
    if (b->frames == NULL) {
        return NERF_ENOMEM;
    }
    uint32_t idx = 0, seen = 0;
    for (const cJSON *fr = frames->child; fr; fr = fr->next, idx++) {
        if (!in_split(b, idx, cfg) || seen++ % cfg->skip != 0) {
            continue;
        }
        frame *f = &b->frames[b->n_frames];
        nerf__transforms_frame_name(fr, idx, f->name, sizeof f->name);
        char where[256];
        snprintf(where, sizeof where, "%s: ", f->name);
        f->index = idx;
        f->in = top;
        rc = cJSON_IsObject(fr) ? NERF_OK
             : nerf__error(NERF_EFORMAT, "%s: %snot a JSON object",
                           b->json_path, where);
        if (rc == NERF_OK) {
            rc = nerf__transforms_read_intrinsics(b->json_path, fr, where,
                                                  &f->in);
        }
        if (rc == NERF_OK) {
            rc = nerf__transforms_read_matrix(b->json_path, fr, f->name,
                                              f->c2w);
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
    const nerf__intrinsics *in = &f->in;
    if ((!isnan(in->w) && in->w != w) || (!isnan(in->h) && in->h != h)) {
        return nerf__error(NERF_EFORMAT, "%s: %s: w x h is %gx%g but "
                           "%s is %ux%u", b->json_path, f->name,
                           in->w, in->h, f->path, (unsigned)w, (unsigned)h);
    }
    double k[4];
    int rc = nerf__transforms_focal(b->json_path, f->name, in, w, h, k);
    if (rc != NERF_OK) {
        return rc;
    }
    v->fx = k[0];
    v->fy = k[1];
    v->cx = k[2];
    v->cy = k[3];
    v->k1 = in->k1;
    v->k2 = in->k2;
    v->p1 = in->p1;
    v->p2 = in->p2;
    v->k3 = in->k3;
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
        /* The distortion acts on normalised coordinates: it does not
         * scale with the image. */
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
    cJSON *root = NULL;
    int rc = nerf__transforms_parse(&b->ds->env, b->json_path, &root);
    if (rc == NERF_OK) {
        rc = parse_frames(b, root, cfg);
    }
    cJSON_Delete(root);
    return rc;
}

int nerf__blender_load(nerf_dataset *ds, const char *dir, const char *name,
                       bool whole, const nerf__dataset_config *cfg)
{
    blender_ctx b = {ds, dir, NULL, NULL, 0, whole};
    char *json_path = nerf__path_join(&ds->env, dir, name);
    if (json_path == NULL) {
        return NERF_ENOMEM;
    }
    b.json_path = json_path;
    int rc = parse_file(&b, cfg);
    if (rc == NERF_OK && b.n_frames == 0 && whole) {
        rc = nerf__error(NERF_EINVAL, "%s: the requested split has no "
                         "frames (holdout %u)", json_path,
                         (unsigned)cfg->llff_holdout);
    }
    if (rc == NERF_OK) {
        rc = load_frames(&b, cfg);
    }
    if (rc == NERF_OK) {
        ds->kind = NERF__DATASET_BLENDER;
        ds->near_bound = 2.0f;
        ds->far_bound = 6.0f;
        if (ds->aabb_scale > 1.0) {
            /* instant-ngp's sign of a scene reaching far beyond its
             * centre: contract it beyond the Blender scenes' bound, and
             * sample from near the cameras to far beyond the scene. */
            ds->unbounded_inner = BLENDER_INNER;
            ds->near_bound = (float)(UNBOUNDED_NEAR * BLENDER_INNER);
            ds->far_bound = (float)(UNBOUNDED_FAR * BLENDER_INNER);
        }
        ds->scene_scale = 1.0;
        nerf__log(&ds->env, NERF_LOG_INFO,
                  "%s: Blender scene, %u images of %ux%u (downscale %u from "
                  "%ux%u), focal %.3f x %.3f, near %g far %g, cameras up to "
                  "%.3f from the origin", json_path, (unsigned)ds->count,
                  (unsigned)ds->width, (unsigned)ds->height,
                  (unsigned)cfg->downscale, (unsigned)ds->src_width,
                  (unsigned)ds->src_height, ds->views[0].fx, ds->views[0].fy,
                  ds->near_bound, ds->far_bound, ds->scene_radius);
        const nerf__view *v = &ds->views[0];
        if (v->k1 != 0.0 || v->k2 != 0.0 || v->p1 != 0.0 || v->p2 != 0.0 ||
            v->k3 != 0.0) {
            nerf__log(&ds->env, NERF_LOG_INFO, "%s: lens distortion (first "
                      "image) k1 %g k2 %g p1 %g p2 %g k3 %g", json_path,
                      v->k1, v->k2, v->p1, v->p2, v->k3);
        }
        if (whole && cfg->llff_holdout > 0) {
            nerf__log(&ds->env, NERF_LOG_INFO, "%s: one file for every "
                      "split: every %u-th frame is test and val, the others "
                      "train", json_path, (unsigned)cfg->llff_holdout);
        } else if (whole) {
            nerf__log(&ds->env, NERF_LOG_INFO, "%s: one file for every "
                      "split, holdout 0: every frame in every split",
                      json_path);
        }
    }
    for (uint32_t i = 0; i < b.n_frames; i++) {
        nerf__free(&ds->env, b.frames[i].path);
    }
    nerf__free(&ds->env, b.frames);
    nerf__free(&ds->env, json_path);
    return rc;
}
