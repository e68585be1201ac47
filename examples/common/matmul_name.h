/*
 * The command-line names of nerf_matmul, shared by the programs that take
 * --matmul or print a model's products.
 */
#ifndef NERF_EXAMPLES_MATMUL_NAME_H
#define NERF_EXAMPLES_MATMUL_NAME_H

#include <stdint.h>

#include "opt_table.h"

/* "fp32|bf16|fp32-onednn", for nerf-bench's usage line. */
#define MATMUL_CHOICES "fp32|bf16|fp32-onednn"

/* The names, as --matmul's choices (opt_table.h). */
extern const opt_choice matmul_choices[];

/* The nerf_matmul named `name`, or -1. */
int matmul_parse(const char *name);

/* The name of nerf_matmul `kind` ("unknown" for another value). */
const char *matmul_name(uint32_t kind);

#endif
