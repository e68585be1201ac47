/*
 * Training with bf16 products reaches about the PSNR of fp32 training:
 * the tiny preset on the built-in scene, as test_train_converges trains
 * it, once with each kind of product from the same seed, and the mean
 * PSNR of the held-out views compared.  Skipped (after saying why) where
 * nerf_matmul_supported() says bf16 is not available.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "train_fixture.h"

/*
 * Settings of test_train_converges.  On the development machine the two
 * runs end within a few tenths of a dB of each other (the figures are
 * printed); MAX_GAP allows for bf16's rounding changing the path the
 * optimiser takes, not for a broken backward pass, which costs many dB.
 */
#define WIDTH 32
#define STEPS 300
#define BATCH 256
#define LEARNING_RATE 5e-3
#define MIN_PSNR 21.0
#define MAX_GAP 1.0

/* Train a tiny model with these products; its test PSNR, or -1. */
static double train(fixture *fx, int matmul, double *train_psnr)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    mo.matmul = (uint32_t)matmul;
    nerf_model *m = NULL;
    nerf_sampler *s = tiny_sampler(0);
    nerf_trainer *t = NULL;
    double psnr = -1.0;
    CHECK_OK(nerf_model_create(&m, &mo));
    if (m == NULL || s == NULL) {
        goto done;
    }
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE, LEARNING_RATE));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE_FINAL,
                                  LEARNING_RATE / 10));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, STEPS));
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = BATCH;
    o.precrop_steps = 100;
    CHECK_OK(nerf_trainer_create(&t, m, fx->train, s, &o));
    if (t == NULL) {
        goto done;
    }
    nerf_train_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    CHECK_OK(nerf_trainer_run(t, STEPS, &st));
    *train_psnr = st.psnr;
    psnr = fixture_test_psnr(m, s, fx->test);
done:
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
    return psnr;
}

TEST(bf16_training_matches_fp32)
{
    fixture fx;
    if (fixture_open(&fx, WIDTH, 40, 4) != NERF_OK) {
        FAILF("fixture: %s", nerf_last_error());
        return;
    }
    double tr32 = 0.0, tr16 = 0.0;
    double fp32 = train(&fx, NERF_MATMUL_FP32, &tr32);
    double bf16 = train(&fx, NERF_MATMUL_BF16, &tr16);
    printf("  %d steps, test PSNR: fp32 %.2f dB, bf16 %.2f dB (train %.2f, "
           "%.2f)\n", STEPS, fp32, bf16, tr32, tr16);
    CHECK(bf16 >= MIN_PSNR);
    CHECK(fabs(bf16 - fp32) <= MAX_GAP);
    fixture_close(&fx);
}

int main(void)
{
    if (!nerf_matmul_supported(NERF_MATMUL_BF16)) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        o.matmul = NERF_MATMUL_BF16;
        nerf_model *m = NULL;
        nerf_model_create(&m, &o);
        printf("SKIP: %s\n", nerf_last_error());
        return 77;
    }
    RUN(bf16_training_matches_fp32);
    HARNESS_EXIT();
}
