/*
 * The command-line names of nerf_matmul, shared by the programs that take
 * --matmul or print a model's products.
 */
#ifndef NERF_EXAMPLES_MATMUL_NAME_H
#define NERF_EXAMPLES_MATMUL_NAME_H

#include <stdint.h>

/* "fp32|bf16|fp32-onednn", for usage lines and error messages. */
#define MATMUL_CHOICES "fp32|bf16|fp32-onednn"

/* The nerf_matmul named `name`, or -1. */
int matmul_parse(const char *name);

/* The name of nerf_matmul `kind` ("unknown" for another value). */
const char *matmul_name(uint32_t kind);

#endif
