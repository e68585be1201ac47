#ifndef NERF_COMMON_CPU_H
#define NERF_COMMON_CPU_H

#include <stdint.h>

/* Processors the process may run on (its affinity; those online where
 * that cannot be read) when first asked, at least 1: the default worker
 * count. */
uint32_t nerf__cpu_count(void);

#endif
