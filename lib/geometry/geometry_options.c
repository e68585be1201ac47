#include "geometry_options.h"

#include <math.h>
#include <string.h>

#include "error.h"
#include "options.h"
#include "progress.h"
#include "space.h"

static void defaults(nerf_mesh_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->resolution = 256;
    o->threshold = 25.0f;
    o->colour = NERF_MESH_COLOUR_NORMAL;
}

NERF_API int nerf_mesh_options_init(nerf_mesh_options *opts,
                                    size_t struct_size)
{
    nerf_mesh_options d;
    defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_mesh_options");
}

/* The box a model holds density in: its space's domain, the central
 * cube of an unbounded one, or the cube of its bound for the reference
 * networks (whose bound is the Blender scenes' 1.5 unless set). */
static void model_box(const nerf_model *model, float lo[3], float hi[3])
{
    const nerf__space *s = nerf__model_space(model);
    const float b = model->opts.bound;
    for (int a = 0; a < 3; a++) {
        if (s->kind == NERF__SPACE_BOX || s->kind == NERF__SPACE_NDC) {
            lo[a] = s->lo[a];
            hi[a] = s->hi[a];
        } else if (s->kind == NERF__SPACE_CONTRACT) {
            lo[a] = -s->inner;
            hi[a] = s->inner;
        } else {
            lo[a] = -b;
            hi[a] = b;
        }
    }
}

int nerf__geometry_setup(const nerf_model *model, const nerf_mesh_options *opts,
                         const char *who, nerf_mesh_options *o,
                         nerf__grid_box *grid)
{
    defaults(o);
    int rc = opts ? nerf__options_read(o, sizeof *o, opts, who) : NERF_OK;
    if (rc != NERF_OK) {
        return rc;
    }
    if (model == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL model", who);
    }
    /* NaN densities would give no surface and a grid of zeros. */
    rc = nerf__model_check_finite(model, who);
    if (rc != NERF_OK) {
        return rc;
    }
    if (!isfinite(o->threshold)) {
        return nerf__error(NERF_EINVAL, "%s: threshold %g is not a finite "
                           "density", who, (double)o->threshold);
    }
    if (o->colour > NERF_MESH_COLOUR_NORMAL) {
        return nerf__error(NERF_EINVAL, "%s: colour %u is not a "
                           "nerf_mesh_colour", who, (unsigned)o->colour);
    }
    if (o->keep_largest > 1) {
        return nerf__error(NERF_EINVAL, "%s: keep_largest must be 0 or 1",
                           who);
    }
    if (o->reserved0 != 0) {
        return nerf__error(NERF_EINVAL, "%s: reserved0 must be 0", who);
    }
    if (o->threads > 1024) {
        return nerf__error(NERF_EINVAL, "%s: threads %u is out of range "
                           "(0..1024)", who, (unsigned)o->threads);
    }
    float lo[3], hi[3];
    int all_zero = 1;
    for (int i = 0; i < 6; i++) {
        all_zero = all_zero && o->box[i] == 0.0f;
    }
    if (all_zero) {
        model_box(model, lo, hi);
    } else {
        memcpy(lo, o->box, sizeof lo);
        memcpy(hi, o->box + 3, sizeof hi);
    }
    return nerf__grid_box_init(grid, lo, hi, o->resolution, who);
}

void nerf__geometry_reporter_init(nerf__geometry_reporter *r,
                                  const nerf_mesh_options *o)
{
    r->cb = o->progress;
    r->user = o->progress_user;
    r->start = nerf__seconds();
}

int nerf__geometry_report(void *ctx, uint64_t done, uint64_t total)
{
    const nerf__geometry_reporter *r = ctx;
    return nerf__progress_report(r->cb, r->user, NERF_PROGRESS_GEOMETRY, done,
                                 total, r->start);
}
