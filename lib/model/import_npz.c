/*
 * nerf_model_import_npz(): weights from the reference implementation's
 * PyTorch state dict, saved with numpy.savez as "coarse.<name>" and
 * "fine.<name>" arrays.  docs/formats.md lists the names and how they map
 * onto our layout; the one difference is that our head fuses the
 * reference's feature_linear (rows 0..width-1) and alpha_linear (row width)
 * into one layer.
 *
 * Without view directions the reference sizes output_linear at 5 rows
 * whenever it also has a fine network ("output_ch = 5 if N_importance > 0"),
 * and its renderer never reads the fifth output.  Such files are real, so
 * that one layer may carry one spare row, which is ignored.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "file_io.h"
#include "model.h"
#include "npy.h"
#include "zip_read.h"

/* A zip without zip64 cannot be larger. */
#define MAX_NPZ ((uint64_t)1 << 32)
/* Room for an .npy header around the data of a member. */
#define NPY_HEADER_ROOM 4096
#define MIN_MEMBER_LIMIT ((size_t)64 << 20)

/* An array to copy into the parameters: rows x cols, or a vector of rows
 * when cols is 0.  The file may hold up to `spare` more rows, ignored. */
typedef struct target {
    size_t offset, rows, cols, spare;
} target;

typedef struct npz_import {
    const nerf__env *env;
    const char *path;
    nerf__zip zip;
    bool *used;    /* per zip entry: claimed by a layer */
    float *params; /* the model's parameter array */
} npz_import;

/* Prefix the current message with the file and member names. */
static int member_error(const npz_import *c, const char *member, int rc)
{
    char where[768];
    snprintf(where, sizeof where, "%s: member '%s'", c->path, member);
    return nerf__error_prefix(rc, where);
}

static int shape_error(const npz_import *c, const char *member,
                       const nerf__npy *a, const target *t)
{
    size_t want[2] = {t->rows, t->cols};
    uint32_t ndim = t->cols ? 2 : 1;
    char expected[160], found[96];
    nerf__npy_format_shape(want, ndim, expected, sizeof expected);
    if (t->spare) {
        size_t at = strlen(expected);
        want[0] += t->spare;
        snprintf(expected + at, sizeof expected - at, " or ");
        at = strlen(expected);
        nerf__npy_format_shape(want, ndim, expected + at, sizeof expected - at);
    }
    nerf__npy_format_shape(a->shape, a->ndim, found, sizeof found);
    return nerf__error(NERF_EFORMAT, "%s: member '%s': expected shape %s, "
                       "found %s", c->path, member, expected, found);
}

/* C order and the target's shape. */
static int check_array(const npz_import *c, const char *member,
                       const nerf__npy *a, const target *t)
{
    if (a->fortran_order) {
        return nerf__error(NERF_EFORMAT, "%s: member '%s': fortran_order "
                           "arrays are not supported (save C-ordered "
                           "arrays)", c->path, member);
    }
    bool ok = a->ndim == (t->cols ? 2u : 1u) && a->shape[0] >= t->rows &&
              a->shape[0] <= t->rows + t->spare &&
              (a->ndim == 1 || a->shape[1] == t->cols);
    return ok ? NERF_OK : shape_error(c, member, a, t);
}

/* The first n elements are the target's: spare rows come last. */
static int convert(const npz_import *c, const char *member,
                   const nerf__npy *a, float *dst, size_t n)
{
    nerf__npy_to_float(a, dst, n);
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(dst[i])) {
            return nerf__error(NERF_EFORMAT, "%s: member '%s': element %zu "
                               "is not a finite float", c->path, member, i);
        }
    }
    return NERF_OK;
}

/* Copy the array "<name>.npy" into the parameters. */
static int import_array(npz_import *c, const char *name, const target *t)
{
    char member[160];
    snprintf(member, sizeof member, "%s.npy", name);
    const nerf__zip_entry *e = nerf__zip_find(&c->zip, member);
    if (e == NULL) {
        return nerf__error(NERF_EFORMAT, "%s: member '%s' is missing",
                           c->path, member);
    }
    c->used[e - c->zip.entries] = true;
    /* A memory guard, generous enough that a member of the wrong shape
     * still reaches the shape check and its clearer message.  The product
     * cannot overflow: the options bounding it were validated. */
    size_t n = t->rows * (t->cols ? t->cols : 1);
    size_t max_size = (n + t->spare * (t->cols ? t->cols : 1)) *
                          sizeof(double) + NPY_HEADER_ROOM;
    if (max_size < MIN_MEMBER_LIMIT) {
        max_size = MIN_MEMBER_LIMIT;
    }
    unsigned char *data = NULL;
    int rc = nerf__zip_extract(&c->zip, c->env, e, max_size, &data);
    if (rc != NERF_OK) {
        nerf__free(c->env, data);
        return nerf__error_prefix(rc, c->path);
    }
    nerf__npy a;
    rc = nerf__npy_parse(data, e->size, &a);
    if (rc != NERF_OK) {
        rc = member_error(c, member, rc);
    } else {
        rc = check_array(c, member, &a, t);
    }
    if (rc == NERF_OK) {
        rc = convert(c, member, &a, c->params + t->offset, n);
    }
    nerf__free(c->env, data);
    return rc;
}

/* A layer "<net>.<layer>.weight" [out, in] and ".bias" [out]. */
static int import_rows(npz_import *c, const char *net, const char *layer,
                       size_t w, size_t b, size_t out, size_t in,
                       size_t spare)
{
    char name[128];
    snprintf(name, sizeof name, "%s.%s.weight", net, layer);
    const target weight = {w, out, in, spare}, bias = {b, out, 0, spare};
    int rc = import_array(c, name, &weight);
    if (rc == NERF_OK) {
        snprintf(name, sizeof name, "%s.%s.bias", net, layer);
        rc = import_array(c, name, &bias);
    }
    return rc;
}

static int import_linear(npz_import *c, const char *net, const char *layer,
                         size_t w, size_t b, size_t out, size_t in)
{
    return import_rows(c, net, layer, w, b, out, in, 0);
}

static int import_head(npz_import *c, const char *prefix,
                       const nerf__network *net)
{
    const nerf__linear *h = &net->head;
    if (!net->use_viewdirs) {
        return import_rows(c, prefix, "output_linear", h->w, h->b, 4,
                           net->width, 1);
    }
    size_t W = net->width;
    int rc = import_linear(c, prefix, "feature_linear", h->w, h->b, W, W);
    if (rc == NERF_OK) {
        rc = import_linear(c, prefix, "alpha_linear", h->w + W * W, h->b + W,
                           1, W);
    }
    if (rc == NERF_OK) {
        rc = import_linear(c, prefix, "views_linears.0", net->view[0].w,
                           net->view[0].b, net->view[0].out, net->view[0].in);
    }
    if (rc == NERF_OK) {
        rc = import_linear(c, prefix, "rgb_linear", net->rgb.w, net->rgb.b, 3,
                           net->rgb.in);
    }
    return rc;
}

static int import_network(npz_import *c, const char *prefix,
                          const nerf__network *net)
{
    for (uint32_t i = 0; i < net->depth; i++) {
        const nerf__linear *l = &net->trunk[i];
        char layer[32];
        snprintf(layer, sizeof layer, "pts_linears.%u", (unsigned)i);
        int rc = import_linear(c, prefix, layer, l->w, l->b, l->out, l->in);
        if (rc != NERF_OK) {
            return rc;
        }
    }
    return import_head(c, prefix, net);
}

/* Members no layer claimed: worth a warning (a typo, or options that do
 * not match the file), not a failure. */
static void warn_unused(const npz_import *c)
{
    for (size_t i = 0; i < c->zip.count; i++) {
        const nerf__zip_entry *e = &c->zip.entries[i];
        if (!c->used[i]) {
            nerf__log(c->env, NERF_LOG_WARN, "%s: ignoring member '%.*s', "
                      "which this model does not use", c->path,
                      (int)(e->name_len > 200 ? 200 : e->name_len), e->name);
        }
    }
}

static int import_file(npz_import *c, nerf_model *m)
{
    static const char *const prefixes[2] = {"coarse", "fine"};
    unsigned char *file = NULL;
    size_t size = 0;
    int rc = nerf__file_read(c->env, c->path, MAX_NPZ, &file, &size);
    if (rc != NERF_OK) {
        return rc;
    }
    rc = nerf__zip_open(&c->zip, c->env, file, size);
    if (rc != NERF_OK) {
        rc = nerf__error_prefix(rc, c->path);
    } else {
        c->used = nerf__calloc(c->env, c->zip.count + 1, sizeof *c->used);
        rc = c->used ? NERF_OK : nerf__error_prefix(NERF_ENOMEM, c->path);
    }
    for (uint32_t i = 0; i < m->n_nets && rc == NERF_OK; i++) {
        rc = import_network(c, prefixes[i], &m->nets[i]);
    }
    if (rc == NERF_OK) {
        warn_unused(c);
    }
    nerf__free(c->env, c->used);
    nerf__zip_close(&c->zip, c->env);
    nerf__free(c->env, file);
    return rc;
}

NERF_API int nerf_model_import_npz(nerf_model **out, const char *path,
                                   const nerf_model_options *opts)
{
    if (out == NULL || path == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_import_npz: NULL %s",
                           out ? "path" : "out");
    }
    *out = NULL;
    /* Creation validates the options and sets up hooks; its random
     * initialisation is then overwritten, since every parameter belongs to
     * exactly one imported array. */
    nerf_model *m = NULL;
    int rc = nerf_model_create(&m, opts);
    if (rc != NERF_OK) {
        return rc;
    }
    npz_import c;
    memset(&c, 0, sizeof c);
    c.env = &m->env;
    c.path = path;
    c.params = m->params;
    rc = import_file(&c, m);
    if (rc != NERF_OK) {
        nerf_model_destroy(m);
        return rc;
    }
    nerf__model_weights_changed(m);
    nerf__log(&m->env, NERF_LOG_DEBUG, "%s: imported %zu parameters into %u "
              "network(s)", path, m->n_params, (unsigned)m->n_nets);
    *out = m;
    return NERF_OK;
}
