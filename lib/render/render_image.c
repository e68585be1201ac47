/* Whole-image rendering of a camera into caller buffers. */
#include <math.h>
#include <string.h>

#include "camera.h"
#include "renderer.h"

typedef struct image_job {
    const nerf_renderer *r;
    nerf__render_setup setup;
    nerf_camera cam;
    bool tiled;
    float *rgb;
    uint8_t *rgb8;
    float *depth, *opacity;
} image_job;

/*
 * Marching renders visit the image in tiles of TILE x TILE pixels, a
 * block of rays each, instead of in rows.  The samples of a tile's rays
 * lie close together at every level of a hash grid, so a block reads
 * fewer of the table's lines and finds more of them in cache, and frames
 * of a trained model render faster (docs/perf-log/
 * 2026-11-26-rendering-a-trained-fast-model.md).  Where each sample's
 * values come from it alone (the fused path; oneDNN's brgemm kernels), a
 * ray's result does not depend on the rays beside it, and a marching
 * render draws no random numbers (rays are numbered by their place in
 * the tile order), so the images are those of rows bit for bit; through
 * the CBLAS, whose kernels may round a sample by the rows of its product,
 * they agree to rounding.  Either way an image is the same for every
 * chunk size and thread count, since its blocks are.  The other samplers
 * keep rows, whose blocks their products were measured and made
 * reproducible on.
 */
#define TILE 8
_Static_assert(TILE * TILE == NERF__RENDER_BLOCK, "a tile is a block");

/*
 * The pixel at position i of the tile order of a width x height image:
 * tiles row by row, each read row by row; the last column and row of
 * tiles are narrower or shorter where TILE does not divide the image.
 */
static size_t tile_pixel(size_t i, uint32_t width, uint32_t height)
{
    const size_t band = (size_t)TILE * width; /* pixels in a row of tiles */
    const size_t ty = i / band, j = i % band;
    const size_t th = height - TILE * ty < TILE ? height - TILE * ty : TILE;
    const size_t tx = j / (TILE * th), in = j % (TILE * th);
    const size_t tw = width - TILE * tx < TILE ? width - TILE * tx : TILE;
    return (TILE * ty + in / tw) * width + TILE * tx + in % tw;
}

/* Rays of the k pixels from position at of the job's order, whose pixel
 * indices go to pix[k]. */
static void block_rays(const image_job *job, size_t at, size_t k,
                       nerf__worker *w, size_t *pix)
{
    if (!job->tiled) {
        nerf__camera_rays(&job->cam, at, k, w->origins, w->directions);
        for (size_t i = 0; i < k; i++) {
            pix[i] = at + i;
        }
        return;
    }
    for (size_t i = 0; i < k; i++) {
        pix[i] = tile_pixel(at + i, job->cam.width, job->cam.height);
    }
    /* By runs of neighbouring pixels, a tile's rows. */
    for (size_t i = 0, run; i < k; i += run) {
        for (run = 1; i + run < k && pix[i + run] == pix[i] + run; run++) {
        }
        nerf__camera_rays(&job->cam, pix[i], run, w->origins + 3 * i,
                          w->directions + 3 * i);
    }
}

static uint8_t to_byte(float c)
{
    if (!(c > 0.0f)) {
        return 0; /* also NaN */
    }
    if (c >= 1.0f) {
        return 255;
    }
    return (uint8_t)(c * 255.0f + 0.5f);
}

static int image_chunk(void *p, nerf__worker *w, size_t first, size_t count)
{
    image_job *job = p;
    size_t pix[NERF__RENDER_BLOCK];
    for (size_t at = first; at < first + count; at += NERF__RENDER_BLOCK) {
        if (nerf__renderer_cancelled(job->r)) {
            return nerf__error(NERF_ECANCELLED, "render cancelled");
        }
        size_t k = first + count - at;
        k = k < NERF__RENDER_BLOCK ? k : NERF__RENDER_BLOCK;
        block_rays(job, at, k, w, pix);
        nerf__render_setup s = job->setup;
        s.first_ray = at;
        nerf__pass_out out[NERF__PASSES];
        memset(out, 0, sizeof out);
        nerf__pass_out *last = &out[nerf__sampler_last_pass(s.sampler)];
        /* Rows write straight into the image; tiles go through the
         * worker's buffers. */
        const bool direct = !job->tiled;
        if (job->rgb && direct) {
            last->rgb = job->rgb + 3 * at;
        } else if (job->rgb || job->rgb8) {
            last->rgb = w->rgb;
        }
        if (job->depth) {
            last->depth = direct ? job->depth + at : w->depth;
        }
        if (job->opacity) {
            last->opacity = direct ? job->opacity + at : w->opacity;
        }
        int rc = nerf__render_batch(&w->batch, &s, k, w->origins,
                                    w->directions, out);
        if (rc != NERF_OK) {
            return rc;
        }
        for (size_t i = 0; i < k && !direct; i++) {
            if (job->rgb) {
                memcpy(job->rgb + 3 * pix[i], w->rgb + 3 * i,
                       3 * sizeof(float));
            }
            if (job->depth) {
                job->depth[pix[i]] = w->depth[i];
            }
            if (job->opacity) {
                job->opacity[pix[i]] = w->opacity[i];
            }
        }
        for (size_t i = 0; i < k && job->rgb8; i++) {
            for (int c = 0; c < 3; c++) {
                job->rgb8[3 * pix[i] + c] = to_byte(w->rgb[3 * i + c]);
            }
        }
    }
    return NERF_OK;
}

static int render_image(nerf_renderer *r, const nerf_camera *camera,
                        float *rgb, uint8_t *rgb8, float *depth,
                        float *opacity, size_t capacity, const char *fn)
{
    if (r == NULL) {
        return nerf__error(NERF_EINVAL, "%s: renderer is NULL", fn);
    }
    image_job job;
    int rc = nerf__camera_read(&job.cam, camera, fn);
    if (rc != NERF_OK) {
        return rc;
    }
    if (rgb == NULL && rgb8 == NULL && depth == NULL && opacity == NULL) {
        return nerf__error(NERF_EINVAL, "%s: every output is NULL", fn);
    }
    size_t pixels = (size_t)job.cam.width * job.cam.height;
    if (capacity < pixels) {
        return nerf__error(NERF_EINVAL, "%s: buffers hold %zu pixels, the "
                           "%ux%u image needs %zu", fn, capacity,
                           job.cam.width, job.cam.height, pixels);
    }
    /* Weights that became NaN in training since the renderer was made. */
    rc = nerf__model_check_finite(r->model, fn);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__renderer_eval_setup(r, &job.setup);
    if (r->sampler->opts.ndc && job.setup.ndc_focal == 0.0f) {
        /* No scene frustum: the camera's own, as the reference does when
         * it renders at the training resolution. */
        job.setup.ndc_focal = job.cam.fx;
        job.setup.ndc_width = (float)job.cam.width;
        job.setup.ndc_height = (float)job.cam.height;
    }
    job.r = r;
    job.tiled = nerf__sampler_marches(r->sampler);
    job.rgb = rgb;
    job.rgb8 = rgb8;
    job.depth = depth;
    job.opacity = opacity;
    return nerf__renderer_run(r, pixels, image_chunk, &job);
}

NERF_API int nerf_renderer_render_image(nerf_renderer *renderer,
                                        const nerf_camera *camera,
                                        float *rgb_out, float *depth_out,
                                        float *opacity_out,
                                        size_t pixel_capacity)
{
    return render_image(renderer, camera, rgb_out, NULL, depth_out,
                        opacity_out, pixel_capacity,
                        "nerf_renderer_render_image");
}

NERF_API int nerf_renderer_render_image_u8(nerf_renderer *renderer,
                                           const nerf_camera *camera,
                                           uint8_t *rgb_out,
                                           float *depth_out,
                                           float *opacity_out,
                                           size_t pixel_capacity)
{
    if (rgb_out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_renderer_render_image_u8: "
                           "rgb_out is NULL");
    }
    return render_image(renderer, camera, NULL, rgb_out, depth_out,
                        opacity_out, pixel_capacity,
                        "nerf_renderer_render_image_u8");
}
