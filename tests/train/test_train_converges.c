/*
 * The tiny preset learns the built-in scene: after a bounded number of
 * steps its renders of the held-out test views reach a stated PSNR, far
 * above what an untrained model or a flat white image scores.  Trained
 * again with bf16 products from the same seed, it reaches about the
 * same PSNR (where nerf_matmul_supported() offers bf16; that half says
 * why it is skipped otherwise).  One file for both, so that the fp32 run
 * both compare with is trained once.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "train_fixture.h"

/*
 * These settings reach 23.4 dB from seed 0 in about 45 s (release build,
 * 2 cores).  A processor that rounds its products otherwise sends
 * training down another path, as another seed does, so the threshold sits
 * below the spread over seeds: NERF_TEST_SEED=0..12 (2026-12, Intel Xeon,
 * 0.11.0) gave 21.29 to 23.38 dB, mean 22.53, sd 0.74, so mean - 4 sd is
 * 19.6, and the runs under NERF_FUSED=0 and under NERF_ISA=baseline with
 * OpenBLAS's Haswell kernels fell within it.  One seed in 13 (4) starts
 * dead: its initial density is nowhere positive, so nothing learns (8.94
 * dB before and after); that is decided by the initial weights, which
 * the seed alone sets on every processor, not by rounding, and seed 0
 * starts alive everywhere.  A broken backward pass costs far more: the
 * untrained model scores 7 to 9 dB.
 *
 * bf16 rounding changes the optimiser's path too: over the same seeds
 * bf16 ended -0.72 to +0.55 dB from fp32 (sd 0.33), so MAX_GAP allows
 * it to end 1.5 dB below, about 4.5 sd; no bound above it.
 *
 * The learning rate is ten times the paper's: the tiny network tolerates
 * it and needs it to learn within a test's budget.  NERF_TEST_STEPS,
 * NERF_TEST_BATCH, NERF_TEST_LR and NERF_TEST_SEED override the settings
 * for experiments.
 */
#define WIDTH 32
#define STEPS 300
#define BATCH 256
#define MIN_PSNR 19.5
#define LEARNING_RATE 5e-3
#define MAX_GAP 1.5

typedef struct run {
    int steps;
    uint32_t batch;
    double lr;
    double before, train, test; /* PSNRs; test -1 when it did not run */
} run;

static run settings(void)
{
    const char *env_steps = getenv("NERF_TEST_STEPS");
    const char *env_batch = getenv("NERF_TEST_BATCH");
    const char *env_lr = getenv("NERF_TEST_LR");
    run r = {
        .steps = env_steps ? atoi(env_steps) : STEPS,
        .batch = env_batch ? (uint32_t)atoi(env_batch) : BATCH,
        .lr = env_lr ? atof(env_lr) : LEARNING_RATE,
        .test = -1.0,
    };
    return r;
}

/* Train a tiny model with these products from the test's seed, filling
 * r's PSNRs. */
static void train(fixture *fx, int matmul, run *r)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    mo.matmul = (uint32_t)matmul;
    mo.seed = fixture_seed();
    nerf_model *m = NULL;
    nerf_sampler *s = tiny_sampler(fixture_seed());
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_model_create(&m, &mo));
    if (m == NULL || s == NULL) {
        goto done;
    }
    r->before = fixture_test_psnr(m, s, fx->test);
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE, r->lr));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE_FINAL,
                                  r->lr / 10));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, r->steps));
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = r->batch;
    o.precrop_steps = 100;
    CHECK_OK(nerf_trainer_create(&t, m, fx->train, s, &o));
    if (t == NULL) {
        goto done;
    }
    nerf_train_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    CHECK_OK(nerf_trainer_run(t, (uint64_t)r->steps, &st));
    r->train = st.psnr;
    r->test = fixture_test_psnr(m, s, fx->test);
done:
    nerf_trainer_destroy(t);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

static fixture fx;
static run fp32;

TEST(tiny_preset_learns_the_builtin_scene)
{
    fp32 = settings();
    train(&fx, NERF_MATMUL_FP32, &fp32);
    printf("  %d steps: train PSNR %.2f, test PSNR %.2f dB (untrained %.2f)\n",
           fp32.steps, fp32.train, fp32.test, fp32.before);
    CHECK(fp32.test >= MIN_PSNR);
    CHECK(fp32.test > fp32.before + 8.0);
}

TEST(bf16_training_matches_fp32)
{
    if (!nerf_matmul_supported(NERF_MATMUL_BF16)) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        o.matmul = NERF_MATMUL_BF16;
        nerf_model *m = NULL;
        nerf_model_create(&m, &o);
        printf("  skipped: %s\n", nerf_last_error());
        return;
    }
    run bf16 = fp32;
    train(&fx, NERF_MATMUL_BF16, &bf16);
    printf("  %d steps, test PSNR: fp32 %.2f dB, bf16 %.2f dB (train %.2f, "
           "%.2f)\n", bf16.steps, fp32.test, bf16.test, fp32.train,
           bf16.train);
    CHECK(bf16.test >= MIN_PSNR);
    CHECK(bf16.test >= fp32.test - MAX_GAP);
}

int main(void)
{
    if (fixture_open(&fx, WIDTH, 40, 4) != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    RUN(tiny_preset_learns_the_builtin_scene);
    RUN(bf16_training_matches_fp32);
    fixture_close(&fx);
    HARNESS_EXIT();
}
