#include "cpu.h"

#include <stdatomic.h>
#include <unistd.h>

uint32_t nerf__cpu_count(void)
{
    /* glibc answers _SC_NPROCESSORS_ONLN by opening and parsing a file
     * in /sys on every call, and the thread pool asks before each loop it
     * runs: thousands of times a second while rendering.  The count is
     * read once; a processor brought online later is not used until the
     * process restarts, which is how the pool's workers are sized anyway.
     * Threads racing on the first call store the same value. */
    static atomic_uint cached;
    uint32_t n = atomic_load_explicit(&cached, memory_order_relaxed);
    if (n == 0) {
        long v = sysconf(_SC_NPROCESSORS_ONLN);
        n = v < 1 ? 1u : v > 1024 ? 1024u : (uint32_t)v;
        atomic_store_explicit(&cached, n, memory_order_relaxed);
    }
    return n;
}
