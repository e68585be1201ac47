/*
 * The dataset handle: images and cameras of one split of a scene, as the
 * Blender and LLFF loaders leave them.  Loaders fill a nerf_dataset through
 * the helpers below; the public getters in dataset.c only read it.
 */
#ifndef NERF_DATASET_DATASET_H
#define NERF_DATASET_DATASET_H

#include <stdbool.h>
#include <stdint.h>

#include "env.h"

typedef enum nerf__dataset_kind {
    NERF__DATASET_BLENDER = 1,
    NERF__DATASET_LLFF = 2,
    NERF__DATASET_COLMAP = 3
} nerf__dataset_kind;

/* The camera of one image, in the units of the stored (downscaled) image. */
typedef struct nerf__view {
    double c2w[12]; /* 3x4 camera-to-world, row-major, OpenGL axes */
    double fx, fy, cx, cy;
    double k1, k2, p1, p2, k3; /* nerf_camera's lens distortion */
} nerf__view;

/*
 * What the reference's spiral render path needs, computed once at load
 * time from all poses of an LLFF scene (not just the loaded split).
 */
typedef struct nerf__spiral {
    double c2w[12]; /* average pose of the recentred cameras */
    double up[3];   /* normalised mean up vector */
    double radii[3]; /* 90th percentile of |position| per axis */
    double focus;   /* depth of the point the path looks at */
} nerf__spiral;

/* Loader settings after the public options struct has been read. */
typedef struct nerf__dataset_config {
    uint32_t split;      /* nerf_split */
    uint32_t downscale;
    uint32_t skip;
    uint32_t white_background;
    uint32_t skip_missing;
    uint32_t llff_holdout;
    uint32_t forward_facing;
    uint32_t ignore_masks;
} nerf__dataset_config;

struct nerf_dataset {
    nerf__env env;
    int kind;              /* nerf__dataset_kind */
    uint32_t count;        /* images in this split */
    uint32_t width, height; /* of the stored images */
    uint32_t src_width, src_height; /* of the files, before downscaling */
    float *pixels;         /* count x height x width x 3, RGB in [0, 1] */
    /* count x height x width coverage of the stored pixels (mean alpha
     * over each block, 65535 = opaque), or NULL when no image has a
     * transparent pixel: with it, a trainer can move the images onto
     * another background (pixels + (bg - alpha_bg) (1 - coverage)) without
     * keeping a second copy of them.  16 bits, not float: half the memory
     * (lego at full size: 128 MB beside 768 MB of colours), and a step of
     * 1.5e-5 in coverage is far below what 8-bit colours resolve. */
    uint16_t *alpha;
    float alpha_bg;        /* the grey pixels were composited onto (0, 1) */
    /* count x height x width: 1 where a pixel counts (trained on, scored),
     * 0 where its image's mask leaves it out; NULL when no image of the
     * split has a mask, so that a capture without masks costs nothing. */
    uint8_t *mask;
    nerf__view *views;     /* count */
    float near_bound, far_bound; /* ray interval: NDC [0, 1] for LLFF */
    int ndc;
    double scene_scale;    /* LLFF: factor applied to positions and bounds */
    double scene_radius;   /* Blender: largest camera distance from the
                              origin; 0 when unknown */
    /* > 0: an unbounded scene (nerf_dataset_space() says UNBOUNDED), whose
     * central part lies within the cube of this half side (world units):
     * the loader decides (a COLMAP model, a transforms file with
     * aabb_scale > 1). */
    double unbounded_inner;
    int white_background;  /* images with alpha were composited on white,
                              so renders of this scene should be too */
    int has_spiral;
    nerf__spiral spiral;
    double aabb_scale;     /* instant-ngp's transforms.json aabb_scale: the
                              scene fills a cube this many times the unit
                              cube; 1 when the files do not say */
};

/* The dataset's aabb_scale (1 for NULL). */
double nerf__dataset_aabb_scale(const nerf_dataset *ds);

/* Allocate room for count images and views (pixels come with the first
 * image, once its size is known). */
int nerf__dataset_reserve(nerf_dataset *ds, uint32_t count);

/*
 * Read the PNG or JPEG at path (nerf__image_read_rgba: told apart by its
 * first bytes, a JPEG turned upright by its Exif orientation) and store it
 * as image index: composited onto white (or black) by its alpha, then
 * box-filtered by factor x factor, and its coverage into ds->alpha
 * (allocated by the first image with a transparent pixel).  The first
 * image fixes the size; a later one of another size is an error naming it.
 */
int nerf__dataset_load_image(nerf_dataset *ds, uint32_t index,
                             const char *path, uint32_t factor,
                             uint32_t white_background);

/* How a layout's mask images say which pixels to leave out. */
typedef enum nerf__mask_rule {
    NERF__MASK_ZERO_DROPS = 0,    /* nerfstudio's mask_path, COLMAP masks/ */
    NERF__MASK_NONZERO_DROPS = 1  /* instant-ngp's dynamic_mask_* */
} nerf__mask_rule;

/*
 * Read the mask image at path for image index (loaded before it, whose
 * file photo names in messages) and store it into ds->mask (allocated by
 * the first mask, every pixel kept): a stored pixel is kept only when
 * every source pixel of its downscaled block is.  The mask must be the
 * size of its photo's file.
 */
int nerf__dataset_load_mask(nerf_dataset *ds, uint32_t index,
                            const char *path, const char *photo,
                            uint32_t factor, nerf__mask_rule rule);

/* The check nerf__dataset_check_image makes, for the mask at path of the
 * photo photo (not loaded): readable, and the size of the loaded photos. */
int nerf__dataset_check_mask(const nerf_dataset *ds, const char *path,
                             const char *photo);

/*
 * Check the image at path that the dataset names but does not load (a
 * frame of another split, or one that skip passes over) as far as its
 * header goes: what nerf__dataset_load_image would refuse before decoding
 * it (not a regular file, neither PNG nor JPEG, a header that does not
 * decode or claims more pixels than the file holds), and a size other than
 * that of the images loaded (ds->src_width x src_height, so after them).
 */
int nerf__dataset_check_image(const nerf_dataset *ds, const char *path);

/* "dir/name" in a buffer from ds->env (free with nerf__free). */
char *nerf__path_join(const nerf__env *env, const char *dir,
                      const char *name);

/*
 * The folder of a downscale factor (docs of nerf_dataset_options.downscale):
 * images_<factor>, else images_M for the largest M dividing it (images for
 * M = 1); its path in *path_out (free with nerf__free) and M in
 * *factor_out.  NERF_EIO naming dir when there is none.
 */
int nerf__find_image_dir(const nerf__env *env, const char *dir,
                         uint32_t factor, char **path_out,
                         uint32_t *factor_out);

/*
 * The mask folder beside the image folder of factor (nerf__find_image_dir's
 * *factor_out): masks/ for images/, masks_<factor>/ for images_<factor>/,
 * in *path_out (free with nerf__free), or NULL when there is none (of any
 * kind: a file in its place is for the mask reads to refuse).
 */
int nerf__find_mask_dir(const nerf__env *env, const char *dir,
                        uint32_t factor, char **path_out);

/*
 * COLMAP's convention for a folder of photos (COLMAP and LLFF layouts):
 * the mask of <image folder>/<name> is mask_dir/<name>.png, 0 = leave out.
 * Loaded into slot (load; photo loaded before it, factor its block size)
 * or checked by its header.  Once a capture has a mask folder every photo
 * needs its mask, so that one lost in copying is an error naming it rather
 * than a photo silently trained on whole.
 */
int nerf__folder_mask(nerf_dataset *ds, const char *mask_dir,
                      const char *name, const char *photo, bool load,
                      uint32_t slot, uint32_t factor);

/*
 * Whether the w x h photos of the folder image_dir, found for factor
 * (nerf__find_image_dir), are what that folder's name says: the full-size
 * photos' full_w x full_h (as source, the poses' file or camera, gives
 * them) divided by factor, to a pixel either way, whichever way the tool
 * that shrank them rounded.  A folder of full-size photos named images_8/
 * would otherwise be read as it is, 64 times the pixels asked for.
 * Factor 1 (images/) passes any size: the intrinsics follow the photos'.
 * NERF_EFORMAT naming the folder, the sizes and source otherwise.
 */
int nerf__check_image_factor(const char *image_dir, uint32_t factor,
                             uint32_t w, uint32_t h, double full_w,
                             double full_h, const char *source);

/*
 * Indices (into n images sorted by name) of the split: every
 * llff_holdout-th image from the first is test and val, the others train,
 * thinned by skip.  Returns how many went to out (room for n).
 */
uint32_t nerf__holdout_split(size_t n, const nerf__dataset_config *cfg,
                             uint32_t *out);

/* Whether a COLMAP model (sparse/0/ or sparse/ holding cameras and images
 * files) is in dir. */
int nerf__colmap_detect(const nerf__env *env, const char *dir, int *found);

/* Loaders.  dir is the scene folder; name is the file that was found. */
/* whole: name is the one transforms.json of every split. */
int nerf__blender_load(nerf_dataset *ds, const char *dir, const char *name,
                       bool whole, const nerf__dataset_config *cfg);
int nerf__llff_load(nerf_dataset *ds, const char *dir,
                    const nerf__dataset_config *cfg);
int nerf__colmap_load(nerf_dataset *ds, const char *dir,
                      const nerf__dataset_config *cfg);

#endif
