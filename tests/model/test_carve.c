/* One allocation carved into 64-byte aligned arrays (env.h). */
#include <stdint.h>
#include <string.h>

#include "../harness.h"
#include "env.h"

TEST(arrays_on_their_own_lines)
{
    const size_t bytes[] = {1, 0, 64, 65, 200, 0};
    const size_t n = sizeof bytes / sizeof bytes[0];
    CHECK_EQ_INT((int)nerf__carve_size(bytes, n), 64 + 0 + 64 + 128 + 256);
    nerf__env env;
    nerf__env_default(&env);
    unsigned char *block = nerf__alloc(&env, nerf__carve_size(bytes, n));
    CHECK(block != NULL);
    if (block == NULL) {
        return;
    }
    unsigned char *at = block;
    unsigned char *p[6];
    for (size_t i = 0; i < n; i++) {
        p[i] = nerf__carve(&at, bytes[i]);
    }
    CHECK(p[0] == block);
    CHECK(p[1] == NULL && p[5] == NULL); /* empty arrays take no room */
    CHECK(p[2] == block + 64);
    CHECK(p[3] == block + 128);
    CHECK(p[4] == block + 256);
    CHECK(at == block + nerf__carve_size(bytes, n));
    for (size_t i = 0; i < n; i++) {
        CHECK(p[i] == NULL || (uintptr_t)p[i] % 64 == 0);
        if (p[i]) {
            memset(p[i], (int)i, bytes[i]); /* ASan: each fits the block */
        }
    }
    nerf__free(&env, block);
}

int main(void)
{
    RUN(arrays_on_their_own_lines);
    HARNESS_EXIT();
}
