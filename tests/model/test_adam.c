/* Adam and the learning-rate schedule against hand-computed numbers. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../harness.h"
#include "adam.h"
#include "dispatch.h"
#include "model.h"
#include "small_grid.h"

TEST(three_steps_by_hand)
{
    /* Values from the update rule evaluated in double precision. */
    static const double want_p[3] = {0.900000019999996, 0.9366103680733917,
                                     0.9502794323117579};
    static const double want_m[3] = {0.05, -0.055, -0.0245};
    static const double want_v[3] = {0.00025, 0.00124975, 0.00131100025};
    static const float g[3] = {0.5f, -1.0f, 0.25f};
    nerf__adam hp = {0.1, 0.1, 1.0, 0.9, 0.999, 1e-7, 0.0, 0.0, 0.0};
    float p = 1.0f, m = 0.0f, v = 0.0f;
    for (int t = 0; t < 3; t++) {
        float grad = g[t];
        nerf__adam_update(&hp, (uint64_t)t + 1, 0.1, 1, &p, &grad, &m, &v, 0);
        CHECK(grad == 0.0f); /* consumed */
        CHECK_NEAR(p, want_p[t], 3e-7);
        CHECK_NEAR(m, want_m[t], 1e-8);
        CHECK_NEAR(v, want_v[t], 1e-10);
    }
}

/* Weight decay adds wd * p to the gradient before the moments see it. */
TEST(weight_decay)
{
    nerf__adam hp = {0.1, 0.1, 1.0, 0.9, 0.99, 1e-15, 0.25, 0.0, 0.0};
    float p[2] = {2.0f, 2.0f}, g[2] = {0.5f, 0.5f}, m[2] = {0}, v[2] = {0};
    nerf__adam_update(&hp, 1, 0.1, 1, &p[0], &g[0], &m[0], &v[0],
                      NERF__ADAM_DECAY);
    nerf__adam_update(&hp, 1, 0.1, 1, &p[1], &g[1], &m[1], &v[1], 0);
    /* Effective gradient 0.5 + 0.25 * 2 = 1 against 0.5 without. */
    CHECK_NEAR(m[0], 0.1, 1e-7);
    CHECK_NEAR(m[1], 0.05, 1e-7);
    CHECK_NEAR(v[0], 0.01, 1e-8);
    /* The first step moves by lr either way (m / sqrt(v) = sign). */
    CHECK_NEAR(p[0], 1.9, 1e-6);
    CHECK_NEAR(p[1], 1.9, 1e-6);
}

/* The moments come out of two roundings each, a product's and a sum's,
 * whatever processor the update's code was compiled for: no clone may
 * fuse a multiply and an add (clang does, where the target has FMA,
 * unless the build says -ffp-contract=off), or a run's result would
 * depend on the machine.  Many values, so that a fused sum differs. */
TEST(moments_rounded_as_written)
{
    nerf__adam hp = {1e-2, 1e-3, 100.0, 0.9, 0.99, 1e-15, 0.0, 0.0, 0.0};
    enum { N = 1024 };
    static float p[N], g[N], m[N], v[N], want_m[N], want_v[N];
    const float b1 = 0.9f, b2 = 0.99f;
    const float one_b1 = (float)(1.0 - 0.9), one_b2 = (float)(1.0 - 0.99);
    for (int i = 0; i < N; i++) {
        p[i] = 0.5f;
        m[i] = 0.001f * (float)(i % 97) - 0.05f;
        v[i] = 0.0001f * (float)(i % 89) + 1e-5f;
        g[i] = 0.0037f * (float)(i % 61) - 0.11f;
        /* Each product and sum stored, so rounded, before the next. */
        const float m1 = b1 * m[i], m2 = one_b1 * g[i];
        want_m[i] = m1 + m2;
        const float v1 = b2 * v[i], v2 = one_b2 * g[i], v3 = v2 * g[i];
        want_v[i] = v1 + v3;
    }
    nerf__adam_update(&hp, 3, 1e-2, N, p, g, m, v, 0);
    int differ = 0;
    for (int i = 0; i < N; i++) {
        differ += m[i] != want_m[i] || v[i] != want_v[i];
    }
    CHECK(differ == 0);
    if (differ) {
        printf("  %d of %d moments differ from two roundings each\n", differ,
               N);
    }
}

/* A sparse range leaves entries with a zero gradient exactly as they
 * were, moments included, and updates the others as a dense one would. */
TEST(sparse_skips_untouched)
{
    nerf__adam hp = {0.1, 0.1, 1.0, 0.9, 0.99, 1e-15, 0.5, 0.0, 0.0};
    enum { N = 64 };
    float ps[N], gs[N], ms[N], vs[N], pd[N], gd[N], md[N], vd[N];
    for (int i = 0; i < N; i++) {
        ps[i] = pd[i] = 0.01f * (float)i - 0.3f;
        ms[i] = md[i] = 0.002f * (float)(i % 7);
        vs[i] = vd[i] = 0.001f * (float)(i % 5) + 1e-4f;
        gs[i] = gd[i] = (i % 3 == 0) ? 0.0f : 0.05f * (float)(i - 30);
    }
    for (uint64_t t = 5; t < 8; t++) {
        nerf__adam_update(&hp, t, 0.1, N, ps, gs, ms, vs, NERF__ADAM_SPARSE);
        nerf__adam_update(&hp, t, 0.1, N, pd, gd, md, vd, 0);
        for (int i = 0; i < N; i++) {
            float g = (i % 3 == 0) ? 0.0f : 0.05f * (float)(i - 30);
            CHECK(gs[i] == 0.0f && gd[i] == 0.0f);
            gs[i] = gd[i] = g;
        }
    }
    for (int i = 0; i < N; i++) {
        if (i % 3 == 0) {
            /* Untouched: as set up (no decay in a sparse range either). */
            CHECK(ps[i] == 0.01f * (float)i - 0.3f);
            CHECK(ms[i] == 0.002f * (float)(i % 7));
            CHECK(vs[i] == 0.001f * (float)(i % 5) + 1e-4f);
            /* Dense Adam would have moved it on its momentum. */
            if (ms[i] != 0.0f) {
                CHECK(pd[i] != ps[i]);
            }
        } else {
            CHECK(ps[i] == pd[i] && ms[i] == md[i] && vs[i] == vd[i]);
        }
    }
}

static nerf_model *grid_model(void)
{
    nerf_model_options o;
    small_grid_options(&o);
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    return m;
}

/* A hash-grid model: the table is updated sparsely, the layers densely
 * with weight decay. */
TEST(model_regions)
{
    nerf_model *m = grid_model();
    if (m == NULL) {
        return;
    }
    double wd = 0.0;
    CHECK_OK(nerf_model_get_param(m, NERF_PARAM_WEIGHT_DECAY, &wd));
    CHECK_NEAR(wd, 1e-6, 1e-18);
    const nerf__network *net = &m->nets[0];
    const size_t table = net->pos_params, layers = net->pos_params + net->pos_enc.u.hash.count;
    CHECK(net->pos_enc.u.hash.count > 2 && layers < m->n_params);
    float *before = malloc(m->n_params * sizeof(float));
    if (before == NULL) {
        nerf_model_destroy(m);
        return;
    }
    memcpy(before, m->params, m->n_params * sizeof(float));
    nerf__model_zero_grad(m);
    m->grads[table + 1] = 0.5f;     /* one touched table entry */
    nerf__model_adam_step(m);
    CHECK(m->params[table] == before[table]);
    CHECK(m->params[table + 1] != before[table + 1]);
    CHECK(m->params[table + 2] == before[table + 2]);
    /* A layer parameter with no gradient still moves: weight decay. */
    size_t w = layers + 3;
    CHECK(before[w] != 0.0f && m->params[w] != before[w]);
    for (size_t i = 0; i < m->n_params; i++) {
        if (m->grads[i] != 0.0f) {
            CHECK(m->grads[i] == 0.0f);
            break;
        }
    }
    free(before);
    nerf_model_destroy(m);
}

/* A corrected update corrects each touched parameter by its own count of
 * updates: one touched for the first time at step 50 moves as step 1 of
 * Adam would, one untouched stays as it was, corrections included, and
 * one whose corrections have reached 1 takes the uncorrected step. */
TEST(corrected_update)
{
    nerf__adam hp = {1e-2, 1e-3, 100.0, 0.9, 0.99, 1e-15, 0.0, 0.0, 0.0};
    enum { N = 3 };
    float p[N] = {0.5f, -0.25f, 1.0f}, g[N], m[N] = {0}, v[N] = {0};
    float r1[N] = {1.0f, 1.0f, 0.0f}, r2[N] = {1.0f, 1.0f, 0.0f};
    const float m2 = 0.125f, v2 = 0.0625f;
    m[2] = m2;
    v[2] = v2;
    float pr = p[0], mr = 0.0f, vr = 0.0f; /* entry 0 by the plain rule */
    for (uint64_t step = 50; step < 80; step++) {
        const float grad = 0.25f * (float)(step % 5 + 1);
        g[0] = g[2] = grad;
        g[1] = 0.0f;
        nerf__adam_update_corrected(&hp, 1e-2, N, p, g, m, v, r1, r2);
        float gr = grad;
        const uint64_t k = step - 49;
        nerf__adam_update(&hp, k, 1e-2, 1, &pr, &gr, &mr, &vr,
                          NERF__ADAM_SPARSE);
        CHECK(g[0] == 0.0f && g[2] == 0.0f);
        CHECK(m[0] == mr && v[0] == vr);
        CHECK_NEAR(p[0], pr, 1e-6);
        CHECK_NEAR(r1[0], pow(0.9, (double)k), 1e-6);
        CHECK_NEAR(r2[0], pow(0.99, (double)k), 1e-6);
    }
    /* Untouched: values and corrections as they were. */
    CHECK(p[1] == -0.25f && m[1] == 0.0f && v[1] == 0.0f);
    CHECK(r1[1] == 1.0f && r2[1] == 1.0f);
    /* Powers at 0 (corrections of 1) stay 0. */
    CHECK(r1[2] == 0.0f && r2[2] == 0.0f);
    float p3 = 1.0f, m3 = m2, v3 = v2;
    for (uint64_t step = 50; step < 80; step++) {
        const float grad = 0.25f * (float)(step % 5 + 1);
        m3 = 0.9f * m3 + (float)(1.0 - 0.9) * grad;
        v3 = 0.99f * v3 + (float)(1.0 - 0.99) * grad * grad;
        p3 -= 1e-2f * m3 / (sqrtf(v3) + 1e-15f);
    }
    CHECK_NEAR(p[2], p3, 1e-6);
    /* The powers go to 0 without passing through subnormals: flushed
     * below 2^-26, where 1 - beta^k is 1 in float anyway. */
    for (int k = 0; k < 2000; k++) {
        g[0] = 0.5f;
        const float r2_was = r2[0];
        nerf__adam_update_corrected(&hp, 1e-2, 1, p, g, m, v, r1, r2);
        CHECK(r1[0] == 0.0f || r1[0] >= 0x1p-26f);
        CHECK(r2[0] == 0.0f || r2[0] >= 0x1p-26f);
        if (r2_was > 0.0f && r2[0] == 0.0f) {
            CHECK(1.0f - r2_was * 0.99f == 1.0f);
        }
    }
    CHECK(r1[0] == 0.0f && r2[0] == 0.0f);
}

/* A range of many parameters, updated by vectors (masked, skipping those
 * whose gradients are all zero), gives what updating each parameter alone
 * gives, bit for bit: 16-wide blocks touched, partly touched and
 * untouched, and a remainder shorter than one. */
TEST(corrected_update_in_blocks)
{
    nerf__adam hp = {1e-2, 1e-3, 100.0, 0.9, 0.99, 1e-15, 0.0, 0.0, 0.0};
    enum { N = 16 * 9 + 5, OFF = 3 };
    static float p[N], g[N], m[N], v[N], r1[N], r2[N];
    static float pa[N], ga[N], ma[N], va[N], r1a[N], r2a[N];
    for (int i = 0; i < N; i++) {
        p[i] = pa[i] = 0.01f * (float)(i % 13) - 0.05f;
        m[i] = ma[i] = v[i] = va[i] = 0.0f;
        r1[i] = r1a[i] = r2[i] = r2a[i] = 1.0f;
    }
    for (int step = 0; step < 6; step++) {
        for (int i = 0; i < N; i++) {
            /* The range's blocks 2 and 6 untouched; 4 touched at one
             * parameter; the rest at most parameters, changing with the
             * step. */
            const int block = (i - OFF) / 16;
            const int touched = block == 2 || block == 6 ? 0
                              : block == 4 ? (i - OFF) % 16 == 7
                              : (i * 7 + step) % 5 != 0;
            g[i] = ga[i] = touched ? 0.1f * (float)((i + step) % 9) - 0.4f
                                   : 0.0f;
        }
        nerf__adam_update_corrected(&hp, 1e-2, N - OFF, p + OFF, g + OFF,
                                    m + OFF, v + OFF, r1 + OFF, r2 + OFF);
        for (int i = OFF; i < N; i++) {
            nerf__adam_update_corrected(&hp, 1e-2, 1, pa + i, ga + i, ma + i,
                                        va + i, r1a + i, r2a + i);
        }
    }
    int differ = 0, changed = 0;
    for (int i = 0; i < N; i++) {
        differ += p[i] != pa[i] || m[i] != ma[i] || v[i] != va[i] ||
                  r1[i] != r1a[i] || r2[i] != r2a[i] ||
                  (i >= OFF && g[i] != 0.0f);
        changed += r1[i] != 1.0f;
    }
    CHECK(differ == 0);
    /* Not all touched, not none: the test saw both kinds of block. */
    CHECK(changed > 16 && changed < N - 32);
    CHECK(r1[OFF + 2 * 16 + 5] == 1.0f && r1[OFF + 4 * 16 + 7] < 1.0f);
}

/* The corrected update through each kernel the processor can run (the
 * portable loop, AVX2's, AVX-512's) gives the same bits: every operation
 * is one IEEE rounding, in the same order.  Ranges that start at each
 * offset within a cache line, blocks touched whole, in part or not at
 * all, gradients of -0 (untouched), subnormal and NaN, and powers on
 * either side of their flush to 0, in blocks whose powers have all
 * flushed or all but one. */
TEST(corrected_kernels_agree)
{
    nerf__adam hp = {1e-2, 1e-3, 100.0, 0.9, 0.99, 1e-15, 0.0, 0.0, 0.0};
    enum { N = 16 * 12 + 7, ARRAYS = 6, STEPS = 5 };
    static float want[ARRAYS][N], got[ARRAYS][N];
    static const int isas[] = {NERF__ISA_AVX2, NERF__ISA_AVX512};
    const char *isa_names[] = {"avx2", "avx512"};
    int compared = 0;
    for (size_t k = 0; k < sizeof isas / sizeof isas[0]; k++) {
        if (isas[k] > nerf__isa_cpu()) {
            continue;
        }
        for (int off = 0; off < 16; off++) {
            float (*a[2])[N] = {want, got};
            for (int w = 0; w < 2; w++) {
                uint32_t s = 12345u;
                for (int i = 0; i < N; i++) {
                    s = s * 1664525u + 1013904223u;
                    a[w][0][i] = (float)(s >> 8) * 0x1p-24f - 0.5f;
                    a[w][2][i] = a[w][3][i] = 0.0f;
                    /* Some powers a step from their flush, and blocks
                     * whose powers have all flushed but one, or all. */
                    a[w][4][i] = i % 11 == 0 ? 0x1p-26f / 0.9f * 1.0001f
                                             : 1.0f;
                    a[w][5][i] = i % 13 == 0 ? 0x1p-26f : 1.0f;
                    if (i / 16 == 7 || (i / 16 == 8 && i % 16 != 4)) {
                        a[w][4][i] = a[w][5][i] = 0.0f;
                    }
                }
            }
            for (int step = 0; step < STEPS; step++) {
                for (int i = 0; i < N; i++) {
                    const int block = i / 16;
                    float g = 0.05f * (float)((i * 7 + step) % 9) - 0.2f;
                    if (i == 100 && step == STEPS - 1) {
                        g = NAN;
                    } else if (block == 3 || (block == 5 && i % 16 != 9) ||
                               (i * 3 + step) % 4 == 0) {
                        g = 0.0f;
                    } else if (i % 17 == 0) {
                        g = -0.0f;
                    } else if (i % 19 == 0) {
                        g = 0x1p-140f;
                    }
                    want[1][i] = got[1][i] = g;
                }
                const size_t n = N - (size_t)off;
                nerf__adam_update_corrected_isa(NERF__ISA_BASELINE, &hp, 1e-2,
                                                n, want[0] + off,
                                                want[1] + off, want[2] + off,
                                                want[3] + off, want[4] + off,
                                                want[5] + off);
                nerf__adam_update_corrected_isa(isas[k], &hp, 1e-2, n,
                                                got[0] + off, got[1] + off,
                                                got[2] + off, got[3] + off,
                                                got[4] + off, got[5] + off);
            }
            CHECK(memcmp(want, got, sizeof want) == 0);
            CHECK(isnan(got[0][100]) == (off <= 100));
        }
        printf("  %s kernel: the same bits as the portable loop\n",
               isa_names[k]);
        compared++;
    }
    if (compared == 0) {
        printf("  no other kernel on this processor than the portable "
               "loop\n");
    }
}

/* A hash-grid model keeps corrections for its table's parameters, not
 * for its layers'. */
TEST(model_corrections)
{
    nerf_model *m = grid_model();
    if (m == NULL) {
        return;
    }
    const size_t table = m->nets[0].pos_params, t = m->n_table;
    CHECK(m->corrected && t == m->nets[0].pos_enc.u.hash.count);
    for (int step = 0; step < 2; step++) {
        nerf__model_zero_grad(m);
        m->grads[table + 1] = 0.5f;
        m->grads[table + 2 + (size_t)step] = 0.5f;
        m->grads[m->n_params - 1] = 0.5f; /* a layer's */
        CHECK_OK(nerf__model_adam_step(m));
    }
    /* 0.9^k, then 0.99^k, for k updates. */
    CHECK(m->adam_r[t + 0] == 1.0f && m->adam_r[0] == 1.0f);
    CHECK_NEAR(m->adam_r[t + 1], 0.99 * 0.99, 1e-7);
    CHECK_NEAR(m->adam_r[t + 2], 0.99, 1e-7);
    CHECK_NEAR(m->adam_r[t + 3], 0.99, 1e-7);
    CHECK_NEAR(m->adam_r[1], 0.9 * 0.9, 1e-7);
    nerf_model_destroy(m);

    /* The paper's models have no table to correct. */
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    CHECK_OK(nerf_model_create(&m, &o));
    CHECK(m && !m->corrected && m->adam_r == NULL);
    nerf_model_destroy(m);
}

TEST(schedule)
{
    nerf__adam hp = {5e-4, 5e-5, 250000.0, 0.9, 0.999, 1e-7, 0.0, 0.0, 0.0};
    CHECK_NEAR(nerf__adam_rate(&hp, 0), 5e-4, 1e-15);
    CHECK_NEAR(nerf__adam_rate(&hp, 250000), 5e-5, 1e-15);
    CHECK_NEAR(nerf__adam_rate(&hp, 125000), sqrt(5e-4 * 5e-5), 1e-15);
}

/* With a decay start, the rate holds until it, then covers the same tenfold
 * decay over the steps left; a start of 0 gives the plain schedule bit for
 * bit. */
TEST(schedule_with_a_start)
{
    nerf__adam hp = {1e-2, 1e-3, 1000.0, 0.9, 0.99, 1e-15, 0.0, 200.0, 0.0};
    CHECK(nerf__adam_rate(&hp, 0) == 1e-2);
    CHECK(nerf__adam_rate(&hp, 200) == 1e-2);
    CHECK_NEAR(nerf__adam_rate(&hp, 600), sqrt(1e-2 * 1e-3), 1e-15);
    CHECK_NEAR(nerf__adam_rate(&hp, 1000), 1e-3, 1e-15);
    CHECK(nerf__adam_rate(&hp, 1400) < 1e-3); /* decaying on, as before */
    nerf__adam plain = hp;
    plain.decay_start = 0.0;
    for (uint64_t t = 0; t < 2000; t += 37) {
        double want = plain.lr * pow(plain.lr_final / plain.lr,
                                     (double)t / plain.decay_steps);
        CHECK(nerf__adam_rate(&plain, t) == want);
    }
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
    /* The tiny preset's rates: 5e-3 decaying to a tenth. */
    CHECK_NEAR(nerf_model_learning_rate(m), 5e-3, 1e-15);
    float before = m->params[7];
    nerf__model_zero_grad(m);
    for (size_t i = 0; i < m->n_params; i++) {
        m->grads[i] = 1.0f;
    }
    nerf__model_adam_step(m);
    CHECK_EQ_INT(nerf_model_step(m), 1);
    /* First Adam step moves every parameter by lr * g/|g| (up to eps). */
    CHECK_NEAR(before - m->params[7], 5e-3, 2e-8);
    CHECK_NEAR(nerf_model_learning_rate(m), sqrt(5e-3 * 5e-4), 1e-15);
    nerf_model_destroy(m);
}

int main(void)
{
    RUN(three_steps_by_hand);
    RUN(weight_decay);
    RUN(moments_rounded_as_written);
    RUN(sparse_skips_untouched);
    RUN(model_regions);
    RUN(corrected_update);
    RUN(corrected_update_in_blocks);
    RUN(corrected_kernels_agree);
    RUN(model_corrections);
    RUN(schedule);
    RUN(schedule_with_a_start);
    RUN(model_step_uses_schedule);
    HARNESS_EXIT();
}
