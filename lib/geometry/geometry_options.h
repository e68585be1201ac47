/*
 * What nerf_mesh_extract() and nerf_density_grid_write() share: reading
 * and checking nerf_mesh_options, the box a model's grid covers, and the
 * progress reports.
 */
#ifndef NERF_GEOMETRY_OPTIONS_H
#define NERF_GEOMETRY_OPTIONS_H

#include <stdint.h>

#include "grid_box.h"
#include "model.h"

/* Read opts (NULL: defaults) into o, check it, and lay the grid over its
 * box (the model's bounds when all zero).  who names the call. */
int nerf__geometry_setup(const nerf_model *model, const nerf_mesh_options *opts,
                         const char *who, nerf_mesh_options *o,
                         nerf__grid_box *grid);

/* The progress callback of o, with the call's start time. */
typedef struct nerf__geometry_reporter {
    nerf_progress_cb cb;
    void *user;
    double start;
} nerf__geometry_reporter;

void nerf__geometry_reporter_init(nerf__geometry_reporter *r,
                                  const nerf_mesh_options *o);

/* A nerf__geometry_progress function over a reporter (ctx). */
int nerf__geometry_report(void *ctx, uint64_t done, uint64_t total);

#endif
