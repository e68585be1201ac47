/* LLFF / "Real Forward-Facing" scenes: poses_bounds.npy and an image folder. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dataset.h"
#include "file_io.h"
#include "image_read.h"
#include "llff_poses.h"
#include "npy.h"
#include "transforms.h"

#define NPY_MAX_BYTES (64u << 20)
/* The least near bound: the poses are scaled by 1 / (0.75 near), which
 * must keep them finite. */
#define NERF__LLFF_MIN_NEAR 1e-6
/* More rows than any capture; stops a bogus shape from driving allocation. */
#define MAX_VIEWS 100000u

typedef struct llff_ctx {
    nerf_dataset *ds;
    const char *dir;
    char *npy_path;
    size_t n;
    double *rows;    /* n x 17, as stored */
    double *poses;   /* n x 12, NeRF axes, then normalised */
    double *bounds;  /* n x 2 */
    char *image_dir;
    uint32_t image_factor; /* the folder's downscale: images_<factor> */
    char *mask_dir;        /* masks/ or masks_<factor>/, or NULL */
    char **names;    /* n image file names, sorted */
    size_t n_names;
} llff_ctx;

static int read_rows(llff_ctx *c)
{
    nerf__env *env = &c->ds->env;
    unsigned char *buf;
    size_t size;
    int rc = nerf__file_read(env, c->npy_path, NPY_MAX_BYTES, &buf, &size);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__npy a;
    rc = nerf__npy_parse(buf, size, &a);
    if (rc != NERF_OK) {
        rc = nerf__error_prefix(rc, c->npy_path);
    } else if (a.dtype != NERF__NPY_F8) {
        rc = nerf__error(NERF_EFORMAT, "%s: dtype is '%s' (expected '<f8')",
                         c->npy_path, nerf__npy_dtype_name(a.dtype));
    } else if (a.fortran_order) {
        rc = nerf__error(NERF_EFORMAT, "%s: data is in Fortran order "
                         "(expected C order)", c->npy_path);
    } else if (a.ndim != 2 || a.shape[1] != NERF__LLFF_ROW ||
               a.shape[0] == 0 || a.shape[0] > MAX_VIEWS) {
        char shape[64];
        nerf__npy_format_shape(a.shape, a.ndim, shape, sizeof shape);
        rc = nerf__error(NERF_EFORMAT, "%s: shape is %s (expected (N, 17) "
                         "with 1 <= N <= %u)", c->npy_path, shape, MAX_VIEWS);
    } else {
        c->n = a.shape[0];
        c->rows = nerf__calloc(env, a.count, sizeof *c->rows);
        if (c->rows == NULL) {
            rc = NERF_ENOMEM;
        } else {
            nerf__npy_to_double(&a, c->rows, a.count);
        }
    }
    nerf__free(env, buf);
    return rc;
}

/*
 * Every row, against the limits of a usable camera (lib/io/transforms.h),
 * named by its index and, once the folder has been listed, its image.
 */
static int check_rows(const llff_ctx *c)
{
    for (size_t i = 0; i < c->n; i++) {
        const double *r = c->rows + NERF__LLFF_ROW * i;
        char name[300];
        if (c->n_names == c->n) {
            snprintf(name, sizeof name, "row %zu (image %.256s)", i,
                     c->names[i]);
        } else {
            snprintf(name, sizeof name, "row %zu", i);
        }
        for (int k = 0; k < NERF__LLFF_ROW; k++) {
            if (!isfinite(r[k])) {
                return nerf__error(NERF_EFORMAT, "%s: %s holds a non-finite "
                                   "value (column %d)", c->npy_path, name, k);
            }
            if (!(fabs(r[k]) <= NERF__CAMERA_MAX_ABS)) {
                return nerf__error(NERF_EFORMAT, "%s: %s: has an entry of "
                                   "magnitude %g, beyond the %g a camera may "
                                   "have (column %d)", c->npy_path, name,
                                   fabs(r[k]), NERF__CAMERA_MAX_ABS, k);
            }
        }
        if (!(r[4] >= 1.0 && r[9] >= 1.0 && r[14] >= NERF__FOCAL_MIN)) {
            return nerf__error(NERF_EFORMAT, "%s: %s: height %g, width %g "
                               "and focal %g must be positive (at least 1, 1 "
                               "and %g)", c->npy_path, name, r[4], r[9],
                               r[14], NERF__FOCAL_MIN);
        }
        if (!(r[15] >= NERF__LLFF_MIN_NEAR && r[16] > r[15])) {
            return nerf__error(NERF_EFORMAT, "%s: %s: bounds near %g, far %g "
                               "(need %g <= near < far)", c->npy_path, name,
                               r[15], r[16], NERF__LLFF_MIN_NEAR);
        }
        double c2w[12];
        nerf__llff_row_pose(r, c2w);
        char text[160];
        const char *why = nerf__pose_problem(c2w, NULL, text, sizeof text);
        if (why != NULL) {
            return nerf__error(NERF_EFORMAT, "%s: %s: %s", c->npy_path, name,
                               why);
        }
    }
    return NERF_OK;
}

static int find_image_dir(llff_ctx *c, uint32_t factor)
{
    return nerf__find_image_dir(&c->ds->env, c->dir, factor, &c->image_dir,
                                &c->image_factor);
}

/* Case-insensitive suffix test on ASCII names. */
static bool has_suffix(const char *name, const char *suffix)
{
    size_t n = strlen(name), s = strlen(suffix);
    if (n <= s) {
        return false;
    }
    for (size_t i = 0; i < s; i++) {
        char ch = name[n - s + i];
        if (ch >= 'A' && ch <= 'Z') {
            ch = (char)(ch - 'A' + 'a');
        }
        if (ch != suffix[i]) {
            return false;
        }
    }
    return true;
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Image files of the folder, sorted by name as the reference does. */
static int list_images(llff_ctx *c)
{
    DIR *d = opendir(c->image_dir);
    if (d == NULL) {
        return nerf__error(errno == ENOENT || errno == ENOTDIR ? NERF_ENOENT
                                                               : NERF_EIO,
                           "%s: cannot open the folder", c->image_dir);
    }
    int rc = NERF_OK;
    size_t cap = 0;
    for (struct dirent *e = readdir(d); e != NULL && rc == NERF_OK;
         e = readdir(d)) {
        const char *nm = e->d_name;
        if (nm[0] == '.' || !(has_suffix(nm, ".png") ||
                              has_suffix(nm, ".jpg") ||
                              has_suffix(nm, ".jpeg"))) {
            continue;
        }
        if (c->n_names == cap) {
            size_t new_cap = cap ? 2 * cap : 64;
            char **grown = nerf__calloc(&c->ds->env, new_cap, sizeof *grown);
            if (grown == NULL) {
                rc = NERF_ENOMEM;
                break;
            }
            if (c->names) {
                memcpy(grown, c->names, cap * sizeof *grown);
            }
            nerf__free(&c->ds->env, c->names);
            c->names = grown;
            cap = new_cap;
        }
        c->names[c->n_names] = nerf__alloc(&c->ds->env, strlen(nm) + 1);
        if (c->names[c->n_names] == NULL) {
            rc = NERF_ENOMEM;
        } else {
            strcpy(c->names[c->n_names++], nm);
        }
    }
    closedir(d);
    if (rc == NERF_OK && c->n_names != c->n) {
        rc = nerf__error(NERF_EFORMAT, "%s: %zu image files, but %s has %zu "
                         "rows", c->image_dir, c->n_names, c->npy_path, c->n);
    }
    if (rc == NERF_OK) {
        qsort(c->names, c->n_names, sizeof *c->names, compare_names);
    }
    return rc;
}

/*
 * Whether the folder's photos are the size its name says, from the header
 * of the first (the others must be of its size): found before any photo
 * is decoded, or a folder of full-size photos would be read whole first.
 */
static int check_folder_scale(llff_ctx *c, const char *name)
{
    char *path = nerf__path_join(&c->ds->env, c->image_dir, name);
    if (path == NULL) {
        return NERF_ENOMEM;
    }
    uint32_t w, h;
    int rc = nerf__image_read_size(&c->ds->env, path, &w, &h);
    if (rc == NERF_OK) {
        rc = nerf__check_image_factor(c->image_dir, c->image_factor, w, h,
                                      c->rows[9], c->rows[4], c->npy_path);
    }
    nerf__free(&c->ds->env, path);
    return rc;
}

static int load_images(llff_ctx *c, const nerf__dataset_config *cfg,
                       const uint32_t *sel, uint32_t count)
{
    nerf_dataset *ds = c->ds;
    uint32_t extra = cfg->downscale / c->image_factor;
    int rc = check_folder_scale(c, c->names[sel[0]]);
    if (rc == NERF_OK) {
        rc = nerf__dataset_reserve(ds, count);
    }
    for (uint32_t i = 0; i < count && rc == NERF_OK; i++) {
        char *path = nerf__path_join(&ds->env, c->image_dir,
                                     c->names[sel[i]]);
        if (path == NULL) {
            return NERF_ENOMEM;
        }
        rc = nerf__dataset_load_image(ds, i, path, extra,
                                      cfg->white_background);
        if (rc == NERF_OK && c->mask_dir != NULL) {
            rc = nerf__folder_mask(ds, c->mask_dir, c->names[sel[i]], path,
                                   true, i, extra);
        }
        nerf__free(&ds->env, path);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    /*
     * One focal for both axes (NDC needs it), from the file's hwf scaled by
     * the actual width; the height must agree with the same scale.
     */
    const double *hwf = c->rows;
    double ratio = ds->src_width / hwf[9];
    if (fabs(hwf[4] * ratio - ds->src_height) > 1.0 + 0.01 * ds->src_height) {
        return nerf__error(NERF_EFORMAT, "%s: images are %ux%u, which does "
                           "not match the %gx%g of %s scaled by %g",
                           c->image_dir, (unsigned)ds->src_width,
                           (unsigned)ds->src_height, hwf[9], hwf[4],
                           c->npy_path, ratio);
    }
    double focal = hwf[14] * ratio / extra;
    for (uint32_t i = 0; i < count; i++) {
        nerf__view *v = &ds->views[i];
        memcpy(v->c2w, c->poses + 12 * (size_t)sel[i], sizeof v->c2w);
        v->fx = v->fy = focal;
        v->cx = 0.5 * ds->width;
        v->cy = 0.5 * ds->height;
    }
    return NERF_OK;
}

/*
 * The images of the folder not loaded (other splits, or passed over by
 * skip), by their headers: sel holds the count loaded, in ascending order.
 */
static int check_others(llff_ctx *c, const uint32_t *sel, uint32_t count)
{
    int rc = NERF_OK;
    for (size_t i = 0, k = 0; i < c->n_names && rc == NERF_OK; i++) {
        if (k < count && sel[k] == i) {
            k++;
            continue;
        }
        char *path = nerf__path_join(&c->ds->env, c->image_dir,
                                     c->names[i]);
        rc = path ? nerf__dataset_check_image(c->ds, path) : NERF_ENOMEM;
        if (rc == NERF_OK && c->mask_dir != NULL) {
            rc = nerf__folder_mask(c->ds, c->mask_dir, c->names[i], path,
                                   false, 0, 1);
        }
        nerf__free(&c->ds->env, path);
    }
    return rc;
}

static int prepare_poses(llff_ctx *c)
{
    nerf__env *env = &c->ds->env;
    c->poses = nerf__calloc(env, c->n, 12 * sizeof *c->poses);
    c->bounds = nerf__calloc(env, c->n, 2 * sizeof *c->bounds);
    double *scratch = nerf__calloc(env, c->n, sizeof *scratch);
    if (c->poses && c->bounds && scratch) {
        for (size_t i = 0; i < c->n; i++) {
            const double *r = c->rows + NERF__LLFF_ROW * i;
            nerf__llff_row_pose(r, c->poses + 12 * i);
            c->bounds[2 * i] = r[15];
            c->bounds[2 * i + 1] = r[16];
        }
        c->ds->scene_scale = nerf__llff_normalize(c->poses, c->bounds, c->n);
        nerf__llff_spiral_setup(c->poses, c->bounds, c->n, scratch,
                                &c->ds->spiral);
        c->ds->has_spiral = 1;
    }
    nerf__free(env, scratch);
    return c->poses && c->bounds && scratch ? NERF_OK : NERF_ENOMEM;
}

static int load(llff_ctx *c, const nerf__dataset_config *cfg)
{
    int rc = read_rows(c);
    if (rc == NERF_OK) {
        rc = find_image_dir(c, cfg->downscale);
    }
    if (rc == NERF_OK && !cfg->ignore_masks) {
        rc = nerf__find_mask_dir(&c->ds->env, c->dir, c->image_factor,
                                 &c->mask_dir);
    }
    if (rc == NERF_OK) {
        rc = list_images(c);
    }
    /* After the listing, so that a bad row names its image too. */
    if (rc == NERF_OK) {
        rc = check_rows(c);
    }
    if (rc == NERF_OK) {
        rc = prepare_poses(c);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    uint32_t *sel = nerf__calloc(&c->ds->env, c->n, sizeof *sel);
    if (sel == NULL) {
        return NERF_ENOMEM;
    }
    uint32_t count = nerf__holdout_split(c->n, cfg, sel);
    if (count == 0) {
        rc = nerf__error(NERF_EINVAL, "%s: the requested split has no images "
                         "(%zu views, holdout %u)", c->dir, c->n,
                         (unsigned)cfg->llff_holdout);
    } else {
        rc = load_images(c, cfg, sel, count);
    }
    if (rc == NERF_OK) {
        rc = check_others(c, sel, count);
    }
    nerf__free(&c->ds->env, sel);
    return rc;
}

int nerf__llff_load(nerf_dataset *ds, const char *dir,
                    const nerf__dataset_config *cfg)
{
    llff_ctx c;
    memset(&c, 0, sizeof c);
    c.ds = ds;
    c.dir = dir;
    c.npy_path = nerf__path_join(&ds->env, dir, "poses_bounds.npy");
    int rc = c.npy_path ? load(&c, cfg) : NERF_ENOMEM;
    if (rc == NERF_OK) {
        double lo = c.bounds[0], hi = c.bounds[1];
        for (size_t i = 0; i < c.n; i++) {
            lo = c.bounds[2 * i] < lo ? c.bounds[2 * i] : lo;
            hi = c.bounds[2 * i + 1] > hi ? c.bounds[2 * i + 1] : hi;
        }
        ds->kind = NERF__DATASET_LLFF;
        ds->ndc = 1;
        ds->near_bound = 0.0f;
        ds->far_bound = 1.0f;
        nerf__log(&ds->env, NERF_LOG_INFO,
                  "%s: LLFF scene, %u of %zu images, %ux%u (from %s, %ux%u, "
                  "downscale %u), focal %.3f, scene scale %.6g, bounds "
                  "[%.4g, %.4g] after scaling, NDC rays in [0, 1]",
                  dir, (unsigned)ds->count, c.n, (unsigned)ds->width,
                  (unsigned)ds->height, c.image_dir, (unsigned)ds->src_width,
                  (unsigned)ds->src_height, (unsigned)cfg->downscale,
                  ds->views[0].fx, ds->scene_scale, lo, hi);
    }
    for (size_t i = 0; i < c.n_names; i++) {
        nerf__free(&ds->env, c.names[i]);
    }
    nerf__free(&ds->env, c.names);
    nerf__free(&ds->env, c.image_dir);
    nerf__free(&ds->env, c.mask_dir);
    nerf__free(&ds->env, c.rows);
    nerf__free(&ds->env, c.poses);
    nerf__free(&ds->env, c.bounds);
    nerf__free(&ds->env, c.npy_path);
    return rc;
}
