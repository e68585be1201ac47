/*
 * The fast preset (hash grid, small MLPs, ray marching through the
 * occupancy grid) on the built-in scene: it reaches a stated test PSNR
 * within a bounded number of steps; renders that skip the cells its grid
 * marks empty agree with renders that sample every cell; and no training
 * sample ever lies in an empty cell.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "field.h"
#include "model.h"
#include "occupancy.h"
#include "renderer.h"
#include "train_fixture.h"
#include "trainer.h"

/*
 * A smaller hash grid than the preset's (8 levels of 2^15 entries, up to
 * 256 cells across the bound) on a 48x48 scene: enough for its few solids
 * and cheap enough for CI, which also runs this under the sanitizers.
 * These settings reach 28.9 dB from seed 0 in about 20 s of training
 * (release build, 2 cores); most of it is the first 100 steps, whose
 * untrained density leaves half the grid occupied (250 samples a ray,
 * against about 45 later), and the 16 updates of every cell in the first
 * 256 steps.  A processor that rounds its products otherwise sends
 * training down another path, as another seed does, so MIN_PSNR sits
 * below the spread over seeds: NERF_TEST_SEED=0..12 (2026-12, Intel Xeon,
 * 0.11.0) gave 28.12 to 30.47 dB, mean 29.61, sd 0.82 (mean - 4 sd:
 * 26.3), and the runs under NERF_FUSED=0 fell within it.  A model that
 * learns nothing scores 8 dB.
 *
 * NERF_TEST_STEPS, NERF_TEST_BATCH, NERF_TEST_LR, NERF_TEST_PRECROP,
 * NERF_TEST_WIDTH, NERF_TEST_CURVE (print the test PSNR every that many
 * steps), NERF_TEST_FULL (the preset's own hash grid) and NERF_TEST_SEED
 * override the settings for experiments.
 */
#define WIDTH 48
#define N_TRAIN 60
#define N_TEST 4
#define STEPS 400
#define BATCH 256
#define PRECROP 50
#define LEARNING_RATE 1e-2
#define MIN_PSNR 25.0

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static nerf_model *fast_model(uint64_t seed)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_FAST);
    if (!getenv("NERF_TEST_FULL")) {
        o.hash_log2_size = 15;
        o.hash_levels = 8;
        o.hash_max_resolution = 256;
    }
    o.seed = seed;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    return m;
}

static nerf_sampler *fast_sampler(uint64_t seed)
{
    nerf_sampler_options o;
    NERF_SAMPLER_OPTIONS_INIT(&o);
    CHECK_OK(nerf_sampler_options_preset(&o, NERF_PRESET_FAST));
    o.seed = seed;
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &o));
    return s;
}

static nerf_renderer *make_renderer(nerf_model *m, nerf_sampler *s)
{
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.white_background = 1;
    nerf_renderer *r = NULL;
    CHECK_OK(nerf_renderer_create(&r, m, s, &ro));
    return r;
}

/* The trained model the later tests look at. */
static fixture fx;
static nerf_model *trained;
static nerf_sampler *sampler;

TEST(fast_preset_learns_the_builtin_scene)
{
    const int steps = fixture_env_int("NERF_TEST_STEPS", STEPS);
    const int curve = fixture_env_int("NERF_TEST_CURVE", 0);
    const char *env_lr = getenv("NERF_TEST_LR");
    const double lr = env_lr ? atof(env_lr) : LEARNING_RATE;
    sampler = fast_sampler(fixture_seed());
    trained = fast_model(fixture_seed());
    nerf_renderer *r = make_renderer(trained, sampler);
    double before = fixture_renderer_psnr(r, fx.test, NULL);
    CHECK_OK(nerf_model_set_param(trained, NERF_PARAM_LEARNING_RATE, lr));
    CHECK_OK(nerf_model_set_param(trained, NERF_PARAM_LEARNING_RATE_FINAL,
                                  lr / 10));
    CHECK_OK(nerf_model_set_param(trained, NERF_PARAM_DECAY_STEPS, steps));
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = (uint32_t)fixture_env_int("NERF_TEST_BATCH", BATCH);
    o.precrop_steps = (uint32_t)fixture_env_int("NERF_TEST_PRECROP", PRECROP);
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, trained, fx.train, sampler, &o));
    nerf_train_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    double train_time = 0.0, spr = 0.0;
    for (int done = 0; t && done < steps;) {
        int n = curve > 0 && steps - done > curve ? curve : steps - done;
        double t0 = now();
        for (int i = 0; i < n; i++) {
            CHECK_OK(nerf_trainer_step(t, &st));
            spr += st.samples_per_ray;
        }
        train_time += now() - t0;
        done += n;
        if (curve > 0) {
            double p = fixture_renderer_psnr(r, fx.test, NULL);
            const nerf__occupancy *g = trained->grid;
            printf("  step %5d  %6.1f s  train %.2f  test %.2f dB  "
                   "samples/ray %.1f  occupied %.2f%%\n", done, train_time,
                   st.psnr, p, st.samples_per_ray,
                   100.0 * (double)g->occupied / (double)g->cells);
        }
    }
    double t0 = now();
    double after = fixture_renderer_psnr(r, fx.test, NULL);
    double render_time = now() - t0;
    printf("  %d steps in %.1f s (%.1f steps/s, %.1f samples/ray): train "
           "PSNR %.2f, test PSNR %.2f dB (untrained %.2f); test views "
           "rendered in %.2f s\n", steps, train_time, steps / train_time,
           spr / steps, st.psnr, after, before, render_time);
    CHECK(st.samples_per_ray > 0.0);
    CHECK(after >= MIN_PSNR);
    CHECK(after > before + 8.0);
    nerf_trainer_destroy(t);
    nerf_renderer_destroy(r);
}

/*
 * The grid of a trained model marks most of the bound empty.  Skipping
 * those cells is exactly rendering with no density in them: a zero
 * density gives alpha 0 exactly, so the transmittance, the weights and the
 * early termination run through the same values, and renders that skip
 * equal, bit for bit, renders that sample every cell and zero the density
 * of the empty ones, as long as each sample's outputs come from it alone
 * (the fused path).  Where the products hold other rows in the two
 * renders (the CBLAS, oneDNN without brgemm) the occupied samples' values
 * differ by rounding, which can move a ray's cut by a sample, whose
 * weight is below the termination's threshold: then they agree within
 * that threshold and half an 8-bit level, far above such rounding.
 *
 * Without zeroing, a model with an exponential density still has some in
 * the empty cells (its floor, about 0.05 per unit here: training stops
 * pushing it down once the grid skips the cells), which a ray crossing the
 * bound integrates into several percent of opacity.  That render is the
 * worse one (haze in front of the background), so the check there is
 * that skipping costs no PSNR.
 */
static double diff(const float *a, const float *b, size_t n, double *mean)
{
    double worst = 0.0, sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = fabs((double)a[i] - b[i]);
        worst = fmax(worst, d);
        sum += d;
    }
    *mean = sum / n;
    return worst;
}

TEST(skipping_is_rendering_empty_cells_as_empty)
{
    if (trained == NULL) {
        FAILF("no trained model");
        return;
    }
    const nerf__occupancy *g = trained->grid;
    CHECK(g->occupied < g->cells / 4);
    uint32_t w, h;
    nerf_dataset_image_size(fx.test, &w, &h);
    const size_t n = (size_t)N_TEST * w * h * 3;
    float *skip = malloc(n * sizeof(float)), *zero = malloc(n * sizeof(float));
    float *all = malloc(n * sizeof(float));
    nerf_renderer *r = make_renderer(trained, sampler);
    double p_skip = fixture_renderer_psnr(r, fx.test, skip);
    nerf__march_test test = {.everywhere = true, .zero_empty = true};
    CHECK_OK(nerf__renderer_set_march_test(r, &test));
    fixture_renderer_psnr(r, fx.test, zero);
    test.zero_empty = false;
    CHECK_OK(nerf__renderer_set_march_test(r, &test));
    double p_all = fixture_renderer_psnr(r, fx.test, all);
    double mean_zero, mean_all;
    double worst_zero = diff(skip, zero, n, &mean_zero);
    double worst_all = diff(skip, all, n, &mean_all);
    printf("  %.2f%% of the cells occupied.  Against sampling every cell "
           "with the empty ones zeroed: largest difference %.2g, mean "
           "%.2g; not zeroed: %.2g and %.2g, test PSNR %.2f dB (%.2f "
           "skipping)\n", 100.0 * (double)g->occupied / (double)g->cells,
           worst_zero, mean_zero, worst_all, mean_all, p_all, p_skip);
    if (nerf__model_rows_alone(trained)) {
        CHECK(worst_zero == 0.0);
    } else {
        printf("  (rows not computed alone: within the threshold)\n");
        CHECK(worst_zero <= NERF__COMPOSITE_EPS_DEFAULT + 0.5 / 255);
    }
    CHECK(p_skip > p_all - 0.05);
    nerf_renderer_destroy(r);
    free(skip);
    free(zero);
    free(all);
}

/* A training batch through the trained model's grid: every sample the
 * network sees lies in a cell the grid marks occupied, and there are far
 * fewer of them than the lattice points inside the bound. */
TEST(no_sample_in_an_empty_cell)
{
    if (trained == NULL) {
        FAILF("no trained model");
        return;
    }
    enum { RAYS = 512 };
    static float o[3 * RAYS], d[3 * RAYS], rgb[3 * RAYS];
    uint32_t w, h;
    nerf_dataset_image_size(fx.train, &w, &h);
    for (uint32_t k = 0; k < RAYS; k++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(fx.train, k % N_TRAIN, &cam));
        size_t pixel = ((size_t)k * 7919u) % ((size_t)w * h);
        CHECK_OK(nerf_camera_rays(&cam, pixel, 1, o + 3 * k, d + 3 * k));
    }
    nerf__env env;
    nerf__env_default(&env);
    nerf__batch b;
    nerf__batch_init(&b, &env);
    nerf__render_setup s;
    memset(&s, 0, sizeof s);
    s.model = trained;
    s.sampler = sampler;
    s.training = true;
    s.keep = true;
    s.white_background = true;
    nerf__pass_out out[NERF__PASSES];
    memset(out, 0, sizeof out);
    out[0].rgb = rgb;
    size_t marched[2] = {0, 0};
    for (int everywhere = 0; everywhere < 2; everywhere++) {
        nerf__march_test test = {.everywhere = everywhere != 0};
        nerf__batch_set_march_test(&b, &test);
        CHECK_OK(nerf__render_batch(&b, &s, RAYS, o, d, out));
        marched[everywhere] = b.marching.samples.total;
        size_t empty = 0;
        for (size_t i = 0; i < b.marching.samples.total; i++) {
            empty += !nerf__occupancy_occupied(trained->grid,
                                               b.marching.points + 3 * i);
        }
        if (!everywhere) {
            CHECK_EQ_INT(empty, 0);
        } else {
            CHECK(empty > 0);
        }
    }
    printf("  %.1f samples per ray, %.1f without skipping\n",
           (double)marched[0] / RAYS, (double)marched[1] / RAYS);
    CHECK(marched[0] > 0 && 4 * marched[0] < marched[1]);
    nerf__batch_release(&b);
}

/* Each of the last step's rays' marched samples, counted again. */
static size_t *marched_rays(nerf_trainer *t, size_t n)
{
    const nerf__occupancy *g = nerf__model_grid(t->model);
    nerf__march_options mo;
    nerf__render_march_options(&t->setup, g, &mo);
    nerf__march_rays rays = nerf__render_march_rays(&t->setup, n,
                                                    t->origins, t->directions);
    size_t *off = malloc((n + 1) * sizeof *off);
    if (off) {
        nerf__march_count(g, &mo, &rays, off);
    }
    return off;
}

/*
 * A step keeps each ray's samples up to where it turns opaque: the
 * composite of its forward uses every kept sample (so the density pass
 * and the forward agree on the densities), a ray with samples left out is
 * opaque after its kept ones (so it was not cut short), the forward's
 * position encodings are the kept samples' own, and behind the trained
 * scene's surfaces many marched samples are left out, most of them never
 * evaluated by the density pass.
 */
TEST(training_keeps_samples_up_to_opacity)
{
    if (trained == NULL) {
        FAILF("no trained model");
        return;
    }
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = 512;
    o.precrop_steps = 0;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, trained, fx.train, sampler, &o));
    /* The weights the step's forward saw: its Adam update changes them. */
    const size_t P = trained->n_params;
    float *before = malloc(P * sizeof *before);
    if (before) {
        memcpy(before, trained->params, P * sizeof *before);
    }
    nerf_train_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    CHECK_OK(nerf_trainer_step(t, &st));
    const nerf__batch *b = &t->batch;
    const nerf__march_state *mb = &b->marching;
    const nerf__march_samples *ms = &mb->samples;
    const nerf__network *net = &trained->nets[0];
    const size_t n = ms->n_rays, kept = ms->total, E = net->pos_width;
    uint32_t *used = malloc(n * sizeof *used);
    float *rgb = malloc(3 * n * sizeof *rgb);
    float *enc = malloc(kept * E * sizeof *enc);
    size_t *marched = marched_rays(t, n);
    size_t short_rays = 0, cut_short = 0, cut = 0;
    if (used && rgb && enc && before && marched && n == (size_t)st.rays) {
        nerf__packed_out po = {.rgb = rgb, .used = used};
        nerf__composite_packed(&mb->packed, &po);
        const nerf__packed_batch *pb = &mb->packed;
        for (size_t k = 0; k < n; k++) {
            const size_t at = ms->offsets[k];
            const uint32_t m = (uint32_t)(ms->offsets[k + 1] - at);
            short_rays += used[k] != m;
            if (m < marched[k + 1] - marched[k]) {
                nerf__composite_state cs;
                nerf__composite_state_init(&cs);
                nerf__composite_packed_ray(&cs, m, pb->t + at, pb->dt + at,
                                           pb->rgb + 3 * at, pb->sigma + at,
                                           pb->eps, NULL);
                cut++;
                cut_short += !(cs.trans < pb->eps);
            }
        }
        /* The encodings the forward took from the density pass are those
         * of the kept samples. */
        nerf__encoding_forward(&net->pos_enc, before + net->pos_params, kept,
                               mb->points, enc, E);
        const nerf__workspace *ws = &b->ws[0];
        CHECK(memcmp(enc, ws->enc_pos, kept * E * sizeof *enc) == 0);
        CHECK(ws->pos != NULL &&
              memcmp(ws->pos, mb->points, 3 * kept * sizeof *enc) == 0);
    } else {
        FAILF("no batch to look at");
    }
    CHECK_EQ_INT(short_rays, 0);
    CHECK_EQ_INT(cut_short, 0);
    CHECK(cut > 0);
    printf("  %zu samples marched, %zu evaluated by the density pass in %u "
           "rounds, %zu kept; %zu rays cut\n", b->n_evaluated,
           mb->cut.evaluated, mb->cut.rounds, kept, cut);
    /* Some rays were cut, so fewer samples were kept than marched; by how
     * many depends on how opaque training made the model (from 7 to 30%
     * fewer over seeds and kernels), which no fixed share bounds. */
    CHECK(kept < b->n_evaluated);
    CHECK(mb->cut.evaluated >= kept && mb->cut.evaluated < b->n_evaluated);
    free(marched);
    free(used);
    free(rgb);
    free(enc);
    free(before);
    nerf_trainer_destroy(t);
}

/* The samples the last step marched for its ray k, marched again. */
static size_t marched_of_ray(nerf_trainer *t, size_t k)
{
    size_t *off = marched_rays(t, k + 1);
    size_t n = off ? off[k + 1] - off[k] : 0;
    free(off);
    return n;
}

/*
 * With batch_samples a step takes the fewest first rays of its batch whose
 * marched samples reach the budget.  Run last: it trains the model on.
 */
TEST(batch_samples_takes_rays_up_to_a_budget)
{
    if (trained == NULL) {
        FAILF("no trained model");
        return;
    }
    enum { RAYS = 1024, BUDGET = 4000 };
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = RAYS;
    o.batch_samples = BUDGET;
    o.precrop_steps = 0;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, trained, fx.train, sampler, &o));
    for (int k = 0; t && k < 3; k++) {
        nerf_train_stats st;
        memset(&st, 0, sizeof st);
        st.struct_size = sizeof st;
        CHECK_OK(nerf_trainer_step(t, &st));
        const nerf__march_samples *ms = &t->batch.marching.samples;
        const size_t n = (size_t)st.rays;
        CHECK(n >= 1 && n < RAYS && n == ms->n_rays);
        CHECK(ms->total == ms->offsets[n]);
        /* The budget counts marched samples; the batch keeps those before
         * each ray turns opaque. */
        const size_t marched = t->batch.n_evaluated;
        CHECK(marched >= BUDGET && ms->total <= marched);
        CHECK(n == 1 || marched - marched_of_ray(t, n - 1) < BUDGET);
        CHECK(fabs(st.samples_per_ray - (double)marched / (double)n) <
              1e-9 * st.samples_per_ray);
        printf("  step %llu: %zu rays, %zu samples marched (%zu kept) for a "
               "budget of %d\n", (unsigned long long)st.step, n, marched,
               ms->total, BUDGET);
    }
    nerf_trainer_destroy(t);
    /* Out of range. */
    o.batch_samples = (1u << 26) + 1;
    t = NULL;
    CHECK(nerf_trainer_create(&t, trained, fx.train, sampler, &o) ==
          NERF_EINVAL);
    CHECK(t == NULL);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/*
 * The trained model's world-unit depth (nerf_renderer_render_depth) finds
 * the scene's true surface: on the test views' pixels that both the model
 * and the exact field see as opaque, its z depth against the field's
 * expected depth (nerf__scene_render_ray: the same t along the same
 * rays), median and 90th percentile of the difference in scene units.
 * Over NERF_TEST_SEED=0..12 and kernel choices (19 runs, see the top of
 * this file) the median ranged 0.019 to 0.033 (mean + 4 sd: 0.046) and
 * the 90th percentile 0.072 to 0.159 (mean + 4 sd: 0.178); a model that
 * put its surfaces elsewhere is off by tenths of a unit.
 */
#define MAX_MEDIAN_DEPTH_ERR 0.06
#define MAX_P90_DEPTH_ERR 0.25

TEST(depth_finds_the_scene_surface)
{
    if (trained == NULL) {
        FAILF("no trained model");
        return;
    }
    uint32_t w, h;
    nerf_dataset_image_size(fx.test, &w, &h);
    const size_t px = (size_t)w * h;
    float *z = malloc(px * sizeof(float)), *op = malloc(px * sizeof(float));
    float *o = malloc(3 * px * sizeof(float));
    float *d = malloc(3 * px * sizeof(float));
    float *err = malloc(N_TEST * px * sizeof(float));
    nerf_renderer *r = make_renderer(trained, sampler);
    size_t n = 0;
    for (uint32_t v = 0; v < nerf_dataset_count(fx.test); v++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(fx.test, v, &cam));
        CHECK_OK(nerf_renderer_render_depth(r, &cam, NULL, NULL, z, op, px));
        CHECK_OK(nerf_camera_rays(&cam, 0, px, o, d));
        for (size_t k = 0; k < px; k++) {
            float rgb[3], depth;
            float a = nerf__scene_render_ray(o + 3 * k, d + 3 * k, 2.0f, 6.0f,
                                             rgb, &depth);
            if (a > 0.95f && op[k] > 0.95f) {
                err[n++] = fabsf(z[k] - depth / a);
            }
        }
    }
    CHECK(n > px / 4);
    qsort(err, n, sizeof *err, cmp_float);
    double median = n ? err[n / 2] : 1e9, p90 = n ? err[n * 9 / 10] : 1e9;
    printf("     depth against the true surface on %zu pixels: median "
           "%.4f, 90th percentile %.4f scene units\n", n, median, p90);
    CHECK(median < MAX_MEDIAN_DEPTH_ERR);
    CHECK(p90 < MAX_P90_DEPTH_ERR);
    nerf_renderer_destroy(r);
    free(z);
    free(op);
    free(o);
    free(d);
    free(err);
}

int main(void)
{
    const int width = fixture_env_int("NERF_TEST_WIDTH", WIDTH);
    if (fixture_open(&fx, (uint32_t)width, N_TRAIN, N_TEST) != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    RUN(fast_preset_learns_the_builtin_scene);
    RUN(skipping_is_rendering_empty_cells_as_empty);
    RUN(no_sample_in_an_empty_cell);
    RUN(depth_finds_the_scene_surface);
    RUN(training_keeps_samples_up_to_opacity);
    RUN(batch_samples_takes_rays_up_to_a_budget);
    nerf_model_destroy(trained);
    nerf_sampler_destroy(sampler);
    fixture_close(&fx);
    HARNESS_EXIT();
}
