/*
 * Hash-grid encoding: layout, the paper's hash on known coordinates,
 * values against closed forms, gradients against finite differences,
 * determinism of the scatter-add, boundary handling, initialisation.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../harness.h"
#include "hashgrid.h"
#include "nerf.h"
#include "rng.h"

static nerf__hashgrid make(uint32_t L, uint32_t F, uint32_t log2_table,
                           uint32_t nmin, uint32_t nmax, const float lo[3],
                           const float hi[3])
{
    nerf__hashgrid hg;
    memset(&hg, 0, sizeof hg);
    hg.levels = L;
    hg.features = F;
    hg.log2_table = log2_table;
    hg.min_resolution = nmin;
    hg.max_resolution = nmax;
    for (int a = 0; a < 3; a++) {
        hg.bound_min[a] = lo[a];
        hg.bound_max[a] = hi[a];
    }
    CHECK_OK(nerf__hashgrid_layout(&hg));
    return hg;
}

static const float unit_lo[3] = {0.0f, 0.0f, 0.0f},
                   unit_hi[3] = {1.0f, 1.0f, 1.0f};
static const float odd_lo[3] = {-1.0f, -2.0f, 0.5f},
                   odd_hi[3] = {1.0f, 2.0f, 1.5f};

static void random_positions(float *pos, size_t n, const float lo[3],
                             const float hi[3], float margin, uint64_t stream)
{
    nerf__rng r = nerf__rng_make(7, stream);
    for (size_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            float e = hi[a] - lo[a];
            pos[3 * i + a] = lo[a] - margin * e +
                             (1.0f + 2.0f * margin) * e * nerf__rng_uniform(&r);
        }
    }
}

/*
 * Reference forward in double, written from the definition: clamp to the
 * bound, scale by N_l, interpolate the 8 corners found through
 * nerf__hashgrid_index (itself checked against hand values below).
 */
static void reference(const nerf__hashgrid *hg, const float *table,
                      const float *x, double *out)
{
    for (uint32_t l = 0; l < hg->levels; l++) {
        double N = hg->resolution[l];
        uint32_t i0[3];
        double f[3];
        for (int a = 0; a < 3; a++) {
            double u = ((double)x[a] - hg->bound_min[a]) /
                       ((double)hg->bound_max[a] - hg->bound_min[a]);
            u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
            double p = u * N;
            double fl = floor(p);
            if (fl > N - 1) {
                fl = N - 1;
            }
            i0[a] = (uint32_t)fl;
            f[a] = p - fl;
        }
        for (uint32_t k = 0; k < hg->features; k++) {
            out[l * hg->features + k] = 0.0;
        }
        for (int c = 0; c < 8; c++) {
            int b[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
            double w = 1.0;
            for (int a = 0; a < 3; a++) {
                w *= b[a] ? f[a] : 1.0 - f[a];
            }
            uint32_t e = nerf__hashgrid_index(hg, l, i0[0] + b[0], i0[1] + b[1],
                                              i0[2] + b[2]);
            CHECK(e < hg->entries[l]);
            for (uint32_t k = 0; k < hg->features; k++) {
                out[l * hg->features + k] +=
                    w * table[hg->offset[l] + (size_t)e * hg->features + k];
            }
        }
    }
}

TEST(default_layout)
{
    nerf__hashgrid hg;
    CHECK_OK(nerf__hashgrid_defaults(&hg, odd_lo, odd_hi));
    CHECK_EQ_INT(hg.levels, 16);
    CHECK_EQ_INT(hg.features, 2);
    CHECK_EQ_INT(hg.log2_table, 19);
    CHECK_EQ_INT(nerf__hashgrid_width(&hg), 32);
    /* floor(16 b^l), b = 128^(1/15) = 1.3819..., worked out by hand: the
     * last one is 2048 exactly, whose unrounded value 2048.000000000003
     * must not fall to 2047. */
    static const uint32_t want[16] = {16,  22,   30,   42,  58,  80,
                                      111, 153,  212,  294, 406, 561,
                                      776, 1072, 1482, 2048};
    size_t offset = 0;
    for (uint32_t l = 0; l < 16; l++) {
        CHECK_EQ_INT(hg.resolution[l], want[l]);
        /* 59^3 = 205379 fits 2^19 = 524288; 81^3 = 531441 does not. */
        CHECK_EQ_INT(hg.dense[l], l < 5);
        uint64_t side = want[l] + 1u;
        CHECK_EQ_INT(hg.entries[l], l < 5 ? side * side * side : 524288u);
        CHECK_EQ_INT(hg.offset[l], offset);
        offset += 2u * hg.entries[l];
    }
    CHECK_EQ_INT(hg.count, offset);
}

TEST(layout_rejects_bad_configs)
{
    nerf__hashgrid hg;
    CHECK_OK(nerf__hashgrid_defaults(&hg, unit_lo, unit_hi));
    CHECK_EQ_INT(nerf__hashgrid_defaults(&hg, unit_hi, unit_lo), NERF_EINVAL);
    CHECK_OK(nerf__hashgrid_defaults(&hg, unit_lo, unit_hi));
    nerf__hashgrid bad = hg;
    bad.levels = 0;
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    bad = hg;
    bad.levels = NERF__HASHGRID_MAX_LEVELS + 1;
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    bad = hg;
    bad.features = 0;
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    bad = hg;
    bad.log2_table = 40;
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    bad = hg;
    bad.max_resolution = 8; /* below min */
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    bad = hg;
    bad.min_resolution = 0;
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    bad = hg;
    bad.bound_max[1] = bad.bound_min[1];
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    bad = hg;
    bad.bound_min[2] = NAN;
    CHECK_EQ_INT(nerf__hashgrid_layout(&bad), NERF_EINVAL);
    /* One level is legal: it sits at N_min. */
    bad = hg;
    bad.levels = 1;
    CHECK_OK(nerf__hashgrid_layout(&bad));
    CHECK_EQ_INT(bad.resolution[0], 16);
}

TEST(hash_of_the_paper_on_known_coordinates)
{
    /*
     * (3, 5, 7), by hand, mod 2^32:
     *   5 * 2654435761 = 13272178805 = 3 * 2^32 + 387276917
     *   7 * 805459861  =  5638219027 = 1 * 2^32 + 1343251731
     *   3 ^ 387276917 ^ 1343251731 = 0x47050565
     * so 0x47050565 mod 2^19 = 329061 and mod 2^10 = 357.
     * (1, 1, 1): 1 ^ 2654435761 ^ 805459861 = 0xae352e25, mod 2^19 = 339493.
     * (64, 0, 64): 64 * 805459861 = 51549431104 = 12 * 2^32 + 9823552,
     *   64 ^ 9823552 = 0x95e500 (64 is bit 6, already set in 9823552), mod
     *   2^19 = 386304.
     */
    CHECK_EQ_INT(nerf__hashgrid_hash(3, 5, 7, 19), 329061);
    CHECK_EQ_INT(nerf__hashgrid_hash(3, 5, 7, 10), 357);
    CHECK_EQ_INT(nerf__hashgrid_hash(3, 5, 7, 28), 0x47050565u & 0xfffffffu);
    CHECK_EQ_INT(nerf__hashgrid_hash(1, 1, 1, 19), 339493);
    CHECK_EQ_INT(nerf__hashgrid_hash(64, 0, 64, 19), 386304);
    CHECK_EQ_INT(nerf__hashgrid_hash(0, 0, 0, 19), 0);

    /* The forward reads that entry: level 1 (N 64, 65^3 > 2^10) is hashed,
     * and the vertex (3, 5, 7) / 64 is exactly representable, so all the
     * weight is on corner (3, 5, 7). */
    nerf__hashgrid hg = make(2, 2, 10, 4, 64, unit_lo, unit_hi);
    CHECK(hg.dense[0]);
    CHECK(!hg.dense[1]);
    CHECK_EQ_INT(hg.resolution[1], 64);
    CHECK_EQ_INT(nerf__hashgrid_index(&hg, 1, 3, 5, 7), 357);
    /* Dense level 0: i + 5 (j + 5 k). */
    CHECK_EQ_INT(nerf__hashgrid_index(&hg, 0, 1, 2, 3), 1 + 5 * (2 + 5 * 3));
    float *table = calloc(hg.count, sizeof(float));
    table[hg.offset[1] + 357 * 2 + 0] = 1.5f;
    table[hg.offset[1] + 357 * 2 + 1] = -2.5f;
    const float x[3] = {3.0f / 64.0f, 5.0f / 64.0f, 7.0f / 64.0f};
    float out[4];
    nerf__hashgrid_forward(&hg, table, 1, x, 3, out, 4, 1);
    CHECK(out[2] == 1.5f);
    CHECK(out[3] == -2.5f);
    CHECK(out[0] == 0.0f && out[1] == 0.0f);
    free(table);
}

/* Table of a dense level set to a linear function of the vertex: feature
 * k of vertex (i, j, l) at level v is c0 + c1 i + c2 j + c3 l, with the
 * coefficients depending on (v, k). */
static void coefficients(uint32_t level, uint32_t k, double c[4])
{
    c[0] = 0.25 * level - 0.5 * k;
    c[1] = 0.125 + 0.01 * level;
    c[2] = -0.0625 * (k + 1);
    c[3] = 0.03 * (level + 1) - 0.02 * k;
}

static float *linear_table(const nerf__hashgrid *hg)
{
    float *table = calloc(hg->count, sizeof(float));
    for (uint32_t v = 0; v < hg->levels; v++) {
        uint32_t side = hg->resolution[v] + 1;
        for (uint32_t l = 0; l < side; l++) {
            for (uint32_t j = 0; j < side; j++) {
                for (uint32_t i = 0; i < side; i++) {
                    uint32_t e = nerf__hashgrid_index(hg, v, i, j, l);
                    for (uint32_t k = 0; k < hg->features; k++) {
                        double c[4];
                        coefficients(v, k, c);
                        table[hg->offset[v] + (size_t)e * hg->features + k] =
                            (float)(c[0] + c[1] * i + c[2] * j + c[3] * l);
                    }
                }
            }
        }
    }
    return table;
}

/* The linear function at position x, as the grid should reproduce it. */
static double linear_value(const nerf__hashgrid *hg, uint32_t v, uint32_t k,
                           const float *x)
{
    double c[4], p[3];
    coefficients(v, k, c);
    for (int a = 0; a < 3; a++) {
        double u = ((double)x[a] - hg->bound_min[a]) /
                   ((double)hg->bound_max[a] - hg->bound_min[a]);
        u = u < 0.0 ? 0.0 : u > 1.0 ? 1.0 : u;
        p[a] = u * hg->resolution[v];
    }
    return c[0] + c[1] * p[0] + c[2] * p[1] + c[3] * p[2];
}

TEST(dense_levels_reproduce_a_linear_function)
{
    /* N 4..16 over 3 levels: 17^3 = 4913 <= 2^13, all dense. */
    nerf__hashgrid hg = make(3, 3, 13, 4, 16, odd_lo, odd_hi);
    for (uint32_t v = 0; v < 3; v++) {
        CHECK(hg.dense[v]);
    }
    CHECK_EQ_INT(hg.resolution[1], 8);
    float *table = linear_table(&hg);
    enum { n = 1000 };
    float *pos = malloc(n * 3 * sizeof(float));
    random_positions(pos, n, odd_lo, odd_hi, 0.2f, 1);
    /* Corners and faces of the bound, exactly. */
    for (int c = 0; c < 8; c++) {
        for (int a = 0; a < 3; a++) {
            pos[3 * c + a] = (c >> a) & 1 ? odd_hi[a] : odd_lo[a];
        }
    }
    const size_t stride = 9 + 2;
    float *out = malloc(n * stride * sizeof(float));
    nerf__hashgrid_forward(&hg, table, n, pos, 3, out, stride, 1);
    double worst = 0.0;
    for (size_t i = 0; i < n; i++) {
        for (uint32_t v = 0; v < 3; v++) {
            for (uint32_t k = 0; k < 3; k++) {
                double want = linear_value(&hg, v, k, &pos[3 * i]);
                double err = fabs(out[i * stride + v * 3 + k] - want);
                worst = err > worst ? err : worst;
            }
        }
    }
    /* Values up to about 2: a few float roundings of the position and of
     * the 8-term sum. */
    CHECK(worst < 2e-5);
    if (worst >= 2e-5) {
        printf("  worst error %g\n", worst);
    }
    free(out);
    free(pos);
    free(table);
}

static void check_against_reference(uint32_t F)
{
    /* Levels 0 and 1 dense, the rest hashed into 2^12 entries. */
    nerf__hashgrid hg = make(5, F, 12, 6, 96, odd_lo, odd_hi);
    CHECK(hg.dense[0]);
    CHECK(!hg.dense[4]);
    float *table = malloc(hg.count * sizeof(float));
    nerf__rng r = nerf__rng_make(3, F);
    for (size_t i = 0; i < hg.count; i++) {
        table[i] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
    }
    enum { n = 700 }; /* not a multiple of the tile */
    float pos[n * 3];
    random_positions(pos, n, odd_lo, odd_hi, 0.1f, 2);
    const uint32_t W = nerf__hashgrid_width(&hg);
    const size_t stride = W + 3;
    float *out = malloc(n * stride * sizeof(float));
    memset(out, 0x7f, n * stride * sizeof(float));
    nerf__hashgrid_forward(&hg, table, n, pos, 3, out, stride, 1);
    double ref[NERF__HASHGRID_MAX_LEVELS * NERF__HASHGRID_MAX_FEATURES];
    int bad = 0;
    for (size_t i = 0; i < n && bad < 5; i++) {
        reference(&hg, table, &pos[3 * i], ref);
        for (uint32_t j = 0; j < W; j++) {
            /* The float position u N is off by up to about N 2^-24 cells
             * and entries differ by up to 2 per cell on each of 3 axes;
             * a wrong corner would be off by ~0.5. */
            double tol =
                2e-6 + 3.0 * 2.0 * hg.resolution[j / F] * 0x1p-24 * 2.0;
            if (fabs(out[i * stride + j] - ref[j]) > tol) {
                FAILF("F=%u sample %zu element %u: %.9g vs %.9g", F, i, j,
                      out[i * stride + j], ref[j]);
                bad++;
            }
        }
        for (size_t j = W; j < stride; j++) {
            unsigned char b;
            memcpy(&b, (char *)&out[i * stride + j], 1);
            CHECK_EQ_INT(b, 0x7f);
        }
    }
    free(out);
    free(table);
}

TEST(hashed_levels_against_reference)
{
    /* 1, 2, 4 and 8 have their own unrolled kernels, 3 the generic one. */
    check_against_reference(1);
    check_against_reference(2);
    check_against_reference(3);
    check_against_reference(4);
    check_against_reference(8);
}

static double loss(const nerf__hashgrid *hg, const float *table, size_t n,
                   const float *pos, const float *c, float *out)
{
    const uint32_t W = nerf__hashgrid_width(hg);
    nerf__hashgrid_forward(hg, table, n, pos, 3, out, W, 1);
    double s = 0.0;
    for (size_t i = 0; i < n * W; i++) {
        s += (double)c[i] * out[i];
    }
    return s;
}

/* The backward of a grid of F features an entry against finite
 * differences of the forward. */
static void check_gradient(uint32_t F)
{
    nerf__hashgrid hg = make(4, F, 9, 3, 40, odd_lo, odd_hi);
    CHECK(hg.dense[0]);
    CHECK(!hg.dense[3]);
    enum { n = 300 };
    const uint32_t W = nerf__hashgrid_width(&hg);
    float pos[n * 3];
    random_positions(pos, n, odd_lo, odd_hi, 0.05f, 3);
    float *c = malloc(n * W * sizeof(float));
    float *out = malloc(n * W * sizeof(float));
    float *table = malloc(hg.count * sizeof(float));
    float *grad = calloc(hg.count, sizeof(float));
    nerf__rng r = nerf__rng_make(4, 0);
    for (size_t i = 0; i < n * W; i++) {
        c[i] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
    }
    for (size_t i = 0; i < hg.count; i++) {
        table[i] = 0.5f * nerf__rng_uniform(&r) - 0.25f;
    }
    /* loss = sum c * out, so d loss / d out = c. */
    nerf__hashgrid_backward(&hg, n, pos, 3, c, W, grad, 1);
    size_t checked = 0, nonzero = 0;
    double worst = 0.0;
    for (size_t e = 0; e < hg.count; e += 1 + e % 7) {
        float keep = table[e];
        const float h = 0.125f; /* the loss is linear in the table */
        table[e] = keep + h;
        double lp = loss(&hg, table, n, pos, c, out);
        table[e] = keep - h;
        double lm = loss(&hg, table, n, pos, c, out);
        table[e] = keep;
        double fd = (lp - lm) / (2.0 * h);
        double err = fabs(fd - grad[e]) / (1.0 + fabs(fd));
        worst = err > worst ? err : worst;
        checked++;
        nonzero += grad[e] != 0.0f;
    }
    CHECK(worst < 1e-4);
    if (worst >= 1e-4) {
        printf("  %u features: worst relative error %g over %zu entries\n",
               F, worst, checked);
    }
    /* Both touched and untouched entries were compared. */
    CHECK(nonzero > 50);
    CHECK(checked - nonzero > 10);

    /* Backward adds to what grad holds. */
    float *added = malloc(hg.count * sizeof(float));
    for (size_t e = 0; e < hg.count; e++) {
        added[e] = 1.0f;
    }
    nerf__hashgrid_backward(&hg, n, pos, 3, c, W, added, 1);
    for (size_t e = 0; e < hg.count; e++) {
        if (fabs(added[e] - 1.0f - grad[e]) > 1e-5 * (1.0 + fabs(grad[e]))) {
            FAILF("entry %zu: %g added to 1, %g added to 0", e, added[e],
                  grad[e]);
            break;
        }
    }
    free(added);
    free(grad);
    free(table);
    free(out);
    free(c);
}

/* 2 features an entry (Mueller et al.'s) and 4 (the fast preset's since
 * 0.10.8) have kernels of their own. */
TEST(gradient_matches_finite_differences)
{
    check_gradient(2);
    check_gradient(4);
}

TEST(backward_is_deterministic_across_runs_and_threads)
{
    nerf__hashgrid hg = make(8, 2, 12, 8, 256, odd_lo, odd_hi);
    enum { n = 50000 }; /* enough for several threads to be used */
    const uint32_t W = nerf__hashgrid_width(&hg);
    float *pos = malloc(n * 3 * sizeof(float));
    float *d = malloc(n * W * sizeof(float));
    random_positions(pos, n, odd_lo, odd_hi, 0.0f, 5);
    nerf__rng r = nerf__rng_make(5, 1);
    for (size_t i = 0; i < (size_t)n * W; i++) {
        d[i] = 2.0f * nerf__rng_uniform(&r) - 1.0f;
    }
    float *first = calloc(hg.count, sizeof(float));
    float *again = malloc(hg.count * sizeof(float));
    nerf__hashgrid_backward(&hg, n, pos, 3, d, W, first, 1);
    const uint32_t threads[] = {1, 2, 3, 4, 8, 1, 2};
    for (size_t t = 0; t < sizeof threads / sizeof threads[0]; t++) {
        memset(again, 0, hg.count * sizeof(float));
        nerf__hashgrid_backward(&hg, n, pos, 3, d, W, again, threads[t]);
        if (memcmp(first, again, hg.count * sizeof(float)) != 0) {
            FAILF("backward with %u threads differs from 1 thread", threads[t]);
        }
    }
    /* Forward too: every element is computed the same way whatever the
     * split. */
    float *out1 = malloc(n * W * sizeof(float));
    float *out2 = malloc(n * W * sizeof(float));
    nerf__hashgrid_forward(&hg, first, n, pos, 3, out1, W, 1);
    nerf__hashgrid_forward(&hg, first, n, pos, 3, out2, W, 3);
    CHECK(memcmp(out1, out2, (size_t)n * W * sizeof(float)) == 0);
    free(out2);
    free(out1);
    free(again);
    free(first);
    free(d);
    free(pos);
}

TEST(inputs_outside_the_bound_are_clamped)
{
    nerf__hashgrid hg = make(4, 2, 10, 4, 64, odd_lo, odd_hi);
    float *table = malloc(hg.count * sizeof(float));
    nerf__hashgrid_init(&hg, table, 9, 0);
    for (size_t i = 0; i < hg.count; i++) {
        table[i] *= 1e4f; /* values of order 1 */
    }
    /* Pairs (outside or odd, where it must land). */
    const float cases[][2][3] = {
        {{-5.0f, 0.3f, 1.0f}, {-1.0f, 0.3f, 1.0f}},
        {{0.2f, 7.0f, 1.2f}, {0.2f, 2.0f, 1.2f}},
        {{0.2f, -1.0f, -3.0f}, {0.2f, -1.0f, 0.5f}},
        {{INFINITY, -INFINITY, 9.0f}, {1.0f, -2.0f, 1.5f}},
        {{NAN, 0.0f, NAN}, {-1.0f, 0.0f, 0.5f}},
    };
    const uint32_t W = nerf__hashgrid_width(&hg);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        float a[32], b[32];
        nerf__hashgrid_forward(&hg, table, 1, cases[i][0], 3, a, W, 1);
        nerf__hashgrid_forward(&hg, table, 1, cases[i][1], 3, b, W, 1);
        if (memcmp(a, b, W * sizeof(float)) != 0) {
            FAILF("case %zu does not read the clamped position", i);
        }
        for (uint32_t j = 0; j < W; j++) {
            CHECK(isfinite(a[j]));
        }
    }
    /* At the far corner the value is the far vertex's entry exactly. */
    float out[32];
    nerf__hashgrid_forward(&hg, table, 1, odd_hi, 3, out, W, 1);
    for (uint32_t l = 0; l < hg.levels; l++) {
        uint32_t N = hg.resolution[l];
        uint32_t e = nerf__hashgrid_index(&hg, l, N, N, N);
        CHECK(out[l * 2] == table[hg.offset[l] + 2 * e]);
        CHECK(out[l * 2 + 1] == table[hg.offset[l] + 2 * e + 1]);
    }
    nerf__hashgrid_forward(&hg, table, 1, odd_lo, 3, out, W, 1);
    for (uint32_t l = 0; l < hg.levels; l++) {
        CHECK(out[l * 2] == table[hg.offset[l]]);
    }
    /* Gradients of clamped samples go where the forward read. */
    float *g1 = calloc(hg.count, sizeof(float));
    float *g2 = calloc(hg.count, sizeof(float));
    const float ones[32] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1,
                            1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    nerf__hashgrid_backward(&hg, 1, cases[3][0], 3, ones, W, g1, 1);
    nerf__hashgrid_backward(&hg, 1, cases[3][1], 3, ones, W, g2, 1);
    CHECK(memcmp(g1, g2, hg.count * sizeof(float)) == 0);
    free(g2);
    free(g1);
    free(table);
}

TEST(initialisation)
{
    nerf__hashgrid hg = make(6, 2, 12, 4, 128, unit_lo, unit_hi);
    float *a = malloc(hg.count * sizeof(float));
    float *b = malloc(hg.count * sizeof(float));
    nerf__hashgrid_init(&hg, a, 11, 100);
    nerf__hashgrid_init(&hg, b, 11, 100);
    CHECK(memcmp(a, b, hg.count * sizeof(float)) == 0);
    double sum = 0.0, sq = 0.0;
    float lo = 1.0f, hi = -1.0f;
    for (size_t i = 0; i < hg.count; i++) {
        lo = a[i] < lo ? a[i] : lo;
        hi = a[i] > hi ? a[i] : hi;
        sum += a[i];
        sq += (double)a[i] * a[i];
    }
    CHECK(lo >= -1e-4f && hi <= 1e-4f);
    CHECK(lo < -0.99e-4f && hi > 0.99e-4f);
    /* Uniform in +-1e-4: mean 0, variance 1e-8 / 3. */
    double mean = sum / hg.count, var = sq / hg.count - mean * mean;
    CHECK(fabs(mean) < 3e-6);
    CHECK_NEAR(var, 1e-8 / 3.0, 0.05e-8);
    nerf__hashgrid_init(&hg, b, 12, 100);
    CHECK(memcmp(a, b, hg.count * sizeof(float)) != 0);
    /* Level l's stream does not depend on the others: a grid of other
     * levels above the same coarsest one starts the same. */
    nerf__hashgrid small = make(3, 2, 12, 4, 16, unit_lo, unit_hi);
    CHECK_EQ_INT(small.entries[0], hg.entries[0]);
    nerf__hashgrid_init(&small, b, 11, 100);
    CHECK(memcmp(a, b, (size_t)small.entries[0] * 2 * sizeof(float)) == 0);
    free(b);
    free(a);
}

int main(void)
{
    RUN(default_layout);
    RUN(layout_rejects_bad_configs);
    RUN(hash_of_the_paper_on_known_coordinates);
    RUN(dense_levels_reproduce_a_linear_function);
    RUN(hashed_levels_against_reference);
    RUN(gradient_matches_finite_differences);
    RUN(backward_is_deterministic_across_runs_and_threads);
    RUN(inputs_outside_the_bound_are_clamped);
    RUN(initialisation);
    HARNESS_EXIT();
}
