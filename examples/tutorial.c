/*
 * tutorial: the program docs/tutorial-c.md walks through.  It writes
 * libnerf's built-in scene, trains a small NeRF on it, reports the PSNR on
 * held-out views and renders an orbit around the scene.
 *
 *   tutorial OUT_DIR [STEPS [FRAMES [PRESET]]]
 *
 * PRESET is tiny (the default), fast or reference; the run is the one
 * `nerf-train --preset PRESET --steps STEPS` makes on OUT_DIR/scene, bit
 * for bit.
 * Everything it writes goes to OUT_DIR: scene/, model.nerf and
 * orbit_NNN.png.
 */
#include <nerf.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* On failure: say which call failed and why, then clean up. */
#define CHECK(call)                                                     \
    do {                                                                \
        rc = (call);                                                    \
        if (rc != NERF_OK) {                                            \
            fprintf(stderr, "%s failed: %s: %s\n", #call,               \
                    nerf_status_string(rc), nerf_last_error());         \
            goto done;                                                  \
        }                                                               \
    } while (0)

#define SIZE 64 /* pixels, for the scene's images and the orbit */

/* Called by nerf_trainer_run() after every step; nonzero would stop it. */
static int on_progress(const nerf_progress *p, void *user)
{
    (void)user;
    if (p->done % 100 == 0 || p->done == p->total) {
        printf("step %4llu/%llu  loss %.5f  psnr %5.2f dB  %.0f s\n",
               (unsigned long long)p->done, (unsigned long long)p->total,
               p->loss, p->psnr, p->elapsed);
        fflush(stdout);
    }
    return 0;
}

/* A camera on a circle of radius 4 at 30 degrees elevation, looking at
 * the origin with z up, as the scene's own cameras do. */
static int orbit_camera(unsigned i, unsigned n, float focal, nerf_camera *cam)
{
    const double pi = 3.14159265358979323846;
    double az = 2.0 * pi * i / n, elev = pi / 6.0;
    float eye[3] = {(float)(4.0 * cos(elev) * cos(az)),
                    (float)(4.0 * cos(elev) * sin(az)),
                    (float)(4.0 * sin(elev))};
    const float target[3] = {0, 0, 0}, up[3] = {0, 0, 1};
    NERF_CAMERA_INIT(cam);
    cam->width = cam->height = SIZE;
    cam->fx = cam->fy = focal;
    cam->cx = cam->cy = 0.5f * SIZE;
    return nerf_camera_look_at(cam, eye, target, up);
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 5) {
        fprintf(stderr, "usage: tutorial OUT_DIR [STEPS [FRAMES [PRESET]]]\n");
        return 2;
    }
    const char *out = argv[1];
    unsigned long steps = argc > 2 ? strtoul(argv[2], NULL, 10) : 1000;
    unsigned frames = argc > 3 ? (unsigned)strtoul(argv[3], NULL, 10) : 12;
    const char *name = argc > 4 ? argv[4] : "tiny";
    const int preset = strcmp(name, "tiny") == 0        ? NERF_PRESET_TINY
                       : strcmp(name, "fast") == 0      ? NERF_PRESET_FAST
                       : strcmp(name, "reference") == 0 ? NERF_PRESET_REFERENCE
                                                        : -1;
    if (steps == 0 || frames == 0 || preset < 0) {
        fprintf(stderr, "tutorial: STEPS and FRAMES must be at least 1, "
                "PRESET tiny, fast or reference\n");
        return 2;
    }
    if (mkdir(out, 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, "tutorial: %s: %s\n", out, strerror(errno));
        return 1;
    }
    char scene_dir[4096], path[4200];
    snprintf(scene_dir, sizeof scene_dir, "%s/scene", out);

    int rc = NERF_OK;
    nerf_dataset *train = NULL, *test = NULL;
    nerf_model *model = NULL;
    nerf_sampler *sampler = NULL;
    nerf_trainer *trainer = NULL;
    nerf_renderer *renderer = NULL;
    float *rgb = malloc(SIZE * SIZE * 3 * sizeof(float));
    if (rgb == NULL) {
        fprintf(stderr, "tutorial: out of memory\n");
        return 1;
    }

    /* 1. The data: the built-in scene, written as a Blender dataset. */
    nerf_scene_options scene;
    NERF_SCENE_OPTIONS_INIT(&scene);
    scene.width = scene.height = SIZE;
    scene.n_train = 60;
    scene.n_val = 0;
    scene.n_test = 4;
    CHECK(nerf_scene_write(scene_dir, &scene));

    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    CHECK(nerf_dataset_load(&train, scene_dir, &dopt));
    dopt.split = NERF_SPLIT_TEST;
    CHECK(nerf_dataset_load(&test, scene_dir, &dopt));

    /* 2. The model: a preset's network and learning rate, placed in the
     * dataset's scene (which matters to the fast preset's grids), with the
     * fastest fp32 products this machine has.  The learning rate decays
     * tenfold over the run. */
    nerf_model_options mopt;
    NERF_MODEL_OPTIONS_INIT(&mopt);
    CHECK(nerf_model_options_preset(&mopt, preset));
    CHECK(nerf_model_options_for_dataset(&mopt, train));
    mopt.matmul = NERF_MATMUL_FP32_FASTEST;
    CHECK(nerf_model_create(&model, &mopt));
    CHECK(nerf_model_set_param(model, NERF_PARAM_DECAY_STEPS, (double)steps));

    /* 3. The sampler: the model's sampling (the preset's sample counts, or
     * its march through the occupancy grid) between the dataset's near
     * and far bounds. */
    nerf_sampler_options sopt;
    NERF_SAMPLER_OPTIONS_INIT(&sopt);
    CHECK(nerf_sampler_options_for(&sopt, model, train,
                                   NERF_SAMPLER_FOR_TRAINING));
    CHECK(nerf_sampler_create(&sampler, &sopt));

    /* 4. Training: batches of random rays across all training images, as
     * many as the model's preset takes. */
    nerf_trainer_options topt;
    NERF_TRAINER_OPTIONS_INIT(&topt);
    CHECK(nerf_trainer_options_for(&topt, model));
    CHECK(nerf_trainer_create(&trainer, model, train, sampler, &topt));
    CHECK(nerf_trainer_set_progress(trainer, on_progress, NULL));
    CHECK(nerf_trainer_run(trainer, steps, NULL));
    snprintf(path, sizeof path, "%s/model.nerf", out);
    CHECK(nerf_model_save(model, path));
    printf("saved %s\n", path);

    /* 5. Evaluation: render each test view, as the model records it is
     * rendered (the scene's background; a fast model's finer march), and
     * compare it with its image. */
    nerf_trainer_destroy(trainer); /* before the sampler it uses */
    trainer = NULL;
    nerf_sampler_destroy(sampler);
    sampler = NULL;
    CHECK(nerf_sampler_options_for(&sopt, model, test,
                                   NERF_SAMPLER_FOR_RENDERING));
    CHECK(nerf_sampler_create(&sampler, &sopt));
    nerf_renderer_options ropt;
    NERF_RENDERER_OPTIONS_INIT(&ropt);
    CHECK(nerf_model_render_settings(model, NULL, &ropt));
    CHECK(nerf_renderer_create(&renderer, model, sampler, &ropt));
    double psnr_sum = 0.0;
    for (uint32_t i = 0; i < nerf_dataset_count(test); i++) {
        nerf_camera cam;
        const float *truth;
        double psnr;
        NERF_CAMERA_INIT(&cam);
        CHECK(nerf_dataset_camera(test, i, &cam));
        CHECK(nerf_renderer_render_image(renderer, &cam, rgb, NULL, NULL,
                                         SIZE * SIZE));
        CHECK(nerf_dataset_image(test, i, &truth));
        CHECK(nerf_psnr(rgb, truth, (size_t)SIZE * SIZE * 3, &psnr));
        psnr_sum += psnr;
    }
    printf("test PSNR %.2f dB over %u views\n",
           psnr_sum / nerf_dataset_count(test), nerf_dataset_count(test));

    /* 6. An orbit: new views from all around, with the training focal. */
    nerf_camera cam0;
    NERF_CAMERA_INIT(&cam0);
    CHECK(nerf_dataset_camera(train, 0, &cam0));
    for (unsigned i = 0; i < frames; i++) {
        nerf_camera cam;
        CHECK(orbit_camera(i, frames, cam0.fx, &cam));
        CHECK(nerf_renderer_render_image(renderer, &cam, rgb, NULL, NULL,
                                         SIZE * SIZE));
        snprintf(path, sizeof path, "%s/orbit_%03u.png", out, i);
        CHECK(nerf_image_write_png(path, SIZE, SIZE, 3, rgb));
    }
    printf("wrote %u orbit views to %s/orbit_*.png\n", frames, out);

done:
    nerf_renderer_destroy(renderer);
    nerf_trainer_destroy(trainer);
    nerf_sampler_destroy(sampler);
    nerf_model_destroy(model);
    nerf_dataset_destroy(test);
    nerf_dataset_destroy(train);
    free(rgb);
    return rc == NERF_OK ? 0 : 1;
}
