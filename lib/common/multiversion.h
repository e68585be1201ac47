/*
 * Hot element-wise loops compiled more than once: for AVX-512, for AVX2
 * and for the baseline x86-64 the library is built for, the widest one
 * nerf__isa() allows (the processor's, or less if NERF_ISA says so:
 * common/dispatch.h) picked on each call.  The loops are memory-bound,
 * and what the wider instruction sets buy is mostly masked loads and
 * stores, which let the compiler vectorise loops with a condition in them
 * (the sparse Adam update) instead of running them one element at a time.
 *
 *     NERF__CLONED(name, (params...), (args...))
 *     {
 *         body
 *     }
 *
 * defines `static void name(params...)`.  The body is written once, in an
 * always-inlined function that each clone's target attribute compiles for
 * its own instruction set; `args` names the parameters again, to pass
 * them on.  The choice costs a load and a branch per call: mark loops
 * that run over a range of items, not a function called per item.
 *
 * The clones compute exactly the same values: the build contracts no
 * multiply-add into a fused one (-ffp-contract=off, meson.build), and
 * vectorisation never reorders a sum.  On other processors, or compilers
 * without target attributes, there is one version.
 */
#ifndef NERF_COMMON_MULTIVERSION_H
#define NERF_COMMON_MULTIVERSION_H

#include "dispatch.h"

/* For the bodies that kernels of several instruction sets share: inlined
 * into each, so that each compiles them for its own target. */
#if defined(__GNUC__)
#  define NERF__ALWAYS_INLINE inline __attribute__((always_inline))
#else
#  define NERF__ALWAYS_INLINE inline
#endif

#if defined(NERF_HAVE_CLONES)
#  define NERF__CLONED(name, params, args)                                  \
      static inline __attribute__((always_inline)) void name##_body params; \
      __attribute__((target("avx512f"))) static void name##_avx512 params   \
      {                                                                     \
          name##_body args;                                                 \
      }                                                                     \
      __attribute__((target("avx2"))) static void name##_avx2 params        \
      {                                                                     \
          name##_body args;                                                 \
      }                                                                     \
      static void name##_baseline params                                    \
      {                                                                     \
          name##_body args;                                                 \
      }                                                                     \
      static void name params                                               \
      {                                                                     \
          switch (nerf__isa()) {                                            \
          case NERF__ISA_AVX512:                                            \
              name##_avx512 args;                                           \
              break;                                                        \
          case NERF__ISA_AVX2:                                              \
              name##_avx2 args;                                             \
              break;                                                        \
          default:                                                          \
              name##_baseline args;                                         \
              break;                                                        \
          }                                                                 \
      }                                                                     \
      static inline __attribute__((always_inline)) void name##_body params
#else
#  define NERF__CLONED(name, params, args) static void name params
#endif

#endif
