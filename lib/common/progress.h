/*
 * The progress reports of long calls (nerf_progress, include/nerf.h): the
 * clock they measure with and the one way a report is made.
 */
#ifndef NERF_COMMON_PROGRESS_H
#define NERF_COMMON_PROGRESS_H

#include <stdint.h>

#include "nerf.h"

/* Seconds on a monotonic clock, for intervals. */
double nerf__seconds(void);

/*
 * Call cb (if not NULL) with a report of the given kind: done of total,
 * and the seconds since start (nerf__seconds()).  Returns what cb returns
 * (nonzero: the caller cancels), 0 without a callback.
 */
int nerf__progress_report(nerf_progress_cb cb, void *user, uint32_t kind,
                          uint64_t done, uint64_t total, double start);

#endif
