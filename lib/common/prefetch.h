/* A hint to fetch a cache line before it is needed, where the compiler
 * has one (gcc and clang), and nothing elsewhere. */
#ifndef NERF_COMMON_PREFETCH_H
#define NERF_COMMON_PREFETCH_H

/* write: 1 if the line will be written; keep: 0 (used once) to 3 (kept
 * in every cache level).  Both must be constants. */
#if defined(__GNUC__)
#  define NERF__PREFETCH(p, write, keep) \
      __builtin_prefetch((p), (write), (keep))
#else
#  define NERF__PREFETCH(p, write, keep) ((void)(p))
#endif

#endif
