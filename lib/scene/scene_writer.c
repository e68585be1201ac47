/*
 * nerf_scene_write(): render the built-in scene into a dataset, so that
 * the demo and the tests need no download.  Here: the options, the object
 * capture's cameras and the Blender layout (transforms_{train,val,test}
 * .json and PNGs or JPEGs, see scene_image.h); the other captures' cameras
 * are in captures.c, the other layouts in files of their own.
 */
#include <cJSON.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "camera.h"
#include "cpu.h"
#include "distortion.h"
#include "env.h"
#include "file_io.h"
#include "field.h"
#include "options.h"
#include "png_io.h"
#include "rng.h"
#include "scene_image.h"
#include "scene_internal.h"

#define NEAR 2.0f
#define FAR 6.0f
#define PI 3.14159265358979323846
#define AABB_SCALE 16

static void scene_defaults(nerf_scene_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->width = 100;
    o->height = 100;
    o->n_train = 100;
    o->n_val = 8;
    o->n_test = 16;
    o->threads = 0;
    o->capture = NERF_SCENE_CAPTURE_OBJECT;
    o->layout = NERF_SCENE_LAYOUT_BLENDER;
}

NERF_API int nerf_scene_options_init(nerf_scene_options *opts,
                                     size_t struct_size)
{
    nerf_scene_options d;
    scene_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_scene_options");
}

static void position(double azimuth, double elevation, double p[3])
{
    p[0] = NERF__SCENE_CAMERA_RADIUS * cos(elevation) * cos(azimuth);
    p[1] = NERF__SCENE_CAMERA_RADIUS * cos(elevation) * sin(azimuth);
    p[2] = NERF__SCENE_CAMERA_RADIUS * sin(elevation);
}

/*
 * Train views cover the upper hemisphere evenly (a Fibonacci spiral in
 * sin(elevation)); validation views are random there; test views circle
 * at a fixed elevation, as the lego test split does.
 */
static void place_camera(int split, uint32_t i, uint32_t n, uint64_t seed,
                         nerf_camera *cam)
{
    double p[3];
    if (split == 0) {
        double s = 0.1 + 0.85 * (i + 0.5) / n;
        double az = i * PI * (3.0 - sqrt(5.0));
        position(az, asin(s), p);
    } else if (split == 1) {
        nerf__rng r = nerf__rng_make(seed, 77 + i);
        double s = 0.1 + 0.85 * nerf__rng_uniform_d(&r);
        position(2.0 * PI * nerf__rng_uniform_d(&r), asin(s), p);
    } else {
        position(2.0 * PI * i / n, 30.0 * PI / 180.0, p);
    }
    const float eye[3] = {(float)p[0], (float)p[1], (float)p[2]};
    const float target[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    /* Cannot fail: eye is 4 units from the target and never straight
     * above it (elevation stays below 90 degrees). */
    nerf_camera_look_at(cam, eye, target, up);
}

nerf__scene_look nerf__scene_look_of(const nerf_scene_options *o)
{
    const int textured = o->texture ? NERF__SCENE_TEXTURED : 0;
    if (o->capture == NERF_SCENE_CAPTURE_OBJECT) {
        return (nerf__scene_look){
            (nerf__scene_world)(NERF__SCENE_SOLIDS | textured), NEAR, FAR, 4};
    }
    /* Nothing stands within a unit of a camera: start at it. */
    return (nerf__scene_look){
        (nerf__scene_world)(NERF__SCENE_SURROUNDED | textured), 0.0f,
        NERF__SCENE_WORLD_FAR, 3};
}

typedef struct view_job {
    const nerf_camera *cam;
    const nerf__scene_look *look;
    uint8_t *px;
    float *zdepth;
    uint32_t row_begin, row_end;
} view_job;

static uint8_t to8(float v)
{
    return (uint8_t)lrintf((v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v) * 255.0f);
}

static void *render_rows(void *arg)
{
    enum { BLOCK = 256 };
    view_job *job = arg;
    const uint32_t w = job->cam->width;
    size_t first = (size_t)job->row_begin * w, last = (size_t)job->row_end * w;
    float o[BLOCK * 3], d[BLOCK * 3];
    for (size_t at = first; at < last; at += BLOCK) {
        size_t n = last - at < BLOCK ? last - at : BLOCK;
        nerf__camera_rays(job->cam, at, n, o, d);
        for (size_t k = 0; k < n; k++) {
            const nerf__scene_look *look = job->look;
            float rgb[3], depth;
            float a = nerf__scene_render_ray_in(look->world, o + 3 * k,
                                                d + 3 * k, look->near,
                                                look->far, rgb, &depth);
            uint8_t *px = job->px + look->channels * (at + k);
            if (look->channels == 4) {
                /* Store straight (not premultiplied) colour with alpha, as
                 * Blender does: compositing rgb*a + (1-a) gives back the
                 * rendered colour on white. */
                for (int c = 0; c < 3; c++) {
                    px[c] = to8(a > 1e-6f ? rgb[c] / a : 0.0f);
                }
                px[3] = to8(a);
            } else {
                /* Opaque to 1e-6: what is left shows black, as in a
                 * photograph. */
                for (int c = 0; c < 3; c++) {
                    px[c] = to8(rgb[c]);
                }
            }
            if (job->zdepth) {
                /* Camera rays have z = -1 in the camera's frame, so t is
                 * the depth along the optical axis. */
                job->zdepth[at + k] = a > 1e-6f ? depth / a : look->far;
            }
        }
    }
    return NULL;
}

void nerf__scene_render_view(const nerf_camera *cam,
                             const nerf__scene_look *look, uint32_t threads,
                             uint8_t *px, float *zdepth)
{
    enum { MAX_THREADS = 64 };
    pthread_t tid[MAX_THREADS];
    view_job jobs[MAX_THREADS];
    bool started[MAX_THREADS] = {false};
    uint32_t t = threads < MAX_THREADS ? threads : MAX_THREADS;
    for (uint32_t k = 0; k < t; k++) {
        uint32_t h = cam->height;
        jobs[k] = (view_job){cam, look, px, zdepth, h * k / t,
                             h * (k + 1) / t};
    }
    for (uint32_t k = 1; k < t; k++) {
        started[k] = pthread_create(&tid[k], NULL, render_rows, &jobs[k]) == 0;
        if (!started[k]) {
            render_rows(&jobs[k]); /* no thread to be had: do it here */
        }
    }
    render_rows(&jobs[0]);
    for (uint32_t k = 1; k < t; k++) {
        if (started[k]) {
            pthread_join(tid[k], NULL);
        }
    }
}

int nerf__scene_make_dir(const char *path)
{
    char buf[4096];
    size_t n = strlen(path);
    if (n == 0 || n >= sizeof buf) {
        return nerf__error(NERF_EINVAL, "nerf_scene_write: bad folder path");
    }
    memcpy(buf, path, n + 1);
    for (size_t i = 1; i <= n; i++) {
        if (buf[i] != '/' && buf[i] != '\0') {
            continue;
        }
        char keep = buf[i];
        buf[i] = '\0';
        if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
            return nerf__error(NERF_EIO, "%s: cannot create directory: %s",
                               buf, strerror(errno));
        }
        buf[i] = keep;
    }
    return NERF_OK;
}

const char *const nerf__scene_split_names[3] = {"train", "val", "test"};

cJSON *nerf__scene_matrix_json(const float c2w[12])
{
    cJSON *rows = cJSON_CreateArray();
    for (int r = 0; r < 4; r++) {
        double v[4] = {0, 0, 0, 1};
        for (int c = 0; r < 3 && c < 4; c++) {
            v[c] = c2w[4 * r + c];
        }
        cJSON_AddItemToArray(rows, cJSON_CreateDoubleArray(v, 4));
    }
    return rows;
}

/* Camera i of n of a split of the options' capture, pinhole. */
static void capture_pose(const nerf_scene_options *o, int split, uint32_t i,
                         uint32_t n, nerf_camera *cam)
{
    if (o->capture == NERF_SCENE_CAPTURE_FORWARD) {
        nerf__scene_forward_camera(o, split, i, n, cam);
        return;
    }
    if (o->capture == NERF_SCENE_CAPTURE_UNBOUNDED) {
        nerf__scene_unbounded_camera(o, split, i, n, cam);
        return;
    }
    if (o->capture == NERF_SCENE_CAPTURE_WALK) {
        nerf__scene_walk_camera(o, split, i, n, cam);
        return;
    }
    NERF_CAMERA_INIT(cam);
    cam->width = o->width;
    cam->height = o->height;
    cam->fx = cam->fy = (float)(0.5 * o->width /
                                tan(0.5 * NERF__SCENE_CAMERA_ANGLE_X));
    cam->cx = 0.5f * (float)o->width;
    cam->cy = 0.5f * (float)o->height;
    place_camera(split, i, n, o->seed, cam);
}

void nerf__scene_capture_camera(const nerf_scene_options *o, int split,
                                uint32_t i, uint32_t n, nerf_camera *cam)
{
    capture_pose(o, split, i, n, cam);
    /* The lens the options photograph through. */
    cam->k1 = o->k1;
    cam->k2 = o->k2;
    cam->p1 = o->p1;
    cam->p2 = o->p2;
    cam->k3 = o->k3;
}

void nerf__scene_lens_json(cJSON *obj, const nerf_scene_options *o,
                           bool always)
{
    static const char *const names[5] = {"k1", "k2", "p1", "p2", "k3"};
    const float k[5] = {o->k1, o->k2, o->p1, o->p2, o->k3};
    bool any = false;
    for (int i = 0; i < 5; i++) {
        any = any || k[i] != 0.0f;
    }
    for (int i = 0; i < 5 && (any || always); i++) {
        cJSON_AddNumberToObject(obj, names[i], (double)k[i]);
    }
}

int nerf__scene_write_json(const nerf__env *env, const char *path,
                           const cJSON *root)
{
    char *text = cJSON_Print(root);
    nerf__span part = {text, text ? strlen(text) : 0};
    int rc = text ? nerf__file_write_atomic(env, path, &part, 1)
                  : nerf__error(NERF_ENOMEM, "%s: out of memory", path);
    cJSON_free(text);
    return rc;
}

static int write_split(const char *dir, int split, uint32_t n,
                       const nerf_scene_options *o, const nerf__env *env,
                       uint8_t *px, uint8_t *mask)
{
    const char *const *names = nerf__scene_split_names;
    const nerf__scene_look look = nerf__scene_look_of(o);
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, names[split]);
    int rc = nerf__scene_make_dir(path);
    cJSON *root = cJSON_CreateObject();
    cJSON *frames = cJSON_CreateArray();
    if (root == NULL || frames == NULL) {
        cJSON_Delete(root);
        cJSON_Delete(frames);
        return nerf__error(NERF_ENOMEM, "%s: out of memory building JSON", dir);
    }
    cJSON_AddNumberToObject(root, "camera_angle_x",
                            o->capture == NERF_SCENE_CAPTURE_OBJECT
                                ? NERF__SCENE_CAMERA_ANGLE_X
                                : NERF__SCENE_WIDE_ANGLE_X);
    /* Only with a lens, so that a pinhole scene's files stay as they
     * were. */
    nerf__scene_lens_json(root, o, false);
    if (o->capture == NERF_SCENE_CAPTURE_UNBOUNDED ||
        o->capture == NERF_SCENE_CAPTURE_WALK) {
        /*
         * instant-ngp's hint that the scene reaches far beyond the unit
         * box: 16 is the largest power of two its grids cascade to that
         * keeps the backdrop (radius 40 units) mostly inside.
         */
        cJSON_AddNumberToObject(root, "aabb_scale", AABB_SCALE);
    }
    cJSON_AddItemToObject(root, "frames", frames);
    for (uint32_t i = 0; i < n && rc == NERF_OK; i++) {
        nerf_camera cam;
        nerf__scene_capture_camera(o, split, i, n, &cam);
        nerf__scene_render_view(&cam, &look, o->threads, px, NULL);
        nerf__scene_vary_view(o, split, i, look.channels, px);
        const bool occluded = nerf__scene_occluded(o, split, i);
        if (occluded) {
            nerf__scene_paint_occluder(o, i, look.channels, px, mask);
        }
        snprintf(path, sizeof path, "%s/%s/r_%u", dir, names[split], i);
        rc = nerf__scene_image_write(env, path, o, look.channels, px);
        cJSON *frame = cJSON_CreateObject();
        char file[64];
        snprintf(file, sizeof file, "./%s/r_%u%s", names[split], i,
                 nerf__scene_image_suffix(o));
        cJSON_AddStringToObject(frame, "file_path", file);
        if (occluded && rc == NERF_OK) {
            snprintf(path, sizeof path, "%s/%s/masks", dir, names[split]);
            rc = nerf__scene_make_dir(path);
            snprintf(file, sizeof file, "./%s/masks/r_%u.png", names[split],
                     i);
            snprintf(path, sizeof path, "%s/%s", dir, file + 2);
            rc = rc == NERF_OK ? nerf__scene_mask_write(env, path, o, mask)
                               : rc;
            cJSON_AddStringToObject(frame, "mask_path", file);
        }
        cJSON_AddItemToObject(frame, "transform_matrix",
                              nerf__scene_matrix_json(cam.c2w));
        cJSON_AddItemToArray(frames, frame);
    }
    if (rc == NERF_OK) {
        snprintf(path, sizeof path, "%s/transforms_%s.json", dir, names[split]);
        rc = nerf__scene_write_json(env, path, root);
    }
    cJSON_Delete(root);
    nerf__log(env, NERF_LOG_INFO, "scene: wrote %u %s views of %ux%u to %s", n,
              names[split], o->width, o->height, dir);
    return rc;
}

/* The capture and layout: known, implemented here, and fitting each other. */
static int check_capture(const nerf_scene_options *o)
{
    static const char *const captures[] = {"object", "forward", "unbounded",
                                           "walk"};
    if (o->capture > NERF_SCENE_CAPTURE_WALK) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: capture %u is "
                           "unknown (0 object, 1 forward, 2 unbounded, "
                           "3 walk)", (unsigned)o->capture);
    }
    if (o->texture > 1) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: texture %u is "
                           "not 0 or 1", (unsigned)o->texture);
    }
    if (o->reserved1 != 0) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: reserved1 "
                           "must be 0");
    }
    if (o->layout > NERF_SCENE_LAYOUT_COLMAP_BINARY) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: layout %u is "
                           "unknown (0 blender, 1 transforms, 2 llff, "
                           "3 colmap text, 4 colmap binary)",
                           (unsigned)o->layout);
    }
    const bool lens = o->k1 != 0.0f || o->k2 != 0.0f || o->p1 != 0.0f ||
                      o->p2 != 0.0f || o->k3 != 0.0f;
    if (lens && o->layout == NERF_SCENE_LAYOUT_LLFF) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: the LLFF layout "
                           "(poses_bounds.npy) has no lens fields");
    }
    if (o->k3 != 0.0f && o->layout >= NERF_SCENE_LAYOUT_COLMAP_TEXT) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: COLMAP's OPENCV "
                           "camera model has no k3");
    }
    /* LLFF's loaders warp every ray to NDC, which only a forward-facing
     * capture fits. */
    if (o->layout == NERF_SCENE_LAYOUT_LLFF &&
        o->capture != NERF_SCENE_CAPTURE_FORWARD) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: the LLFF layout "
                           "holds forward-facing captures only, not the %s "
                           "capture", captures[o->capture]);
    }
    return NERF_OK;
}

NERF_API int nerf_scene_write(const char *dir, const nerf_scene_options *opts)
{
    nerf_scene_options o;
    scene_defaults(&o);
    if (dir == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_scene_write: dir is NULL");
    }
    int rc = nerf__options_read(&o, sizeof o, opts, "nerf_scene_options");
    if (rc != NERF_OK) {
        return rc;
    }
    if (o.width < NERF_SCENE_MIN_SIDE || o.height < NERF_SCENE_MIN_SIDE ||
        o.width > NERF_SCENE_MAX_SIDE || o.height > NERF_SCENE_MAX_SIDE) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: image size "
                           "%ux%u is outside %d..%d", o.width, o.height,
                           NERF_SCENE_MIN_SIDE, NERF_SCENE_MAX_SIDE);
    }
    if (o.n_train < 1 || o.n_train > NERF_SCENE_MAX_VIEWS ||
        o.n_val > NERF_SCENE_MAX_VIEWS || o.n_test > NERF_SCENE_MAX_VIEWS) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: view counts must "
                           "be 1..%d (train) and 0..%d (val, test)",
                           NERF_SCENE_MAX_VIEWS, NERF_SCENE_MAX_VIEWS);
    }
    if (o.appearance > NERF_SCENE_APPEARANCE_VARIED) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: appearance %u "
                           "is unknown (0 constant, 1 varied)",
                           (unsigned)o.appearance);
    }
    if (o.appearance == NERF_SCENE_APPEARANCE_VARIED &&
        o.layout != NERF_SCENE_LAYOUT_BLENDER) {
        /* The other layouts' loaders choose the held-out views, which
         * must keep the scene's own look. */
        return nerf__error(NERF_EINVAL, "nerf_scene_options: appearance "
                           "changes need the Blender layout, whose test "
                           "views the writer knows");
    }
    if (o.occluders > 1) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: occluders must "
                           "be 0 or 1");
    }
    if (o.occluders && o.layout == NERF_SCENE_LAYOUT_LLFF) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: occluders are "
                           "written for the Blender, transforms and COLMAP "
                           "layouts, not LLFF");
    }
    rc = check_capture(&o);
    rc = rc == NERF_OK ? nerf__scene_image_check(&o) : rc;
    if (rc != NERF_OK) {
        return rc;
    }
    const double lens[5] = {o.k1, o.k2, o.p1, o.p2, o.k3};
    char text[96];
    const char *why = nerf__lens_problem(lens, text, sizeof text);
    if (why != NULL) {
        return nerf__error(NERF_EINVAL, "nerf_scene_options: %s", why);
    }
    if (o.threads == 0) {
        o.threads = nerf__cpu_count();
    }
    nerf__env env;
    rc = nerf__env_from_hooks(&env, o.hooks);
    if (rc != NERF_OK) {
        return rc;
    }
    rc = nerf__scene_make_dir(dir);
    uint8_t *px = rc == NERF_OK
                      ? nerf__alloc(&env, (size_t)o.width * o.height * 4)
                      : NULL;
    uint8_t *mask = rc == NERF_OK && o.occluders
                        ? nerf__alloc(&env, (size_t)o.width * o.height)
                        : NULL;
    if (rc == NERF_OK && (px == NULL || (o.occluders && mask == NULL))) {
        rc = NERF_ENOMEM;
    }
    if (rc == NERF_OK && o.layout == NERF_SCENE_LAYOUT_TRANSFORMS) {
        rc = nerf__scene_write_transforms(dir, &o, &env, px);
    }
    if (rc == NERF_OK && o.layout == NERF_SCENE_LAYOUT_LLFF) {
        rc = nerf__scene_write_llff(dir, &o, &env, px);
    }
    if (rc == NERF_OK && (o.layout == NERF_SCENE_LAYOUT_COLMAP_TEXT ||
                          o.layout == NERF_SCENE_LAYOUT_COLMAP_BINARY)) {
        rc = nerf__scene_write_colmap(dir, &o, &env, px);
    }
    const uint32_t counts[3] = {o.n_train, o.n_val, o.n_test};
    for (int split = 0; split < 3 && rc == NERF_OK &&
                        o.layout == NERF_SCENE_LAYOUT_BLENDER;
         split++) {
        rc = write_split(dir, split, counts[split], &o, &env, px, mask);
    }
    nerf__free(&env, px);
    nerf__free(&env, mask);
    return rc;
}
