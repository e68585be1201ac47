/*
 * What appearance codes and masks buy on the built-in scene, over seeds:
 * each line trains the fast preset (with a small hash grid, as the
 * training tests do) on one capture and prints its test PSNR, so that a
 * pair of lines with the same seed shows one difference.  It asserts
 * nothing: tests/train/test_appearance.c and test_masks.c check what
 * holds on any machine, this prints the figures docs/api-notes.md gives.
 *
 *   bench_captures CAPTURE SEED [STEPS [TEST_VIEWS [WIDTH [TRAIN_VIEWS]]]]
 *
 * (defaults 800 steps, 16 test views, 48 pixels square, 60 training
 * views; 1024 rays a step)
 *
 * CAPTURE is one of: constant, constant-codes, varied, varied-codes
 * (photos of one look or of varied exposure, trained without or with
 * codes), clean, occluded-masks, occluded (the capture without
 * occluders, with them and their masks, with them and no masks), and
 * scattered: the capture without occluders, masked in each training view
 * at as many pixels as the occluder's mask leaves out there, drawn at
 * random over the view (instant-ngp's dynamic_mask_ files), which tells
 * what losing those pixels costs from what the occluder's place does.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <nerf.h>

#define BATCH 1024
#define PRECROP 50

static int fail(const char *what)
{
    fprintf(stderr, "bench_captures: %s: %s\n", what, nerf_last_error());
    return 1;
}

/* A scene folder this program made under /tmp, and all it holds. */
static void remove_dir(const char *dir)
{
    char cmd[64];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_captures: could not remove %s\n", dir);
    }
}

/* The scattered capture's masks in dir, beside its training images
 * train/r_<i>.png: for view i, as many pixels as the occluded capture's
 * mask of view i leaves out, each pixel kept or not by a fixed stream so
 * that every run draws the same masks. */
static int scatter_masks(const char *dir, const nerf_scene_options *clean)
{
    char odir[] = "/tmp/bench_captures.XXXXXX";
    if (mkdtemp(odir) == NULL) {
        perror("bench_captures: mkdtemp");
        return 1;
    }
    nerf_scene_options so = *clean;
    so.occluders = 1;
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    nerf_dataset *occ = NULL;
    int rc = 1;
    if (nerf_scene_write(odir, &so) != NERF_OK ||
        nerf_dataset_load(&occ, odir, &dopt) != NERF_OK) {
        rc = fail("the occluded capture");
        goto out;
    }
    const size_t px = (size_t)so.width * so.height;
    uint8_t *drop = malloc(px);
    uint64_t state = 0x9e3779b97f4a7c15u;
    rc = drop ? 0 : 1;
    for (uint32_t i = 0; rc == 0 && i < so.n_train; i++) {
        const uint8_t *mask;
        if (nerf_dataset_mask(occ, i, &mask) != NERF_OK) {
            rc = fail("nerf_dataset_mask");
            continue;
        }
        size_t left = 0;
        for (size_t k = 0; k < px; k++) {
            left += mask[k] == 0;
            drop[k] = 0;
        }
        /* Draw `left` distinct pixels. */
        for (size_t k = 0; k < left;) {
            state = state * 6364136223846793005u + 1442695040888963407u;
            size_t at = (size_t)((state >> 33) % px);
            if (!drop[at]) {
                drop[at] = 255;
                k++;
            }
        }
        char path[sizeof odir + 64];
        snprintf(path, sizeof path, "%s/train/dynamic_mask_r_%u.png", dir,
                 (unsigned)i);
        if (left > 0 && nerf_image_write_png8(path, so.width, so.height, 1,
                                              drop) != NERF_OK) {
            rc = fail("nerf_image_write_png8");
        }
    }
    free(drop);
out:
    nerf_dataset_destroy(occ);
    remove_dir(odir);
    return rc;
}

static double test_psnr(nerf_model *m, nerf_sampler *s, nerf_dataset *test)
{
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.white_background = 1;
    nerf_renderer *r = NULL;
    if (nerf_renderer_create(&r, m, s, &ro) != NERF_OK) {
        return -1.0;
    }
    uint32_t w, h, n = nerf_dataset_count(test);
    nerf_dataset_image_size(test, &w, &h);
    const size_t px = (size_t)w * h;
    float *out = malloc(px * 3 * sizeof *out);
    double sum = 0.0;
    for (uint32_t i = 0; out && i < n; i++) {
        nerf_camera cam;
        NERF_CAMERA_INIT(&cam);
        const float *truth;
        double p = -1.0;
        if (nerf_dataset_camera(test, i, &cam) != NERF_OK ||
            nerf_dataset_image(test, i, &truth) != NERF_OK ||
            nerf_renderer_render_image(r, &cam, out, NULL, NULL, px) !=
                NERF_OK ||
            nerf_psnr(out, truth, px * 3, &p) != NERF_OK) {
            sum = -1.0 * n;
            break;
        }
        sum += p;
    }
    free(out);
    nerf_renderer_destroy(r);
    return out ? sum / n : -1.0;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: bench_captures CAPTURE SEED [STEPS "
                "[TEST_VIEWS [WIDTH [TRAIN_VIEWS]]]]\n");
        return 2;
    }
    const char *capture = argv[1];
    const uint64_t seed = strtoull(argv[2], NULL, 10);
    const int steps = argc > 3 ? atoi(argv[3]) : 800;
    const uint32_t n_test = argc > 4 ? (uint32_t)atoi(argv[4]) : 16;
    const uint32_t width = argc > 5 ? (uint32_t)atoi(argv[5]) : 48;
    const uint32_t n_train = argc > 6 ? (uint32_t)atoi(argv[6]) : 60;
    const int codes = strstr(capture, "-codes") != NULL;
    const int occluded = strncmp(capture, "occluded", 8) == 0;
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = so.height = width;
    so.n_train = n_train;
    so.n_val = 0;
    so.n_test = n_test;
    if (strncmp(capture, "varied", 6) == 0) {
        so.appearance = NERF_SCENE_APPEARANCE_VARIED;
    } else if (occluded) {
        so.occluders = 1;
    } else if (strcmp(capture, "clean") != 0 &&
               strcmp(capture, "scattered") != 0 &&
               strncmp(capture, "constant", 8) != 0) {
        fprintf(stderr, "bench_captures: unknown capture '%s'\n", capture);
        return 2;
    }
    char dir[] = "/tmp/bench_captures.XXXXXX";
    if (mkdtemp(dir) == NULL) {
        perror("bench_captures: mkdtemp");
        return 1;
    }
    int rc = 1;
    nerf_dataset *train = NULL, *test = NULL;
    nerf_model *m = NULL;
    nerf_sampler *s = NULL;
    nerf_trainer *t = NULL;
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    dopt.ignore_masks = strcmp(capture, "occluded") == 0;
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_FAST);
    mo.hash_levels = 8;
    mo.hash_log2_size = 15;
    mo.hash_max_resolution = 256;
    mo.seed = seed;
    nerf_sampler_options sopt;
    NERF_SAMPLER_OPTIONS_INIT(&sopt);
    nerf_sampler_options_preset(&sopt, NERF_PRESET_FAST);
    sopt.seed = seed;
    nerf_trainer_options to;
    NERF_TRAINER_OPTIONS_INIT(&to);
    to.batch_rays = BATCH;
    to.precrop_steps = PRECROP;
    to.appearance_codes = (uint32_t)codes;
    if (nerf_scene_write(dir, &so) != NERF_OK) {
        rc = fail("nerf_scene_write");
    } else if (strcmp(capture, "scattered") == 0 &&
               scatter_masks(dir, &so) != 0) {
        rc = 1;
    } else if (nerf_dataset_load(&train, dir, &dopt) != NERF_OK) {
        rc = fail("nerf_dataset_load");
    } else if ((dopt.split = NERF_SPLIT_TEST,
                nerf_dataset_load(&test, dir, &dopt)) != NERF_OK) {
        rc = fail("nerf_dataset_load");
    } else if (nerf_model_create(&m, &mo) != NERF_OK ||
               nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, steps) !=
                   NERF_OK) {
        rc = fail("nerf_model_create");
    } else if (nerf_sampler_create(&s, &sopt) != NERF_OK) {
        rc = fail("nerf_sampler_create");
    } else if (nerf_trainer_create(&t, m, train, s, &to) != NERF_OK ||
               nerf_trainer_run(t, (uint64_t)steps, NULL) != NERF_OK) {
        rc = fail("training");
    } else {
        printf("%-15s seed %llu, %ux%u, %u views, %d steps of %d rays: "
               "test PSNR %.3f dB (%u views)\n", capture,
               (unsigned long long)seed, (unsigned)width, (unsigned)width,
               (unsigned)n_train, steps, BATCH, test_psnr(m, s, test),
               (unsigned)n_test);
        rc = 0;
    }
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    nerf_dataset_destroy(train);
    nerf_dataset_destroy(test);
    remove_dir(dir);
    return rc;
}
