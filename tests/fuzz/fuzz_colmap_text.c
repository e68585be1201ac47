/*
 * libFuzzer target for the COLMAP loader on text models (.txt); see
 * fuzz_colmap.h for what the first byte picks.
 */
#define COLMAP_BINARY 0
#include "fuzz_colmap.h"
