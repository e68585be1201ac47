/*
 * The thread pool behind the element-wise passes: every item is visited
 * exactly once, loops too small to pay for a wake-up stay on the caller,
 * concurrent and nested callers fall back to their own
 * thread, a forked child still works, and the fused gradient passes give
 * bit-identical results to a plain serial loop.
 */
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "fused.h"
#include "../harness.h"
#include "parallel.h"

#define N 100000

typedef struct visit_job {
    atomic_int *count;
    atomic_int ranges;
    int nested;
} visit_job;

static void visit(void *ctx, size_t begin, size_t end)
{
    visit_job *j = ctx;
    atomic_fetch_add(&j->ranges, 1);
    for (size_t i = begin; i < end; i++) {
        atomic_fetch_add(&j->count[i], 1);
    }
}

static void visit_nested(void *ctx, size_t begin, size_t end)
{
    visit_job *j = ctx;
    /* A call from inside a range: must run inline, not deadlock. */
    visit_job inner = {.count = j->count + begin};
    atomic_init(&inner.ranges, 0);
    nerf__parallel_for(end - begin, 1000, visit, &inner);
    atomic_fetch_add(&j->ranges, 1);
}

static int count_ok(atomic_int *count, size_t n, int expect)
{
    for (size_t i = 0; i < n; i++) {
        if (atomic_load(&count[i]) != expect) {
            return 0;
        }
    }
    return 1;
}

static atomic_int counts[4][N];

TEST(every_item_once)
{
    const size_t sizes[] = {0, 1, 2, 3, 17, 1000, N};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        memset(counts[0], 0, sizeof counts[0]);
        visit_job j = {.count = counts[0]};
        atomic_init(&j.ranges, 0);
        nerf__parallel_for(sizes[s], 1000, visit, &j);
        CHECK(count_ok(counts[0], sizes[s], 1));
        CHECK(count_ok(counts[0] + sizes[s], N - sizes[s], 0));
        if (sizes[s] == N) {
            /* Enough work to split: as many ranges as threads. */
            CHECK_EQ_INT(atomic_load(&j.ranges), nerf__parallel_threads());
        }
    }
    memset(counts[0], 0, sizeof counts[0]);
    visit_job small = {.count = counts[0]};
    atomic_init(&small.ranges, 0);
    /* 10^5 single operations are not worth a wake-up: one range. */
    nerf__parallel_for(N, 0, visit, &small);
    CHECK(count_ok(counts[0], N, 1));
    CHECK_EQ_INT(atomic_load(&small.ranges), 1);
}

typedef struct where_job {
    pthread_t caller;
    atomic_int ranges, elsewhere;
} where_job;

static void note_thread(void *ctx, size_t begin, size_t end)
{
    where_job *j = ctx;
    atomic_fetch_add(&j->ranges, 1);
    if (!pthread_equal(pthread_self(), j->caller)) {
        atomic_fetch_add(&j->elsewhere, 1);
    }
}

/*
 * A renderer's 64-ray block costs tens of microseconds a pass, less than
 * waking a worker and waiting for it: it stays on the calling thread.
 * Handing such loops over made one render worker several times slower
 * than running them itself (docs/perf-log/
 * 2026-11-26-rendering-a-trained-fast-model.md).
 */
TEST(small_loops_stay_on_the_caller)
{
    where_job j = {.caller = pthread_self()};
    atomic_init(&j.ranges, 0);
    atomic_init(&j.elsewhere, 0);
    /* A round of 64 rays by 4 samples through a hash grid's 16 levels,
     * at 50 operations a level. */
    nerf__parallel_for(256, 16 * 50, note_thread, &j);
    /* 64 rays' march of up to 8 samples each. */
    nerf__parallel_for(64, 200 + 64 * 8, note_thread, &j);
    CHECK_EQ_INT(atomic_load(&j.ranges), 2);
    CHECK_EQ_INT(atomic_load(&j.elsewhere), 0);
    /* A whole millisecond of work: worth splitting where there are cores
     * to split it over. */
    nerf__parallel_for(64, 64000, note_thread, &j);
    if (nerf__parallel_threads() > 1) {
        CHECK(atomic_load(&j.ranges) >= 4);
        CHECK(atomic_load(&j.elsewhere) >= 1);
    } else {
        CHECK_EQ_INT(atomic_load(&j.ranges), 3);
    }
}

TEST(nested_calls_run_inline)
{
    memset(counts[0], 0, sizeof counts[0]);
    visit_job j = {.count = counts[0]};
    atomic_init(&j.ranges, 0);
    nerf__parallel_for(N, 1000, visit_nested, &j);
    CHECK(count_ok(counts[0], N, 1));
}

static void *caller(void *arg)
{
    atomic_int *count = arg;
    for (int rep = 0; rep < 50; rep++) {
        visit_job j = {.count = count};
        atomic_init(&j.ranges, 0);
        nerf__parallel_for(N, 1000, visit, &j);
    }
    return NULL;
}

TEST(concurrent_callers)
{
    memset(counts, 0, sizeof counts);
    pthread_t t[4];
    for (int i = 0; i < 4; i++) {
        CHECK_EQ_INT(pthread_create(&t[i], NULL, caller, counts[i]), 0);
    }
    for (int i = 0; i < 4; i++) {
        pthread_join(t[i], NULL);
        CHECK(count_ok(counts[i], N, 50));
    }
}

TEST(forked_child)
{
    /* The parent's pool has started (the tests above): the child has its
     * state but none of its threads, and must still finish. */
    pid_t pid = fork();
    CHECK(pid >= 0);
    if (pid == 0) {
        memset(counts[0], 0, sizeof counts[0]);
        visit_job j = {.count = counts[0]};
        atomic_init(&j.ranges, 0);
        nerf__parallel_for(N, 1000, visit, &j);
        _exit(count_ok(counts[0], N, 1) ? 0 : 1);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

/*
 * The bias gradients sum the same way whatever the split: the plain one
 * over all rows in order, the ReLU one by blocks of NERF__RELU_ROWS rows
 * added in block order.
 */
TEST(gradient_passes_match_serial)
{
    const size_t n = 3000, cols = 257, ld = 260;
    float *y = malloc(n * ld * sizeof(float));
    float *dy = malloc(n * ld * sizeof(float));
    float *dy_ref = malloc(n * ld * sizeof(float));
    float db[257], db_ref[257], db2[257], db2_ref[257];
    CHECK(y && dy && dy_ref);
    if (!(y && dy && dy_ref)) {
        return;
    }
    uint32_t state = 12345;
    for (size_t i = 0; i < n * ld; i++) {
        state = state * 1664525u + 1013904223u;
        y[i] = (float)((int)(state >> 8) % 2001 - 1000) / 1000.0f;
        state = state * 1664525u + 1013904223u;
        dy[i] = dy_ref[i] = (float)(state >> 8) / 16777216.0f - 0.5f;
    }
    for (size_t c = 0; c < cols; c++) {
        db[c] = db_ref[c] = 0.25f;
        db2[c] = db2_ref[c] = -0.5f;
    }
    nerf__bias_backward(n, cols, dy, ld, db2);
    float *partial = malloc(NERF__RELU_PARTIALS(n, cols) * sizeof(float));
    CHECK(partial != NULL);
    if (partial == NULL) {
        free(y);
        free(dy);
        free(dy_ref);
        return;
    }
    nerf__relu_backward_bias(n, cols, y, ld, dy, ld, db, partial);
    for (size_t i = 0; i < n; i++) {
        for (size_t c = 0; c < cols; c++) {
            db2_ref[c] += dy_ref[i * ld + c];
        }
    }
    for (size_t r0 = 0; r0 < n; r0 += NERF__RELU_ROWS) {
        float part[257] = {0};
        for (size_t i = r0; i < n && i < r0 + NERF__RELU_ROWS; i++) {
            for (size_t c = 0; c < cols; c++) {
                float g = y[i * ld + c] > 0.0f ? dy_ref[i * ld + c] : 0.0f;
                dy_ref[i * ld + c] = g;
                part[c] += g;
            }
        }
        for (size_t c = 0; c < cols; c++) {
            db_ref[c] += part[c];
        }
    }
    CHECK(memcmp(db, db_ref, sizeof db) == 0);
    CHECK(memcmp(db2, db2_ref, sizeof db2) == 0);
    int same = 1;
    for (size_t i = 0; i < n; i++) {
        same &= memcmp(dy + i * ld, dy_ref + i * ld, cols * sizeof(float)) == 0;
    }
    CHECK(same);
    free(partial);
    free(y);
    free(dy);
    free(dy_ref);
}

int main(void)
{
    RUN(every_item_once);
    RUN(small_loops_stay_on_the_caller);
    RUN(nested_calls_run_inline);
    RUN(concurrent_callers);
    RUN(forked_child);
    RUN(gradient_passes_match_serial);
    HARNESS_EXIT();
}
