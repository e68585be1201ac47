#include "parallel.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <unistd.h>

#include "cpu.h"

/*
 * Below this much work (in the simple operations of parallel.h, about four
 * to a nanosecond) a part is not worth waking a thread for.  Waking a
 * sleeping worker and waiting for it costs more than many small loops take,
 * above all on a virtual machine, so a job is split only once it has work
 * for two such parts; bench_parallel measures the break-even
 * (docs/perf-log/2026-11-26-rendering-a-trained-fast-model.md).
 */
#define MIN_WORK_PER_PART ((size_t)1 << 18)
#define MAX_WORKERS 63

/*
 * Workers sleep on a condition variable rather than spin: between two
 * element-wise passes the BLAS's own threads need these cores, and a
 * spinning pool would take time from them.
 */
static struct {
    pthread_mutex_t mu;
    pthread_cond_t work_cv, done_cv;
    pthread_t threads[MAX_WORKERS];
    unsigned n_workers;
    pid_t pid;          /* the process that started the workers */
    bool started, stop;
    uint64_t gen;       /* incremented for every job */
    /* The current job, read by workers under mu. */
    nerf__range_fn fn;
    void *ctx;
    size_t n;
    unsigned parts;     /* part 0 is the caller's, part k worker k-1's */
    unsigned pending;   /* workers yet to finish their part */
} pool = {
    .mu = PTHREAD_MUTEX_INITIALIZER,
    .work_cv = PTHREAD_COND_INITIALIZER,
    .done_cv = PTHREAD_COND_INITIALIZER,
};

static atomic_flag busy = ATOMIC_FLAG_INIT;

static _Thread_local bool inline_only;

void nerf__parallel_set_inline(int on)
{
    inline_only = on != 0;
}

static void part_range(size_t n, unsigned parts, unsigned k, size_t *begin,
                       size_t *end)
{
    *begin = n * k / parts;
    *end = n * (k + 1) / parts;
}

static void *worker_main(void *arg)
{
    const unsigned index = (unsigned)(size_t)arg; /* runs part index + 1 */
    uint64_t seen = 0;
    pthread_mutex_lock(&pool.mu);
    for (;;) {
        while (pool.gen == seen && !pool.stop) {
            pthread_cond_wait(&pool.work_cv, &pool.mu);
        }
        if (pool.stop) {
            break;
        }
        seen = pool.gen;
        if (index + 1 >= pool.parts) {
            continue; /* not needed for this job */
        }
        nerf__range_fn fn = pool.fn;
        void *ctx = pool.ctx;
        size_t begin, end;
        part_range(pool.n, pool.parts, index + 1, &begin, &end);
        pthread_mutex_unlock(&pool.mu);
        fn(ctx, begin, end);
        pthread_mutex_lock(&pool.mu);
        if (--pool.pending == 0) {
            pthread_cond_signal(&pool.done_cv);
        }
    }
    pthread_mutex_unlock(&pool.mu);
    return NULL;
}

/* Called with busy held, so only one thread ever starts the workers. */
static void start_workers(void)
{
    if (pool.started) {
        return;
    }
    pool.started = true;
    pool.pid = getpid();
    unsigned want = nerf__cpu_count() - 1;
    if (want > MAX_WORKERS) {
        want = MAX_WORKERS;
    }
    for (unsigned i = 0; i < want; i++) {
        /* A pool short of workers still works: the caller runs the rest. */
        if (pthread_create(&pool.threads[i], NULL, worker_main,
                           (void *)(size_t)i) != 0) {
            break;
        }
        pool.n_workers = i + 1;
    }
}

/* After fork() the child has the pool's state but not its threads. */
static bool usable(void)
{
    return !pool.started || pool.pid == getpid();
}

unsigned nerf__parallel_threads(void)
{
    unsigned cores = nerf__cpu_count();
    return cores > MAX_WORKERS + 1 ? MAX_WORKERS + 1 : cores;
}

void nerf__parallel_for(size_t n, size_t cost, nerf__range_fn fn, void *ctx)
{
    if (n == 0) {
        return;
    }
    size_t work = n * (cost ? cost : 1);
    size_t parts = work / MIN_WORK_PER_PART;
    unsigned threads = nerf__parallel_threads();
    if (parts > threads) {
        parts = threads;
    }
    if (parts > n) {
        parts = n;
    }
    if (parts < 2 || inline_only || atomic_flag_test_and_set(&busy)) {
        fn(ctx, 0, n);
        return;
    }
    if (!usable()) {
        atomic_flag_clear(&busy);
        fn(ctx, 0, n);
        return;
    }
    start_workers();
    if (parts > pool.n_workers + 1) {
        parts = pool.n_workers + 1;
    }
    if (parts < 2) {
        atomic_flag_clear(&busy);
        fn(ctx, 0, n);
        return;
    }
    pthread_mutex_lock(&pool.mu);
    pool.fn = fn;
    pool.ctx = ctx;
    pool.n = n;
    pool.parts = (unsigned)parts;
    pool.pending = (unsigned)parts - 1;
    pool.gen++;
    pthread_cond_broadcast(&pool.work_cv);
    pthread_mutex_unlock(&pool.mu);

    size_t begin, end;
    part_range(n, (unsigned)parts, 0, &begin, &end);
    fn(ctx, begin, end);

    pthread_mutex_lock(&pool.mu);
    while (pool.pending > 0) {
        pthread_cond_wait(&pool.done_cv, &pool.mu);
    }
    pthread_mutex_unlock(&pool.mu);
    atomic_flag_clear(&busy);
}

typedef struct blocks_job {
    nerf__block_fn fn;
    void *ctx;
} blocks_job;

static void run_blocks(void *ctx, size_t begin, size_t end)
{
    const blocks_job *j = ctx;
    for (size_t b = begin; b < end; b++) {
        j->fn(j->ctx, b);
    }
}

void nerf__parallel_blocks(size_t n_blocks, size_t cost_per_block,
                           nerf__block_fn fn, void *ctx)
{
    blocks_job j = {fn, ctx};
    nerf__parallel_for(n_blocks, cost_per_block, run_blocks, &j);
}

/* Stop and join the workers when the library is unloaded, so that no
 * thread is left waiting inside unmapped code. */
__attribute__((destructor)) static void stop_workers(void)
{
    if (!pool.started || pool.pid != getpid()) {
        return;
    }
    pthread_mutex_lock(&pool.mu);
    pool.stop = true;
    pthread_cond_broadcast(&pool.work_cv);
    pthread_mutex_unlock(&pool.mu);
    for (unsigned i = 0; i < pool.n_workers; i++) {
        pthread_join(pool.threads[i], NULL);
    }
    pool.n_workers = 0;
}
