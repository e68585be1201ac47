/*
 * random_background: each training ray's target and render finished on
 * the same random colour, drawn per ray; opaque images and the default
 * left exactly as they were; bad values refused.
 */
#include <string.h>

#include "../fail_alloc.h"
#include "camera.h"
#include "dataset.h"
#include "model.h"
#include "parallel.h"
#include "sampler.h"
#include "train_fixture.h"
#include "trainer.h"

enum { SIDE = 32, IMAGES = 6, BATCH = 64 };

static fixture fx;

static nerf_trainer *make(nerf_model *m, nerf_sampler *s,
                          const nerf_dataset *ds, int32_t random_bg)
{
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = BATCH;
    o.precrop_steps = 2;
    o.random_background = random_bg;
    nerf_trainer *t = NULL;
    CHECK_OK(nerf_trainer_create(&t, m, ds, s, &o));
    return t;
}

TEST(bad_values_refused)
{
    nerf_model *m = tiny_model(1);
    nerf_sampler *s = tiny_sampler(1);
    const int32_t bad[] = {-1, 2, 255};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        nerf_trainer_options o;
        NERF_TRAINER_OPTIONS_INIT(&o);
        o.random_background = bad[i];
        nerf_trainer *t = (nerf_trainer *)&o;
        CHECK_EQ_INT(nerf_trainer_create(&t, m, fx.train, s, &o),
                     NERF_EINVAL);
        CHECK(t == NULL);
        CHECK(fx_has(nerf_last_error(), "random_background"));
    }
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* The dataset pixel a trainer ray goes through: the camera and pixel
 * whose ray is bitwise the same.  -1 if none. */
static long find_pixel(const nerf_trainer *t, const float *o, const float *d,
                       float *ro, float *rd)
{
    const size_t per = (size_t)t->width * t->height;
    for (uint32_t i = 0; i < t->n_images; i++) {
        nerf__camera_rays(&t->cameras[i], 0, per, ro, rd);
        if (memcmp(ro, o, 3 * sizeof(float)) != 0) {
            continue;
        }
        for (size_t p = 0; p < per; p++) {
            if (memcmp(rd + 3 * p, d, 3 * sizeof(float)) == 0 &&
                memcmp(ro + 3 * p, o, 3 * sizeof(float)) == 0) {
                return (long)(i * per + p);
            }
        }
    }
    return -1;
}

/*
 * Step k's rays of a trainer with random_background and one without: the
 * same rays; each background the ray's own draw; each target the pixel
 * moved onto it by its coverage; and the render of the rays finished on
 * the same colours, on both the stratified and the marching path.
 */
static void check_step(nerf_trainer *plain, nerf_trainer *rb, uint64_t k)
{
    const nerf_dataset *ds = fx.train;
    nerf__trainer_pick_rays(plain, k);
    nerf__trainer_pick_rays(rb, k);
    CHECK(memcmp(plain->origins, rb->origins, sizeof(float) * 3 * BATCH) ==
          0);
    CHECK(memcmp(plain->directions, rb->directions,
                 sizeof(float) * 3 * BATCH) == 0);
    const size_t per = (size_t)SIDE * SIDE;
    float *ro = malloc(sizeof(float) * 3 * per);
    float *rd = malloc(sizeof(float) * 3 * per);
    int bad_bg = 0, bad_target = 0, lost = 0, clear = 0, opaque = 0;
    for (uint32_t r = 0; r < BATCH; r++) {
        nerf__rng g = nerf__ray_rng(rb->model->opts.seed,
                                    NERF__STREAM_BACKGROUND,
                                    k * BATCH + r);
        const float *bg = rb->backgrounds + 3 * r;
        for (int c = 0; c < 3; c++) {
            bad_bg += bg[c] != nerf__rng_uniform(&g);
        }
        long at = find_pixel(rb, rb->origins + 3 * r, rb->directions + 3 * r,
                             ro, rd);
        if (at < 0) {
            lost++;
            continue;
        }
        const float *px = ds->pixels + 3 * (size_t)at;
        const double a = ds->alpha[at] / 65535.0;
        clear += a < 0.01;
        opaque += a > 0.99;
        for (int c = 0; c < 3; c++) {
            /* pixel = rgb a + 1 (1 - a), so rgb a + bg (1 - a) is: */
            double want = px[c] + (bg[c] - 1.0) * (1.0 - a);
            bad_target += fabs(rb->targets[3 * r + c] - want) > 1e-6;
            bad_target += plain->targets[3 * r + c] != px[c];
        }
    }
    free(ro);
    free(rd);
    CHECK_EQ_INT(bad_bg, 0);
    CHECK_EQ_INT(lost, 0);
    CHECK_EQ_INT(bad_target, 0);
    /* Both kinds of pixel were drawn, so the test saw the background. */
    CHECK(clear > 0 && opaque > 0);

    /* The render the step trains: finished on the same colours. */
    float rgb[2][3 * BATCH], black[2][3 * BATCH], opac[2][BATCH];
    nerf__pass_out out[2];
    for (int p = 0; p < 2; p++) {
        out[p] = (nerf__pass_out){rgb[p], NULL, NULL, opac[p]};
    }
    rb->setup.first_ray = k * BATCH;
    CHECK_OK(nerf__render_batch(&rb->batch, &rb->setup, BATCH, rb->origins,
                                rb->directions, out));
    nerf__render_setup s = rb->setup;
    s.background = NULL;
    s.white_background = false;
    for (int p = 0; p < 2; p++) {
        out[p].rgb = black[p];
    }
    nerf__batch b;
    nerf__batch_init(&b, &rb->env);
    CHECK_OK(nerf__render_batch(&b, &s, BATCH, rb->origins, rb->directions,
                                out));
    int bad = 0;
    double shown = 0.0;
    for (uint32_t p = 0; p < b.n_pass; p++) {
        for (int r = 0; r < BATCH; r++) {
            shown += 1.0 - opac[p][r];
            for (int c = 0; c < 3; c++) {
                float want = black[p][3 * r + c] +
                             (1.0f - opac[p][r]) * rb->backgrounds[3 * r + c];
                bad += fabsf(rgb[p][3 * r + c] - want) > 1e-5f;
            }
        }
    }
    const uint32_t passes = b.n_pass;
    nerf__batch_release(&b);
    CHECK_EQ_INT(bad, 0);
    printf("  step %llu: %d clear and %d opaque pixels, mean render "
           "transparency %.3f\n", (unsigned long long)k, clear, opaque,
           shown / (passes * BATCH));
    CHECK(shown > 0.1 * BATCH);
}

TEST(target_and_render_share_the_background)
{
    CHECK(fx.train->alpha != NULL);
    if (fx.train->alpha == NULL) {
        return;
    }
    for (int fast = 0; fast < 2; fast++) {
        nerf_model *m = fast ? fixture_fast_model(5, 4, 12, 64) : tiny_model(5);
        nerf_sampler *s = fast ? fixture_fast_sampler(6) : tiny_sampler(6);
        if (m == NULL || s == NULL) {
            nerf_sampler_destroy(s);
            nerf_model_destroy(m);
            continue;
        }
        /* A fresh model is opaque almost everywhere; lower its density
         * so that the renders show their backgrounds. */
        const nerf__network *nw = &m->nets[0];
        m->params[fast ? nw->head.b : nw->head.b + nw->width] -= 2.0f;
        nerf_trainer *plain = make(m, s, fx.train, 0);
        nerf_trainer *rb = make(m, s, fx.train, 1);
        if (plain && rb) {
            CHECK(!plain->random_bg && plain->backgrounds == NULL &&
                  plain->setup.background == NULL);
            CHECK(rb->random_bg && rb->setup.background == rb->backgrounds);
            CHECK(rb->march == (fast == 1));
            check_step(plain, rb, 0); /* central crop */
            check_step(plain, rb, 7);
        }
        nerf_trainer_destroy(plain);
        nerf_trainer_destroy(rb);
        nerf_sampler_destroy(s);
        nerf_model_destroy(m);
    }
}

/* The rays of a step are drawn in order and filled in on the pool's
 * threads: the same rays, targets and backgrounds whichever thread fills
 * which ray, as the calling thread alone fills them. */
TEST(rays_whatever_the_split)
{
    enum { MANY = 4096 };
    nerf_model *m = fixture_fast_model(3, 4, 12, 64);
    nerf_sampler *s = fixture_fast_sampler(4);
    nerf_trainer_options o;
    NERF_TRAINER_OPTIONS_INIT(&o);
    o.batch_rays = MANY;
    o.random_background = 1;
    nerf_trainer *t = NULL;
    if (m && s) {
        CHECK_OK(nerf_trainer_create(&t, m, fx.train, s, &o));
    }
    if (t != NULL) {
        const size_t bytes = sizeof(float) * 3 * MANY;
        float *pooled = malloc(4 * bytes);
        nerf__trainer_pick_rays(t, 9);
        memcpy(pooled, t->origins, bytes);
        memcpy(pooled + 3 * MANY, t->directions, bytes);
        memcpy(pooled + 6 * MANY, t->targets, bytes);
        memcpy(pooled + 9 * MANY, t->backgrounds, bytes);
        nerf__parallel_set_inline(1);
        nerf__trainer_pick_rays(t, 9);
        nerf__parallel_set_inline(0);
        CHECK(memcmp(pooled, t->origins, bytes) == 0);
        CHECK(memcmp(pooled + 3 * MANY, t->directions, bytes) == 0);
        CHECK(memcmp(pooled + 6 * MANY, t->targets, bytes) == 0);
        CHECK(memcmp(pooled + 9 * MANY, t->backgrounds, bytes) == 0);
        /* Drawn across the images, within them. */
        const size_t plane = (size_t)SIDE * SIDE;
        int images[IMAGES] = {0}, outside = 0;
        for (size_t r = 0; r < MANY; r++) {
            outside += t->picked[r] >= IMAGES * plane;
            if (t->picked[r] < IMAGES * plane) {
                images[t->picked[r] / plane]++;
            }
        }
        CHECK_EQ_INT(outside, 0);
        for (int i = 0; i < IMAGES; i++) {
            CHECK(images[i] > MANY / IMAGES / 2);
        }
        free(pooled);
    }
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/* Weights after `steps` steps of a fresh model. */
static float *train(const nerf_dataset *ds, int fast, int32_t random_bg,
                    int steps, size_t *n)
{
    nerf_model *m = fast ? fixture_fast_model(3, 4, 12, 64) : tiny_model(3);
    nerf_sampler *s = fast ? fixture_fast_sampler(4) : tiny_sampler(4);
    nerf_trainer *t = m && s ? make(m, s, ds, random_bg) : NULL;
    for (int i = 0; t && i < steps; i++) {
        CHECK_OK(nerf_trainer_step(t, NULL));
    }
    float *w = NULL;
    if (m) {
        *n = m->n_params;
        w = malloc(sizeof(float) * m->n_params);
        memcpy(w, m->params, sizeof(float) * m->n_params);
    }
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    return w;
}

static int same(const float *a, const float *b, size_t n)
{
    return a && b && memcmp(a, b, n * sizeof(float)) == 0;
}

/* The training images rewritten as opaque RGB files, as they were loaded
 * (on white), into a copy of the scene's folder. */
static nerf_dataset *opaque_copy(char *dir, size_t size)
{
    snprintf(dir, size, "%s/opaque", fx.dir);
    mkdir(dir, 0777);
    fx_mkdir(dir, "train");
    char src[1024], dst[1024];
    fx_path(src, sizeof src, fx.dir, "transforms_train.json");
    fx_path(dst, sizeof dst, dir, "transforms_train.json");
    FILE *f = fopen(src, "rb");
    static char text[1 << 16];
    size_t got = f ? fread(text, 1, sizeof text, f) : 0;
    if (f) {
        fclose(f);
    }
    fx_write_bytes(dst, text, got);
    uint16_t *px = malloc(sizeof(uint16_t) * 3 * SIDE * SIDE);
    for (uint32_t i = 0; i < IMAGES; i++) {
        const float *rgb = NULL;
        CHECK_OK(nerf_dataset_image(fx.train, i, &rgb));
        for (size_t k = 0; rgb && k < 3 * SIDE * SIDE; k++) {
            px[k] = (uint16_t)(rgb[k] * 65535.0f + 0.5f);
        }
        char name[64];
        snprintf(name, sizeof name, "train/r_%u.png", (unsigned)i);
        fx_path(dst, sizeof dst, dir, name);
        fx_write_png(dst, SIDE, SIDE, 2, 16, px, NULL, 0, NULL, 0);
    }
    free(px);
    nerf_dataset *ds = NULL;
    CHECK_OK(nerf_dataset_load(&ds, dir, NULL));
    return ds;
}

/*
 * The option changes training only where there is alpha: on opaque
 * images it gives the weights of 0 bit for bit, on the built-in scene
 * (RGBA) it does not; and it is as deterministic as the rest.
 */
TEST(opaque_images_ignore_it)
{
    char dir[1024];
    nerf_dataset *opaque = opaque_copy(dir, sizeof dir);
    CHECK(opaque && opaque->alpha == NULL);
    for (int fast = 0; fast < 2 && opaque; fast++) {
        const int steps = fast ? 20 : 4;
        size_t n = 0;
        float *o0 = train(opaque, fast, 0, steps, &n);
        float *o1 = train(opaque, fast, 1, steps, &n);
        CHECK(same(o0, o1, n));
        float *a0 = train(fx.train, fast, 0, steps, &n);
        float *a1 = train(fx.train, fast, 1, steps, &n);
        float *a1_again = train(fx.train, fast, 1, steps, &n);
        CHECK(!same(a0, a1, n));
        CHECK(same(a1, a1_again, n));
        free(o0);
        free(o1);
        free(a0);
        free(a1);
        free(a1_again);
    }
    nerf_dataset_destroy(opaque);
}

/* The backgrounds' buffer is one more allocation: each failure of the
 * trainer's allocations is NERF_ENOMEM and leaks nothing. */
TEST(allocation_failures)
{
    nerf_sampler *s = tiny_sampler(1);
    nerf_model *m = tiny_model(1);
    nerf_hooks hooks;
    fail_alloc f;
    fail_alloc_hooks(&hooks, &f);
    int succeeded_at[2] = {0, 0};
    for (int rb = 0; rb < 2; rb++) {
        for (int k = 1; k < 40 && !succeeded_at[rb]; k++) {
            f = (fail_alloc){0, k, 0};
            nerf_trainer_options o;
            NERF_TRAINER_OPTIONS_INIT(&o);
            o.batch_rays = 16;
            o.random_background = rb;
            o.hooks = &hooks;
            nerf_trainer *t = NULL;
            int rc = nerf_trainer_create(&t, m, fx.train, s, &o);
            if (rc == NERF_OK) {
                rc = nerf_trainer_step(t, NULL);
            }
            if (rc == NERF_OK) {
                succeeded_at[rb] = k;
            } else {
                CHECK_EQ_INT(rc, NERF_ENOMEM);
            }
            nerf_trainer_destroy(t);
            CHECK_EQ_INT(f.live, 0);
        }
    }
    CHECK(succeeded_at[0] > 2);
    CHECK_EQ_INT(succeeded_at[1], succeeded_at[0] + 1);
    nerf_model_destroy(m);
    nerf_sampler_destroy(s);
}

int main(void)
{
    int rc = fixture_open(&fx, SIDE, IMAGES, 0);
    if (rc != NERF_OK) {
        printf("fixture: %s\n", nerf_last_error());
        return 1;
    }
    RUN(bad_values_refused);
    RUN(target_and_render_share_the_background);
    RUN(rays_whatever_the_split);
    RUN(opaque_images_ignore_it);
    RUN(allocation_failures);
    fixture_close(&fx);
    HARNESS_EXIT();
}
