/* nerf-eval: PSNR and SSIM of a trained model on a split of its scene. */
#include <nerf.h>

#include <cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/cli.h"
#include "common/opt_table.h"
#include "common/progress.h"
#include "common/scene_setup.h"
#include "common/shared_opts.h"

#define PROG "nerf-eval"

static const char about[] =
    "Render every view of a split of the scene MODEL was trained on and\n"
    "compare it with the scene's image: PSNR (dB, higher is better) and SSIM\n"
    "(0..1, Gaussian window 11, sigma 1.5) per view and on average.  Views\n"
    "are numbered by their index in the split: \"view 16\" is its 17th image.\n";

static const char after[] =
    "It writes no file: the table (or --json) goes to stdout.\n"
    "Examples:\n"
    "  nerf-eval --model lego.nerf --data lego --downscale 8 --skip 8\n"
    "  nerf-eval --model fern.nerf --data fern --downscale 8 --json \\\n"
    "      > fern-eval.json\n";

typedef struct args {
    const char *model, *data;
    uint64_t split, downscale, skip;
    int64_t march; /* -1: the model's */
    int json;
    uint32_t appearance;
    int no_masks;
} args;

static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    a->split = NERF_SPLIT_TEST;
    a->downscale = 1;
    a->skip = 1;
    a->march = -1;
    const opt opts[] = {
        {OPT_MODEL(&a->model)},
        {.name = "--data", OPT_TEXT_TO(&a->data), .flags = OPT_REQUIRED,
         .value = "DIR",
         .help = "the scene (required): Blender, transforms.json, LLFF\n"
                 "or COLMAP, as for nerf-train"},
        {OPT_SPLIT(&a->split),
         .help = "train, val or test (default {default})"},
        {OPT_DOWNSCALE(&a->downscale),
         .help = "load the images K times smaller (default {default}: full\n"
                 "size); use the value MODEL was trained with"},
        {OPT_SKIP(&a->skip),
         .help = "score only every K-th view of the split (views 0, K,\n"
                 "2K, ...), to save time, as the reference's \"testskip\"\n"
                 "(default {default}: every view)"},
        {OPT_MARCH_STEPS("--march-steps", &a->march),
         .help = "render a marching model (the fast preset) in steps\n"
                 "of its grid's diagonal / N, {range}, instead of the\n"
                 "N MODEL records (nerf-train --render-march-steps,\n"
                 "1280 for fast since 0.10.9; 1024 before, as it\n"
                 "trains): finer steps integrate each ray more exactly\n"
                 "and take longer (docs/performance.md; default:\n"
                 "MODEL's)"},
        {OPT_APPEARANCE(&a->appearance),
         .help = "a model with appearance codes (nerf-train\n"
                 "--appearance-codes) renders with: neutral (the mean\n"
                 "of its codes, the default) or training image A's\n"
                 "code; the output says which"},
        {OPT_NO_MASKS(&a->no_masks),
         .help = "score every pixel, even those the scene's masks leave\n"
                 "out (by default a masked pixel counts in neither\n"
                 "score, and the output says how many were left out)"},
        {.name = "--json", OPT_FLAG_SETS(&a->json, 1),
         .help = "print one JSON object on stdout instead of the table:\n"
                 "{\"psnr\", \"ssim\", \"views\", \"seconds\",\n"
                 "\"appearance\", \"masked_pixels\", \"pixels\", \"per_view\":\n"
                 "[{\"view\", \"psnr\", \"ssim\", \"masked_pixels\"},\n"
                 "...]} (default off)"},
        {.name = NULL},
    };
    const opt_program p = {.name = PROG, .opts = opts, .column = 17,
                           .about = about, .after = after};
    return opt_parse(&p, argc, argv);
}

/* Render and score every view; per-view figures go into per_view. */
static int evaluate(const args *a, nerf_renderer *r, const nerf_dataset *ds,
                    cJSON *per_view, double *psnr_out, double *ssim_out,
                    uint64_t *masked_out)
{
    *masked_out = 0;
    uint32_t n = nerf_dataset_count(ds), w, h;
    nerf_dataset_image_size(ds, &w, &h);
    float *rgb = malloc((size_t)w * h * 3 * sizeof(float));
    if (rgb == NULL) {
        fprintf(stderr, "nerf-eval: out of memory\n");
        return NERF_ENOMEM;
    }
    progress bar;
    progress_begin(&bar, "nerf-eval", n);
    double psnr_sum = 0.0, ssim_sum = 0.0;
    int rc = NERF_OK;
    for (uint32_t i = 0; i < n && rc == NERF_OK; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        const float *truth = NULL;
        double psnr = 0.0, ssim = 0.0;
        rc = nerf_dataset_camera(ds, i, &cam);
        if (rc == NERF_OK) {
            rc = nerf_dataset_image(ds, i, &truth);
        }
        if (rc == NERF_OK) {
            rc = nerf_renderer_render_image(r, &cam, rgb, NULL, NULL,
                                            (size_t)w * h);
        }
        const uint8_t *mask = NULL;
        if (rc == NERF_OK) {
            rc = nerf_dataset_mask(ds, i, &mask);
        }
        uint64_t left_out = 0;
        for (size_t p = 0; mask != NULL && p < (size_t)w * h; p++) {
            left_out += mask[p] == 0;
        }
        /* A view its mask leaves whole scores as it always has. */
        if (left_out == 0) {
            mask = NULL;
        }
        if (rc == NERF_OK) {
            rc = mask ? nerf_psnr_masked(rgb, truth, mask, (size_t)w * h, 3,
                                         &psnr)
                      : nerf_psnr(rgb, truth, (size_t)w * h * 3, &psnr);
        }
        if (rc == NERF_OK) {
            rc = mask ? nerf_ssim_masked(rgb, truth, mask, w, h, 3, &ssim)
                      : nerf_ssim(rgb, truth, w, h, 3, &ssim);
        }
        *masked_out += left_out;
        if (rc != NERF_OK) {
            break;
        }
        psnr_sum += psnr;
        ssim_sum += ssim;
        /* The dataset keeps every skip-th view of the split: number them
         * as the split does, so that view 16 is the split's view 16. */
        uint64_t view = (uint64_t)i * a->skip;
        if (a->json) {
            cJSON *v = cJSON_CreateObject();
            cJSON_AddNumberToObject(v, "view", (double)view);
            cJSON_AddNumberToObject(v, "psnr", psnr);
            cJSON_AddNumberToObject(v, "ssim", ssim);
            cJSON_AddNumberToObject(v, "masked_pixels", (double)left_out);
            cJSON_AddItemToArray(per_view, v);
        } else if (left_out > 0) {
            printf("view %3llu  psnr %6.2f  ssim %.4f  (%llu pixels masked "
                   "out)\n", (unsigned long long)view, psnr, ssim,
                   (unsigned long long)left_out);
        } else {
            printf("view %3llu  psnr %6.2f  ssim %.4f\n",
                   (unsigned long long)view, psnr, ssim);
        }
        char note[64];
        snprintf(note, sizeof note, "mean psnr %.2f", psnr_sum / (i + 1));
        progress_update(&bar, i + 1, note);
    }
    free(rgb);
    *psnr_out = n ? psnr_sum / n : 0.0;
    *ssim_out = n ? ssim_sum / n : 0.0;
    return rc;
}

int main(int argc, char **argv)
{
    cli_blas_single_thread();
    args a;
    if (parse(argc, argv, &a) != 0) {
        return 2;
    }
    double start = progress_now();
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = "nerf-eval";
    nerf_model *m = NULL;
    nerf_dataset *ds = NULL;
    nerf_sampler *s = NULL;
    nerf_renderer *r = NULL;
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    dopt.split = (uint32_t)a.split;
    dopt.downscale = (uint32_t)a.downscale;
    dopt.skip = (uint32_t)a.skip;
    dopt.ignore_masks = (uint32_t)a.no_masks;
    dopt.hooks = &hooks;
    int rc = nerf_model_load(&m, a.model, &hooks);
    if (rc == NERF_OK) {
        dopt.forward_facing = setup_forward_facing(m, -1);
        rc = nerf_dataset_load(&ds, a.data, &dopt);
    }
    if (rc == NERF_OK) {
        sampler_choice c = SAMPLER_AS_RECORDED;
        c.march_steps = a.march;
        rc = setup_sampler(&s, m, ds, &c);
    }
    if (rc == NERF_OK) {
        nerf_renderer_options ro;
        NERF_RENDERER_OPTIONS_INIT(&ro);
        ro.white_background = (uint32_t)setup_white_background(ds);
        ro.appearance = a.appearance;
        ro.hooks = &hooks;
        rc = nerf_renderer_create(&r, m, s, &ro);
    }
    char look[96] = "";
    if (rc == NERF_OK) {
        appearance_text(m, a.appearance, look, sizeof look);
        if (!a.json) {
            printf("appearance: %s\n", look);
        }
    }
    cJSON *root = cJSON_CreateObject();
    cJSON *per_view = cJSON_CreateArray();
    double psnr = 0.0, ssim = 0.0;
    uint64_t masked = 0;
    if (rc == NERF_OK) {
        rc = evaluate(&a, r, ds, per_view, &psnr, &ssim, &masked);
    }
    if (rc == NERF_OK) {
        double seconds = progress_now() - start;
        uint32_t w = 0, h = 0;
        nerf_dataset_image_size(ds, &w, &h);
        uint64_t pixels = (uint64_t)w * h * nerf_dataset_count(ds);
        if (a.json) {
            cJSON_AddNumberToObject(root, "psnr", psnr);
            cJSON_AddNumberToObject(root, "ssim", ssim);
            cJSON_AddNumberToObject(root, "views", nerf_dataset_count(ds));
            cJSON_AddNumberToObject(root, "seconds", seconds);
            cJSON_AddStringToObject(root, "appearance", look);
            cJSON_AddNumberToObject(root, "masked_pixels", (double)masked);
            cJSON_AddNumberToObject(root, "pixels", (double)pixels);
            cJSON_AddItemToObject(root, "per_view", per_view);
            per_view = NULL;
            char *text = cJSON_PrintUnformatted(root);
            printf("%s\n", text ? text : "{}");
            cJSON_free(text);
        } else {
            printf("mean      psnr %6.2f  ssim %.4f  (%u views, %.1f s)\n",
                   psnr, ssim, nerf_dataset_count(ds), seconds);
            if (nerf_dataset_has_masks(ds)) {
                printf("masks left %llu of %llu pixels out of the scores "
                       "(%.2f%%)\n", (unsigned long long)masked,
                       (unsigned long long)pixels,
                       pixels ? 100.0 * (double)masked / (double)pixels
                              : 0.0);
            }
        }
    } else {
        cli_report("nerf-eval", rc);
    }
    cJSON_Delete(per_view);
    cJSON_Delete(root);
    nerf_renderer_destroy(r);
    nerf_sampler_destroy(s);
    nerf_dataset_destroy(ds);
    nerf_model_destroy(m);
    return rc == NERF_OK ? 0 : 1;
}
