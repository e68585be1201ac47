/*
 * Whole-image and ray-batch rendering with a tiny model: bitwise identical
 * results for every chunk size and thread count, agreement with the
 * public building blocks (sampler, model query, compositing), progress and
 * cancellation, and argument checks.
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "composite.h"
#include "composite_packed.h"
#include "cpu.h"
#include "gemm.h"
#include "march.h"
#include "model.h"
#include "nerf.h"
#include "network_fused.h"
#include "occupancy.h"
#include "renderer.h"
#include "rng.h"
#include "smm.h"

/* Few pixels, and a quarter of the tiny preset's samples a ray: in CI's
 * aarch64 stage, under qemu, a tiny-model render of 24x16 took about 20 s,
 * and these tests render dozens.  What they test holds for any count. */
#define W 16
#define H 12
#define NPIX (W * H)
#define N_COARSE 8
#define N_FINE 16

static nerf_model *tiny_model(void)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    mo.seed = 3;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &mo));
    return m;
}

static void tiny_sampler_options(nerf_sampler_options *so)
{
    NERF_SAMPLER_OPTIONS_INIT(so);
    nerf_sampler_options_preset(so, NERF_PRESET_TINY);
    so->n_coarse = N_COARSE;
    so->n_fine = N_FINE;
}

static nerf_sampler *tiny_sampler(uint32_t ndc)
{
    nerf_sampler_options so;
    tiny_sampler_options(&so);
    if (ndc) {
        so.ndc = 1;
        so.t_near = 0.0f;
        so.t_far = 1.0f;
    }
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &so));
    return s;
}

static nerf_renderer *renderer(nerf_model *m, nerf_sampler *s,
                               uint32_t chunk, uint32_t threads,
                               uint32_t white)
{
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.chunk_rays = chunk;
    ro.threads = threads;
    ro.white_background = white;
    nerf_renderer *r = NULL;
    CHECK_OK(nerf_renderer_create(&r, m, s, &ro));
    return r;
}

/* A camera 4 units from the origin on +z, looking at it. */
static void test_camera(nerf_camera *c)
{
    NERF_CAMERA_INIT(c);
    c->width = W;
    c->height = H;
    c->fx = c->fy = 0.5f * W / tanf(0.35f);
    c->cx = 0.5f * W;
    c->cy = 0.5f * H;
    c->c2w[3] = 0.1f;
    c->c2w[7] = -0.2f;
    c->c2w[11] = 4.0f;
}

typedef struct image {
    float rgb[3 * NPIX], depth[NPIX], opacity[NPIX];
} image;

/*
 * Two renders whose blocks hold different rays agree bit for bit only
 * where the network computes every sample alone: the fused path does
 * (mlp/network_fused.h), the per-layer CBLAS path does not (its kernels
 * may round a row by the product's size and the row's place in it,
 * mlp/gemm.h), and oneDNN does while its primitives are brgemm.  Such a
 * comparison forces the fused path, where the model fits it (a oneDNN
 * model does not), from before its renderers are made (a workspace
 * reserved off the fused path stays off it) to the end, and asks
 * nerf__model_rows_alone() afterwards.  Returns the variant to restore.
 */
static int force_fused(void)
{
    const int was = nerf__smm_variant();
    CHECK_OK(nerf__smm_use(nerf__smm_best()));
    return was;
}

static void restore_fused(int was)
{
    CHECK_OK(nerf__smm_use(was));
}

/*
 * The order in which render_image visits a marching render's pixels
 * (render_image.c): 8x8 tiles, row of tiles by row of tiles, each tile
 * read row by row, narrower or shorter at the right and bottom edges.
 * Its 64-ray blocks are 64 consecutive pixels of this order.
 */
static void tile_order(uint32_t w, uint32_t h, size_t *pix)
{
    size_t i = 0;
    for (uint32_t ty = 0; ty < h; ty += 8) {
        for (uint32_t tx = 0; tx < w; tx += 8) {
            for (uint32_t y = ty; y < ty + 8 && y < h; y++) {
                for (uint32_t x = tx; x < tx + 8 && x < w; x++) {
                    pix[i++] = (size_t)y * w + x;
                }
            }
        }
    }
}

/*
 * render_rays on the n rays o, d taken in the tile order of a w x h image,
 * the results put back at their pixels: the same rays in the same 64-ray
 * blocks as render_image's, so the same computation on any kernel.
 */
static void render_rays_tiled(nerf_renderer *r, uint32_t w, uint32_t h,
                              const float *o, const float *d, float *rgb,
                              float *depth, float *opac)
{
    enum { MAXPIX = 17 * 17 };
    static size_t pix[MAXPIX];
    static float to[3 * MAXPIX], td[3 * MAXPIX], trgb[3 * MAXPIX],
        tdepth[MAXPIX], topac[MAXPIX];
    const size_t n = (size_t)w * h;
    CHECK(n <= MAXPIX);
    if (n > MAXPIX) {
        return;
    }
    tile_order(w, h, pix);
    for (size_t i = 0; i < n; i++) {
        memcpy(to + 3 * i, o + 3 * pix[i], 3 * sizeof(float));
        memcpy(td + 3 * i, d + 3 * pix[i], 3 * sizeof(float));
    }
    CHECK_OK(nerf_renderer_render_rays(r, n, to, td, trgb, tdepth, topac));
    for (size_t i = 0; i < n; i++) {
        memcpy(rgb + 3 * pix[i], trgb + 3 * i, 3 * sizeof(float));
        depth[pix[i]] = tdepth[i];
        opac[pix[i]] = topac[i];
    }
}

TEST(chunks_and_threads_bitwise)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = tiny_sampler(0);
    nerf_camera cam;
    test_camera(&cam);
    static image ref, img;
    nerf_renderer *r = renderer(m, s, 64, 1, 1);
    CHECK_OK(nerf_renderer_render_image(r, &cam, ref.rgb, ref.depth,
                                        ref.opacity, NPIX));
    nerf_renderer_destroy(r);
    double mean = 0.0;
    for (int i = 0; i < NPIX; i++) {
        /* The fine pass composites N_COARSE + N_FINE samples. */
        CHECK(isfinite(ref.rgb[3 * i]) && ref.opacity[i] >= 0.0f &&
              ref.opacity[i] <= float_opacity_max(N_COARSE + N_FINE));
        mean += ref.opacity[i] / NPIX;
    }
    /* A random model is neither empty nor opaque everywhere. */
    CHECK(mean > 0.01 && mean < 0.999);
    /* Bit for bit on every kernel: whatever the chunk size (rounded up to
     * a multiple of the block) and the threads, the renderer evaluates
     * the same fixed blocks of NERF__RENDER_BLOCK rays from the first,
     * each one product per pass, and gemm.c cuts products at fixed rows
     * whatever the threads.  The chunks below are smaller than, equal to,
     * not multiples of and larger than the block. */
    _Static_assert(NERF__RENDER_BLOCK == 64, "the cases assume 64");
    static const uint32_t cases[][2] = {
        {1, 1}, {64, 2}, {100, 3}, {128, 2}, {200, 4}, {4096, 0}, {65, 7},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        memset(&img, 0xff, sizeof img);
        r = renderer(m, s, cases[k][0], cases[k][1], 1);
        CHECK_OK(nerf_renderer_render_image(r, &cam, img.rgb, img.depth,
                                            img.opacity, NPIX));
        if (memcmp(&img, &ref, sizeof img) != 0) {
            FAILF("chunk %u, threads %u: image differs", cases[k][0],
                  cases[k][1]);
        }
        /* Again with the same handle: reused scratch, same bits. */
        CHECK_OK(nerf_renderer_render_image(r, &cam, img.rgb, img.depth,
                                            img.opacity, NPIX));
        CHECK(memcmp(&img, &ref, sizeof img) == 0);
        nerf_renderer_destroy(r);
    }

    /* 8 bits: the float image rounded. */
    static uint8_t rgb8[3 * NPIX];
    r = renderer(m, s, 96, 2, 1);
    CHECK_OK(nerf_renderer_render_image_u8(r, &cam, rgb8, NULL, NULL, NPIX));
    for (int i = 0; i < 3 * NPIX; i++) {
        float c = fminf(fmaxf(ref.rgb[i], 0.0f), 1.0f);
        CHECK(rgb8[i] == (uint8_t)(c * 255.0f + 0.5f));
    }
    /* Only some outputs. */
    CHECK_OK(nerf_renderer_render_image(r, &cam, NULL, img.depth, NULL, NPIX));
    CHECK(memcmp(img.depth, ref.depth, sizeof img.depth) == 0);

    /* The same rays through render_rays: same blocks, same bits. */
    static float o[3 * NPIX], d[3 * NPIX];
    CHECK_OK(nerf_camera_rays(&cam, 0, NPIX, o, d));
    memset(&img, 0, sizeof img);
    CHECK_OK(nerf_renderer_render_rays(r, NPIX, o, d, img.rgb, img.depth,
                                       img.opacity));
    CHECK(memcmp(&img, &ref, sizeof img) == 0);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/*
 * A fast-preset model (a small hash grid) whose occupancy grid keeps a
 * ball and a slab: the camera's rays cross empty cells, occupied ones, and
 * both.  Random weights: the density is neither empty nor opaque.
 */
static int grid_shape(void *ctx, size_t n, const float *xyz, float *sigma)
{
    (void)ctx;
    for (size_t i = 0; i < n; i++) {
        const float *p = xyz + 3 * i;
        float r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        sigma[i] = r2 < 0.36f || fabsf(p[1] + 0.5f) < 0.1f ? 100.0f : 0.0f;
    }
    return 0;
}

static nerf_model *fast_model(void)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_FAST);
    mo.hash_levels = 4;
    mo.hash_log2_size = 12;
    mo.hash_max_resolution = 64;
    mo.seed = 3;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &mo));
    if (m) {
        CHECK_OK(nerf__occupancy_update(m->grid, grid_shape, NULL,
                                        m->grid->cells));
        CHECK(m->grid->occupied > 0 && m->grid->occupied < m->grid->cells);
    }
    return m;
}

static nerf_sampler *fast_sampler(uint32_t max_samples)
{
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, NERF_PRESET_FAST);
    so.max_samples = max_samples;
    nerf_sampler *s = NULL;
    CHECK_OK(nerf_sampler_create(&s, &so));
    return s;
}

TEST(marching_chunks_and_threads_bitwise)
{
    nerf_model *m = fast_model();
    nerf_sampler *s = fast_sampler(1024);
    if (!m || !s) {
        return;
    }
    nerf_camera cam;
    test_camera(&cam);
    static image ref, img;
    nerf_renderer *r = renderer(m, s, 64, 1, 1);
    CHECK_OK(nerf_renderer_render_image(r, &cam, ref.rgb, ref.depth,
                                        ref.opacity, NPIX));
    nerf_renderer_destroy(r);
    int empty = 0, partial = 0;
    for (int i = 0; i < NPIX; i++) {
        /* At most max_samples samples a ray are composited. */
        CHECK(isfinite(ref.rgb[3 * i]) && ref.opacity[i] >= 0.0f &&
              ref.opacity[i] <= float_opacity_max(1024));
        empty += ref.opacity[i] == 0.0f;
        partial += ref.opacity[i] > 0.01f && ref.opacity[i] < 0.99f;
        if (ref.opacity[i] == 0.0f) {
            /* No sample: the white background. */
            CHECK(ref.rgb[3 * i] == 1.0f && ref.depth[i] == 0.0f);
        }
    }
    CHECK(empty > 0 && partial > 0 && empty < NPIX);
    static const uint32_t cases[][2] = {
        {1, 1}, {64, 2}, {100, 3}, {200, 4}, {4096, 0}, {65, 7},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        memset(&img, 0xff, sizeof img);
        r = renderer(m, s, cases[k][0], cases[k][1], 1);
        CHECK_OK(nerf_renderer_render_image(r, &cam, img.rgb, img.depth,
                                            img.opacity, NPIX));
        if (memcmp(&img, &ref, sizeof img) != 0) {
            FAILF("marching, chunk %u, threads %u: image differs",
                  cases[k][0], cases[k][1]);
        }
        CHECK_OK(nerf_renderer_render_image(r, &cam, img.rgb, img.depth,
                                            img.opacity, NPIX));
        CHECK(memcmp(&img, &ref, sizeof img) == 0);
        nerf_renderer_destroy(r);
    }
    /* The same rays through render_rays, in the image's tile order: the
     * same blocks, the same bits on every kernel (marching_image_in_tiles
     * compares the rows' order too). */
    static float o[3 * NPIX], d[3 * NPIX];
    CHECK_OK(nerf_camera_rays(&cam, 0, NPIX, o, d));
    r = renderer(m, s, 128, 2, 1);
    memset(&img, 0, sizeof img);
    render_rays_tiled(r, W, H, o, d, img.rgb, img.depth, img.opacity);
    CHECK(memcmp(&img, &ref, sizeof img) == 0);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/*
 * Marching renders visit the image in 8x8 tiles: every pixel once, the
 * partial tiles of sizes 8 does not divide included, for every output and
 * the 8-bit form, whatever the threads.  Against render_rays on the rays
 * in tile order (the same blocks: equal on every kernel), and on the rays
 * in rows, where each block holds other rays: equal where every sample is
 * computed alone, which the fused path promises.
 */
static bool check_image_against(nerf_renderer *r, const nerf_camera *cam,
                                nerf_model *rows, const float *ref_rgb,
                                const float *ref_depth, const float *ref_opac)
{
    enum { MAXPIX = 13 * 17 };
    static float rgb[3 * MAXPIX], depth[MAXPIX], opac[MAXPIX];
    static float opac2[MAXPIX], depth8[MAXPIX];
    static uint8_t rgb8[3 * MAXPIX];
    const size_t n = (size_t)cam->width * cam->height;
    memset(rgb, 0xff, sizeof rgb);
    memset(depth, 0xff, sizeof depth);
    memset(opac, 0xff, sizeof opac);
    memset(rgb8, 0, sizeof rgb8);
    CHECK_OK(nerf_renderer_render_image(r, cam, rgb, depth, opac, n));
    CHECK_OK(nerf_renderer_render_image(r, cam, NULL, NULL, opac2, n));
    CHECK_OK(nerf_renderer_render_image_u8(r, cam, rgb8, depth8, NULL, n));
    if (rows && !nerf__model_rows_alone(rows)) {
        return false;
    }
    if (memcmp(rgb, ref_rgb, 3 * n * sizeof(float)) != 0 ||
        memcmp(depth, ref_depth, n * sizeof(float)) != 0 ||
        memcmp(opac, ref_opac, n * sizeof(float)) != 0) {
        FAILF("%ux%u, %u threads: the image is not its rays' render (%s)",
              cam->width, cam->height, r->threads, rows ? "rows" : "tiles");
    }
    CHECK(memcmp(opac2, ref_opac, n * sizeof(float)) == 0);
    int bad = 0;
    for (size_t i = 0; i < 3 * n; i++) {
        float v = fminf(fmaxf(ref_rgb[i], 0.0f), 1.0f);
        bad += rgb8[i] != (uint8_t)(v * 255.0f + 0.5f);
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(memcmp(depth8, ref_depth, n * sizeof(float)) == 0);
    return true;
}

TEST(marching_image_in_tiles)
{
    static const uint32_t sizes[][2] = {{13, 11}, {8, 8}, {1, 1}, {9, 17}};
    enum { MAXPIX = 13 * 17 };
    static float o[3 * MAXPIX], d[3 * MAXPIX];
    static float ref_rgb[3 * MAXPIX], ref_depth[MAXPIX], ref_opac[MAXPIX];
    for (int rows = 0; rows < 2; rows++) {
        /* In rows, from before the model's first render (see
         * force_fused()). */
        const int was = rows ? force_fused() : nerf__smm_variant();
        nerf_model *m = fast_model();
        nerf_sampler *s = fast_sampler(1024);
        int skipped = 0;
        for (size_t c = 0; m && s && c < sizeof sizes / sizeof sizes[0];
             c++) {
            nerf_camera cam;
            test_camera(&cam);
            cam.width = sizes[c][0];
            cam.height = sizes[c][1];
            cam.cx = 0.5f * (float)cam.width;
            cam.cy = 0.5f * (float)cam.height;
            const size_t n = (size_t)cam.width * cam.height;
            CHECK_OK(nerf_camera_rays(&cam, 0, n, o, d));
            nerf_renderer *r = renderer(m, s, 64, 1, 1);
            if (rows) {
                CHECK_OK(nerf_renderer_render_rays(r, n, o, d, ref_rgb,
                                                   ref_depth, ref_opac));
            } else {
                render_rays_tiled(r, cam.width, cam.height, o, d, ref_rgb,
                                  ref_depth, ref_opac);
            }
            nerf_renderer_destroy(r);
            for (uint32_t threads = 1; threads <= 3; threads += 2) {
                r = renderer(m, s, 128, threads, 1);
                skipped += !check_image_against(r, &cam, rows ? m : NULL,
                                                ref_rgb, ref_depth, ref_opac);
                nerf_renderer_destroy(r);
            }
        }
        if (skipped > 0) {
            /* A oneDNN model that made a primitive other than brgemm: its
             * rows may round by their neighbours, and no bound on a whole
             * render is derived here.  The tile order above holds. */
            CHECK(rows);
            printf("  rays in rows against the image not compared: this "
                   "oneDNN model does not compute samples alone\n");
        }
        nerf_sampler_destroy(s);
        nerf_model_destroy(m);
        restore_fused(was);
    }
}

/*
 * The render of one pixel's ray from the building blocks: the whole march,
 * a model query on all of its samples and compositing with early
 * termination, cut to `limit` samples.  The largest difference from the
 * renderer's rgb, depth (over the far bound) and opacity; *opaque counts
 * the rays that stop before their last sample.
 */
static double ray_against_blocks(nerf_model *m, const nerf__march_samples *ms,
                                 size_t k, const float *o, const float *d,
                                 uint32_t limit, const float *rgb,
                                 float depth, float opac, int *cut,
                                 int *opaque)
{
    enum { MAX = 1024 };
    static float pts[3 * MAX], dirs[3 * MAX], c[3 * MAX], sig[MAX];
    const size_t at = ms->offsets[k];
    const uint32_t n = (uint32_t)(ms->offsets[k + 1] - at);
    CHECK(n <= MAX);
    if (n > MAX) {
        return INFINITY;
    }
    float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (uint32_t i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            pts[3 * i + a] = o[a] + ms->t[at + i] * d[a];
            dirs[3 * i + a] = d[a] / len;
        }
    }
    if (n > 0) {
        CHECK_OK(nerf_model_query(m, NERF_NETWORK_COARSE, n, pts, dirs, c,
                                  sig));
    }
    uint32_t use = n < limit ? n : limit;
    *cut += use < n;
    nerf__composite_state st;
    nerf__composite_state_init(&st);
    uint32_t used = nerf__composite_packed_ray(
        &st, use, ms->t + at, ms->dt + at, c, sig,
        NERF__COMPOSITE_EPS_DEFAULT, NULL);
    *opaque += used < use;
    double worst = 0.0;
    for (int a = 0; a < 3; a++) {
        worst = fmax(worst, fabs(st.rgb[a] - rgb[a]));
    }
    worst = fmax(worst, fabs(st.depth - depth) / 6.0);
    return fmax(worst, fabs(st.opacity - opac));
}

/*
 * The render in pieces is the render of the whole march: every pixel's
 * ray rebuilt from the building blocks, bit for bit where the network
 * computes each sample alone.  The renderer evaluates the colour of only
 * the samples it composites, which matters for rays that turn opaque
 * inside a piece: the model again with its densities raised has many.
 * max_samples cuts rays as documented.
 */
TEST(marching_matches_building_blocks)
{
    /* A ray alone against the renderer's blocks: the fused path, from
     * before the model's first evaluation (see force_fused()). */
    const int was = force_fused();
    nerf_model *m = fast_model();
    if (!m) {
        restore_fused(was);
        return;
    }
    nerf_camera cam;
    test_camera(&cam);
    static float o[3 * NPIX], d[3 * NPIX], rgb[3 * NPIX];
    static float depth[NPIX], opac[NPIX];
    CHECK_OK(nerf_camera_rays(&cam, 0, NPIX, o, d));
    const nerf__network *net = &m->nets[0];
    /* A fresh table's entries are so small that every sample gets about
     * the same features: spread them, so that a sample coloured from
     * another's row would show. */
    nerf__rng rng = nerf__rng_make(17, 0);
    for (size_t i = 0; i < nerf__encoding_params(&net->pos_enc); i++) {
        m->params[net->pos_params + i] = nerf__rng_uniform(&rng) - 0.5f;
    }
    nerf__model_weights_changed(m);
    float *density_bias =
        m->params + net->head.b + nerf__network_sigma_col(net);
    const float raise = 4.0f;
    const uint32_t limits[2] = {1024, 5};
    for (int v = 0; v < 4; v++) {
        const uint32_t limit = limits[v % 2];
        if (v == 2) {
            *density_bias += raise;
            nerf__model_weights_changed(m);
        }
        nerf_sampler *s = fast_sampler(limit);
        nerf_renderer *r = renderer(m, s, 64, 1, 0);
        CHECK_OK(nerf_renderer_render_rays(r, NPIX, o, d, rgb, depth, opac));
        nerf__march_options mo;
        nerf__march_defaults(&mo, m->grid);
        nerf__march_samples ms;
        nerf__env env;
        nerf__env_default(&env);
        nerf__march_samples_init(&ms, &env);
        nerf__march_rays rays = {.n = NPIX, .origins = o, .dirs = d,
                                 .near_all = 2.0f, .far_all = 6.0f};
        CHECK_OK(nerf__march_run(m->grid, &mo, &rays, &ms));
        double worst = 0.0;
        int cut = 0, opaque = 0;
        for (size_t k = 0; k < NPIX; k++) {
            worst = fmax(worst, ray_against_blocks(
                                    m, &ms, k, o + 3 * k, d + 3 * k, limit,
                                    rgb + 3 * k, depth[k], opac[k], &cut,
                                    &opaque));
        }
        printf("  density bias +%g, max_samples %u: largest difference "
               "%.3g (%d rays cut, %d opaque)\n",
               v < 2 ? 0.0f : raise, limit, worst, cut, opaque);
        /* Every sample computed alone (the fused path, or oneDNN all
         * brgemm): the same bits.  A oneDNN model that made another
         * primitive may round a row by its neighbours, and through early
         * termination a rounding can move where a ray stops; no bound is
         * derived for that, so only the measure above is shown. */
        if (nerf__model_rows_alone(m)) {
            CHECK(worst == 0.0);
        } else {
            printf("  not compared: this oneDNN model does not compute "
                   "samples alone\n");
        }
        CHECK(limit == 1024 ? cut == 0 : cut > 0);
        if (v == 2) {
            CHECK(opaque > NPIX / 4);
        }
        nerf__march_samples_release(&ms);
        nerf_renderer_destroy(r);
        nerf_sampler_destroy(s);
    }
    /* A marching sampler needs a model with a grid. */
    nerf_model *tiny = tiny_model();
    nerf_sampler *s = fast_sampler(1024);
    nerf_renderer *r = NULL;
    CHECK_EQ_INT(nerf_renderer_create(&r, tiny, s, NULL), NERF_EINVAL);
    CHECK(r == NULL && strstr(nerf_last_error(), "occupancy grid") != NULL);
    nerf_sampler_destroy(s);
    nerf_model_destroy(tiny);
    nerf_model_destroy(m);
    restore_fused(was);
}

/*
 * The render of a few rays rebuilt from the public pieces the way the
 * renderer computes a block (render_stratified.c): coarse samples of
 * every ray, one model query over all of them in ray order, compositing
 * and fine samples ray by ray, one query over all the fine pass's
 * samples.  The products have the shapes and rows the renderer's have
 * (QUERY_BLOCK, 4096 samples, keeps each query one block), so on any
 * kernel the bits are the same.
 */
TEST(matches_building_blocks)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = tiny_sampler(0);
    nerf_renderer *r = renderer(m, s, 64, 1, 0);
    nerf_camera cam;
    test_camera(&cam);
    enum { R = 5, NC = N_COARSE, NF = N_FINE, NS = NC + NF };
    _Static_assert(R * NS <= 4096 && R <= 64,
                   "one query block, one render block");
    const size_t pix[R] = {0, 3 + 2 * W, 14 + 5 * W, 5 + 6 * W, NPIX - 1};
    float o[3 * R], d[3 * R], rgb[3 * R], depth[R], opac[R], len[R];
    for (int k = 0; k < R; k++) {
        CHECK_OK(nerf_camera_rays(&cam, pix[k], 1, o + 3 * k, d + 3 * k));
        const float *dk = d + 3 * k;
        len[k] = sqrtf(dk[0] * dk[0] + dk[1] * dk[1] + dk[2] * dk[2]);
    }
    CHECK_OK(nerf_renderer_render_rays(r, R, o, d, rgb, depth, opac));
    static float tc[R * NC], tf[R * NS], w[R * NS], pts[3 * R * NS],
        dirs[3 * R * NS], c[3 * R * NS], sig[R * NS];
    CHECK_OK(nerf_sampler_sample_coarse(s, R, 0, 0, NULL, tc));
    int bad = 0;
    for (int pass = 0; pass < 2; pass++) {
        const float *t = pass ? tf : tc;
        const int n = pass ? NS : NC;
        for (int k = 0; k < R; k++) {
            for (int i = 0; i < n; i++) {
                for (int a = 0; a < 3; a++) {
                    pts[3 * (k * n + i) + a] = o[3 * k + a] +
                                               d[3 * k + a] * t[k * n + i];
                    dirs[3 * (k * n + i) + a] = d[3 * k + a] / len[k];
                }
            }
        }
        CHECK_OK(nerf_model_query(m, pass ? NERF_NETWORK_FINE
                                          : NERF_NETWORK_COARSE,
                                  (size_t)R * n, pts, dirs, c, sig));
        for (int k = 0; k < R; k++) {
            nerf__ray_out out;
            nerf__composite_ray(n, t + k * n, len[k], c + 3 * k * n,
                                sig + k * n, false, w + k * n, &out);
            if (pass == 1) {
                bad += memcmp(out.rgb, rgb + 3 * k, sizeof out.rgb) != 0 ||
                       out.depth != depth[k] || out.opacity != opac[k];
            }
        }
        if (pass == 0) {
            CHECK_OK(nerf_sampler_sample_fine(s, R, 0, 0, tc, w, NULL, tf));
        }
    }
    CHECK_EQ_INT(bad, 0);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

TEST(ndc_render)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = tiny_sampler(1);
    nerf_renderer *r = renderer(m, s, 64, 2, 0);
    nerf_camera cam;
    test_camera(&cam);
    cam.c2w[11] = 0.0f;
    static image img;
    CHECK_OK(nerf_renderer_render_image(r, &cam, img.rgb, img.depth,
                                        img.opacity, NPIX));
    for (int i = 0; i < NPIX; i++) {
        CHECK(isfinite(img.rgb[3 * i]) && img.depth[i] >= 0.0f &&
              img.depth[i] <= 1.0f + 1e-5f);
    }
    /* Rays need the scene's frustum in the sampler. */
    static float o[3 * NPIX], d[3 * NPIX], rgb[3 * NPIX];
    CHECK_OK(nerf_camera_rays(&cam, 0, NPIX, o, d));
    CHECK_EQ_INT(nerf_renderer_render_rays(r, NPIX, o, d, rgb, NULL, NULL),
                 NERF_EINVAL);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_sampler_options so;
    tiny_sampler_options(&so);
    so.ndc = 1;
    so.t_near = 0.0f;
    so.t_far = 1.0f;
    so.ndc_focal = cam.fx;
    so.ndc_width = W;
    so.ndc_height = H;
    CHECK_OK(nerf_sampler_create(&s, &so));
    r = renderer(m, s, 64, 2, 0);
    CHECK_OK(nerf_renderer_render_rays(r, NPIX, o, d, rgb, NULL, NULL));
    CHECK(memcmp(rgb, img.rgb, sizeof rgb) == 0);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

typedef struct progress_log {
    int calls;
    uint64_t last, total;
    int monotonic;
    int cancel_at;
    nerf_renderer *r;
    int use_cancel_fn;
} progress_log;

static int on_progress(const nerf_progress *p, void *user)
{
    progress_log *log = user;
    log->calls++;
    if (p->struct_size < sizeof *p || p->kind != NERF_PROGRESS_RENDER ||
        p->done < log->last || p->done > p->total || p->elapsed < 0.0) {
        log->monotonic = 0;
    }
    log->last = p->done;
    log->total = p->total;
    if (log->cancel_at && log->calls >= log->cancel_at) {
        if (log->use_cancel_fn) {
            nerf_renderer_cancel(log->r); /* from inside: also allowed */
            return 0;
        }
        return 1;
    }
    return 0;
}

TEST(progress_and_cancel)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = tiny_sampler(0);
    nerf_camera cam;
    test_camera(&cam);
    static image img;
    for (uint32_t threads = 1; threads <= 3; threads += 2) {
        nerf_renderer *r = renderer(m, s, 64, threads, 0);
        progress_log log = {0, 0, 0, 1, 0, r, 0};
        CHECK_OK(nerf_renderer_set_progress(r, on_progress, &log));
        CHECK_OK(nerf_renderer_render_image(r, &cam, img.rgb, NULL, NULL,
                                            NPIX));
        CHECK(log.monotonic && log.last == NPIX && log.total == NPIX);
        CHECK(log.calls >= 1 && log.calls <= NPIX / 64);
        if (threads == 1) {
            CHECK_EQ_INT(log.calls, NPIX / 64);
        }
        /* Nonzero from the callback cancels.  With several threads the
         * other chunks may all be done by then; the call still reports
         * the cancellation.  They may even all be done before the calling
         * thread first wakes (a slow or emulated machine), so that the
         * callback runs once, for the whole image, and never gets to
         * return nonzero: then the render is whole. */
        log = (progress_log){0, 0, 0, 1, 2, r, 0};
        int rc = nerf_renderer_render_image(r, &cam, img.rgb, NULL, NULL,
                                            NPIX);
        if (log.calls >= 2) {
            CHECK_EQ_INT(rc, NERF_ECANCELLED);
        } else {
            CHECK(threads > 1 && rc == NERF_OK && log.last == NPIX);
        }
        CHECK(threads > 1 || log.last == 2 * 64);
        /* Nonzero from the first call cancels whatever the timing. */
        log = (progress_log){0, 0, 0, 1, 1, r, 0};
        CHECK_EQ_INT(nerf_renderer_render_image(r, &cam, img.rgb, NULL, NULL,
                                                NPIX), NERF_ECANCELLED);
        CHECK(log.calls == 1);
        /* So does nerf_renderer_cancel(), unless every chunk was already
         * finished when it came. */
        log = (progress_log){0, 0, 0, 1, 1, r, 1};
        rc = nerf_renderer_render_image(r, &cam, img.rgb, NULL, NULL,
                                            NPIX);
        CHECK(rc == NERF_ECANCELLED ||
              (threads > 1 && rc == NERF_OK && log.last == NPIX));
        /* A cancel between calls does not affect the next call. */
        nerf_renderer_cancel(r);
        CHECK_OK(nerf_renderer_set_progress(r, NULL, NULL));
        CHECK_OK(nerf_renderer_render_image(r, &cam, img.rgb, NULL, NULL,
                                            NPIX));
        nerf_renderer_destroy(r);
    }
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

typedef struct canceller {
    nerf_renderer *r;
    atomic_int stop;
} canceller;

static void *cancel_loop(void *arg)
{
    canceller *c = arg;
    while (!atomic_load(&c->stop)) {
        nerf_renderer_cancel(c->r);
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    }
    return NULL;
}

TEST(cancel_from_another_thread)
{
    /* One chunk holding the whole image: the flag is also checked between
     * the 64-ray batches inside a chunk.  The other thread cancels every
     * millisecond, since each call clears the flag when it starts. */
    nerf_model *m = tiny_model();
    nerf_sampler *s = tiny_sampler(0);
    for (uint32_t threads = 1; threads <= 2; threads++) {
        nerf_renderer *r = renderer(m, s, 1u << 20, threads, 0);
        nerf_camera cam;
        test_camera(&cam);
        cam.width = cam.height = 96;
        float *rgb = malloc(sizeof(float) * 3 * 96 * 96);
        canceller c = {r, 0};
        pthread_t tid;
        CHECK(pthread_create(&tid, NULL, cancel_loop, &c) == 0);
        int rc = nerf_renderer_render_image(r, &cam, rgb, NULL, NULL,
                                            96 * 96);
        atomic_store(&c.stop, 1);
        pthread_join(tid, NULL);
        CHECK_EQ_INT(rc, NERF_ECANCELLED);
        free(rgb);
        nerf_renderer_destroy(r);
    }
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

TEST(argument_checks)
{
    nerf_model *m = tiny_model();
    nerf_sampler *s = tiny_sampler(0);
    nerf_renderer *r = NULL;
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    CHECK(ro.chunk_rays == 512 && ro.threads == 0 &&
          ro.raw_noise_std == NERF_NOISE_AUTO && ro.white_background == 0);
    CHECK_EQ_INT(nerf_renderer_create(&r, NULL, s, &ro), NERF_EINVAL);
    /* Since 0.4 no sampler means the model's own (test_export). */
    CHECK_OK(nerf_renderer_create(&r, m, NULL, &ro));
    nerf_renderer_destroy(r);
    r = NULL;
    ro.chunk_rays = 0;
    CHECK_EQ_INT(nerf_renderer_create(&r, m, s, &ro), NERF_EINVAL);
    ro.chunk_rays = 64;
    ro.raw_noise_std = -0.5f;
    CHECK_EQ_INT(nerf_renderer_create(&r, m, s, &ro), NERF_EINVAL);
    ro.raw_noise_std = 0.0f;
    ro.white_background = 2;
    CHECK_EQ_INT(nerf_renderer_create(&r, m, s, &ro), NERF_EINVAL);
    CHECK(r == NULL);
    CHECK_OK(nerf_renderer_create(&r, m, s, NULL));
    nerf_camera cam;
    test_camera(&cam);
    static image img;
    CHECK_EQ_INT(nerf_renderer_render_image(r, &cam, img.rgb, NULL, NULL,
                                            NPIX - 1), NERF_EINVAL);
    CHECK_EQ_INT(nerf_renderer_render_image(r, &cam, NULL, NULL, NULL, NPIX),
                 NERF_EINVAL);
    CHECK_EQ_INT(nerf_renderer_render_image_u8(r, &cam, NULL, img.depth, NULL,
                                               NPIX), NERF_EINVAL);
    CHECK_EQ_INT(nerf_renderer_render_image(NULL, &cam, img.rgb, NULL, NULL,
                                            NPIX), NERF_EINVAL);
    cam.fy = -1.0f;
    CHECK_EQ_INT(nerf_renderer_render_image(r, &cam, img.rgb, NULL, NULL,
                                            NPIX), NERF_EINVAL);
    float o[6] = {0, 0, 4, 0, 0, 4}, d[6] = {0, 0, -1, 0, 0, 0}, c[6];
    CHECK_EQ_INT(nerf_renderer_render_rays(r, 2, o, d, c, NULL, NULL),
                 NERF_EINVAL);
    d[5] = NAN;
    CHECK_EQ_INT(nerf_renderer_render_rays(r, 2, o, d, c, NULL, NULL),
                 NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "ray 1") != NULL);
    CHECK_OK(nerf_renderer_render_rays(r, 1, o, d, c, NULL, NULL));
    CHECK_OK(nerf_renderer_render_rays(r, 0, NULL, NULL, c, NULL, NULL));
    CHECK_EQ_INT(nerf_renderer_set_progress(NULL, NULL, NULL), NERF_EINVAL);
    nerf_renderer_cancel(NULL);
    nerf_renderer_destroy(r);
    nerf_renderer_destroy(NULL);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
}

/*
 * Left to the library, the workers of a renderer whose model goes
 * through the BLAS share the cores with the BLAS's threads; a model on
 * the fused path calls no BLAS and gets a worker per core, whatever the
 * BLAS's thread count.
 */
TEST(default_workers)
{
    nerf_model *fast = fast_model(), *tiny = tiny_model();
    nerf_sampler *s = fast_sampler(1024);
    nerf_renderer *rf = NULL, *rt = NULL;
    if (fast && tiny && s) {
        CHECK_OK(nerf_renderer_create(&rf, fast, s, NULL));
        CHECK_OK(nerf_renderer_create(&rt, tiny, NULL, NULL));
    }
    if (rf && rt) {
        const uint32_t cores = nerf__cpu_count();
        const int blas = nerf__blas_threads();
        uint32_t shared = blas > 1 ? cores / (uint32_t)blas : cores;
        shared = shared ? shared : 1;
        printf("  %u cores, BLAS on %d threads: %u workers for the fast "
               "model, %u for the tiny one\n", cores, blas, rf->threads,
               rt->threads);
        CHECK(nerf__model_uses_blas(tiny));
        CHECK_EQ_INT(rt->threads, shared);
        /* Off the fused path where the library keeps it off, or where
         * oneDNN computes the products (NERF_FP32_PRODUCTS=onednn). */
        CHECK(nerf__model_uses_blas(fast) ==
              (fast->onednn != NULL || nerf__smm_default() == NERF__SMM_OFF));
        CHECK_EQ_INT(rf->threads,
                     nerf__model_uses_blas(fast) ? shared : cores);
    }
    nerf_renderer_destroy(rf);
    nerf_renderer_destroy(rt);
    nerf_sampler_destroy(s);
    nerf_model_destroy(fast);
    nerf_model_destroy(tiny);
}

int main(void)
{
    RUN(chunks_and_threads_bitwise);
    RUN(matches_building_blocks);
    RUN(marching_chunks_and_threads_bitwise);
    RUN(marching_matches_building_blocks);
    RUN(marching_image_in_tiles);
    RUN(ndc_render);
    RUN(progress_and_cancel);
    RUN(cancel_from_another_thread);
    RUN(argument_checks);
    RUN(default_workers);
    HARNESS_EXIT();
}
