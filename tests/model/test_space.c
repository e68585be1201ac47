/* Scene spaces: which points may hold density. */
#include <math.h>

#include "../harness.h"
#include "space.h"

TEST(world_holds_everything)
{
    nerf__space s;
    nerf__space_world(&s);
    const float p[4][3] = {{0, 0, 0}, {1e30f, -1e30f, 0}, {NAN, 0, 0},
                           {INFINITY, 0, 0}};
    for (int i = 0; i < 4; i++) {
        CHECK(nerf__space_contains(&s, p[i]));
    }
}

TEST(cube_is_inclusive_and_refuses_nan)
{
    nerf__space s;
    nerf__space_cube(&s, 1.5f);
    CHECK_EQ_INT(s.kind, NERF__SPACE_BOX);
    const float in[3][3] = {{0, 0, 0}, {1.5f, -1.5f, 1.5f}, {-1.5f, 0, 1.4f}};
    for (int i = 0; i < 3; i++) {
        CHECK(nerf__space_contains(&s, in[i]));
    }
    const float out[4][3] = {{1.5001f, 0, 0}, {0, -1.6f, 0}, {0, 0, 2.0f},
                             {0, NAN, 0}};
    for (int i = 0; i < 4; i++) {
        CHECK(!nerf__space_contains(&s, out[i]));
    }
}

int main(void)
{
    RUN(world_holds_everything);
    RUN(cube_is_inclusive_and_refuses_nan);
    HARNESS_EXIT();
}
