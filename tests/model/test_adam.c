/* Adam and the learning-rate schedule against hand-computed numbers. */
#include "../harness.h"
#include "adam.h"
#include "model.h"

TEST(three_steps_by_hand)
{
    /* Values from the update rule evaluated in double precision. */
    static const double want_p[3] = {0.900000019999996, 0.9366103680733917,
                                     0.9502794323117579};
    static const double want_m[3] = {0.05, -0.055, -0.0245};
    static const double want_v[3] = {0.00025, 0.00124975, 0.00131100025};
    static const float g[3] = {0.5f, -1.0f, 0.25f};
    nerf__adam hp = {0.1, 0.1, 1.0, 0.9, 0.999, 1e-7};
    float p = 1.0f, m = 0.0f, v = 0.0f;
    for (int t = 0; t < 3; t++) {
        nerf__adam_update(&hp, (uint64_t)t + 1, 0.1, 1, &p, &g[t], &m, &v);
        CHECK_NEAR(p, want_p[t], 3e-7);
        CHECK_NEAR(m, want_m[t], 1e-8);
        CHECK_NEAR(v, want_v[t], 1e-10);
    }
}

TEST(schedule)
{
    nerf__adam hp = {5e-4, 5e-5, 250000.0, 0.9, 0.999, 1e-7};
    CHECK_NEAR(nerf__adam_rate(&hp, 0), 5e-4, 1e-15);
    CHECK_NEAR(nerf__adam_rate(&hp, 250000), 5e-5, 1e-15);
    CHECK_NEAR(nerf__adam_rate(&hp, 125000), sqrt(5e-4 * 5e-5), 1e-15);
}

TEST(model_step_uses_schedule)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m == NULL) {
        return;
    }
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, 2.0));
    CHECK_NEAR(nerf_model_learning_rate(m), 5e-4, 1e-15);
    float before = m->params[7];
    nerf__model_zero_grad(m);
    for (size_t i = 0; i < m->n_params; i++) {
        m->grads[i] = 1.0f;
    }
    nerf__model_adam_step(m);
    CHECK_EQ_INT(nerf_model_step(m), 1);
    /* First Adam step moves every parameter by lr * g/|g| (up to eps). */
    CHECK_NEAR(before - m->params[7], 5e-4, 2e-8);
    CHECK_NEAR(nerf_model_learning_rate(m), sqrt(5e-4 * 5e-5), 1e-15);
    nerf_model_destroy(m);
}

int main(void)
{
    RUN(three_steps_by_hand);
    RUN(schedule);
    RUN(model_step_uses_schedule);
    HARNESS_EXIT();
}
