/*
 * The default thread counts follow the processors the process may run on,
 * not those online: a process confined to one (taskset, a cpuset, `mpirun
 * --bind-to core`) gets a pool of one thread.  Its own program, because
 * the count is read once per process.
 */
#define _GNU_SOURCE
#include <sched.h>

#include "../harness.h"
#include "cpu.h"
#include "parallel.h"

int main(void)
{
#if defined(__linux__) && defined(CPU_COUNT)
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) != 0) {
        printf("skip: sched_getaffinity() failed\n");
        return 77;
    }
    const int usable = CPU_COUNT(&set);
    int first = 0;
    while (first < CPU_SETSIZE && !CPU_ISSET(first, &set)) {
        first++;
    }
    CPU_ZERO(&set);
    CPU_SET(first, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) {
        printf("skip: cannot confine the process to processor %d\n", first);
        return 77;
    }
    printf("  %d processor(s) usable, confined to processor %d\n", usable,
           first);
    CHECK(nerf__cpu_count() == 1);
    CHECK(nerf__parallel_threads() == 1);
    HARNESS_EXIT();
#else
    (void)harness_failed;
    (void)harness_current_failed;
    printf("skip: no CPU affinity on this system\n");
    return 77;
#endif
}
