/*
 * A tiny test harness.  Each test file defines TEST(name) functions and a
 * main() that runs them with RUN(name); a failed check prints where and why
 * and marks the test failed without stopping the others.  Exit status 77
 * tells meson a test was skipped.
 */
#ifndef NERF_TEST_HARNESS_H
#define NERF_TEST_HARNESS_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static int harness_failed;
static int harness_current_failed;

#define TEST(name) static void test_##name(void)

#define RUN(name)                                                          \
    do {                                                                   \
        harness_current_failed = 0;                                        \
        test_##name();                                                     \
        printf("%s %s\n", harness_current_failed ? "FAIL" : "ok  ", #name); \
        fflush(stdout);                                                    \
        if (harness_current_failed) {                                      \
            harness_failed++;                                              \
        }                                                                  \
    } while (0)

#define HARNESS_EXIT() return harness_failed ? 1 : 0

#define FAILF(...)                                                         \
    do {                                                                   \
        printf("  %s:%d: ", __FILE__, __LINE__);                           \
        printf(__VA_ARGS__);                                               \
        printf("\n");                                                      \
        harness_current_failed = 1;                                        \
    } while (0)

#define CHECK(cond)                                                        \
    do {                                                                   \
        if (!(cond)) {                                                     \
            FAILF("check failed: %s", #cond);                              \
        }                                                                  \
    } while (0)

#define CHECK_EQ_INT(a, b)                                                 \
    do {                                                                   \
        long long va_ = (long long)(a), vb_ = (long long)(b);              \
        if (va_ != vb_) {                                                  \
            FAILF("%s == %s: %lld != %lld", #a, #b, va_, vb_);             \
        }                                                                  \
    } while (0)

/* A nerf_* call that must succeed; prints nerf_last_error() if it fails. */
#define CHECK_OK(call)                                                     \
    do {                                                                   \
        int rc_ = (call);                                                  \
        if (rc_ != 0) {                                                    \
            FAILF("%s returned %d: %s", #call, rc_, nerf_last_error());    \
        }                                                                  \
    } while (0)

#define CHECK_NEAR(a, b, tol)                                              \
    do {                                                                   \
        double va_ = (double)(a), vb_ = (double)(b);                       \
        if (!(fabs(va_ - vb_) <= (tol))) {                                 \
            FAILF("%s ~ %s: %.9g vs %.9g (tol %g)", #a, #b, va_, vb_,      \
                  (double)(tol));                                          \
        }                                                                  \
    } while (0)

#endif
