/* What the loaders of photo folders (LLFF, COLMAP) share: the downscale
 * rule's image folder and the every-n-th hold-out split. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "dataset.h"

static bool is_dir(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

int nerf__find_image_dir(const nerf__env *env, const char *dir,
                         uint32_t factor, char **path_out,
                         uint32_t *factor_out)
{
    for (uint32_t m = factor; m >= 1; m--) {
        if (factor % m != 0) {
            continue;
        }
        char name[32];
        if (m == 1) {
            snprintf(name, sizeof name, "images");
        } else {
            snprintf(name, sizeof name, "images_%u", (unsigned)m);
        }
        char *path = nerf__path_join(env, dir, name);
        if (path == NULL) {
            return NERF_ENOMEM;
        }
        if (is_dir(path)) {
            *path_out = path;
            *factor_out = m;
            return NERF_OK;
        }
        nerf__free(env, path);
    }
    return nerf__error(NERF_ENOENT, "%s: no image folder for downscale %u "
                       "(looked for images_%u/, images_M/ with M dividing "
                       "%u, and images/)", dir, (unsigned)factor,
                       (unsigned)factor, (unsigned)factor);
}

int nerf__find_mask_dir(const nerf__env *env, const char *dir,
                        uint32_t factor, char **path_out)
{
    char name[32];
    if (factor == 1) {
        snprintf(name, sizeof name, "masks");
    } else {
        snprintf(name, sizeof name, "masks_%u", (unsigned)factor);
    }
    *path_out = nerf__path_join(env, dir, name);
    if (*path_out == NULL) {
        return NERF_ENOMEM;
    }
    struct stat st;
    if (stat(*path_out, &st) != 0) {
        nerf__free(env, *path_out);
        *path_out = NULL;
    }
    return NERF_OK;
}

int nerf__folder_mask(nerf_dataset *ds, const char *mask_dir,
                      const char *name, const char *photo, bool load,
                      uint32_t slot, uint32_t factor)
{
    size_t n = strlen(name);
    char *file = nerf__alloc(&ds->env, n + 5);
    if (file == NULL) {
        return NERF_ENOMEM;
    }
    memcpy(file, name, n);
    strcpy(file + n, ".png");
    char *path = nerf__path_join(&ds->env, mask_dir, file);
    nerf__free(&ds->env, file);
    if (path == NULL) {
        return NERF_ENOMEM;
    }
    int rc = load ? nerf__dataset_load_mask(ds, slot, path, photo, factor,
                                            NERF__MASK_ZERO_DROPS)
                  : nerf__dataset_check_mask(ds, path, photo);
    nerf__free(&ds->env, path);
    return rc;
}

int nerf__check_image_factor(const char *image_dir, uint32_t factor,
                             uint32_t w, uint32_t h, double full_w,
                             double full_h, const char *source)
{
    double k = factor;
    if (factor == 1 ||
        (fabs(k * w - full_w) <= k && fabs(k * h - full_h) <= k)) {
        return NERF_OK;
    }
    return nerf__error(NERF_EFORMAT, "%s: the photos are %ux%u, but %s says "
                       "the full-size photos are %gx%g, which divided by %u "
                       "is %.6gx%.6g: images_%u/ must hold the photos "
                       "downscaled %u times", image_dir, (unsigned)w,
                       (unsigned)h, source, full_w, full_h, (unsigned)factor,
                       full_w / k, full_h / k, (unsigned)factor,
                       (unsigned)factor);
}

uint32_t nerf__holdout_split(size_t n, const nerf__dataset_config *cfg,
                             uint32_t *out)
{
    uint32_t count = 0, seen = 0;
    for (size_t i = 0; i < n; i++) {
        bool held = cfg->llff_holdout > 0 && i % cfg->llff_holdout == 0;
        bool want = cfg->split == NERF_SPLIT_TRAIN ? !held : held;
        if (want && seen++ % cfg->skip == 0) {
            out[count++] = (uint32_t)i;
        }
    }
    return count;
}
