/* Status strings and the thread-local last-error contract. */
#include <nerf.h>

#include <pthread.h>
#include <string.h>

#include "../harness.h"

TEST(status_strings)
{
    static const int codes[] = {NERF_OK, NERF_ERROR, NERF_EINVAL, NERF_ENOMEM,
                                NERF_EIO, NERF_EFORMAT, NERF_ECANCELLED,
                                NERF_EVERSION, NERF_ENOENT,
                                NERF_EUNRECOGNISED};
    for (size_t i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        const char *s = nerf_status_string(codes[i]);
        CHECK(s != NULL && s[0] != '\0');
        CHECK(strcmp(s, "unknown status") != 0);
        for (size_t j = 0; j < i; j++) {
            CHECK(strcmp(s, nerf_status_string(codes[j])) != 0);
        }
    }
    CHECK(strcmp(nerf_status_string(-1000), "unknown status") == 0);
    CHECK(strcmp(nerf_status_string(NERF_EINVAL), "invalid argument") == 0);
    /* A missing file or a folder that is no dataset is not a failing
     * disk: their names must not say "input/output". */
    CHECK(strcmp(nerf_status_string(NERF_ENOENT), "no such file or folder")
          == 0);
    CHECK(strstr(nerf_status_string(NERF_EUNRECOGNISED), "not a") != NULL);
}

TEST(last_error_names_what_failed)
{
    nerf_clear_error();
    CHECK(strcmp(nerf_last_error(), "") == 0);
    nerf_hooks h;
    CHECK_EQ_INT(nerf_hooks_init(NULL, sizeof h), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "nerf_hooks") != NULL);
    /* Successful calls leave the message alone. */
    CHECK_OK(NERF_HOOKS_INIT(&h));
    CHECK(strstr(nerf_last_error(), "nerf_hooks") != NULL);
    CHECK_EQ_INT(h.struct_size, sizeof h);
    CHECK_EQ_INT(h.log_level, NERF_LOG_INFO);
    CHECK(h.alloc == NULL && h.free == NULL && h.log_cb == NULL);
}

/* Two threads fail in lock-step; each must see only its own message. */
static pthread_barrier_t barrier;

static void *fail_with_size(void *arg)
{
    size_t size = (size_t)(uintptr_t)arg;
    char expect[64];
    snprintf(expect, sizeof expect, "struct_size %zu ", size);
    nerf_hooks h;
    int bad = 0;
    for (int i = 0; i < 1000; i++) {
        pthread_barrier_wait(&barrier);
        if (nerf_hooks_init(&h, size) != NERF_EINVAL) {
            bad++;
        }
        pthread_barrier_wait(&barrier);
        if (strstr(nerf_last_error(), expect) == NULL) {
            bad++;
        }
    }
    return (void *)(uintptr_t)bad;
}

TEST(last_error_is_thread_local)
{
    pthread_t a, b;
    void *ra, *rb;
    pthread_barrier_init(&barrier, NULL, 2);
    pthread_create(&a, NULL, fail_with_size, (void *)(uintptr_t)2);
    pthread_create(&b, NULL, fail_with_size, (void *)(uintptr_t)3);
    pthread_join(a, &ra);
    pthread_join(b, &rb);
    pthread_barrier_destroy(&barrier);
    CHECK_EQ_INT((uintptr_t)ra, 0);
    CHECK_EQ_INT((uintptr_t)rb, 0);
}

TEST(version_matches_header)
{
    CHECK_EQ_INT(nerf_version_number(), NERF_VERSION_NUMBER);
    CHECK(strcmp(nerf_version_string(), NERF_VERSION_STRING) == 0);
    CHECK(strstr(nerf_build_info(), NERF_VERSION_STRING) != NULL);
    CHECK(strstr(nerf_build_info(), "blas") != NULL);
    CHECK(strstr(nerf_build_info(), "; libjpeg ") != NULL);
}

int main(void)
{
    RUN(status_strings);
    RUN(last_error_names_what_failed);
    RUN(last_error_is_thread_local);
    RUN(version_matches_header);
    HARNESS_EXIT();
}
