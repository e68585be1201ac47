/*
 * Counter-based random numbers.  A stream is a key plus a counter, so its
 * whole state is two integers: a checkpoint stores them and a resumed run
 * continues exactly, and a worker can jump to any position of a stream
 * without drawing what came before (results then do not depend on how work
 * is split between threads).
 */
#ifndef NERF_COMMON_RNG_H
#define NERF_COMMON_RNG_H

#include <math.h>
#include <stdint.h>

typedef struct nerf__rng {
    uint64_t key;
    uint64_t counter;
} nerf__rng;

/* The splitmix64 finaliser: a bijective mix with good avalanche. */
static inline uint64_t nerf__mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

/* A stream identified by (seed, stream), positioned at counter 0. */
static inline nerf__rng nerf__rng_make(uint64_t seed, uint64_t stream)
{
    nerf__rng r;
    r.key = nerf__mix64(seed ^ nerf__mix64(stream + UINT64_C(0x9e3779b97f4a7c15)));
    r.counter = 0;
    return r;
}

static inline uint64_t nerf__rng_next(nerf__rng *r)
{
    r->counter++;
    return nerf__mix64(r->key + r->counter * UINT64_C(0x9e3779b97f4a7c15));
}

/* Uniform in [0, 1) with 24 random bits, exact in float. */
static inline float nerf__rng_uniform(nerf__rng *r)
{
    return (float)(nerf__rng_next(r) >> 40) * (1.0f / 16777216.0f);
}

/* Uniform in [0, 1) with 53 random bits. */
static inline double nerf__rng_uniform_d(nerf__rng *r)
{
    return (double)(nerf__rng_next(r) >> 11) * (1.0 / 9007199254740992.0);
}

/* Standard normal by Box-Muller; consumes two draws. */
static inline double nerf__rng_normal(nerf__rng *r)
{
    double u1 = 1.0 - nerf__rng_uniform_d(r); /* (0, 1]: log is finite */
    double u2 = nerf__rng_uniform_d(r);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

#endif
