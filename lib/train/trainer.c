#include "trainer.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "camera.h"
#include "dataset.h"
#include "file_io.h"
#include "options.h"

static void trainer_defaults(nerf_trainer_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->batch_rays = 1024;
    o->precrop_steps = 500;
    o->precrop_fraction = 0.5f;
    o->raw_noise_std = NERF_NOISE_AUTO;
    o->white_background = -1;
}

NERF_API int nerf_trainer_options_init(nerf_trainer_options *opts,
                                       size_t struct_size)
{
    nerf_trainer_options d;
    trainer_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_trainer_options");
}

static int check_options(const void *opts)
{
    const nerf_trainer_options *o = opts;
    const char *what = NULL;
    if (o->batch_rays < 1 || o->batch_rays > NERF__BATCH_RAYS_MAX) {
        what = "batch_rays must be 1..1048576";
    } else if (!(o->precrop_fraction > 0.0f && o->precrop_fraction <= 1.0f)) {
        what = "precrop_fraction must be in (0, 1]";
    } else if (!(o->raw_noise_std == NERF_NOISE_AUTO ||
                 (o->raw_noise_std >= 0.0f && o->raw_noise_std < 1e6f))) {
        what = "raw_noise_std must be >= 0 or NERF_NOISE_AUTO";
    } else if (o->white_background < -1 || o->white_background > 1) {
        what = "white_background must be -1 (auto), 0 or 1";
    } else if (o->checkpoint_every > 0 && o->checkpoint_path == NULL) {
        what = "checkpoint_every needs a checkpoint_path";
    } else if (o->reserved0 != 0) {
        what = "reserved0 must be 0";
    } else if (o->batch_samples > NERF__BATCH_SAMPLES_MAX) {
        what = "batch_samples must be 0..67108864";
    } else if (o->random_background != 0 && o->random_background != 1) {
        what = "random_background must be 0 or 1";
    } else if (o->worker_count > (1u << 20)) {
        what = "worker_count must be 0..1048576";
    } else if (o->worker_rank >= (o->worker_count ? o->worker_count : 1u)) {
        what = o->worker_count > 1
                   ? "worker_rank must be less than worker_count"
                   : "worker_rank must be 0 without worker_count";
    } else if (o->worker_count > 1 && o->grad_hook == NULL) {
        what = "worker_count > 1 needs a grad_hook to sum the workers' "
               "gradients";
    } else if (o->checksum_every > 0 && o->checksum_hook == NULL) {
        what = "checksum_every needs a checksum_hook";
    } else if (o->reserved1 != 0) {
        what = "reserved1 must be 0";
    } else if (!(o->checkpoint_seconds >= 0.0 &&
                 o->checkpoint_seconds <= 1e12)) { /* also NaN */
        what = "checkpoint_seconds must be a finite time >= 0";
    } else if (o->checkpoint_seconds > 0.0 && o->checkpoint_path == NULL) {
        what = "checkpoint_seconds needs a checkpoint_path";
    } else if (o->render_march_steps > 65536) {
        what = "render_march_steps must be 0..65536";
    } else if (o->appearance_codes > 1) {
        what = "appearance_codes must be 0 or 1";
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_options: %s", what);
    }
    return NERF_OK;
}

static int load_cameras(nerf_trainer *t)
{
    t->cameras = nerf__calloc(&t->env, t->n_images, sizeof *t->cameras);
    if (t->cameras == NULL) {
        return NERF_ENOMEM;
    }
    for (uint32_t i = 0; i < t->n_images; i++) {
        nerf_camera c;
        NERF_CAMERA_INIT(&c);
        int rc = nerf_dataset_camera(t->dataset, i, &c);
        if (rc == NERF_OK) {
            rc = nerf__camera_read(&t->cameras[i], &c, "nerf_trainer_create");
        }
        if (rc != NERF_OK) {
            return rc;
        }
    }
    return NERF_OK;
}

static int alloc_buffers(nerf_trainer *t)
{
    const size_t n = (size_t)t->opts.batch_rays * 3;
    float **bufs[] = {&t->origins, &t->directions, &t->targets, &t->rgb[0],
                      &t->rgb[1], &t->d_rgb[0], &t->d_rgb[1]};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++) {
        *bufs[i] = nerf__calloc(&t->env, n, sizeof(float));
        if (*bufs[i] == NULL) {
            return NERF_ENOMEM;
        }
    }
    t->picked = nerf__calloc(&t->env, t->opts.batch_rays, sizeof(size_t));
    if (t->picked == NULL) {
        return NERF_ENOMEM;
    }
    if (t->random_bg) {
        t->backgrounds = nerf__calloc(&t->env, n, sizeof(float));
        if (t->backgrounds == NULL) {
            return NERF_ENOMEM;
        }
    }
    if (t->workers > 1 && t->march && t->opts.batch_samples > 0) {
        t->march_offsets = nerf__calloc(&t->env, (size_t)t->opts.batch_rays + 1,
                                        sizeof *t->march_offsets);
        if (t->march_offsets == NULL) {
            return NERF_ENOMEM;
        }
    }
    return NERF_OK;
}

static char *copy_string(const nerf__env *env, const char *s)
{
    size_t n = strlen(s) + 1;
    char *c = nerf__alloc(env, n);
    if (c) {
        memcpy(c, s, n);
    }
    return c;
}

static void setup_render(nerf_trainer *t)
{
    nerf__render_setup *s = &t->setup;
    memset(s, 0, sizeof *s);
    s->model = t->model;
    s->sampler = t->sampler;
    s->training = true;
    s->keep = true;
    s->white_background = t->white;
    s->noise_std = t->noise_std;
    /* Workers find the whole batch's cut themselves and render only
     * their share of it (workers.c). */
    s->sample_budget = t->workers > 1 ? 0 : t->opts.batch_samples;
    s->background = t->backgrounds;
    if (t->sampler->opts.ndc) {
        /* The NDC frustum of a forward-facing scene is that of its
         * training images unless the sampler fixes one. */
        bool own = t->sampler->opts.ndc_focal > 0.0f;
        s->ndc_focal = own ? t->sampler->opts.ndc_focal : t->cameras[0].fx;
        s->ndc_width = own ? (float)t->sampler->opts.ndc_width
                           : (float)t->cameras[0].width;
        s->ndc_height = own ? (float)t->sampler->opts.ndc_height
                            : (float)t->cameras[0].height;
    }
}

/*
 * The model keeps what it is trained with, so that its checkpoints render
 * right for a caller who knows nothing of the scene: the sampler with the
 * NDC frustum of the training images, and the background its renders
 * are composited on (with a random background too: that one is only for
 * the loss).
 */
static void record_render_settings(nerf_trainer *t)
{
    nerf_sampler_options so = t->sampler->opts;
    if (so.ndc && !(so.ndc_focal > 0.0f)) {
        so.ndc_focal = t->setup.ndc_focal;
        so.ndc_width = (uint32_t)t->setup.ndc_width;
        so.ndc_height = (uint32_t)t->setup.ndc_height;
    }
    if (t->opts.render_march_steps > 0) {
        /* Checked in range by check_options(); options that do not march
         * are left as they are. */
        nerf_sampler_options_set_march(&so, t->opts.render_march_steps);
    }
    if (nerf_model_set_render_settings(t->model, &so, t->white ? 1u : 0u) !=
        NERF_OK) {
        /* A created sampler passes the same checks: cannot happen. */
        nerf__log(&t->env, NERF_LOG_WARN, "trainer: the model does not "
                  "record its render settings (%s)", nerf_last_error());
    }
}

NERF_API int nerf_trainer_create(nerf_trainer **out, nerf_model *model,
                                 const nerf_dataset *dataset,
                                 const nerf_sampler *sampler,
                                 const nerf_trainer_options *opts)
{
    if (out == NULL || model == NULL || dataset == NULL || sampler == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_create: NULL argument");
    }
    *out = NULL;
    nerf_trainer_options o;
    trainer_defaults(&o);
    nerf__env env;
    int rc = nerf__options_open(&o, sizeof o, opts, "nerf_trainer_options",
                                check_options, &o.hooks, &env);
    if (rc != NERF_OK) {
        return rc;
    }
    if (dataset->count == 0) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_create: the dataset "
                           "has no images");
    }
    rc = nerf__render_check_pair(model, sampler, "nerf_trainer_create");
    if (rc == NERF_OK) {
        /* Adam cannot bring NaN weights back: resume from a checkpoint
         * saved before the run diverged. */
        rc = nerf__model_check_finite(model, "nerf_trainer_create");
    }
    if (rc != NERF_OK) {
        return rc;
    }
    if (model->weights_only) {
        /* Adam from zero moments at a late step would take steps several
         * times too large, undoing the training it was meant to extend. */
        return nerf__error(NERF_EINVAL, "nerf_trainer_create: the model was "
                           "loaded from a weights-only export, which holds "
                           "no optimiser state to train on with; resume "
                           "from the full checkpoint it was exported from");
    }
    nerf_trainer *t = nerf__calloc(&env, 1, sizeof *t);
    if (t == NULL) {
        return NERF_ENOMEM;
    }
    t->env = env;
    t->opts = o;
    t->opts.hooks = NULL;
    t->opts.checkpoint_path = NULL;
    t->model = model;
    t->dataset = dataset;
    t->sampler = sampler;
    t->march = nerf__sampler_marches(sampler);
    t->workers = o.worker_count > 1 ? o.worker_count : 1;
    t->n_images = dataset->count;
    t->width = dataset->width;
    t->height = dataset->height;
    t->white = o.white_background == -1 ? dataset->white_background != 0
                                         : o.white_background == 1;
    /* Opaque images have nothing to put a background behind. */
    t->random_bg = o.random_background == 1 && dataset->alpha != NULL;
    t->noise_std = o.raw_noise_std == NERF_NOISE_AUTO
                       ? (sampler->opts.ndc ? 1.0f : 0.0f)
                       : o.raw_noise_std;
    if (sampler->opts.ndc) {
        t->opts.precrop_steps = 0; /* forward-facing: the reference has none */
    }
    nerf__batch_init(&t->batch, &env);
    atomic_init(&t->cancel, 0);
    rc = load_cameras(t);
    if (rc == NERF_OK) {
        rc = alloc_buffers(t);
    }
    if (rc == NERF_OK && o.checkpoint_path) {
        t->checkpoint_path = copy_string(&env, o.checkpoint_path);
        rc = t->checkpoint_path ? NERF_OK : NERF_ENOMEM;
    }
    if (rc == NERF_OK && o.checkpoint_path) {
        /* Now, not at the first save, maybe hours of training later. */
        rc = nerf__file_check_writable(&env, o.checkpoint_path);
    }
    if (rc == NERF_OK) {
        /* The only change to the model a failed create could leave. */
        rc = nerf__trainer_appearance_setup(t);
    }
    if (rc != NERF_OK) {
        nerf_trainer_destroy(t);
        return rc;
    }
    setup_render(t);
    record_render_settings(t);
    nerf__trainer_exchange_init(t);
    char per_step[64];
    if (o.batch_samples > 0) {
        snprintf(per_step, sizeof per_step, "up to %u rays of %u samples",
                 o.batch_rays, o.batch_samples);
    } else {
        snprintf(per_step, sizeof per_step, "%u rays", o.batch_rays);
    }
    if (t->workers > 1) {
        nerf__log(&env, NERF_LOG_INFO, "trainer: worker %u of %u, training on "
                  "its share of each step's rays", (unsigned)o.worker_rank,
                  (unsigned)t->workers);
    }
    nerf__log(&env, NERF_LOG_INFO, "trainer: %u images of %ux%u, %s per "
              "step, %s background, density noise %g, precrop %u steps%s",
              t->n_images, t->width, t->height, per_step,
              t->random_bg ? "random" : t->white ? "white" : "black",
              t->march ? 0.0 : (double)t->noise_std, t->opts.precrop_steps,
              t->march ? ", ray marching through the occupancy grid" : "");
    nerf__trainer_record_data(t);
    nerf__trainer_record_batch(t);
    *out = t;
    return NERF_OK;
}

NERF_API void nerf_trainer_destroy(nerf_trainer *t)
{
    if (t == NULL) {
        return;
    }
    nerf__env env = t->env;
    nerf__batch_release(&t->batch);
    nerf__workspace_release(&t->model->env, &t->density_ws);
    float *bufs[] = {t->origins, t->directions, t->targets, t->rgb[0],
                     t->rgb[1], t->d_rgb[0], t->d_rgb[1]};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; i++) {
        nerf__free(&env, bufs[i]);
    }
    nerf__free(&env, t->backgrounds);
    nerf__trainer_appearance_free(t);
    nerf__free(&env, t->picked);
    nerf__free(&env, t->march_offsets);
    nerf__free(&env, t->cameras);
    nerf__free(&env, t->checkpoint_path);
    nerf__free(&env, t);
}

NERF_API int nerf_trainer_set_progress(nerf_trainer *t, nerf_progress_cb cb,
                                       void *user)
{
    if (t == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_trainer_set_progress: trainer "
                           "is NULL");
    }
    t->progress = cb;
    t->progress_user = user;
    return NERF_OK;
}

NERF_API void nerf_trainer_cancel(nerf_trainer *t)
{
    if (t) {
        atomic_store(&t->cancel, 1);
    }
}
