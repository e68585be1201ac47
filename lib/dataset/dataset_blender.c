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

/* The transforms files a load reads: the split's and the other two. */
#define MAX_FILES 3

typedef struct frame {
    uint32_t index;  /* position in the file's frames list */
    uint32_t file;   /* which of blender_ctx.json_paths lists it */
    bool load;       /* in the split, kept by skip; else only checked */
    bool dropped;    /* loaded, but its image is missing (skip_missing) */
    char name[224];  /* for messages: index and file_path */
    char *path;
    char *mask;      /* its mask image, or NULL */
    nerf__mask_rule rule;
    double c2w[12];
    nerf__intrinsics in;
} frame;

/* Everything one load needs, so that the helpers take one pointer. */
typedef struct blender_ctx {
    nerf_dataset *ds;
    const char *dir;
    const char *json_path;   /* the split's file: json_paths[0] */
    char *json_paths[MAX_FILES];
    uint32_t n_files;
    frame *frames;           /* of every file, in file order */
    uint32_t n_frames, cap;
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
static int frame_path(const blender_ctx *b, const char *json_path,
                      const cJSON *fr, const char *frame_name, uint32_t idx,
                      char **out)
{
    const cJSON *fp = cJSON_GetObjectItemCaseSensitive(fr, "file_path");
    if (!cJSON_IsString(fp) || fp->valuestring[0] == '\0') {
        return nerf__error(NERF_EFORMAT, "%s: frame %u: %s 'file_path'",
                           json_path, (unsigned)idx,
                           fp == NULL ? "missing field" : "bad string in");
    }
    const char *name = fp->valuestring;
    while (name[0] == '.' && name[1] == '/') {
        name += 2;
    }
    const char *base = strrchr(name, '/');
    base = base ? base + 1 : name;
    /* Not a name an extension could turn into a file's. */
    if (base[0] == '\0' || strcmp(base, ".") == 0 ||
        strcmp(base, "..") == 0) {
        return nerf__error(NERF_EFORMAT, "%s: %s: file_path '%.256s' names "
                           "a folder, not an image", json_path, frame_name,
                           fp->valuestring);
    }
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
 * The frame's mask, when it has one: nerfstudio's mask_path (relative to
 * the json's folder, 0 = leave out), else instant-ngp's
 * dynamic_mask_<image stem>.png beside the image (nonzero = something
 * that moves: leave out), which instant-ngp finds by its name alone.
 */
static int frame_mask(const blender_ctx *b, const char *json_path,
                      const cJSON *fr, frame *f)
{
    nerf__env *env = &b->ds->env;
    const cJSON *mp = cJSON_GetObjectItemCaseSensitive(fr, "mask_path");
    if (mp != NULL) {
        if (!cJSON_IsString(mp) || mp->valuestring[0] == '\0') {
            return nerf__error(NERF_EFORMAT, "%s: %s: 'mask_path' is not "
                               "a file name", json_path, f->name);
        }
        const char *name = mp->valuestring;
        while (name[0] == '.' && name[1] == '/') {
            name += 2;
        }
        f->mask = nerf__path_join(env, b->dir, name);
        f->rule = NERF__MASK_ZERO_DROPS;
        return f->mask ? NERF_OK : NERF_ENOMEM;
    }
    const char *base = strrchr(f->path, '/');
    base = base ? base + 1 : f->path;
    const char *dot = strrchr(base, '.');
    size_t stem = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    size_t head = (size_t)(base - f->path);
    static const char prefix[] = "dynamic_mask_";
    char *path = nerf__alloc(env, head + sizeof prefix + stem + 5);
    if (path == NULL) {
        return NERF_ENOMEM;
    }
    memcpy(path, f->path, head);
    memcpy(path + head, prefix, sizeof prefix - 1);
    memcpy(path + head + sizeof prefix - 1, base, stem);
    strcpy(path + head + sizeof prefix - 1 + stem, ".png");
    struct stat st;
    if (lstat(path, &st) != 0) {
        nerf__free(env, path);
        return NERF_OK;
    }
    f->mask = path;
    f->rule = NERF__MASK_NONZERO_DROPS;
    return NERF_OK;
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

/* Room for n more frames. */
static int reserve_frames(blender_ctx *b, size_t n)
{
    if (b->n_frames + n <= b->cap) {
        return NERF_OK;
    }
    if (n > UINT32_MAX - b->n_frames) {
        return nerf__error(NERF_EFORMAT, "%s: too many frames", b->json_path);
    }
    uint32_t cap = b->n_frames + (uint32_t)n;
    frame *grown = nerf__calloc(&b->ds->env, cap ? cap : 1, sizeof *grown);
    if (grown == NULL) {
        return NERF_ENOMEM;
    }
    if (b->n_frames > 0) {
        memcpy(grown, b->frames, b->n_frames * sizeof *grown);
    }
    nerf__free(&b->ds->env, b->frames);
    b->frames = grown;
    b->cap = cap;
    return NERF_OK;
}

/*
 * Collect every frame of file b->json_paths[file], checked as a load
 * checks it, marking those to load: when the file is the split's, the
 * frames of the split that the skip setting keeps.  The others are only
 * checked, so that a broken frame of any split is found now.
 */
static int parse_frames(blender_ctx *b, uint32_t file, const cJSON *root,
                        const nerf__dataset_config *cfg)
{
    const char *json_path = b->json_paths[file];
    nerf__intrinsics top;
    const cJSON *frames = NULL;
    double aabb_scale;
    int rc = nerf__transforms_top(json_path, root, &top, &frames,
                                  &aabb_scale);
    if (rc == NERF_OK) {
        rc = reserve_frames(b, (size_t)cJSON_GetArraySize(frames));
    }
    if (rc != NERF_OK) {
        return rc;
    }
    if (file == 0) {
        b->ds->aabb_scale = aabb_scale;
    }
    uint32_t idx = 0, seen = 0;
    for (const cJSON *fr = frames->child; fr; fr = fr->next, idx++) {
        frame *f = &b->frames[b->n_frames];
        memset(f, 0, sizeof *f);
        if (file == 0 && in_split(b, idx, cfg)) {
            f->load = seen++ % cfg->skip == 0;
        }
        nerf__transforms_frame_name(fr, idx, f->name, sizeof f->name);
        char where[256];
        snprintf(where, sizeof where, "%s: ", f->name);
        f->index = idx;
        f->file = file;
        f->in = top;
        rc = cJSON_IsObject(fr) ? NERF_OK
             : nerf__error(NERF_EFORMAT, "%s: %snot a JSON object",
                           json_path, where);
        if (rc == NERF_OK) {
            rc = nerf__transforms_read_intrinsics(json_path, fr, where,
                                                  &f->in);
        }
        if (rc == NERF_OK) {
            rc = nerf__transforms_read_matrix(json_path, fr, f->name,
                                              f->c2w);
        }
        if (rc == NERF_OK) {
            rc = frame_path(b, json_path, fr, f->name, idx, &f->path);
        }
        if (rc == NERF_OK && !cfg->ignore_masks) {
            rc = frame_mask(b, json_path, fr, f);
        }
        if (rc != NERF_OK) {
            nerf__free(&b->ds->env, f->path);
            nerf__free(&b->ds->env, f->mask);
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
                           "%s is %ux%u", b->json_paths[f->file], f->name,
                           in->w, in->h, f->path, (unsigned)w, (unsigned)h);
    }
    double k[4];
    int rc = nerf__transforms_focal(b->json_paths[f->file], f->name, in, w,
                                    h, k);
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

/*
 * The frames to load, without those whose image is missing when
 * skip_missing says to drop them; returns how many are left.
 */
static uint32_t drop_missing(blender_ctx *b, const nerf__dataset_config *cfg)
{
    uint32_t kept = 0, missing = 0;
    for (uint32_t i = 0; i < b->n_frames; i++) {
        frame *f = &b->frames[i];
        if (!f->load) {
            continue;
        }
        if (cfg->skip_missing && file_missing(f->path)) {
            f->load = false;
            f->dropped = true;
            missing++;
        } else {
            kept++;
        }
    }
    if (missing > 0) {
        nerf__log(&b->ds->env, NERF_LOG_WARN, "%s: skipped %u frame(s) whose "
                  "image is missing", b->json_path, (unsigned)missing);
    }
    return kept;
}

/* Load the images of the kept frames and set up their cameras. */
static int load_frames(blender_ctx *b, const nerf__dataset_config *cfg)
{
    nerf_dataset *ds = b->ds;
    uint32_t kept = drop_missing(b, cfg);
    if (kept == 0) {
        return nerf__error(NERF_EFORMAT, "%s: no frames to load", b->json_path);
    }
    int rc = nerf__dataset_reserve(ds, kept);
    double k = cfg->downscale;
    for (uint32_t i = 0, slot = 0; i < b->n_frames && rc == NERF_OK; i++) {
        const frame *f = &b->frames[i];
        if (!f->load) {
            continue;
        }
        rc = nerf__dataset_load_image(ds, slot, f->path, cfg->downscale,
                                      cfg->white_background);
        if (rc == NERF_OK && f->mask != NULL) {
            rc = nerf__dataset_load_mask(ds, slot, f->mask, f->path,
                                         cfg->downscale, f->rule);
        }
        nerf__view *v = &ds->views[slot++];
        if (rc == NERF_OK) {
            rc = resolve_intrinsics(b, f, ds->src_width, ds->src_height, v);
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

/*
 * The frames not loaded, by their images' headers: whatever the load of
 * their split (or without skip) would refuse before decoding a pixel, or
 * for the image's size.  An image that is not there is only a warning,
 * once per file: whether its split can do without it is for that load to
 * say (skip_missing), as lego's val split, which ships one image in 8,
 * shows.
 */
static int check_frames(blender_ctx *b)
{
    uint32_t missing[MAX_FILES] = {0};
    const char *first[MAX_FILES] = {NULL};
    int rc = NERF_OK;
    for (uint32_t i = 0; i < b->n_frames && rc == NERF_OK; i++) {
        const frame *f = &b->frames[i];
        if (f->load || f->dropped) {
            continue;
        }
        if (file_missing(f->path)) {
            first[f->file] = missing[f->file]++ ? first[f->file] : f->path;
            continue;
        }
        nerf__view v;
        rc = nerf__dataset_check_image(b->ds, f->path);
        if (rc == NERF_OK && f->mask != NULL) {
            rc = nerf__dataset_check_mask(b->ds, f->mask, f->path);
        }
        if (rc == NERF_OK) {
            rc = resolve_intrinsics(b, f, b->ds->src_width,
                                    b->ds->src_height, &v);
        }
    }
    for (uint32_t k = 0; k < b->n_files && rc == NERF_OK; k++) {
        if (missing[k] > 0) {
            nerf__log(&b->ds->env, NERF_LOG_WARN, "%s: %u frame(s) have "
                      "no image (the first: %s): not loaded now, and a load "
                      "of their split will need skip_missing or a skip that "
                      "passes them", b->json_paths[k], (unsigned)missing[k],
                      first[k]);
        }
    }
    return rc;
}

static int parse_file(blender_ctx *b, uint32_t file,
                      const nerf__dataset_config *cfg)
{
    cJSON *root = NULL;
    int rc = nerf__transforms_parse(&b->ds->env, b->json_paths[file], &root);
    if (rc == NERF_OK) {
        rc = parse_frames(b, file, root, cfg);
    }
    cJSON_Delete(root);
    return rc;
}

/*
 * The split's file, then, in a folder of one file per split, the files of
 * the other splits that are there (of any kind: a FIFO is refused by the
 * reader, not passed over).
 */
static int parse_files(blender_ctx *b, const char *name,
                       const nerf__dataset_config *cfg)
{
    static const char *const others[] = {"transforms_train.json",
                                         "transforms_val.json",
                                         "transforms_test.json"};
    nerf__env *env = &b->ds->env;
    b->json_paths[b->n_files++] = nerf__path_join(env, b->dir, name);
    for (size_t k = 0; k < 3 && !b->whole; k++) {
        if (strcmp(others[k], name) == 0) {
            continue;
        }
        char *path = nerf__path_join(env, b->dir, others[k]);
        struct stat st;
        if (path != NULL && stat(path, &st) != 0) {
            nerf__free(env, path);
            continue;
        }
        b->json_paths[b->n_files++] = path;
    }
    for (uint32_t f = 0; f < b->n_files; f++) {
        if (b->json_paths[f] == NULL) {
            return NERF_ENOMEM;
        }
    }
    b->json_path = b->json_paths[0];
    int rc = NERF_OK;
    for (uint32_t f = 0; f < b->n_files && rc == NERF_OK; f++) {
        rc = parse_file(b, f, cfg);
    }
    return rc;
}

int nerf__blender_load(nerf_dataset *ds, const char *dir, const char *name,
                       bool whole, const nerf__dataset_config *cfg)
{
    blender_ctx b;
    memset(&b, 0, sizeof b);
    b.ds = ds;
    b.dir = dir;
    b.whole = whole;
    int rc = parse_files(&b, name, cfg);
    const char *json_path = b.json_path;
    uint32_t n_load = 0;
    for (uint32_t i = 0; i < b.n_frames; i++) {
        n_load += b.frames[i].load;
    }
    if (rc == NERF_OK && n_load == 0 && whole) {
        rc = nerf__error(NERF_EINVAL, "%s: the requested split has no "
                         "frames (holdout %u)", json_path,
                         (unsigned)cfg->llff_holdout);
    }
    if (rc == NERF_OK) {
        rc = load_frames(&b, cfg);
    }
    if (rc == NERF_OK) {
        rc = check_frames(&b);
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
        nerf__free(&ds->env, b.frames[i].mask);
    }
    nerf__free(&ds->env, b.frames);
    for (uint32_t f = 0; f < b.n_files; f++) {
        nerf__free(&ds->env, b.json_paths[f]);
    }
    return rc;
}
