/* sched_getaffinity() and CPU_COUNT() are GNU extensions. */
#define _GNU_SOURCE
#include "cpu.h"

#include <sched.h>
#include <stdatomic.h>
#include <unistd.h>

/*
 * The processors this process may run on.  Under taskset, a container's
 * cpuset or `mpirun --bind-to core` they are fewer than those online, and
 * threads beyond them would only take turns on the same cores: two ranks
 * bound to a core each, each with a pool sized for the whole machine,
 * would run four threads on two cores.
 */
static long usable_cpus(void)
{
#if defined(__linux__) && defined(CPU_COUNT)
    cpu_set_t set;
    /* Fails (EINVAL) where the kernel's mask is wider than a cpu_set_t,
     * on machines of over 1024 processors: then count those online. */
    if (sched_getaffinity(0, sizeof set, &set) == 0) {
        int n = CPU_COUNT(&set);
        if (n > 0) {
            return n;
        }
    }
#endif
    return sysconf(_SC_NPROCESSORS_ONLN);
}

uint32_t nerf__cpu_count(void)
{
    /* glibc answers _SC_NPROCESSORS_ONLN by opening and parsing a file
     * in /sys on every call, and the thread pool asks before each loop it
     * runs: thousands of times a second while rendering.  The count is
     * read once; a processor brought online later, or an affinity changed
     * later, is not used until the process restarts, which is how the
     * pool's workers are sized anyway.  Threads racing on the first call
     * store the same value. */
    static atomic_uint cached;
    uint32_t n = atomic_load_explicit(&cached, memory_order_relaxed);
    if (n == 0) {
        long v = usable_cpus();
        n = v < 1 ? 1u : v > 1024 ? 1024u : (uint32_t)v;
        atomic_store_explicit(&cached, n, memory_order_relaxed);
    }
    return n;
}
