/*
 * A model's density and colour as fields the geometry code samples: the
 * fine network when the model has one, spread over the cores in blocks
 * that each keep their own workspace between calls.
 */
#ifndef NERF_GEOMETRY_MODEL_FIELD_H
#define NERF_GEOMETRY_MODEL_FIELD_H

#include <stddef.h>

#include "model.h"

/* Points per network call: large products, bounded workspaces.  A call
 * for fewer than 2 NERF__FIELD_CHUNK points runs on the calling thread
 * alone, as one network call, whatever the thread count. */
#define NERF__FIELD_CHUNK 4096

typedef struct nerf__model_field {
    const nerf_model *model;
    int net;               /* network index */
    unsigned blocks;       /* threads, one workspace each */
    nerf__workspace *ws;   /* [blocks] */
    float *mapped;         /* [blocks][CHUNK x 3]: contracted points */
    float *sigma;          /* [blocks][CHUNK]: colour_views' densities */
} nerf__model_field;

/* threads 0: every core of the library's pool. */
int nerf__model_field_init(nerf__model_field *f, const nerf_model *model,
                           unsigned threads);
void nerf__model_field_release(nerf__model_field *f);

/* Density (after the model's activation, so >= 0) at n points of the
 * model's space; ctx is the nerf__model_field (a nerf__field sampler). */
int nerf__model_field_density(void *ctx, size_t n, const float *points,
                              float *out);

/* Colours in [0, 1] at n points seen along the unit directions dirs (n x
 * 3).  A model without view directions ignores them. */
int nerf__model_field_colour(nerf__model_field *f, size_t n,
                             const float *points, const float *dirs,
                             float *rgb);

/*
 * Colours in [0, 1] at each of n points seen along views unit directions:
 * dirs and rgb have n x views rows, row p views + d for point p's view d.
 * The density network runs once a point, not once a row.
 */
int nerf__model_field_colour_views(nerf__model_field *f, size_t n,
                                   const float *points, uint32_t views,
                                   const float *dirs, float *rgb);

#endif
