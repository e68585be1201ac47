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

TEST(ndc_box_spans_depth_and_a_margin)
{
    nerf__space s;
    nerf__space_ndc(&s, 1.5f);
    CHECK_EQ_INT(s.kind, NERF__SPACE_NDC);
    const float in[3] = {1.4f, -1.4f, 0.99f}, out[3] = {0.0f, 0.0f, 1.01f};
    CHECK(nerf__space_contains(&s, in));
    CHECK(!nerf__space_contains(&s, out));
}

TEST(contraction_keeps_the_cube_and_squeezes_the_rest)
{
    nerf__space s;
    nerf__space_contract(&s, 2.0f);
    CHECK_EQ_INT(s.kind, NERF__SPACE_CONTRACT);
    CHECK(s.lo[0] == -4.0f && s.hi[2] == 4.0f);
    /* Identity inside the cube. */
    const float p[3] = {1.9f, -2.0f, 0.3f};
    float q[3];
    nerf__space_to_domain(&s, p, q);
    CHECK(q[0] == p[0] && q[1] == p[1] && q[2] == p[2]);
    /* Outside: into the shell, monotone along a ray, back by the inverse. */
    float last = 2.0f;
    for (float r = 2.5f; r < 1e7f; r *= 1.7f) {
        const float x[3] = {0.3f * r, -r, 0.7f * r};
        float y[3], back[3];
        nerf__space_to_domain(&s, x, y);
        CHECK(nerf__space_contains(&s, y));
        const float n = nerf__space_norm(y);
        CHECK(n > last && n < 4.0f);
        CHECK_NEAR(n, (2.0f - 2.0f / r) * 2.0f, 1e-5);
        last = n;
        nerf__space_from_domain(&s, y, back);
        /* Far out the shell is thin: float resolves r only to about
         * r^2 / inner ulps of the contracted norm. */
        if (r < 1e4f) {
            for (int a = 0; a < 3; a++) {
                CHECK_NEAR(back[a], x[a], 1e-5 * r + 2.5e-7 * r * r);
            }
        }
    }
    /* Infinite and NaN coordinates end outside the domain. */
    const float inf[3] = {INFINITY, 0.0f, 0.0f}, nan[3] = {0.0f, NAN, 5.0f};
    nerf__space_to_domain(&s, inf, q);
    CHECK(!nerf__space_contains(&s, q));
    nerf__space_to_domain(&s, nan, q);
    CHECK(!nerf__space_contains(&s, q));
}

int main(void)
{
    RUN(world_holds_everything);
    RUN(cube_is_inclusive_and_refuses_nan);
    RUN(ndc_box_spans_depth_and_a_margin);
    RUN(contraction_keeps_the_cube_and_squeezes_the_rest);
    HARNESS_EXIT();
}
