/*
 * Camera paths: the poses to render, read from a NumPy array of matrices
 * or from a transforms-style JSON file (parsed by the same code as the
 * Blender dataset loader, so both accept the same files).
 */
#include <cJSON.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "camera.h"
#include "env.h"
#include "error.h"
#include "file_io.h"
#include "npy.h"
#include "options.h"
#include "transforms.h"

/* Far more frames than any render path; stops a bogus file from driving
 * allocation. */
#define MAX_POSES 100000u
#define MAX_SIDE 65536u
#define MAX_BYTES (64u << 20)
#define PI_D 3.14159265358979323846

struct nerf_camera_path {
    nerf__env env;
    uint32_t count;
    nerf_camera *cameras; /* count, full size */
};

/* Everything one load needs, so that the helpers take one pointer. */
typedef struct path_ctx {
    nerf_camera_path *cp;
    const char *path;
    const char *unit; /* "pose" (npy) or "frame" (JSON), for messages */
    nerf_camera_path_options o;
} path_ctx;

static void camera_path_defaults(nerf_camera_path_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
}

NERF_API int nerf_camera_path_options_init(nerf_camera_path_options *opts,
                                           size_t struct_size)
{
    nerf_camera_path_options d;
    camera_path_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_camera_path_options");
}

static int read_options(nerf_camera_path_options *o,
                        const nerf_camera_path_options *in)
{
    camera_path_defaults(o);
    if (in == NULL) {
        return NERF_OK;
    }
    int rc = nerf__options_read(o, sizeof *o, in, "nerf_camera_path_options");
    if (rc != NERF_OK) {
        return rc;
    }
    const char *what = NULL;
    if ((o->width == 0) != (o->height == 0)) {
        what = "set width and height together, or leave both 0";
    } else if (o->width > MAX_SIDE || o->height > MAX_SIDE) {
        what = "width and height must be at most 65536";
    } else if (o->flags & ~(NERF_CAMERA_PATH_FILE_SIZE |
                            NERF_CAMERA_PATH_FILE_INTRINSICS)) {
        what = "unknown flags";
    } else if (!(isfinite(o->focal) && o->focal >= 0.0f)) {
        what = "focal must be positive (or 0 for none)";
    } else if (!(isfinite(o->fov_x) && o->fov_x >= 0.0f &&
                 o->fov_x < 180.0f)) {
        what = "fov_x must be in (0, 180) degrees (or 0 for none)";
    } else if (o->focal > 0.0f && o->fov_x > 0.0f) {
        what = "set focal or fov_x, not both";
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "nerf_camera_path_options: %s", what);
    }
    return NERF_OK;
}

/* The file's image size of a frame, if it gives one: *w = *h = 0 if not. */
static int file_size(const path_ctx *c, const char *name,
                     const nerf__intrinsics *in, uint32_t *w, uint32_t *h)
{
    *w = *h = 0;
    if (in == NULL || (isnan(in->w) && isnan(in->h))) {
        return NERF_OK;
    }
    if (isnan(in->w) || isnan(in->h)) {
        return nerf__error(NERF_EFORMAT, "%s: %s: gives %s but not %s",
                           c->path, name, isnan(in->w) ? "h" : "w",
                           isnan(in->w) ? "w" : "h");
    }
    double v[2] = {in->w, in->h};
    for (int i = 0; i < 2; i++) {
        if (!(v[i] >= 1.0 && v[i] <= MAX_SIDE && v[i] == floor(v[i]))) {
            return nerf__error(NERF_EFORMAT, "%s: %s: %c %g is not a "
                               "whole number of pixels in 1..65536", c->path,
                               name, i ? 'h' : 'w', v[i]);
        }
    }
    *w = (uint32_t)in->w;
    *h = (uint32_t)in->h;
    return NERF_OK;
}

/* The options' intrinsics, when they give any: {fx, fy, cx, cy}. */
static bool option_focal(const path_ctx *c, uint32_t w, uint32_t h,
                         double k[4])
{
    double f = c->o.focal;
    if (c->o.fov_x > 0.0f) {
        f = 0.5 * w / tan(0.5 * c->o.fov_x * PI_D / 180.0);
    }
    k[0] = k[1] = f;
    k[2] = 0.5 * w;
    k[3] = 0.5 * h;
    return f > 0.0;
}

/*
 * Camera `name` from its pose and, for a JSON frame, its intrinsics (NULL for
 * a .npy pose, which has none).
 */
static int make_camera(const path_ctx *c, const char *name, const double *c2w,
                       const nerf__intrinsics *in, nerf_camera *cam)
{
    uint32_t fw, fh;
    int rc = file_size(c, name, in, &fw, &fh);
    if (rc != NERF_OK) {
        return rc;
    }
    bool keep_file = fw > 0 && (c->o.width == 0 ||
                                (c->o.flags & NERF_CAMERA_PATH_FILE_SIZE));
    uint32_t w = keep_file ? fw : c->o.width;
    uint32_t h = keep_file ? fh : c->o.height;
    if (w == 0 && in == NULL) {
        return nerf__error(NERF_EINVAL, "%s: a .npy camera path holds no "
                           "image size: set width and height", c->path);
    }
    if (w == 0) {
        return nerf__error(NERF_EINVAL, "%s: %s: the file gives no image "
                           "size (w, h): set width and height", c->path,
                           name);
    }
    double k[4];
    bool file_focal = in && (!isnan(in->fl_x) || !isnan(in->angle_x));
    bool file_first = c->o.flags & NERF_CAMERA_PATH_FILE_INTRINSICS;
    if (!option_focal(c, w, h, k) || (file_focal && file_first)) {
        if (in == NULL) {
            return nerf__error(NERF_EINVAL, "%s: a .npy camera path holds no "
                               "intrinsics: set focal or fov_x", c->path);
        }
        /* The file's intrinsics are in pixels of its own image size when
         * it gives one; rescaling them keeps the field of view. */
        double rw = fw > 0 ? fw : w, rh = fh > 0 ? fh : h;
        rc = nerf__transforms_focal(c->path, name, in, rw, rh, k);
        if (rc != NERF_OK) {
            return rc;
        }
        k[0] *= w / rw;
        k[2] *= w / rw;
        k[1] *= h / rh;
        k[3] *= h / rh;
    }
    nerf_camera_init(cam, sizeof *cam);
    cam->width = w;
    cam->height = h;
    bool fits = true;
    for (int i = 0; i < 12; i++) {
        cam->c2w[i] = (float)c2w[i];
        fits = fits && isfinite(cam->c2w[i]);
    }
    if (!fits) {
        return nerf__error(NERF_EFORMAT, "%s: %s: the matrix has a value "
                           "beyond the range of float", c->path, name);
    }
    cam->fx = (float)k[0];
    cam->fy = (float)k[1];
    cam->cx = (float)k[2];
    cam->cy = (float)k[3];
    if (!(isfinite(cam->fx) && cam->fx > 0.0f && isfinite(cam->fy) &&
          cam->fy > 0.0f && isfinite(cam->cx) && isfinite(cam->cy))) {
        return nerf__error(NERF_EFORMAT, "%s: %s: focal %g x %g or "
                           "principal point (%g, %g) out of range", c->path,
                           name, k[0], k[1], k[2], k[3]);
    }
    return NERF_OK;
}

static int reserve(path_ctx *c, size_t n)
{
    if (n == 0) {
        return nerf__error(NERF_EFORMAT, "%s: the file holds no %ss", c->path,
                           c->unit);
    }
    if (n > MAX_POSES) {
        return nerf__error(NERF_EFORMAT, "%s: %zu %ss are more than the %u "
                           "allowed", c->path, n, c->unit, MAX_POSES);
    }
    c->cp->cameras = nerf__calloc(&c->cp->env, n, sizeof *c->cp->cameras);
    return c->cp->cameras ? NERF_OK : NERF_ENOMEM;
}

static int load_npy(path_ctx *c, const unsigned char *buf, size_t size)
{
    nerf__env *env = &c->cp->env;
    c->unit = "pose";
    nerf__npy a;
    int rc = nerf__npy_parse(buf, size, &a);
    if (rc != NERF_OK) {
        return nerf__error_prefix(rc, c->path);
    }
    if (a.fortran_order) {
        return nerf__error(NERF_EFORMAT, "%s: data is in Fortran order "
                           "(expected C order)", c->path);
    }
    bool matrices = a.ndim == 3 && (a.shape[1] == 3 || a.shape[1] == 4) &&
                    a.shape[2] == 4;
    bool flat = a.ndim == 2 && (a.shape[1] == 12 || a.shape[1] == 16);
    if (!matrices && !flat) {
        char shape[64];
        nerf__npy_format_shape(a.shape, a.ndim, shape, sizeof shape);
        return nerf__error(NERF_EFORMAT, "%s: shape is %s (expected (N, 3, "
                           "4), (N, 4, 4), (N, 12) or (N, 16))", c->path,
                           shape);
    }
    size_t n = a.shape[0];
    size_t per = n ? a.count / n : 0; /* 12 or 16 values a pose */
    rc = reserve(c, n);
    double *v = rc == NERF_OK ? nerf__calloc(env, a.count, sizeof *v) : NULL;
    if (rc == NERF_OK && v == NULL) {
        rc = NERF_ENOMEM;
    }
    if (rc == NERF_OK) {
        nerf__npy_to_double(&a, v, a.count);
    }
    for (size_t i = 0; i < n && rc == NERF_OK; i++) {
        const double *m = v + i * per;
        char text[160], name[32];
        const char *why = nerf__pose_problem(m, per == 16 ? m + 12 : NULL,
                                             text, sizeof text);
        snprintf(name, sizeof name, "pose %zu", i);
        if (why != NULL) {
            rc = nerf__error(NERF_EFORMAT, "%s: %s %s", c->path, name, why);
        } else {
            rc = make_camera(c, name, m, NULL, &c->cp->cameras[i]);
        }
    }
    if (rc == NERF_OK) {
        c->cp->count = (uint32_t)n;
    }
    nerf__free(env, v);
    return rc;
}

static int load_json(path_ctx *c, const unsigned char *buf, size_t size)
{
    c->unit = "frame";
    cJSON *root = NULL;
    const cJSON *frames = NULL;
    nerf__intrinsics top;
    int rc = nerf__transforms_parse_text(c->path, buf, size, &root);
    if (rc == NERF_OK) {
        double aabb_scale; /* checked as the loader does, not used */
        rc = nerf__transforms_top(c->path, root, &top, &frames, &aabb_scale);
    }
    if (rc == NERF_OK) {
        rc = reserve(c, (size_t)cJSON_GetArraySize(frames));
    }
    uint32_t idx = 0;
    for (const cJSON *fr = frames ? frames->child : NULL;
         fr && rc == NERF_OK; fr = fr->next, idx++) {
        char name[224], where[256];
        nerf__transforms_frame_name(fr, idx, name, sizeof name);
        snprintf(where, sizeof where, "%s: ", name);
        nerf__intrinsics in = top;
        double c2w[12];
        rc = cJSON_IsObject(fr) ? NERF_OK
             : nerf__error(NERF_EFORMAT, "%s: %snot a JSON object", c->path,
                           where);
        if (rc == NERF_OK) {
            rc = nerf__transforms_read_intrinsics(c->path, fr, where, &in);
        }
        if (rc == NERF_OK) {
            rc = nerf__transforms_read_matrix(c->path, fr, name, c2w);
        }
        if (rc == NERF_OK) {
            rc = make_camera(c, name, c2w, &in, &c->cp->cameras[idx]);
        }
    }
    if (rc == NERF_OK) {
        c->cp->count = idx;
    }
    cJSON_Delete(root);
    return rc;
}

static bool has_npy_name(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && strcmp(path + n - 4, ".npy") == 0;
}

static int load(path_ctx *c)
{
    nerf__env *env = &c->cp->env;
    unsigned char *buf;
    size_t size;
    int rc = nerf__file_read(env, c->path, MAX_BYTES, &buf, &size);
    if (rc != NERF_OK) {
        return rc;
    }
    static const char magic[] = "\x93NUMPY";
    bool npy = (size >= sizeof magic - 1 &&
                memcmp(buf, magic, sizeof magic - 1) == 0) ||
               has_npy_name(c->path);
    rc = npy ? load_npy(c, buf, size) : load_json(c, buf, size);
    nerf__free(env, buf);
    if (rc == NERF_OK) {
        const nerf_camera *cam = &c->cp->cameras[0];
        nerf__log(env, NERF_LOG_INFO, "%s: camera path of %u %s%s (%s), "
                  "first %ux%u with focal %.3f x %.3f", c->path,
                  (unsigned)c->cp->count, c->unit,
                  c->cp->count == 1 ? "" : "s", npy ? "npy" : "JSON",
                  (unsigned)cam->width, (unsigned)cam->height, cam->fx,
                  cam->fy);
    }
    return rc;
}

NERF_API int nerf_camera_path_load(nerf_camera_path **out, const char *path,
                                   const nerf_camera_path_options *opts)
{
    if (out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_camera_path_load: out is NULL");
    }
    *out = NULL;
    if (path == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_camera_path_load: path is "
                           "NULL");
    }
    path_ctx c = {NULL, path, "pose", {0}};
    nerf__env env;
    int rc = read_options(&c.o, opts);
    if (rc == NERF_OK) {
        rc = nerf__env_from_hooks(&env, c.o.hooks);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    c.cp = nerf__calloc(&env, 1, sizeof *c.cp);
    if (c.cp == NULL) {
        return NERF_ENOMEM;
    }
    c.cp->env = env;
    rc = load(&c);
    if (rc != NERF_OK) {
        nerf_camera_path_destroy(c.cp);
        return rc;
    }
    *out = c.cp;
    return NERF_OK;
}

NERF_API void nerf_camera_path_destroy(nerf_camera_path *camera_path)
{
    if (camera_path == NULL) {
        return;
    }
    nerf__env env = camera_path->env;
    nerf__free(&env, camera_path->cameras);
    nerf__free(&env, camera_path);
}

NERF_API uint32_t nerf_camera_path_count(const nerf_camera_path *camera_path)
{
    return camera_path ? camera_path->count : 0;
}

NERF_API int nerf_camera_path_camera(const nerf_camera_path *camera_path,
                                     uint32_t index, nerf_camera *out)
{
    const char *fn = "nerf_camera_path_camera";
    if (camera_path == NULL || out == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL argument", fn);
    }
    if (index >= camera_path->count) {
        return nerf__error(NERF_EINVAL, "%s: index %u is out of range (the "
                           "path has %u cameras)", fn, (unsigned)index,
                           (unsigned)camera_path->count);
    }
    return nerf__camera_write(out, &camera_path->cameras[index], fn);
}
