/*
 * What a model file holds, as a JSON object: nerf-info prints it as text
 * or as JSON, so both say the same.
 */
#ifndef NERF_EXAMPLES_MODEL_INFO_H
#define NERF_EXAMPLES_MODEL_INFO_H

#include <cJSON.h>
#include <nerf.h>
#include <stdio.h>

/*
 * The description of model, loaded from path (whose size is given in
 * bytes): preset, encodings, networks, parameter count, whether the
 * weights are finite, step, space, matmul, what the file holds and the
 * render settings.  NULL when out of memory.
 */
cJSON *model_info(const nerf_model *model, const char *path, long long bytes);

/* Print a description as "key  value" lines, nested objects as k=v. */
void model_info_print_text(const cJSON *info, FILE *out);

#endif
