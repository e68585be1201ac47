/*
 * COLMAP sparse models beside a photo folder: the poses and intrinsics of
 * sparse/0/ (or sparse/), centred and scaled by the rule of
 * docs/formats.md, with near and far bounds from the sparse points.
 */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "colmap.h"
#include "colmap_poses.h"
#include "dataset.h"
#include "file_io.h"
#include "image_read.h"
#include "llff_poses.h"

/* Margins around the sparse points' depth percentiles. */
#define NEAR_MARGIN 0.9
#define FAR_MARGIN 1.1
/* Half side of the central cube of a COLMAP scene's contracted space, in
 * the units the placement leaves (farthest camera at 1). */
#define COLMAP_INNER 1.0

/* The bounds of a model without points (in units of the farthest camera's
 * distance from the centre). */
#define DEFAULT_NEAR 0.01
#define DEFAULT_FAR 10.0
/* Points nearer a camera than this (a millionth of the farthest camera's
 * distance from the centre) are not in front of it: a near bound that
 * small would vanish as a float. */
#define MIN_DEPTH 1e-6

static const char *const subdirs[] = {"sparse/0", "sparse"};
static const char *const kinds[][3] = {
    {"cameras.bin", "images.bin", "points3D.bin"},
    {"cameras.txt", "images.txt", "points3D.txt"},
};

typedef struct colmap_ctx {
    nerf_dataset *ds;
    const char *dir;
    char *paths[3];          /* cameras, images, points3D (may not exist) */
    int binary;
    bool has_points;
    nerf__colmap_model m;
    uint32_t *order;         /* image indices sorted by name */
    double *poses;           /* c2w per sorted image, normalised */
    nerf__similarity sim;
    double near, far;
    char *image_dir;
    uint32_t image_factor;
    char *mask_dir;          /* masks/ (masks_M/ beside images_M/), or NULL */
} colmap_ctx;

/* Of any kind: a FIFO in a model file's place is for its reader to
 * refuse, not a reason to look elsewhere. */
static bool is_present(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/*
 * The first of sparse/0, sparse holding cameras and images files, binary
 * before text: COLMAP writes binary by default and it holds the doubles
 * exactly.  On return paths[] are set (found) or NULL (not found).
 */
static int locate(const nerf__env *env, const char *dir, char *paths[3],
                  int *binary)
{
    for (size_t s = 0; s < 2; s++) {
        for (int k = 0; k < 2; k++) {
            bool ok = true;
            for (int f = 0; f < 3; f++) {
                char name[64];
                snprintf(name, sizeof name, "%s/%s", subdirs[s], kinds[k][f]);
                paths[f] = nerf__path_join(env, dir, name);
                if (paths[f] == NULL) {
                    ok = false;
                } else if (f < 2 && !is_present(paths[f])) {
                    ok = false;
                }
            }
            if (ok) {
                *binary = k == 0;
                return NERF_OK;
            }
            bool oom = paths[0] == NULL || paths[1] == NULL ||
                       paths[2] == NULL;
            for (int f = 0; f < 3; f++) {
                nerf__free(env, paths[f]);
                paths[f] = NULL;
            }
            if (oom) {
                return NERF_ENOMEM;
            }
        }
    }
    return NERF_OK;
}

int nerf__colmap_detect(const nerf__env *env, const char *dir, int *found)
{
    char *paths[3];
    int binary;
    int rc = locate(env, dir, paths, &binary);
    *found = rc == NERF_OK && paths[0] != NULL;
    for (int f = 0; f < 3; f++) {
        nerf__free(env, paths[f]);
    }
    return rc;
}

static int read_model(colmap_ctx *c)
{
    typedef int (*parse_fn)(const nerf__env *, const char *,
                            const unsigned char *, size_t, int,
                            nerf__colmap_model *);
    static const parse_fn parsers[3] = {nerf__colmap_parse_cameras,
                                        nerf__colmap_parse_images,
                                        nerf__colmap_parse_points};
    nerf__env *env = &c->ds->env;
    c->has_points = is_present(c->paths[2]);
    int rc = NERF_OK;
    for (int f = 0; f < 3 && rc == NERF_OK; f++) {
        if (f == 2 && !c->has_points) {
            break;
        }
        unsigned char *buf;
        size_t size;
        rc = nerf__file_read(env, c->paths[f], NERF__COLMAP_MAX_BYTES, &buf,
                             &size);
        if (rc == NERF_OK) {
            rc = parsers[f](env, c->paths[f], buf, size, c->binary, &c->m);
            nerf__free(env, buf);
        }
    }
    return rc;
}

typedef struct named {
    const char *name;
    uint32_t index;
} named;

static int compare_named(const void *a, const void *b)
{
    return strcmp(((const named *)a)->name, ((const named *)b)->name);
}

typedef struct id_index {
    uint32_t id, index;      /* image id, position in name order */
} id_index;

static int compare_id(const void *a, const void *b)
{
    uint32_t x = ((const id_index *)a)->id, y = ((const id_index *)b)->id;
    return (x > y) - (x < y);
}

/*
 * Name order (the split follows it), refusing repeated names and ids; ids
 * receives (id, sorted position) pairs sorted by id, for the tracks.
 */
static int order_images(colmap_ctx *c, named *tmp, id_index *ids)
{
    size_t n = c->m.n_images;
    const nerf__colmap_image *im = c->m.images;
    for (size_t i = 0; i < n; i++) {
        tmp[i] = (named){im[i].name, (uint32_t)i};
    }
    qsort(tmp, n, sizeof *tmp, compare_named);
    for (size_t i = 0; i < n; i++) {
        if (i > 0 && strcmp(tmp[i].name, tmp[i - 1].name) == 0) {
            return nerf__error(NERF_EFORMAT, "%s: image '%.256s' appears "
                               "twice", c->paths[1], tmp[i].name);
        }
        c->order[i] = tmp[i].index;
        ids[i] = (id_index){im[tmp[i].index].id, (uint32_t)i};
    }
    qsort(ids, n, sizeof *ids, compare_id);
    for (size_t i = 1; i < n; i++) {
        if (ids[i].id == ids[i - 1].id) {
            return nerf__error(NERF_EFORMAT, "%s: image id %u appears twice",
                               c->paths[1], (unsigned)ids[i].id);
        }
    }
    return NERF_OK;
}

/* Sorted position of image id, or -1 when no image has it. */
static long find_id(const id_index *ids, size_t n, uint32_t id)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (ids[mid].id == id) {
            return (long)ids[mid].index;
        }
        if (ids[mid].id < id) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return -1;
}

typedef struct depth_of {
    uint32_t image;          /* sorted position */
    double depth;
} depth_of;

static int compare_depth(const void *a, const void *b)
{
    const depth_of *x = a, *y = b;
    if (x->image != y->image) {
        return (x->image > y->image) - (x->image < y->image);
    }
    return (x->depth > y->depth) - (x->depth < y->depth);
}

/* Linear interpolation between order statistics, as NumPy's default. */
static double percentile(const depth_of *v, size_t n, double q)
{
    double pos = q * (double)(n - 1);
    size_t lo = (size_t)floor(pos);
    size_t hi = lo + 1 < n ? lo + 1 : lo;
    return v[lo].depth + (v[hi].depth - v[lo].depth) * (pos - (double)lo);
}

/*
 * Per image, the q_lo and q_hi percentiles of the depths (along its
 * optical axis, at least MIN_DEPTH in front of it) of the sparse points
 * whose track holds it, in the placed units, into range (2 per image; NAN
 * for an image that sees none).  Track entries naming an image the model
 * does not have are skipped.  *seen counts the images with depths;
 * widest gets the least low and the largest high percentile of them.
 */
static int depth_ranges(colmap_ctx *c, const id_index *ids, double q_lo,
                        double q_hi, double *range, size_t *seen,
                        double widest[2])
{
    size_t n = c->m.n_images;
    depth_of *d = nerf__calloc(&c->ds->env, c->m.n_track ? c->m.n_track : 1,
                               sizeof *d);
    if (d == NULL) {
        return NERF_ENOMEM;
    }
    size_t nd = 0;
    for (size_t p = 0; p < c->m.n_points; p++) {
        const nerf__colmap_point *pt = &c->m.points[p];
        for (size_t k = 0; k < pt->track_len; k++) {
            long at = find_id(ids, n, c->m.track[pt->track_first + k]);
            if (at < 0) {
                continue;
            }
            /* Depth along the camera's forward axis, -z in OpenGL axes. */
            const double *m = c->poses + 12 * (size_t)at;
            double z = 0.0;
            for (int a = 0; a < 3; a++) {
                double x = c->sim.scale * (c->sim.rot[3 * a] *
                                           (pt->xyz[0] - c->sim.centre[0]) +
                                           c->sim.rot[3 * a + 1] *
                                           (pt->xyz[1] - c->sim.centre[1]) +
                                           c->sim.rot[3 * a + 2] *
                                           (pt->xyz[2] - c->sim.centre[2]));
                z -= m[4 * a + 2] * (x - m[4 * a + 3]);
            }
            if (z > MIN_DEPTH) {
                d[nd++] = (depth_of){(uint32_t)at, z};
            }
        }
    }
    qsort(d, nd, sizeof *d, compare_depth);
    for (size_t i = 0; i < 2 * n; i++) {
        range[i] = NAN;
    }
    *seen = 0;
    widest[0] = INFINITY;
    widest[1] = 0.0;
    for (size_t first = 0; first < nd;) {
        size_t last = first;
        while (last < nd && d[last].image == d[first].image) {
            last++;
        }
        range[2 * d[first].image] = percentile(d + first, last - first, q_lo);
        range[2 * d[first].image + 1] = percentile(d + first, last - first,
                                                   q_hi);
        widest[0] = fmin(widest[0], range[2 * d[first].image]);
        widest[1] = fmax(widest[1], range[2 * d[first].image + 1]);
        (*seen)++;
        first = last;
    }
    nerf__free(&c->ds->env, d);
    return NERF_OK;
}

/*
 * Near and far of an unbounded scene: 0.9 x the least 1st percentile of
 * the images' depths, 1.1 x the largest 99th, in the scaled units.
 */
static int bounds(colmap_ctx *c, const id_index *ids)
{
    size_t n = c->m.n_images, seen;
    double *range = nerf__calloc(&c->ds->env, 2 * n, sizeof *range);
    if (range == NULL) {
        return NERF_ENOMEM;
    }
    double w[2] = {INFINITY, 0.0};
    int rc = depth_ranges(c, ids, 0.01, 0.99, range, &seen, w);
    double lo = w[0], hi = w[1];
    nerf__free(&c->ds->env, range);
    if (rc != NERF_OK || seen == 0 || !(hi > lo)) {
        c->near = DEFAULT_NEAR;
        c->far = DEFAULT_FAR;
    } else {
        c->near = NEAR_MARGIN * lo;
        c->far = FAR_MARGIN * hi;
    }
    return rc;
}

/* The COLMAP poses in name order, in OpenGL axes and COLMAP's units. */
static void raw_poses(colmap_ctx *c)
{
    for (size_t i = 0; i < c->m.n_images; i++) {
        const nerf__colmap_image *im = &c->m.images[c->order[i]];
        nerf__colmap_to_c2w(im->q, im->t, c->poses + 12 * i);
    }
}

/* Then the similarity of docs/formats.md. */
static int normalise(colmap_ctx *c)
{
    nerf__env *env = &c->ds->env;
    size_t n = c->m.n_images, np = c->m.n_points;
    double *pts = nerf__calloc(env, np ? 3 * np : 1, sizeof *pts);
    double *scratch = nerf__calloc(env, n > np ? n : np, sizeof *scratch);
    if (pts == NULL || scratch == NULL) {
        nerf__free(env, pts);
        nerf__free(env, scratch);
        return NERF_ENOMEM;
    }
    raw_poses(c);
    for (size_t p = 0; p < np; p++) {
        memcpy(pts + 3 * p, c->m.points[p].xyz, 3 * sizeof *pts);
    }
    nerf__colmap_similarity(c->poses, n, pts, np, scratch, &c->sim);
    for (size_t i = 0; i < n; i++) {
        nerf__similarity_pose(&c->sim, c->poses + 12 * i);
    }
    nerf__free(env, pts);
    nerf__free(env, scratch);
    return NERF_OK;
}

/*
 * A forward-facing capture placed as LLFF places one (LLFF's own poses
 * come from COLMAP this way): per-image bounds from the depths at LLFF's
 * percentiles, then its rescaling, recentring and spiral.  An image that
 * sees no point takes the widest bounds of the others, which only the
 * spiral and the scale read.
 */
static int place_forward(colmap_ctx *c, const id_index *ids)
{
    nerf__env *env = &c->ds->env;
    size_t n = c->m.n_images, seen;
    memset(&c->sim, 0, sizeof c->sim);
    c->sim.rot[0] = c->sim.rot[4] = c->sim.rot[8] = 1.0;
    c->sim.scale = 1.0;
    raw_poses(c);
    double *range = nerf__calloc(env, 2 * n, sizeof *range);
    double *scratch = nerf__calloc(env, n, sizeof *scratch);
    double w[2];
    int rc = range && scratch ? depth_ranges(c, ids, 0.001, 0.999, range,
                                             &seen, w)
                              : NERF_ENOMEM;
    if (rc == NERF_OK && seen == 0) {
        rc = nerf__error(NERF_EFORMAT, "%s: a forward-facing scene needs "
                         "sparse points in front of its cameras for its "
                         "depth bounds, and this model has none",
                         c->has_points ? c->paths[2] : c->paths[1]);
    }
    if (rc == NERF_OK) {
        double lo = w[0], hi = w[1];
        for (size_t i = 0; i < n; i++) {
            if (isnan(range[2 * i])) {
                range[2 * i] = lo;
                range[2 * i + 1] = hi;
            }
        }
        c->sim.scale = nerf__llff_normalize(c->poses, range, n);
        nerf__llff_spiral_setup(c->poses, range, n, scratch,
                                &c->ds->spiral);
        c->ds->has_spiral = 1;
        c->near = lo * c->sim.scale;
        c->far = hi * c->sim.scale;
    }
    nerf__free(env, range);
    nerf__free(env, scratch);
    return rc;
}

/*
 * Whether the photo at path, which the model names for image im, is a
 * regular file: "missing" when it is not there (COLMAP has no skip_missing:
 * the model registered it), else what it is instead.
 */
static int check_photo_file(const colmap_ctx *c, const nerf__colmap_image *im,
                            const char *path)
{
    int rc = nerf__file_check_regular(path);
    if (rc == NERF_ENOENT) {
        return nerf__error(NERF_ENOENT, "%s: missing: %s names image %u "
                           "'%.256s', which is not in %s", path, c->paths[1],
                           (unsigned)im->id, im->name, c->image_dir);
    }
    if (rc != NERF_OK) {
        char why[512];
        snprintf(why, sizeof why, "%s", nerf_last_error());
        return nerf__error(rc, "%s (%s names it for image %u)", why,
                           c->paths[1], (unsigned)im->id);
    }
    return NERF_OK;
}

/*
 * Whether w x h photos in the image folder are the size its name says for
 * the camera of sorted image i.
 */
static int check_folder_scale(const colmap_ctx *c, uint32_t i, uint32_t w,
                              uint32_t h)
{
    const nerf__colmap_image *im = &c->m.images[c->order[i]];
    const nerf__colmap_camera *cam = nerf__colmap_find_camera(&c->m,
                                                              im->camera_id);
    char source[1100];
    snprintf(source, sizeof source, "camera %u in %s", (unsigned)cam->id,
             c->paths[0]);
    return nerf__check_image_factor(c->image_dir, c->image_factor, w, h,
                                    cam->width, cam->height, source);
}

/*
 * The same from the header of sorted image i's photo, before any photo is
 * decoded: a folder of full-size photos would otherwise be read whole
 * first.  A photo that cannot be read is left to the load to name.
 */
static int check_first_photo_scale(colmap_ctx *c, uint32_t i)
{
    const nerf__colmap_image *im = &c->m.images[c->order[i]];
    char *path = nerf__path_join(&c->ds->env, c->image_dir, im->name);
    if (path == NULL) {
        return NERF_ENOMEM;
    }
    uint32_t w, h;
    int rc = NERF_OK;
    if (nerf__image_read_size(&c->ds->env, path, &w, &h) == NERF_OK) {
        rc = check_folder_scale(c, i, w, h);
    }
    nerf__free(&c->ds->env, path);
    return rc;
}

/* Intrinsics of the camera of sorted image i for the stored image size. */
static int view_intrinsics(colmap_ctx *c, uint32_t i, const char *path,
                           uint32_t extra, nerf__view *v)
{
    const nerf__colmap_image *im = &c->m.images[c->order[i]];
    const nerf__colmap_camera *cam = nerf__colmap_find_camera(&c->m,
                                                              im->camera_id);
    nerf_dataset *ds = c->ds;
    double ratio = (double)ds->src_width / cam->width;
    if (fabs(cam->height * ratio - ds->src_height) >
        1.0 + 0.01 * ds->src_height) {
        return nerf__error(NERF_EFORMAT, "%s: the image is %ux%u, which does "
                           "not match the %ux%u of camera %u in %s scaled by "
                           "%g", path, (unsigned)ds->src_width,
                           (unsigned)ds->src_height, (unsigned)cam->width,
                           (unsigned)cam->height, (unsigned)cam->id,
                           c->paths[0], ratio);
    }
    int rc = check_folder_scale(c, i, ds->src_width, ds->src_height);
    if (rc != NERF_OK) {
        return rc;
    }
    double s = ratio / extra;
    v->fx = cam->fx * s;
    v->fy = cam->fy * s;
    v->cx = cam->cx * s;
    v->cy = cam->cy * s;
    v->k1 = cam->k1;
    v->k2 = cam->k2;
    v->p1 = cam->p1;
    v->p2 = cam->p2;
    v->k3 = cam->k3;
    return NERF_OK;
}

/* The photo of sorted image i, loaded into slot when load, else checked
 * by its header; its camera into v. */
static int take_photo(colmap_ctx *c, uint32_t i, bool load, uint32_t slot,
                      const nerf__dataset_config *cfg, nerf__view *v)
{
    nerf_dataset *ds = c->ds;
    uint32_t extra = cfg->downscale / c->image_factor;
    const nerf__colmap_image *im = &c->m.images[c->order[i]];
    char *path = nerf__path_join(&ds->env, c->image_dir, im->name);
    if (path == NULL) {
        return NERF_ENOMEM;
    }
    int rc = check_photo_file(c, im, path);
    if (rc == NERF_OK && load) {
        rc = nerf__dataset_load_image(ds, slot, path, extra,
                                      cfg->white_background);
    } else if (rc == NERF_OK) {
        rc = nerf__dataset_check_image(ds, path);
    }
    if (rc == NERF_OK && c->mask_dir != NULL) {
        rc = nerf__folder_mask(ds, c->mask_dir, im->name, path, load, slot,
                               extra);
    }
    if (rc == NERF_OK) {
        rc = view_intrinsics(c, i, path, extra, v);
    }
    nerf__free(&ds->env, path);
    return rc;
}

/*
 * Load the photos of the split (sel, count of them, ascending), then check
 * the others (other splits, or passed over by skip) by their headers.
 */
static int load_images(colmap_ctx *c, const nerf__dataset_config *cfg,
                       const uint32_t *sel, uint32_t count)
{
    nerf_dataset *ds = c->ds;
    int rc = check_first_photo_scale(c, sel[0]);
    if (rc == NERF_OK) {
        rc = nerf__dataset_reserve(ds, count);
    }
    bool distorted = false;
    for (uint32_t k = 0; k < count && rc == NERF_OK; k++) {
        nerf__view *v = &ds->views[k];
        rc = take_photo(c, sel[k], true, k, cfg, v);
        if (rc == NERF_OK) {
            memcpy(v->c2w, c->poses + 12 * (size_t)sel[k], sizeof v->c2w);
            distorted = distorted || v->k1 != 0.0 || v->k2 != 0.0 ||
                        v->p1 != 0.0 || v->p2 != 0.0 || v->k3 != 0.0;
        }
    }
    for (uint32_t i = 0, k = 0; i < c->m.n_images && rc == NERF_OK; i++) {
        nerf__view scratch;
        if (k < count && sel[k] == i) {
            k++;
        } else {
            rc = take_photo(c, i, false, 0, cfg, &scratch);
        }
    }
    if (rc == NERF_OK && distorted) {
        /* Applied to each pixel's ray (nerf_camera's model); said once,
         * since it changes what a pinhole render of the scene shows. */
        const nerf__view *v = &ds->views[0];
        nerf__log(&ds->env, NERF_LOG_INFO, "%s: lens distortion (first "
                  "image) k1 %g k2 %g p1 %g p2 %g", c->paths[0], v->k1,
                  v->k2, v->p1, v->p2);
    }
    return rc;
}

static int load(colmap_ctx *c, const nerf__dataset_config *cfg)
{
    nerf__env *env = &c->ds->env;
    int rc = read_model(c);
    if (rc != NERF_OK) {
        return rc;
    }
    size_t n = c->m.n_images;
    if (n > UINT32_MAX) {
        return nerf__error(NERF_EFORMAT, "%s: too many images", c->paths[1]);
    }
    c->order = nerf__calloc(env, n, sizeof *c->order);
    c->poses = nerf__calloc(env, n, 12 * sizeof *c->poses);
    named *tmp = nerf__calloc(env, n, sizeof *tmp);
    id_index *ids = nerf__calloc(env, n, sizeof *ids);
    uint32_t *sel = nerf__calloc(env, n, sizeof *sel);
    if (c->order == NULL || c->poses == NULL || tmp == NULL || ids == NULL ||
        sel == NULL) {
        rc = NERF_ENOMEM;
    }
    if (rc == NERF_OK) {
        rc = order_images(c, tmp, ids);
    }
    if (rc == NERF_OK && cfg->forward_facing) {
        rc = place_forward(c, ids);
    } else if (rc == NERF_OK) {
        rc = normalise(c);
        if (rc == NERF_OK) {
            rc = bounds(c, ids);
        }
    }
    if (rc == NERF_OK) {
        rc = nerf__find_image_dir(env, c->dir, cfg->downscale, &c->image_dir,
                                  &c->image_factor);
    }
    if (rc == NERF_OK && !cfg->ignore_masks) {
        rc = nerf__find_mask_dir(env, c->dir, c->image_factor, &c->mask_dir);
    }
    uint32_t count = 0;
    if (rc == NERF_OK) {
        count = nerf__holdout_split(n, cfg, sel);
        if (count == 0) {
            rc = nerf__error(NERF_EINVAL, "%s: the requested split has no "
                             "images (%zu views, holdout %u)", c->dir, n,
                             (unsigned)cfg->llff_holdout);
        }
    }
    if (rc == NERF_OK) {
        rc = load_images(c, cfg, sel, count);
    }
    nerf__free(env, tmp);
    nerf__free(env, ids);
    nerf__free(env, sel);
    return rc;
}

int nerf__colmap_load(nerf_dataset *ds, const char *dir,
                      const nerf__dataset_config *cfg)
{
    colmap_ctx c;
    memset(&c, 0, sizeof c);
    c.ds = ds;
    c.dir = dir;
    int rc = locate(&ds->env, dir, c.paths, &c.binary);
    if (rc == NERF_OK && c.paths[0] == NULL) {
        rc = nerf__error(NERF_EIO, "%s: no COLMAP model (sparse/0/ or "
                         "sparse/ with cameras and images files)", dir);
    }
    if (rc == NERF_OK) {
        rc = load(&c, cfg);
    }
    if (rc == NERF_OK) {
        ds->kind = NERF__DATASET_COLMAP;
        ds->scene_scale = c.sim.scale;
        if (cfg->forward_facing) {
            ds->ndc = 1;
            ds->near_bound = 0.0f;
            ds->far_bound = 1.0f;
        } else {
            /* The farthest camera is at distance 1 from the centre, so
             * every camera is in the unit cube, and the contraction takes
             * what lies beyond it: the background a capture sees past its
             * subject. */
            ds->unbounded_inner = COLMAP_INNER;
            ds->near_bound = (float)c.near;
            ds->far_bound = (float)c.far;
            ds->scene_radius = 1.0;
        }
        nerf__log(&ds->env, NERF_LOG_INFO,
                  "%s: COLMAP model (%s, %s), %u of %zu images, %ux%u (from "
                  "%s, %ux%u, downscale %u), %zu points, %s, scale %.6g, "
                  "bounds [%.4g, %.4g]%s",
                  dir, c.paths[1], c.binary ? "binary" : "text",
                  (unsigned)ds->count, c.m.n_images, (unsigned)ds->width,
                  (unsigned)ds->height, c.image_dir, (unsigned)ds->src_width,
                  (unsigned)ds->src_height, (unsigned)cfg->downscale,
                  c.m.n_points, cfg->forward_facing ? "forward-facing"
                                                    : "unbounded",
                  c.sim.scale, c.near, c.far,
                  cfg->forward_facing ? " after scaling, NDC rays in [0, 1]"
                                      : "");
    }
    for (int f = 0; f < 3; f++) {
        nerf__free(&ds->env, c.paths[f]);
    }
    nerf__colmap_free(&ds->env, &c.m);
    nerf__free(&ds->env, c.order);
    nerf__free(&ds->env, c.poses);
    nerf__free(&ds->env, c.image_dir);
    nerf__free(&ds->env, c.mask_dir);
    return rc;
}
