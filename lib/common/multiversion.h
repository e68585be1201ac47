/*
 * Hot element-wise loops compiled more than once: for AVX-512, for AVX2
 * and for the baseline x86-64 the library is built for, the best one
 * picked by the dynamic loader on the machine that runs it
 * (target_clones, in gcc and clang).  Mark only static functions with it:
 * clang emits the resolver in the defining file alone, so a call from
 * another file would not link.  The loops are memory-bound, and what the wider
 * instruction sets buy is mostly masked loads and stores, which let the
 * compiler vectorise loops with a condition in them (the sparse Adam
 * update) instead of running them one element at a time.
 *
 * The clones compute exactly the same values: the build contracts no
 * multiply-add into a fused one (-ffp-contract=off, meson.build), and
 * vectorisation never reorders a sum.  Elsewhere (compilers without
 * target_clones, other processors) NERF__MULTIVERSION is empty.
 */
#ifndef NERF_COMMON_MULTIVERSION_H
#define NERF_COMMON_MULTIVERSION_H

#if defined(NERF_HAVE_TARGET_CLONES)
#  define NERF__MULTIVERSION \
      __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#  define NERF__MULTIVERSION
#endif

#endif
