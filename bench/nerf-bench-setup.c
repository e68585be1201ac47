/*
 * What every measurement starts from: a preset's model and samplers, the
 * view the renders look through, and the images training draws from (the
 * built-in scene written to a temporary folder, or --data's scene).
 */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "nerf-bench.h"

int preset_make(preset_setup *p, int id, int matmul, const nerf_dataset *ds)
{
    memset(p, 0, sizeof *p);
    p->id = id;
    p->name = id == NERF_PRESET_TINY   ? "tiny"
              : id == NERF_PRESET_FAST ? "fast"
                                       : "reference";
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, id);
    mo.matmul = (uint32_t)matmul;
    /* As nerf-train sets a run up: a hash-grid model in the scene's space
     * (NDC for LLFF scenes), sampled within the scene's bounds. */
    if (ds != NULL && nerf_model_options_for_dataset(&mo, ds) != NERF_OK) {
        return -1;
    }
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, id);
    if (nerf_model_create(&p->model, &mo) != NERF_OK) {
        return -1;
    }
    if (ds != NULL &&
        nerf_sampler_options_for(&so, p->model, ds,
                                 NERF_SAMPLER_FOR_TRAINING) != NERF_OK) {
        return -1;
    }
    if (nerf_sampler_create(&p->train_sampler, &so) != NERF_OK) {
        return -1;
    }
    so.perturb = 0;
    if (nerf_sampler_create(&p->eval_sampler, &so) != NERF_OK) {
        return -1;
    }
    p->march = nerf__sampler_marches(p->train_sampler);
    p->n_coarse = so.n_coarse;
    p->n_fine = so.n_fine;
    p->passes = nerf__sampler_last_pass(p->eval_sampler) + 1;
    p->samples[0] = (int)so.n_coarse;
    p->samples[1] = (int)(so.n_coarse + so.n_fine);
    return 0;
}

void preset_release(preset_setup *p)
{
    nerf_sampler_destroy(p->eval_sampler);
    nerf_sampler_destroy(p->train_sampler);
    nerf_model_destroy(p->model);
}

/* A Blender-like view of the built-in scene: as far from the origin and
 * as wide as the scene's own cameras, from in front and half as high. */
void view_camera(nerf_camera *c, uint32_t side)
{
    NERF_CAMERA_INIT(c);
    c->width = c->height = side;
    c->fx = c->fy =
        0.5f * (float)side / tanf(0.5f * (float)NERF__SCENE_CAMERA_ANGLE_X);
    c->cx = c->cy = 0.5f * (float)side;
    const double r = NERF__SCENE_CAMERA_RADIUS / sqrt(5.0);
    const float eye[3] = {0.0f, (float)(-2.0 * r), (float)r};
    const float target[3] = {0.0f, 0.0f, 0.0f}, up[3] = {0.0f, 0.0f, 1.0f};
    nerf_camera_look_at(c, eye, target, up);
}

int render_camera(nerf_camera *c, uint32_t width, const nerf_dataset *ds)
{
    if (ds == NULL) {
        view_camera(c, width);
        return 0;
    }
    NERF_CAMERA_INIT(c);
    if (nerf_dataset_camera(ds, 0, c) != NERF_OK) {
        return -1;
    }
    const float s = (float)width / (float)c->width;
    uint32_t height = (uint32_t)lroundf((float)c->height * s);
    c->width = width;
    c->height = height > 0 ? height : 1;
    c->fx *= s;
    c->fy *= s;
    c->cx *= s;
    c->cy *= s;
    return 0;
}

/* ---- the dataset: the built-in scene in a temporary folder -------------- */

static void remove_tree(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0) {
        return;
    }
    if (S_ISDIR(st.st_mode)) {
        DIR *d = opendir(path);
        if (d) {
            struct dirent *e;
            while ((e = readdir(d)) != NULL) {
                if (strcmp(e->d_name, ".") == 0 ||
                    strcmp(e->d_name, "..") == 0) {
                    continue;
                }
                size_t len = strlen(path) + strlen(e->d_name) + 2;
                char *child = malloc(len);
                if (child) {
                    snprintf(child, len, "%s/%s", path, e->d_name);
                    remove_tree(child);
                    free(child);
                }
            }
            closedir(d);
        }
        rmdir(path);
    } else {
        unlink(path);
    }
}

nerf_dataset *make_dataset(uint32_t side, uint32_t views)
{
    const char *tmp = getenv("TMPDIR");
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/nerf-bench-XXXXXX",
             tmp && *tmp ? tmp : "/tmp");
    if (mkdtemp(dir) == NULL) {
        perror("nerf-bench: mkdtemp");
        return NULL;
    }
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = so.height = side;
    so.n_train = views;
    so.n_val = 0;
    so.n_test = 0;
    nerf_dataset *ds = NULL;
    if (nerf_scene_write(dir, &so) != NERF_OK ||
        nerf_dataset_load(&ds, dir, NULL) != NERF_OK) {
        fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        ds = NULL;
    }
    /* The images are in memory now. */
    remove_tree(dir);
    return ds;
}

/* ---- the dataset: a scene's training split (--data) --------------------- */

/* --data: a real scene's training images; the run records their size. */
nerf_dataset *load_dataset(run_info *ri)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = ri->downscale;
    nerf_dataset *ds = NULL;
    if (nerf_dataset_load(&ds, ri->data, &o) != NERF_OK) {
        fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        return NULL;
    }
    uint32_t w = 0, h = 0;
    nerf_dataset_image_size(ds, &w, &h);
    ri->train_side = w;
    ri->train_height = h;
    ri->train_views = nerf_dataset_count(ds);
    return ds;
}
