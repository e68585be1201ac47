/*
 * Weights-only exports (nerf_model_export) and the render settings a model
 * carries (nerf_model_set_render_settings, nerf_model_render_settings):
 * what each file holds, what loading gives back, and the guesses for a
 * model that recorded nothing.
 */
#include "../harness.h"
#include "ckpt_fixture.h"

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static bool all_zero(const float *x, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (x[i] != 0.0f) {
            return false;
        }
    }
    return true;
}

TEST(export_holds_the_weights_without_the_moments)
{
    char full[128], weights[128], again[128];
    path_in(full, sizeof full, "full.ckpt");
    path_in(weights, sizeof weights, "weights.ckpt");
    path_in(again, sizeof again, "again.ckpt");
    nerf_model *m = trained_model(true);
    CHECK_EQ_INT(nerf_model_contents(m) & NERF_MODEL_HAS_OPTIMIZER,
                 NERF_MODEL_HAS_OPTIMIZER);
    CHECK_OK(nerf_model_save(m, full));
    CHECK_OK(nerf_model_export(m, weights));
    /* Parameters and two moment arrays against the parameters alone. */
    const long a = file_size(full), b = file_size(weights);
    printf("  checkpoint %ld bytes, export %ld bytes\n", a, b);
    CHECK(b > 0 && 2 * b < a);
    nerf_model *w = NULL;
    CHECK_OK(nerf_model_load(&w, weights, NULL));
    if (m && w) {
        CHECK_EQ_INT(nerf_model_contents(w) & NERF_MODEL_HAS_OPTIMIZER, 0);
        CHECK_EQ_INT(nerf_model_step(w), 3);
        CHECK_EQ_INT(w->n_params, m->n_params);
        CHECK(memcmp(w->params, m->params, m->n_params * sizeof(float)) == 0);
        CHECK(all_zero(w->adam_m, w->n_params));
        CHECK(all_zero(w->adam_v, w->n_params));
        /* It computes what the original computes. */
        float rgb_a[3 * 37], rgb_b[3 * 37], s_a[37], s_b[37];
        query(m, NERF_NETWORK_FINE, rgb_a, s_a);
        query(w, NERF_NETWORK_FINE, rgb_b, s_b);
        CHECK(memcmp(rgb_a, rgb_b, sizeof rgb_a) == 0);
        CHECK(memcmp(s_a, s_b, sizeof s_a) == 0);
        /* Saving it again cannot turn its zeros into optimiser state. */
        CHECK_OK(nerf_model_save(w, again));
        CHECK_EQ_INT(file_size(again), b);
    }
    nerf_model *w2 = NULL;
    CHECK_OK(nerf_model_load(&w2, again, NULL));
    CHECK_EQ_INT(nerf_model_contents(w2) & NERF_MODEL_HAS_OPTIMIZER, 0);
    nerf_model *f = NULL;
    CHECK_OK(nerf_model_load(&f, full, NULL));
    CHECK_EQ_INT(nerf_model_contents(f) & NERF_MODEL_HAS_OPTIMIZER,
                 NERF_MODEL_HAS_OPTIMIZER);
    CHECK_EQ_INT(nerf_model_export(NULL, weights), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_export(m, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_contents(NULL), 0);
    nerf_model_destroy(f);
    nerf_model_destroy(w2);
    nerf_model_destroy(w);
    nerf_model_destroy(m);
}

static nerf_model *model_of(int preset, uint32_t space)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, preset);
    o.space = space;
    if (preset == NERF_PRESET_FAST) {
        o.hash_log2_size = 12; /* small and quick */
    }
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    return m;
}

/* A model that recorded nothing gets what its shape suggests. */
TEST(guessed_settings)
{
    nerf_sampler_options so;
    nerf_renderer_options ro;
    nerf_model *tiny = model_of(NERF_PRESET_TINY, NERF_SPACE_BOX);
    nerf_model *ndc = model_of(NERF_PRESET_FAST, NERF_SPACE_NDC);
    nerf_model *far = model_of(NERF_PRESET_FAST, NERF_SPACE_UNBOUNDED);
    if (!tiny || !ndc || !far) {
        goto out;
    }
    CHECK_EQ_INT(nerf_model_contents(tiny) & NERF_MODEL_HAS_RENDER_SETTINGS,
                 0);
    NERF_SAMPLER_OPTIONS_INIT(&so);
    NERF_RENDERER_OPTIONS_INIT(&ro);
    so.seed = 99;
    CHECK_OK(nerf_model_render_settings(tiny, &so, &ro));
    CHECK_EQ_INT(so.n_coarse, 32);
    CHECK_EQ_INT(so.n_fine, 64);
    CHECK_EQ_INT(so.march_steps, 0);
    CHECK(so.t_near == 2.0f && so.t_far == 6.0f && so.ndc == 0);
    CHECK_EQ_INT(ro.white_background, 1);
    CHECK_EQ_INT(so.seed, 99); /* the caller's */
    NERF_SAMPLER_OPTIONS_INIT(&so);
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.white_background = 1;
    CHECK_OK(nerf_model_render_settings(ndc, &so, &ro));
    CHECK_EQ_INT(so.march_steps, 1024);
    CHECK(so.ndc == 1 && so.t_near == 0.0f && so.t_far == 1.0f);
    CHECK_EQ_INT(ro.white_background, 0);
    NERF_SAMPLER_OPTIONS_INIT(&so);
    CHECK_OK(nerf_model_render_settings(far, &so, NULL));
    CHECK(so.ndc == 0 && so.t_far > 1000.0f);
    CHECK_EQ_INT(nerf_model_render_settings(far, NULL, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_render_settings(NULL, &so, NULL), NERF_EINVAL);
out:
    nerf_model_destroy(tiny);
    nerf_model_destroy(ndc);
    nerf_model_destroy(far);
}

static void check_recorded(const nerf_model *m, const char *what)
{
    nerf_sampler_options so;
    nerf_renderer_options ro;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.white_background = 1;
    so.perturb = 1;
    so.seed = 7;
    printf("  %s\n", what);
    if (m == NULL) {
        FAILF("no model");
        return;
    }
    CHECK_EQ_INT(nerf_model_contents(m) & NERF_MODEL_HAS_RENDER_SETTINGS,
                 NERF_MODEL_HAS_RENDER_SETTINGS);
    CHECK_OK(nerf_model_render_settings(m, &so, &ro));
    CHECK_EQ_INT(so.n_coarse, 16);
    CHECK_EQ_INT(so.n_fine, 8);
    CHECK_EQ_INT(so.lindisp, 1);
    CHECK_EQ_INT(so.paper_bins, 1);
    CHECK(so.t_near == 0.25f && so.t_far == 1.0f);
    CHECK_EQ_INT(so.ndc, 1);
    CHECK(so.ndc_focal == 40.0f && so.ndc_width == 30 && so.ndc_height == 20);
    CHECK_EQ_INT(so.march_steps, 0);
    /* The caller's randomness is the caller's. */
    CHECK_EQ_INT(so.perturb, 1);
    CHECK_EQ_INT(so.seed, 7);
    CHECK_EQ_INT(ro.white_background, 0);
}

/* What is recorded comes back, through a checkpoint and an export too. */
TEST(recorded_settings_travel_with_the_model)
{
    char full[128], weights[128];
    path_in(full, sizeof full, "render.ckpt");
    path_in(weights, sizeof weights, "render-weights.ckpt");
    nerf_model *m = model_of(NERF_PRESET_TINY, NERF_SPACE_BOX);
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    so.n_coarse = 16;
    so.n_fine = 8;
    so.lindisp = 1;
    so.paper_bins = 1;
    so.ndc = 1;
    so.t_near = 0.25f;
    so.t_far = 3.5f; /* NDC depths end at 1: refused as a sampler would */
    so.seed = 1234;
    CHECK_EQ_INT(nerf_model_set_render_settings(m, &so, 0), NERF_EINVAL);
    so.t_far = 1.0f;
    so.ndc_focal = 40.0f; /* a frustum half set */
    CHECK_EQ_INT(nerf_model_set_render_settings(m, &so, 0), NERF_EINVAL);
    so.ndc_width = 30;
    so.ndc_height = 20;
    CHECK_EQ_INT(nerf_model_set_render_settings(m, &so, 2), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_set_render_settings(NULL, &so, 0), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_set_render_settings(m, NULL, 0), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_contents(m) & NERF_MODEL_HAS_RENDER_SETTINGS, 0);
    CHECK_OK(nerf_model_set_render_settings(m, &so, 0));
    check_recorded(m, "as set");
    CHECK_OK(nerf_model_save(m, full));
    CHECK_OK(nerf_model_export(m, weights));
    nerf_model *a = NULL, *b = NULL;
    CHECK_OK(nerf_model_load(&a, full, NULL));
    CHECK_OK(nerf_model_load(&b, weights, NULL));
    check_recorded(a, "from the checkpoint");
    check_recorded(b, "from the export");
    if (a) {
        /* Values no sampler takes (as in a forged file): refused. */
        nerf_sampler_options got;
        NERF_SAMPLER_OPTIONS_INIT(&got);
        a->render_sampler.t_far = 3.5f;
        CHECK_EQ_INT(nerf_model_render_settings(a, &got, NULL), NERF_EFORMAT);
    }
    nerf_model_destroy(a);
    nerf_model_destroy(b);
    nerf_model_destroy(m);
}

/* A w x h render of m from z = 4 looking at the origin, by renderer r. */
static void render(nerf_renderer *r, float *rgb, uint32_t w, uint32_t h)
{
    nerf_camera cam;
    NERF_CAMERA_INIT(&cam);
    cam.width = w;
    cam.height = h;
    cam.fx = cam.fy = 10.0;
    cam.cx = 0.5 * w;
    cam.cy = 0.5 * h;
    const double c2w[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 4};
    for (int i = 0; i < 12; i++) {
        cam.c2w[i] = c2w[i];
    }
    CHECK_OK(nerf_renderer_render_image(r, &cam, rgb, NULL, NULL,
                                        (size_t)w * h));
}

/*
 * nerf_renderer_create() without a sampler renders as the model was
 * trained: the same pixels as a sampler and background the caller made
 * from its settings, and with options given, the options' background.
 */
TEST(renderer_without_a_sampler_uses_the_model)
{
    enum { W = 6, H = 5, N = 3 * W * H };
    nerf_model *m = model_of(NERF_PRESET_TINY, NERF_SPACE_BOX);
    if (m == NULL) {
        return;
    }
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    so.n_coarse = 16;
    so.n_fine = 8;
    so.t_near = 3.0f;
    so.t_far = 5.0f;
    CHECK_OK(nerf_model_set_render_settings(m, &so, 1));
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &so));
    nerf_renderer_options white, black;
    NERF_RENDERER_OPTIONS_INIT(&white);
    NERF_RENDERER_OPTIONS_INIT(&black);
    white.white_background = 1;
    nerf_renderer *want = NULL, *got = NULL, *given = NULL, *dark = NULL;
    CHECK_OK(nerf_renderer_create(&want, m, s, &white));
    CHECK_OK(nerf_renderer_create(&got, m, NULL, NULL));
    CHECK_OK(nerf_renderer_create(&given, m, NULL, &black));
    CHECK_OK(nerf_renderer_create(&dark, m, s, &black));
    static float a[N], b[N], c[N], d[N];
    if (want && got && given && dark) {
        render(want, a, W, H);
        render(got, b, W, H);
        render(given, c, W, H);
        render(dark, d, W, H);
        CHECK(memcmp(a, b, sizeof a) == 0);
        CHECK(memcmp(c, d, sizeof c) == 0);
        /* An untrained model is partly transparent: backgrounds show. */
        CHECK(memcmp(a, c, sizeof a) != 0);
    }
    nerf_renderer_destroy(want);
    nerf_renderer_destroy(got);
    nerf_renderer_destroy(given);
    nerf_renderer_destroy(dark);
    /* Settings no sampler takes (a forged file): no renderer. */
    m->render_sampler.t_far = 1.0f;
    nerf_renderer *bad = NULL;
    CHECK_EQ_INT(nerf_renderer_create(&bad, m, NULL, NULL), NERF_EFORMAT);
    CHECK(bad == NULL);
    CHECK_EQ_INT(nerf_renderer_create(&bad, NULL, s, NULL), NERF_EINVAL);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

int main(void)
{
    make_tmpdir();
    RUN(export_holds_the_weights_without_the_moments);
    RUN(guessed_settings);
    RUN(recorded_settings_travel_with_the_model);
    RUN(renderer_without_a_sampler_uses_the_model);
    remove_tree(tmpdir);
    HARNESS_EXIT();
}
