#include "transforms.h"

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "distortion.h"
#include "error.h"
#include "file_io.h"

#define PI_D 3.14159265358979323846

void nerf__intrinsics_none(nerf__intrinsics *in)
{
    in->angle_x = in->angle_y = in->fl_x = in->fl_y = NAN;
    in->cx = in->cy = in->w = in->h = NAN;
    in->k1 = in->k2 = in->p1 = in->p2 = in->k3 = 0.0;
}

int nerf__transforms_parse_text(const char *path, const unsigned char *text,
                                size_t size, cJSON **root_out)
{
    const char *end = NULL;
    *root_out = cJSON_ParseWithLengthOpts((const char *)text, size, &end, 0);
    if (*root_out == NULL) {
        size_t pos = end ? (size_t)(end - (const char *)text) : 0;
        size_t line = 1;
        for (size_t i = 0; i < pos && i < size; i++) {
            line += text[i] == '\n';
        }
        return nerf__error(NERF_EFORMAT, "%s: invalid JSON at line %zu (byte "
                           "%zu)", path, line, pos);
    }
    return NERF_OK;
}

int nerf__transforms_parse(const nerf__env *env, const char *path,
                           cJSON **root_out)
{
    *root_out = NULL;
    unsigned char *text;
    size_t size;
    int rc = nerf__file_read(env, path, NERF__TRANSFORMS_MAX_BYTES, &text,
                             &size);
    if (rc == NERF_OK) {
        rc = nerf__transforms_parse_text(path, text, size, root_out);
        nerf__free(env, text);
    }
    return rc;
}

/* Read key as a finite number into *out when present. */
static int get_number(const char *path, const cJSON *obj, const char *key,
                      const char *where, double *out)
{
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (item == NULL) {
        return NERF_OK;
    }
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble)) {
        return nerf__error(NERF_EFORMAT, "%s: %sfield '%s' is not a finite "
                           "number", path, where, key);
    }
    *out = item->valuedouble;
    return NERF_OK;
}

void nerf__transforms_frame_name(const cJSON *frame, uint32_t idx, char *buf,
                                 size_t size)
{
    const cJSON *fp = cJSON_IsObject(frame)
                          ? cJSON_GetObjectItemCaseSensitive(frame, "file_path")
                          : NULL;
    if (cJSON_IsString(fp) && fp->valuestring[0] != '\0') {
        snprintf(buf, size, "frame %u (%.200s)", (unsigned)idx,
                 fp->valuestring);
    } else {
        snprintf(buf, size, "frame %u", (unsigned)idx);
    }
}

/* The intrinsics obj gave, against the limits of transforms.h. */
static int check_intrinsics(const char *path, const char *where,
                            const nerf__intrinsics *in)
{
    const double angles[2] = {in->angle_x, in->angle_y};
    for (int i = 0; i < 2; i++) {
        if (!isnan(angles[i]) && !(angles[i] > 0.0 && angles[i] < PI_D)) {
            return nerf__error(NERF_EFORMAT, "%s: %scamera_angle_%c %g is not "
                               "in (0, pi)", path, where, i ? 'y' : 'x',
                               angles[i]);
        }
    }
    const double focals[2] = {in->fl_x, in->fl_y};
    for (int i = 0; i < 2; i++) {
        if (!isnan(focals[i]) && !(focals[i] >= NERF__FOCAL_MIN &&
                                   focals[i] <= NERF__CAMERA_MAX_ABS)) {
            return nerf__error(NERF_EFORMAT, "%s: %sfocal length must be "
                               "positive, within [%g, %g] pixels (fl_%c %g)",
                               path, where, NERF__FOCAL_MIN,
                               NERF__CAMERA_MAX_ABS, i ? 'y' : 'x',
                               focals[i]);
        }
    }
    const double centre[2] = {in->cx, in->cy};
    for (int i = 0; i < 2; i++) {
        if (!isnan(centre[i]) && !(fabs(centre[i]) <= NERF__CAMERA_MAX_ABS)) {
            return nerf__error(NERF_EFORMAT, "%s: %sc%c %g is beyond +-%g",
                               path, where, i ? 'y' : 'x', centre[i],
                               NERF__CAMERA_MAX_ABS);
        }
    }
    const double k[5] = {in->k1, in->k2, in->p1, in->p2, in->k3};
    char text[96];
    const char *why = nerf__lens_problem(k, text, sizeof text);
    if (why != NULL) {
        return nerf__error(NERF_EFORMAT, "%s: %s%s", path, where, why);
    }
    return NERF_OK;
}

/*
 * Lens models other than nerf_camera's: a fisheye is another function of
 * the angle, and OpenCV's rational model divides by a polynomial, so
 * reading their files as our model would give wrong rays without a word.
 */
static int check_lens_model(const char *path, const cJSON *obj,
                            const char *where)
{
    static const char *const higher[] = {"k4", "k5", "k6"};
    for (size_t i = 0; i < sizeof higher / sizeof higher[0]; i++) {
        const cJSON *k = cJSON_GetObjectItemCaseSensitive(obj, higher[i]);
        if (k != NULL && !(cJSON_IsNumber(k) && k->valuedouble == 0.0)) {
            return nerf__error(NERF_EFORMAT, "%s: %s'%s' (a fisheye or "
                               "rational lens model) is not supported: only "
                               "k1, k2, p1, p2, k3", path, where, higher[i]);
        }
    }
    const cJSON *fisheye = cJSON_GetObjectItemCaseSensitive(obj, "is_fisheye");
    const cJSON *model = cJSON_GetObjectItemCaseSensitive(obj,
                                                          "camera_model");
    bool bad_model = cJSON_IsString(model) &&
                     (strstr(model->valuestring, "FISHEYE") != NULL ||
                      strcmp(model->valuestring, "EQUIRECTANGULAR") == 0);
    if (cJSON_IsTrue(fisheye) || bad_model) {
        return nerf__error(NERF_EFORMAT, "%s: %s%s lens is not supported: "
                           "only OpenCV's k1, k2, p1, p2, k3 model", path,
                           where, bad_model ? model->valuestring
                                            : "a fisheye");
    }
    return NERF_OK;
}

int nerf__transforms_read_intrinsics(const char *path, const cJSON *obj,
                                     const char *where, nerf__intrinsics *in)
{
    int rc = check_lens_model(path, obj, where);
    static const char *const keys[] = {"camera_angle_x", "camera_angle_y",
                                       "fl_x", "fl_y", "cx", "cy", "w", "h",
                                       "k1", "k2", "p1", "p2", "k3"};
    double *fields[] = {&in->angle_x, &in->angle_y, &in->fl_x, &in->fl_y,
                        &in->cx, &in->cy, &in->w, &in->h,
                        &in->k1, &in->k2, &in->p1, &in->p2, &in->k3};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0] && rc == NERF_OK;
         i++) {
        rc = get_number(path, obj, keys[i], where, fields[i]);
    }
    return rc == NERF_OK ? check_intrinsics(path, where, in) : rc;
}

/* aabb_scale: instant-ngp's scene box, in units of the unit cube. */
static int read_aabb_scale(const char *path, const cJSON *root, double *out)
{
    double v = 1.0;
    int rc = get_number(path, root, "aabb_scale", "", &v);
    if (rc != NERF_OK) {
        return rc;
    }
    int e;
    /* A power of two is a mantissa of exactly one half. */
    if (!(v >= 1.0 && v <= NERF__AABB_SCALE_MAX && frexp(v, &e) == 0.5)) {
        return nerf__error(NERF_EFORMAT, "%s: aabb_scale %g is not a power "
                           "of two in 1..%d", path, v, NERF__AABB_SCALE_MAX);
    }
    *out = v;
    return NERF_OK;
}

int nerf__transforms_top(const char *path, const cJSON *root,
                         nerf__intrinsics *top, const cJSON **frames_out,
                         double *aabb_scale)
{
    if (!cJSON_IsObject(root)) {
        return nerf__error(NERF_EFORMAT, "%s: the top level is not a JSON "
                           "object", path);
    }
    nerf__intrinsics_none(top);
    int rc = nerf__transforms_read_intrinsics(path, root, "", top);
    if (rc == NERF_OK) {
        rc = read_aabb_scale(path, root, aabb_scale);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    if (!cJSON_IsArray(frames)) {
        return nerf__error(NERF_EFORMAT, "%s: %s 'frames'", path,
                           frames ? "not a list:" : "missing field");
    }
    *frames_out = frames;
    return NERF_OK;
}

static double det3(const double *m, size_t stride)
{
    const double *r0 = m, *r1 = m + stride, *r2 = m + 2 * stride;
    return r0[0] * (r1[1] * r2[2] - r1[2] * r2[1]) -
           r0[1] * (r1[0] * r2[2] - r1[2] * r2[0]) +
           r0[2] * (r1[0] * r2[1] - r1[1] * r2[0]);
}

const char *nerf__pose_problem(const double c2w[12], const double *last,
                               char *buf, size_t size)
{
    for (int k = 0; k < 16; k++) {
        if (!isfinite(k < 12 ? c2w[k] : last ? last[k - 12] : 0.0)) {
            return "has a NaN or infinite value";
        }
    }
    for (int k = 0; k < 12; k++) {
        if (!(fabs(c2w[k]) <= NERF__CAMERA_MAX_ABS)) {
            snprintf(buf, size, "has an entry of magnitude %g, beyond the "
                     "%g a pose may have", fabs(c2w[k]),
                     NERF__CAMERA_MAX_ABS);
            return buf;
        }
    }
    static const double homogeneous[4] = {0.0, 0.0, 0.0, 1.0};
    for (int c = 0; last != NULL && c < 4; c++) {
        /* Exported matrices carry float noise; anything more is not a
         * rigid pose. */
        if (!(fabs(last[c] - homogeneous[c]) <= 1e-4)) {
            return "has a last row other than [0, 0, 0, 1]";
        }
    }
    /* The rotation's columns turn pixel directions into rays: a column
     * of (nearly) no length, or three in (nearly) one plane, collapse
     * the image onto a line. */
    double product = 1.0;
    for (int c = 0; c < 3; c++) {
        double n = sqrt(c2w[c] * c2w[c] + c2w[4 + c] * c2w[4 + c] +
                        c2w[8 + c] * c2w[8 + c]);
        if (!(n >= NERF__POSE_MIN_COLUMN)) {
            snprintf(buf, size, "has a degenerate rotation (column %d has "
                     "length %g, under %g)", c, n, NERF__POSE_MIN_COLUMN);
            return buf;
        }
        product *= n;
    }
    if (!(fabs(det3(c2w, 4)) >= NERF__POSE_MIN_DET_RATIO * product)) {
        snprintf(buf, size, "has a degenerate rotation (its columns are "
                 "(nearly) in one plane: |det| %g for lengths whose product "
                 "is %g)", fabs(det3(c2w, 4)), product);
        return buf;
    }
    return NULL;
}

/* transform_matrix: 4 rows (or the top 3) of 4 finite numbers. */
int nerf__transforms_read_matrix(const char *path, const cJSON *frame,
                                 const char *name, double c2w[12])
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(frame,
                                                      "transform_matrix");
    if (m == NULL) {
        return nerf__error(NERF_EFORMAT, "%s: %s: missing field "
                           "'transform_matrix'", path, name);
    }
    int rows = cJSON_IsArray(m) ? cJSON_GetArraySize(m) : -1;
    if (rows != 3 && rows != 4) {
        return nerf__error(NERF_EFORMAT, "%s: %s: transform_matrix "
                           "must be a list of 4 rows of 4 numbers", path,
                           name);
    }
    double last[4] = {0.0, 0.0, 0.0, 1.0};
    for (int r = 0; r < rows; r++) {
        const cJSON *row = cJSON_GetArrayItem(m, r);
        if (!cJSON_IsArray(row) || cJSON_GetArraySize(row) != 4) {
            return nerf__error(NERF_EFORMAT, "%s: %s: transform_matrix "
                               "row %d is not a list of 4 numbers", path,
                               name, r);
        }
        for (int c = 0; c < 4; c++) {
            const cJSON *v = cJSON_GetArrayItem(row, c);
            if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) {
                return nerf__error(NERF_EFORMAT, "%s: %s: "
                                   "transform_matrix[%d][%d] is not a finite "
                                   "number", path, name, r, c);
            }
            double *dst = r < 3 ? &c2w[r * 4 + c] : &last[c];
            *dst = v->valuedouble;
        }
    }
    char text[160];
    const char *why = nerf__pose_problem(c2w, last, text, sizeof text);
    if (why != NULL) {
        return nerf__error(NERF_EFORMAT, "%s: %s: transform_matrix %s",
                           path, name, why);
    }
    return NERF_OK;
}

int nerf__transforms_focal(const char *path, const char *name,
                           const nerf__intrinsics *in, double w, double h,
                           double out[4])
{
    char where[256];
    snprintf(where, sizeof where, "%s: ", name);
    int rc = check_intrinsics(path, where, in);
    if (rc != NERF_OK) {
        return rc;
    }
    double fx, fy;
    if (!isnan(in->fl_x)) {
        fx = in->fl_x;
    } else if (!isnan(in->angle_x)) {
        fx = 0.5 * w / tan(0.5 * in->angle_x);
    } else {
        return nerf__error(NERF_EFORMAT, "%s: %s: missing field "
                           "'camera_angle_x' (or 'fl_x')", path, name);
    }
    if (!isnan(in->fl_y)) {
        fy = in->fl_y;
    } else if (!isnan(in->angle_y)) {
        fy = 0.5 * h / tan(0.5 * in->angle_y);
    } else {
        fy = fx;
    }
    /* Also from an angle: near pi, the focal goes to 0. */
    if (!(fx >= NERF__FOCAL_MIN && fx <= NERF__CAMERA_MAX_ABS) ||
        !(fy >= NERF__FOCAL_MIN && fy <= NERF__CAMERA_MAX_ABS)) {
        return nerf__error(NERF_EFORMAT, "%s: %s: focal length must be "
                           "positive, within [%g, %g] pixels (fx %g, fy %g)",
                           path, name, NERF__FOCAL_MIN, NERF__CAMERA_MAX_ABS,
                           fx, fy);
    }
    out[0] = fx;
    out[1] = fy;
    out[2] = isnan(in->cx) ? 0.5 * w : in->cx;
    out[3] = isnan(in->cy) ? 0.5 * h : in->cy;
    return NERF_OK;
}
