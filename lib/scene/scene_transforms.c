/*
 * The built-in scene as one instant-ngp style transforms.json: every view
 * in one file, explicit intrinsics and lens at top level, images under
 * images/.  Whoever loads it chooses the split (every llff_holdout-th
 * frame held out).
 */
#include <stdio.h>

#include "error.h"
#include "scene_image.h"
#include "scene_internal.h"

/*
 * The object's solids fill a sphere of radius 1.6: 0.53 in instant-ngp's
 * unit cube (it scales positions by 0.33), a little more than the cube's
 * half side, so its box must be twice the cube.  The opaque captures'
 * backdrop at radius 40 needs the largest box instant-ngp's grids cascade
 * to that keeps it mostly inside.
 */
#define AABB_SCALE_OBJECT 2
#define AABB_SCALE_SURROUNDED 16

/* Top-level fields: the intrinsics every frame shares. */
static void top_fields(cJSON *root, const nerf_scene_options *o)
{
    nerf_camera cam;
    nerf__scene_capture_camera(o, 0, 0, 1, &cam);
    cJSON_AddNumberToObject(root, "fl_x", cam.fx);
    cJSON_AddNumberToObject(root, "fl_y", cam.fy);
    cJSON_AddNumberToObject(root, "cx", cam.cx);
    cJSON_AddNumberToObject(root, "cy", cam.cy);
    cJSON_AddNumberToObject(root, "w", o->width);
    cJSON_AddNumberToObject(root, "h", o->height);
    nerf__scene_lens_json(root, o, true);
    cJSON_AddNumberToObject(root, "aabb_scale",
                            o->capture == NERF_SCENE_CAPTURE_OBJECT
                                ? AABB_SCALE_OBJECT
                                : AABB_SCALE_SURROUNDED);
}

int nerf__scene_write_transforms(const char *dir, const nerf_scene_options *o,
                                 const nerf__env *env, uint8_t *px)
{
    const nerf__scene_look look = nerf__scene_look_of(o);
    char path[4096];
    snprintf(path, sizeof path, "%s/images", dir);
    int rc = nerf__scene_make_dir(path);
    uint8_t *mask = NULL;
    if (rc == NERF_OK && o->occluders) {
        snprintf(path, sizeof path, "%s/masks", dir);
        rc = nerf__scene_make_dir(path);
        mask = nerf__alloc(env, (size_t)o->width * o->height);
        if (rc == NERF_OK && mask == NULL) {
            return NERF_ENOMEM;
        }
    }
    cJSON *root = cJSON_CreateObject();
    cJSON *frames = cJSON_CreateArray();
    if (root == NULL || frames == NULL) {
        nerf__free(env, mask);
        cJSON_Delete(root);
        cJSON_Delete(frames);
        return nerf__error(NERF_ENOMEM, "%s: out of memory building JSON", dir);
    }
    top_fields(root, o);
    cJSON_AddItemToObject(root, "frames", frames);
    const uint32_t counts[3] = {o->n_train, o->n_val, o->n_test};
    uint32_t written = 0;
    for (int split = 0; split < 3; split++) {
        for (uint32_t i = 0; i < counts[split] && rc == NERF_OK; i++) {
            nerf_camera cam;
            nerf__scene_capture_camera(o, split, i, counts[split], &cam);
            nerf__scene_render_view(&cam, &look, o->threads, px, NULL);
            const bool occluded = nerf__scene_occluded(o, split, i);
            if (occluded) {
                nerf__scene_paint_occluder(o, i, look.channels, px, mask);
            }
            char file[64];
            snprintf(file, sizeof file, "images/%s_%u",
                     nerf__scene_split_names[split], i);
            snprintf(path, sizeof path, "%s/%s", dir, file);
            rc = nerf__scene_image_write(env, path, o, look.channels, px);
            snprintf(file, sizeof file, "images/%s_%u%s",
                     nerf__scene_split_names[split], i,
                     nerf__scene_image_extension(o));
            cJSON *frame = cJSON_CreateObject();
            cJSON_AddStringToObject(frame, "file_path", file);
            if (occluded && rc == NERF_OK) {
                snprintf(file, sizeof file, "masks/%s_%u.png",
                         nerf__scene_split_names[split], i);
                snprintf(path, sizeof path, "%s/%s", dir, file);
                rc = nerf__scene_mask_write(env, path, o, mask);
                cJSON_AddStringToObject(frame, "mask_path", file);
            }
            cJSON_AddItemToObject(frame, "transform_matrix",
                                  nerf__scene_matrix_json(cam.c2w));
            cJSON_AddItemToArray(frames, frame);
            written++;
        }
    }
    if (rc == NERF_OK) {
        snprintf(path, sizeof path, "%s/transforms.json", dir);
        rc = nerf__scene_write_json(env, path, root);
    }
    cJSON_Delete(root);
    nerf__free(env, mask);
    nerf__log(env, NERF_LOG_INFO, "scene: wrote %u views of %ux%u to "
              "%s/transforms.json", (unsigned)written, o->width, o->height,
              dir);
    return rc;
}
