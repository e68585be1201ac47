/*
 * Baked models (nerf_bake_*): what they refuse, that their renders follow
 * the networks' on the built-in scene, that skipping empty space is
 * exactly sampling it, and that a pixel does not depend on the image it
 * is rendered in.
 *
 * NERF_TEST_STEPS and NERF_TEST_SEED override the training,
 * NERF_TEST_DEGREE and NERF_TEST_DIRECTIONS the bakes, for experiments.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "train_fixture.h"
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
/*
 * The same for the opacities, which depend on the densities alone: what
 * checks a forward-facing bake, whose colours follow the networks' less
 * closely.  Its networks, trained on few photos of a narrow cone of
 * directions, change their colours with the direction more than
 * spherical harmonics of degree 1 or 2 follow (docs/viewer.md).
 */
#define MIN_OPACITY_PSNR 28.0

static fixture fx;
static nerf_model *trained;

static bool quick(void)
{
    return getenv("NERF_TEST_QUICK") != NULL;
}

/* In the sanitizer run a few steps leave most of the grid occupied, which
 * would take minutes to bake: keep the cells of a central cube of 16
 * only, enough for every path of the code. */
static void carve_for_quick_runs(nerf_model *m)
{
    if (!quick()) {
        return;
    }
    nerf__occupancy *g = m->grid;
    const uint32_t r = g->res, lo = r / 2 - 8, hi = r / 2 + 8;
    for (size_t c = 0; c < g->cells; c++) {
        const uint32_t x = (uint32_t)(c % r), y = (uint32_t)(c / r % r);
        const uint32_t z = (uint32_t)(c / r / r);
        if (x < lo || x >= hi || y < lo || y >= hi || z < lo || z >= hi) {
            g->bits[c / 64] &= ~((uint64_t)1 << (c % 64));
        }
    }
}

/* Train m with s on ds for the test's steps. */
static void train(nerf_model *m, nerf_sampler *s, nerf_dataset *ds,
                  uint32_t precrop)
{
    const int steps = fixture_env_int("NERF_TEST_STEPS",
                                      quick() ? QUICK_STEPS : STEPS);
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, steps));
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = BATCH;
    o.precrop_steps = precrop;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, ds, s, &o));
    for (int i = 0; t && i < steps; i++) {
        CHECK_OK(nerf_trainer_step(t, NULL));
    }
    nerf_trainer_destroy(t);
    carve_for_quick_runs(m);
}

/* The bake options of these tests. */
static nerf_bake_options options(void)
{
    nerf_bake_options o;
    NERF_BAKE_OPTIONS_INIT(&o);
    o.subdivisions = SUBDIVISIONS;
    o.sh_degree = (uint32_t)fixture_env_int("NERF_TEST_DEGREE",
                                            (int)o.sh_degree);
    o.directions = (uint32_t)fixture_env_int("NERF_TEST_DIRECTIONS",
                                             (int)o.directions);
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

/* Mean PSNRs of m's bake (o) against its networks over the views of
 * test: of the colours (returned) and of the opacities (*opacity_psnr);
 * checks every output pixel is in range. */
static double bake_against_networks(nerf_model *m, nerf_dataset *test,
                                    const nerf_bake_options *o,
                                    const char *what, double *opacity_psnr)
{
    nerf_bake *b = NULL;
    CHECK_OK(nerf_bake_create(&b, m, o));
    nerf_renderer *r = NULL;
    CHECK_OK(nerf_renderer_create(&r, m, NULL, NULL));
    if (b == NULL || r == NULL) {
        nerf_bake_destroy(b);
        nerf_renderer_destroy(r);
        return -1.0;
    }
    nerf_bake_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    CHECK_OK(nerf_bake_stats_get(b, &st));
    CHECK_EQ_INT(st.resolution, 128 * o->subdivisions);
    CHECK(st.bricks > 0 && st.points > 0 && st.bytes > 0);
    uint32_t w, h;
    nerf_dataset_image_size(test, &w, &h);
    const size_t px = (size_t)w * h;
    float *net = malloc(px * 3 * sizeof(float));
    float *baked = malloc(px * 3 * sizeof(float));
    float *op = malloc(px * sizeof(float));
    float *net_op = malloc(px * sizeof(float));
    double sum = 0.0, sum_op = 0.0;
    const uint32_t n = nerf_dataset_count(test);
    for (uint32_t i = 0; i < n; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        CHECK_OK(nerf_dataset_camera(test, i, &cam));
        CHECK_OK(nerf_renderer_render_image(r, &cam, net, NULL, net_op, px));
        CHECK_OK(nerf_bake_render_image(b, &cam, baked, NULL, op, px));
        bool in_range = true;
        for (size_t p = 0; p < px; p++) {
            in_range &= op[p] >= 0.0f && op[p] <= 1.0f + 1e-6f;
            for (int c = 0; c < 3; c++) {
                in_range &= baked[3 * p + c] >= 0.0f &&
                            baked[3 * p + c] <= 1.0f;
            }
        }
        CHECK(in_range);
        double p = 0.0;
        CHECK_OK(nerf_psnr(baked, net, px * 3, &p));
        sum += p;
        /* Clamped: opacities may pass 1 by a rounding. */
        for (size_t q = 0; q < px; q++) {
            op[q] = fminf(op[q], 1.0f);
            net_op[q] = fminf(net_op[q], 1.0f);
        }
        CHECK_OK(nerf_psnr(op, net_op, px, &p));
        sum_op += p;
    }
    *opacity_psnr = sum_op / n;
    printf("  %s: %llu bricks, %llu points, %.1f MB: against the "
           "networks' renders, the bake's colours score %.2f dB, its "
           "opacities %.2f dB\n", what,
           (unsigned long long)st.bricks, (unsigned long long)st.points,
           (double)st.bytes / 1e6, sum / n, *opacity_psnr);
    free(net);
    free(net_op);
    free(baked);
    free(op);
    nerf_renderer_destroy(r);
    nerf_bake_destroy(b);
    return sum / n;
}

TEST(renders_follow_the_networks)
{
    const nerf_bake_options o = options();
    double op = 0.0;
    const double psnr = bake_against_networks(trained, fx.test, &o,
                                              "the object", &op);
    if (!quick()) {
        CHECK(psnr >= MIN_BAKE_PSNR);
        CHECK(op >= MIN_OPACITY_PSNR);
    }
}

/* A forward-facing capture: a model in NDC, whose bake marches the rays
 * warped into NDC and takes its colours along the world rays. */
TEST(forward_facing_renders_follow_the_networks)
{
    fixture f;
    memset(&f, 0, sizeof f);
    snprintf(f.dir, sizeof f.dir, "%s", fx_make_temp_dir());
    nerf_scene_options so;
    fixture_scene_options(&so, 40, N_TRAIN, N_TEST);
    so.height = 30;
    so.capture = NERF_SCENE_CAPTURE_FORWARD;
    so.layout = NERF_SCENE_LAYOUT_LLFF;
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    CHECK_OK(nerf_scene_write(f.dir, &so));
    CHECK_OK(nerf_dataset_load(&f.train, f.dir, &dopt));
    dopt.split = NERF_SPLIT_TEST;
    CHECK_OK(nerf_dataset_load(&f.test, f.dir, &dopt));
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_sampler_options sopt;
    NERF_SAMPLER_OPTIONS_INIT(&sopt);
    nerf_model *m = NULL;
    nerf_sampler *s = NULL;
    if (f.train && f.test) {
        CHECK_OK(nerf_model_options_preset(&mo, NERF_PRESET_FAST));
        CHECK_OK(nerf_model_options_for_dataset(&mo, f.train));
        mo.hash_log2_size = 15;
        mo.hash_levels = 8;
        mo.hash_max_resolution = 256;
        mo.seed = fixture_seed();
        CHECK_EQ_INT(mo.space, NERF_SPACE_NDC);
        CHECK_OK(nerf_model_create(&m, &mo));
        CHECK_OK(nerf_sampler_options_for(&sopt, m, f.train,
                                          NERF_SAMPLER_FOR_TRAINING));
        sopt.seed = fixture_seed();
        CHECK_OK(nerf_sampler_create(&s, &sopt));
    }
    if (m && s) {
        train(m, s, f.train, 0);
        /* One voxel a cell: the grid of a forward-facing capture is
         * little carved, and its bricks are many. */
        nerf_bake_options o = options();
        o.subdivisions = 1;
        double op = 0.0;
        bake_against_networks(m, f.test, &o, "forward-facing, NDC", &op);
        if (!quick()) {
            CHECK(op >= MIN_OPACITY_PSNR);
        }
    }
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    fixture_close(&f);
}

static size_t px_of(const nerf_camera *cam)
{
    return (size_t)cam->width * cam->height;
}

/* Whether b renders cam to the same bits with the first-hit bounds and
 * the distance field as with neither (every sample of every ray looked
 * at), with something opaque in view if asked; says which camera when
 * not. */
static bool same_bits_without_skips(nerf_bake *b, const nerf_camera *cam,
                                    const char *what, bool opaque)
{
    const size_t px = (size_t)cam->width * cam->height;
    const size_t cells = (size_t)b->res * b->res * b->res;
    float *a = malloc(px * 5 * sizeof(float));
    float *c = malloc(px * 5 * sizeof(float));
    uint8_t *saved = malloc(cells);
    bool same = false;
    if (a && c && saved) {
        CHECK_OK(nerf_bake_render_image(b, cam, a, a + 3 * px, a + 4 * px,
                                        px));
        memcpy(saved, b->empty, cells);
        memset(b->empty, 0, cells);
        b->first_hits = false;
        CHECK_OK(nerf_bake_render_image(b, cam, c, c + 3 * px, c + 4 * px,
                                        px));
        b->first_hits = true;
        memcpy(b->empty, saved, cells);
        same = memcmp(a, c, px * 5 * sizeof(float)) == 0;
        /* A render that met nothing would prove little (a model trained
         * for the sanitizers' few steps is mostly haze). */
        float most = 0.0f;
        for (size_t p = 0; p < px; p++) {
            most = fmaxf(most, a[4 * px + p]);
        }
        if (opaque && !(most > (quick() ? 0.0f : 0.5f))) {
            printf("  %s: nothing opaque in view\n", what);
            same = false;
        }
    }
    if (!same) {
        printf("  %s: the skips changed the render\n", what);
    }
    free(saved);
    free(a);
    free(c);
    return same;
}

/*
 * A render that skips empty space takes the same samples in cells with
 * bricks as one that visits every sample (a skip, from the distance
 * field or from the bounds drawn from the surface cells, lands on the
 * ray's lattice of steps, short of the exit by a margin far above its
 * rounding), and samples in cells without bricks add nothing: the same
 * bits, whatever the camera.  Also, each pixel is its ray's alone: a view
 * cropped out of a larger one has the same pixels.
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
    CHECK(same_bits_without_skips(b, &cam, "a test view", true));
    nerf_camera corner = cam;
    corner.flags |= NERF_CAMERA_PIXEL_CORNER;
    CHECK(same_bits_without_skips(b, &corner, "rays through pixel corners",
                                  true));
    /* A pose that is no rotation: its rays R (x, y, -1) are twice as
     * long, and the bounds must follow them (they undo R). */
    nerf_camera scaled = cam;
    for (int r = 0; r < 3; r++) {
        for (int k = 0; k < 3; k++) {
            scaled.c2w[4 * r + k] *= 2.0f;
        }
    }
    scaled.fx *= 2.0f;
    scaled.fy *= 2.0f;
    CHECK(same_bits_without_skips(b, &scaled, "a scaled pose", true));
    /* Looking past the bricks, 70 degrees aside, with a wide view: the
     * camera's plane cuts through them, and cells that cross it have no
     * bounded image. */
    float centre[3], eye[3], target[3];
    for (int a = 0; a < 3; a++) {
        centre[a] = 0.5f * (b->used_lo[a] + b->used_hi[a]);
    }
    const float reach = b->used_hi[1] - b->used_lo[1];
    const float up[3] = {0.0f, 0.0f, 1.0f};
    for (int a = 0; a < 3; a++) {
        eye[a] = centre[a];
        target[a] = centre[a];
    }
    eye[1] -= 1.5f * reach;
    target[0] += 1.5f * reach * sinf(1.25f);
    target[1] = eye[1] + 1.5f * reach * cosf(1.25f);
    nerf_camera aside = cam;
    CHECK_OK(nerf_camera_look_at(&aside, eye, target, up));
    aside.fx = aside.fy = 0.15f * (float)aside.width;
    /* (The sanitizers' bricks, a central cube, are out of its view.) */
    CHECK(same_bits_without_skips(b, &aside, "a view past the bricks",
                                  !quick()));
    /* Among the bricks: no bounds at all (and, nearer than the model's
     * t_near to most of them, little to see). */
    size_t inner = 0;
    while (b->brick_of[inner] < 0) {
        inner++;
    }
    for (int a = 0; a < 3; a++) {
        const size_t v = a == 0 ? inner % b->res
                         : a == 1 ? inner / b->res % b->res
                                  : inner / b->res / b->res;
        eye[a] = b->lo[a] + ((float)v + 0.5f) * b->cell[a];
    }
    nerf_camera inside = cam;
    CHECK_OK(nerf_camera_look_at(&inside, eye, centre, up));
    float *bounds = malloc(2 * px_of(&inside) * sizeof(float));
    CHECK(bounds && !nerf__bake_first_hits(b, &inside, bounds,
                                           bounds + px_of(&inside)));
    free(bounds);
    CHECK(same_bits_without_skips(b, &inside, "a camera among the bricks",
                                  false));

    const uint32_t w = cam.width, h = cam.height;
    const size_t px = (size_t)w * h;
    float *a = malloc(px * 3 * sizeof(float));
    float *c = malloc(px * 3 * sizeof(float));
    CHECK_OK(nerf_bake_render_image(b, &cam, a, NULL, NULL, px));
    /* The lower right quarter, on its own (its squares of shared bounds
     * fall elsewhere). */
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
    free(a);
    free(c);
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
    nerf_sampler *s = fixture_fast_sampler(fixture_seed());
    trained = fixture_fast_model(fixture_seed(), 8, 15, 256);
    if (trained && s) {
        train(trained, s, fx.train, 50);
    }
    nerf_sampler_destroy(s);
    RUN(refuses_what_it_cannot_bake);
    RUN(progress_can_cancel);
    RUN(renders_follow_the_networks);
    RUN(forward_facing_renders_follow_the_networks);
    RUN(skipping_and_cropping_change_no_pixel);
    RUN(render_refuses_bad_calls);
    nerf_model_destroy(trained);
    fixture_close(&fx);
    HARNESS_EXIT();
}
