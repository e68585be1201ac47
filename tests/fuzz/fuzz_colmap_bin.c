/*
 * libFuzzer target for the COLMAP loader on binary models (.bin); see
 * fuzz_colmap.h for what the first byte picks.
 */
#define COLMAP_BINARY 1
#include "fuzz_colmap.h"
