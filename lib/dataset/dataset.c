/* The public dataset API: options, format detection and getters. */
#include "dataset.h"

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "camera.h"
#include "file_io.h"
#include "llff_poses.h"
#include "options.h"

/* Downscale factors beyond this leave nothing of any real image. */
#define MAX_DOWNSCALE 256u

static void dataset_defaults(nerf_dataset_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->split = NERF_SPLIT_TRAIN;
    o->downscale = 1;
    o->skip = 1;
    o->white_background = 1;
    o->skip_missing = 0;
    o->llff_holdout = 8;
}

NERF_API int nerf_dataset_options_init(nerf_dataset_options *opts,
                                       size_t struct_size)
{
    nerf_dataset_options d;
    dataset_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_dataset_options");
}

static int read_options(nerf_dataset_options *o, const nerf_dataset_options *in)
{
    dataset_defaults(o);
    if (in == NULL) {
        return NERF_OK;
    }
    int rc = nerf__options_read(o, sizeof *o, in, "nerf_dataset_options");
    if (rc != NERF_OK) {
        return rc;
    }
    const char *what = NULL;
    if (o->split > NERF_SPLIT_TEST) {
        what = "split is not a nerf_split";
    } else if (o->downscale < 1 || o->downscale > MAX_DOWNSCALE) {
        what = "downscale must be 1..256";
    } else if (o->skip < 1) {
        what = "skip must be at least 1";
    } else if (o->white_background > 1 || o->skip_missing > 1 ||
               o->forward_facing > 1 || o->ignore_masks > 1) {
        what = "white_background, skip_missing, forward_facing and "
               "ignore_masks must be 0 or 1";
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "nerf_dataset_options: %s", what);
    }
    return NERF_OK;
}

/*
 * Whether dir/name is there, in *found: of any kind, so that a FIFO or a
 * folder in a file's place picks the layout whose loader then says what
 * is wrong with it, rather than no layout at all.  Fails only when the
 * path cannot be allocated: reading that as "absent" would send the
 * detection on to another layout and report a missing file instead of
 * NERF_ENOMEM.
 */
static int is_present(const nerf__env *env, const char *dir, const char *name,
                      bool *found)
{
    char *path = nerf__path_join(env, dir, name);
    if (path == NULL) {
        return NERF_ENOMEM;
    }
    struct stat st;
    *found = stat(path, &st) == 0;
    nerf__free(env, path);
    return NERF_OK;
}

/* Pick the loader from the files present in dir. */
static int detect_and_load(nerf_dataset *ds, const char *dir,
                           const nerf__dataset_config *cfg)
{
    static const char *const split_names[] = {"train", "val", "test"};
    struct stat st;
    if (stat(dir, &st) != 0) {
        char text[128];
        if (strerror_r(errno, text, sizeof text) != 0) {
            snprintf(text, sizeof text, "error %d", errno);
        }
        int status = errno == ENOENT || errno == ENOTDIR ? NERF_ENOENT
                                                         : NERF_EIO;
        return nerf__error(status, "%s: cannot open: %s", dir, text);
    }
    if (!S_ISDIR(st.st_mode)) {
        return nerf__error(NERF_EUNRECOGNISED, "%s: %s, not a dataset "
                           "folder", dir, nerf__file_kind(st.st_mode));
    }
    char name[64];
    snprintf(name, sizeof name, "transforms_%s.json", split_names[cfg->split]);
    bool split_json = false, all_json = false, llff = false;
    int rc = is_present(&ds->env, dir, name, &split_json);
    if (rc == NERF_OK && !split_json) {
        rc = is_present(&ds->env, dir, "transforms.json", &all_json);
    }
    if (rc == NERF_OK && !split_json && !all_json) {
        rc = is_present(&ds->env, dir, "poses_bounds.npy", &llff);
    }
    int colmap = 0;
    if (rc == NERF_OK && !split_json && !all_json && !llff) {
        rc = nerf__colmap_detect(&ds->env, dir, &colmap);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    if (split_json) {
        return nerf__blender_load(ds, dir, name, false, cfg);
    }
    if (all_json) {
        return nerf__blender_load(ds, dir, "transforms.json", true, cfg);
    }
    if (llff) {
        return nerf__llff_load(ds, dir, cfg);
    }
    if (colmap) {
        return nerf__colmap_load(ds, dir, cfg);
    }
    /* A Blender scene without the split asked for lacks a file; only a
     * folder with none of them is not a dataset. */
    for (int k = 0; k < 3; k++) {
        char other[64];
        bool found = false;
        snprintf(other, sizeof other, "transforms_%s.json", split_names[k]);
        rc = is_present(&ds->env, dir, other, &found);
        if (rc != NERF_OK) {
            return rc;
        }
        if (found) {
            return nerf__error(NERF_ENOENT, "%s: no %s: this Blender scene "
                               "has no %s split (it has %s)", dir, name,
                               split_names[cfg->split], other);
        }
    }
    return nerf__error(NERF_EUNRECOGNISED, "%s: no %s, transforms.json, "
                       "poses_bounds.npy or COLMAP model (sparse/0/ or "
                       "sparse/): not a known dataset layout", dir, name);
}

/*
 * A trainer draws only kept pixels, so a split with none left is refused
 * now rather than by every later call; the count left out goes to the
 * log, as the loaders' other figures do.
 */
static int check_masks(nerf_dataset *ds, const char *dir)
{
    size_t n = (size_t)ds->count * ds->width * ds->height, kept = 0;
    for (size_t i = 0; i < n; i++) {
        kept += ds->mask[i] != 0;
    }
    if (kept == 0) {
        return nerf__error(NERF_EFORMAT, "%s: the masks leave out every "
                           "pixel of the split", dir);
    }
    nerf__log(&ds->env, NERF_LOG_INFO, "%s: masks leave out %zu of %zu "
              "pixels (%.2f%%)", dir, n - kept, n,
              100.0 * (double)(n - kept) / (double)n);
    return NERF_OK;
}

NERF_API int nerf_dataset_load(nerf_dataset **out, const char *dir,
                               const nerf_dataset_options *opts)
{
    if (out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_dataset_load: out is NULL");
    }
    *out = NULL;
    if (dir == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_dataset_load: dir is NULL");
    }
    nerf_dataset_options o;
    nerf__env env;
    int rc = read_options(&o, opts);
    if (rc == NERF_OK) {
        rc = nerf__env_from_hooks(&env, o.hooks);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    nerf_dataset *ds = nerf__calloc(&env, 1, sizeof *ds);
    if (ds == NULL) {
        return NERF_ENOMEM;
    }
    ds->env = env;
    ds->aabb_scale = 1.0;
    nerf__dataset_config cfg = {o.split, o.downscale, o.skip,
                                o.white_background, o.skip_missing,
                                o.llff_holdout, o.forward_facing,
                                o.ignore_masks};
    rc = detect_and_load(ds, dir, &cfg);
    if (rc == NERF_OK && o.forward_facing &&
        ds->kind == NERF__DATASET_BLENDER) {
        rc = nerf__error(NERF_EINVAL, "%s: forward_facing is for COLMAP "
                         "models (LLFF scenes are forward-facing anyway); "
                         "this is a Blender scene", dir);
    }
    if (rc != NERF_OK) {
        nerf_dataset_destroy(ds);
        return rc;
    }
    if (ds->mask != NULL) {
        rc = check_masks(ds, dir);
        if (rc != NERF_OK) {
            nerf_dataset_destroy(ds);
            return rc;
        }
    }
    ds->white_background = ds->kind == NERF__DATASET_BLENDER &&
                           o.white_background;
    *out = ds;
    return NERF_OK;
}

NERF_API void nerf_dataset_destroy(nerf_dataset *ds)
{
    if (ds == NULL) {
        return;
    }
    nerf__env env = ds->env;
    nerf__free(&env, ds->pixels);
    nerf__free(&env, ds->alpha);
    nerf__free(&env, ds->mask);
    nerf__free(&env, ds->views);
    nerf__free(&env, ds);
}

NERF_API uint32_t nerf_dataset_count(const nerf_dataset *ds)
{
    return ds ? ds->count : 0;
}

NERF_API int nerf_dataset_get_format(const nerf_dataset *ds)
{
    return ds ? ds->kind : 0;
}

NERF_API int nerf_dataset_image_size(const nerf_dataset *ds,
                                     uint32_t *width_out,
                                     uint32_t *height_out)
{
    if (ds == NULL || width_out == NULL || height_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_dataset_image_size: NULL "
                           "argument");
    }
    *width_out = ds->width;
    *height_out = ds->height;
    return NERF_OK;
}

static int check_index(const nerf_dataset *ds, uint32_t index,
                       const void *out, const char *fn)
{
    if (ds == NULL || out == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL argument", fn);
    }
    if (index >= ds->count) {
        return nerf__error(NERF_EINVAL, "%s: index %u is out of range (the "
                           "dataset has %u images)", fn, (unsigned)index,
                           (unsigned)ds->count);
    }
    return NERF_OK;
}

NERF_API int nerf_dataset_image(const nerf_dataset *ds, uint32_t index,
                                const float **rgb_out)
{
    int rc = check_index(ds, index, rgb_out, "nerf_dataset_image");
    if (rc == NERF_OK) {
        *rgb_out = ds->pixels + (size_t)index * ds->width * ds->height * 3;
    }
    return rc;
}

NERF_API int nerf_dataset_has_masks(const nerf_dataset *ds)
{
    return ds != NULL && ds->mask != NULL;
}

NERF_API int nerf_dataset_mask(const nerf_dataset *ds, uint32_t index,
                               const uint8_t **mask_out)
{
    int rc = check_index(ds, index, mask_out, "nerf_dataset_mask");
    if (rc == NERF_OK) {
        *mask_out = ds->mask ? ds->mask + (size_t)index * ds->width *
                                              ds->height
                             : NULL;
    }
    return rc;
}

double nerf__dataset_aabb_scale(const nerf_dataset *ds)
{
    return ds ? ds->aabb_scale : 1.0;
}

/* Write a camera of the dataset's image size with view v's intrinsics,
 * its lens when lens is set, and the pose c2w into the caller's struct. */
static int write_camera(const nerf_dataset *ds, const double *c2w,
                        const nerf__view *v, bool lens, nerf_camera *out,
                        const char *fn)
{
    nerf_camera cam;
    nerf_camera_init(&cam, sizeof cam);
    cam.width = ds->width;
    cam.height = ds->height;
    for (int i = 0; i < 12; i++) {
        cam.c2w[i] = (float)c2w[i];
    }
    cam.fx = (float)v->fx;
    cam.fy = (float)v->fy;
    cam.cx = (float)v->cx;
    cam.cy = (float)v->cy;
    if (lens) {
        cam.k1 = (float)v->k1;
        cam.k2 = (float)v->k2;
        cam.p1 = (float)v->p1;
        cam.p2 = (float)v->p2;
        cam.k3 = (float)v->k3;
    }
    return nerf__camera_write(out, &cam, fn);
}

NERF_API int nerf_dataset_camera(const nerf_dataset *ds, uint32_t index,
                                 nerf_camera *out)
{
    int rc = check_index(ds, index, out, "nerf_dataset_camera");
    if (rc != NERF_OK) {
        return rc;
    }
    const nerf__view *v = &ds->views[index];
    return write_camera(ds, v->c2w, v, true, out, "nerf_dataset_camera");
}

NERF_API int nerf_dataset_bounds(const nerf_dataset *ds, float *near_out,
                                 float *far_out)
{
    if (ds == NULL || near_out == NULL || far_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_dataset_bounds: NULL argument");
    }
    *near_out = ds->near_bound;
    *far_out = ds->far_bound;
    return NERF_OK;
}

NERF_API int nerf_dataset_is_ndc(const nerf_dataset *ds)
{
    return ds ? ds->ndc : 0;
}

NERF_API int nerf_dataset_space(const nerf_dataset *ds, uint32_t *space_out,
                                float *bound_out)
{
    if (ds == NULL || space_out == NULL || bound_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_dataset_space: NULL argument");
    }
    if (ds->ndc) {
        /* NDC x and y are within [-1, 1] for the reference frustum; the
         * other cameras of a capture see a little past it. */
        *space_out = NERF_SPACE_NDC;
        *bound_out = 1.5f;
    } else if (ds->unbounded_inner > 0.0) {
        *space_out = NERF_SPACE_UNBOUNDED;
        *bound_out = (float)ds->unbounded_inner;
    } else {
        /* The Blender scenes' bound, which the fast preset has. */
        *space_out = NERF_SPACE_BOX;
        *bound_out = 1.5f;
    }
    return NERF_OK;
}

NERF_API int nerf_dataset_spiral_camera(const nerf_dataset *ds,
                                        uint32_t index, uint32_t n_views,
                                        nerf_camera *out)
{
    const char *fn = "nerf_dataset_spiral_camera";
    if (ds == NULL || out == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL argument", fn);
    }
    if (!ds->has_spiral) {
        return nerf__error(NERF_EINVAL, "%s: only forward-facing scenes "
                           "(LLFF, or COLMAP loaded with forward_facing) "
                           "have a spiral path", fn);
    }
    if (n_views == 0 || index >= n_views) {
        return nerf__error(NERF_EINVAL, "%s: view %u of %u is out of range",
                           fn, (unsigned)index, (unsigned)n_views);
    }
    double c2w[12];
    nerf__llff_spiral_pose(&ds->spiral, index, n_views, c2w);
    const nerf__view *v = &ds->views[0];
    /* A path to render, not a photo: the ideal (pinhole) camera. */
    return write_camera(ds, c2w, v, false, out, fn);
}
