/*
 * Baked models (nerf_bake_*): what they refuse, that their renders follow
 * the networks' on the built-in scene, that skipping empty space is
 * exactly sampling it, and that a pixel does not depend on the image it
 * is rendered in.
 *
 * NERF_TEST_STEPS and NERF_TEST_SEED override the training for
 * experiments.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../train/train_fixture.h"
#include "bake.h"
#include "model.h"
#include "occupancy.h"

#define WIDTH 48
#define N_TRAIN 60
#define N_TEST 4
#define STEPS 400
#define QUICK_STEPS 30
#define BATCH 256

/*
 * The bakes here take 2 subdivisions (256 points across the bound): the
 * views are 48 pixels wide, each pixel spans about 1/40 of the bound.
 */
#define SUBDIVISIONS 2
/*
 * The bake's renders against the networks' on the test views.  What they
 * differ by is the bake's interpolation between points 1/256 of the
 * bound apart and its fit of the colours; a bake that misplaced its
 * bricks, its corners or its colours by one voxel or one channel scores
 * below 20 dB.  Measured: see the test's output.
 */
#define MIN_BAKE_PSNR 28.0

static fixture fx;
static nerf_model *trained;

static bool quick(void)
{
    return getenv("NERF_TEST_QUICK") != NULL;
}

static void train(void)
{
    const int steps = fixture_env_int("NERF_TEST_STEPS",
                                      quick() ? QUICK_STEPS : STEPS);
    nerf_sampler *s = fixture_fast_sampler(fixture_seed());
    trained = fixture_fast_model(fixture_seed(), 8, 15, 256);
    CHECK_OK(nerf_model_set_param(trained, NERF_PARAM_DECAY_STEPS, steps));
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = BATCH;
    o.precrop_steps = 50;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, trained, fx.train, s, &o));
    for (int i = 0; t && i < steps; i++) {
        CHECK_OK(nerf_trainer_step(t, NULL));
    }
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    if (quick()) {
        /* A few steps leave most of the grid occupied, which would take
         * minutes to bake under the sanitizers: keep the cells of a
         * central cube of 16 only, enough for every path of the code. */
        nerf__occupancy *g = trained->grid;
        const uint32_t r = g->res, lo = r / 2 - 8, hi = r / 2 + 8;
        for (size_t c = 0; c < g->cells; c++) {
            const uint32_t x = (uint32_t)(c % r), y = (uint32_t)(c / r % r);
            const uint32_t z = (uint32_t)(c / r / r);
            if (x < lo || x >= hi || y < lo || y >= hi || z < lo || z >= hi) {
                g->bits[c / 64] &= ~((uint64_t)1 << (c % 64));
            }
        }
    }
}

/* The bake options of these tests. */
static nerf_bake_options options(void)
{
    nerf_bake_options o;
    NERF_BAKE_OPTIONS_INIT(&o);
    o.subdivisions = SUBDIVISIONS;
    return o;
}

static bool says(const char *what)
{
    const char *e = nerf_last_error();
    bool ok = e && strstr(e, what) != NULL;
    if (!ok) {
        printf("  error \"%s\" does not say \"%s\"\n", e ? e : "", what);
    }
    return ok;
}

TEST(refuses_what_it_cannot_bake)
{
    nerf_bake *b = (nerf_bake *)&fx; /* must be reset to NULL */
    nerf_bake_options o;
    CHECK_OK(NERF_BAKE_OPTIONS_INIT(&o));
    CHECK(nerf_bake_create(NULL, trained, &o) == NERF_EINVAL);
    CHECK(nerf_bake_create(&b, NULL, &o) == NERF_EINVAL);
    CHECK(b == NULL);
    const struct {
        uint32_t subdivisions, degree, directions;
        const char *says;
    } bad[] = {
        {0, 1, 8, "subdivisions"}, {17, 1, 8, "subdivisions"},
        {4, 3, 16, "sh_degree"},   {4, 2, 8, "directions"},
        {4, 0, 0, "directions"},   {4, 1, 1025, "directions"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        NERF_BAKE_OPTIONS_INIT(&o);
        o.subdivisions = bad[i].subdivisions;
        o.sh_degree = bad[i].degree;
        o.directions = bad[i].directions;
        CHECK(nerf_bake_create(&b, trained, &o) == NERF_EINVAL);
        CHECK(says(bad[i].says));
    }
    /* Too large for the memory allowed: refused before it is made. */
    NERF_BAKE_OPTIONS_INIT(&o);
    o.max_bytes = 1000;
    CHECK(nerf_bake_create(&b, trained, &o) == NERF_ENOMEM);
    CHECK(says("max_bytes"));
    /* A model that does not march has no cells to bake. */
    nerf_model *tiny = tiny_model(1);
    CHECK(nerf_bake_create(&b, tiny, NULL) == NERF_EINVAL);
    CHECK(says("occupancy grid"));
    nerf_model_destroy(tiny);
    /* An appearance code the model does not have. */
    NERF_BAKE_OPTIONS_INIT(&o);
    o.appearance = 3;
    CHECK(nerf_bake_create(&b, trained, &o) == NERF_EINVAL);
    CHECK(says("appearance"));
    CHECK(b == NULL);
    nerf_bake_destroy(NULL);
}

/* Cancelling from the progress callback stops the bake. */
static int stop_at_once(const nerf_progress *p, void *user)
{
    (void)p;
    ++*(int *)user;
    return 1;
}

TEST(progress_can_cancel)
{
    nerf_bake_options o;
    NERF_BAKE_OPTIONS_INIT(&o);
    int calls = 0;
    o.progress = stop_at_once;
    o.progress_user = &calls;
    nerf_bake *b = NULL;
    CHECK(nerf_bake_create(&b, trained, &o) == NERF_ECANCELLED);
    CHECK(b == NULL);
    CHECK_EQ_INT(calls, 1);
}

TEST(renders_follow_the_networks)
{
    nerf_bake *b = NULL;
    const nerf_bake_options o = options();
    CHECK_OK(nerf_bake_create(&b, trained, &o));
    if (b == NULL) {
        return;
    }
    nerf_bake_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    CHECK_OK(nerf_bake_stats_get(b, &st));
    CHECK_EQ_INT(st.resolution, 128 * SUBDIVISIONS);
    CHECK(st.bricks > 0 && st.points > 0 && st.bytes > 0);
    nerf_renderer *r = NULL;
    CHECK_OK(nerf_renderer_create(&r, trained, NULL, NULL));
    const size_t px = (size_t)WIDTH * WIDTH;
    float *net = malloc(px * 3 * sizeof(float));
    float *baked = malloc(px * 3 * sizeof(float));
    float *op = malloc(px * sizeof(float));
    double sum = 0.0;
    const uint32_t n = nerf_dataset_count(fx.test);
    for (uint32_t i = 0; i < n; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(fx.test, i, &cam));
        CHECK_OK(nerf_renderer_render_image(r, &cam, net, NULL, NULL, px));
        CHECK_OK(nerf_bake_render_image(b, &cam, baked, NULL, op, px));
        for (size_t p = 0; p < px; p++) {
            CHECK(op[p] >= 0.0f && op[p] <= 1.0f + 1e-6f);
            for (int c = 0; c < 3; c++) {
                CHECK(baked[3 * p + c] >= 0.0f && baked[3 * p + c] <= 1.0f);
            }
        }
        double p = 0.0;
        CHECK_OK(nerf_psnr(baked, net, px * 3, &p));
        sum += p;
    }
    printf("  %llu bricks, %llu points, %.1f MB: the bake's renders "
           "score %.2f dB against the networks'\n",
           (unsigned long long)st.bricks, (unsigned long long)st.points,
           (double)st.bytes / 1e6, sum / n);
    if (!quick()) {
        CHECK(sum / n >= MIN_BAKE_PSNR);
    }
    free(net);
    free(baked);
    free(op);
    nerf_renderer_destroy(r);
    nerf_bake_destroy(b);
}

/*
 * A render that skips empty space takes the same samples in cells with
 * bricks as one that visits every sample (the skip lands on the ray's
 * lattice of steps, short of the exit by a margin far above its
 * rounding), and samples in cells without bricks add nothing: the same
 * bits.  Also, each pixel is its ray's alone: a view cropped out of a
 * larger one has the same pixels.
 */
TEST(skipping_and_cropping_change_no_pixel)
{
    nerf_bake *b = NULL;
    const nerf_bake_options o = options();
    CHECK_OK(nerf_bake_create(&b, trained, &o));
    if (b == NULL) {
        return;
    }
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_dataset_camera(fx.test, 0, &cam));
    const uint32_t w = cam.width, h = cam.height;
    const size_t px = (size_t)w * h;
    float *a = malloc(px * 3 * sizeof(float));
    float *c = malloc(px * 3 * sizeof(float));
    float *da = malloc(px * sizeof(float));
    float *dc = malloc(px * sizeof(float));
    CHECK_OK(nerf_bake_render_image(b, &cam, a, da, NULL, px));
    const size_t cells = (size_t)b->res * b->res * b->res;
    uint8_t *saved = malloc(cells);
    memcpy(saved, b->empty, cells);
    memset(b->empty, 0, cells);
    CHECK_OK(nerf_bake_render_image(b, &cam, c, dc, NULL, px));
    CHECK(memcmp(a, c, px * 3 * sizeof(float)) == 0);
    CHECK(memcmp(da, dc, px * sizeof(float)) == 0);
    memcpy(b->empty, saved, cells);
    /* The lower right quarter, on its own. */
    nerf_camera q = cam;
    q.width = w / 2 + 3;
    q.height = h / 2 + 1;
    q.cx -= (float)(w - q.width);
    q.cy -= (float)(h - q.height);
    CHECK_OK(nerf_bake_render_image(b, &q, c, NULL, NULL, px));
    for (uint32_t y = 0; y < q.height; y++) {
        const size_t from = ((size_t)(y + h - q.height) * w + (w - q.width));
        CHECK(memcmp(a + 3 * from, c + 3 * (size_t)y * q.width,
                     3 * q.width * sizeof(float)) == 0);
    }
    free(saved);
    free(a);
    free(c);
    free(da);
    free(dc);
    nerf_bake_destroy(b);
}

TEST(render_refuses_bad_calls)
{
    nerf_bake *b = NULL;
    nerf_bake_options o;
    NERF_BAKE_OPTIONS_INIT(&o);
    o.subdivisions = 1;
    CHECK_OK(nerf_bake_create(&b, trained, &o));
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    CHECK_OK(nerf_dataset_camera(fx.test, 0, &cam));
    float rgb[3 * WIDTH * WIDTH];
    const size_t px = (size_t)WIDTH * WIDTH;
    CHECK(nerf_bake_render_image(NULL, &cam, rgb, NULL, NULL, px) ==
          NERF_EINVAL);
    CHECK(nerf_bake_render_image(b, NULL, rgb, NULL, NULL, px) == NERF_EINVAL);
    CHECK(nerf_bake_render_image(b, &cam, NULL, NULL, NULL, px) ==
          NERF_EINVAL);
    CHECK(nerf_bake_render_image(b, &cam, rgb, NULL, NULL, px - 1) ==
          NERF_EINVAL);
    CHECK(says("capacity"));
    nerf_camera bad = cam;
    bad.fx = -1.0f;
    CHECK(nerf_bake_render_image(b, &bad, rgb, NULL, NULL, px) == NERF_EINVAL);
    CHECK(nerf_bake_stats_get(b, NULL) == NERF_EINVAL);
    nerf_bake_destroy(b);
}

int main(void)
{
    if (fixture_open(&fx, WIDTH, N_TRAIN, N_TEST) != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    train();
    RUN(refuses_what_it_cannot_bake);
    RUN(progress_can_cancel);
    RUN(renders_follow_the_networks);
    RUN(skipping_and_cropping_change_no_pixel);
    RUN(render_refuses_bad_calls);
    nerf_model_destroy(trained);
    fixture_close(&fx);
    HARNESS_EXIT();
}
