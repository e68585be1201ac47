/*
 * What a data-parallel step exchanges (docs/distributed.md): the
 * parameter counts of the fast and reference presets, the hash table's
 * share of them, and the hash-table entries a step of the fast preset
 * touches on the built-in scene, counted by a gradient hook (the nonzeros
 * a worker would send as pairs).  It prints figures and asserts nothing.
 *
 *   bench_exchange [STEPS [BATCH [WIDTH]]]   (defaults 300, 1024, 64)
 */
#include <nerf.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef struct counter {
    uint64_t nonzero, span, dense;
    uint64_t steps;
} counter;

static int count_hook(void *user, float *grads, size_t n, nerf_exchange *x)
{
    counter *c = user;
    uint64_t nz = 0, span = 0;
    for (uint32_t r = 0; r < x->n_sparse; r++) {
        span += x->sparse_end[r] - x->sparse_begin[r];
        for (uint64_t i = x->sparse_begin[r]; i < x->sparse_end[r]; i++) {
            nz += grads[i] != 0.0f;
        }
    }
    c->nonzero = nz;
    c->span = span;
    c->dense = n - span;
    c->steps++;
    return 0;
}

static int check(int rc, const char *what)
{
    if (rc != NERF_OK) {
        fprintf(stderr, "bench_exchange: %s: %s\n", what, nerf_last_error());
        exit(1);
    }
    return rc;
}

static void preset_counts(int preset, const char *name)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, preset);
    nerf_model *m = NULL;
    check(nerf_model_create(&m, &o), "nerf_model_create");
    printf("%-9s parameters %zu (%.2f MB as fp32)\n", name,
           nerf_model_param_count(m), 4e-6 * (double)nerf_model_param_count(m));
    nerf_model_destroy(m);
}

int main(int argc, char **argv)
{
    const int steps = argc > 1 ? atoi(argv[1]) : 300;
    const uint32_t batch = argc > 2 ? (uint32_t)atoi(argv[2]) : 1024;
    const uint32_t width = argc > 3 ? (uint32_t)atoi(argv[3]) : 64;
    preset_counts(NERF_PRESET_FAST, "fast");
    preset_counts(NERF_PRESET_REFERENCE, "reference");

    char dir[] = "/tmp/bench-exchange.XXXXXX";
    if (mkdtemp(dir) == NULL) {
        perror("mkdtemp");
        return 1;
    }
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = so.height = width;
    so.n_val = so.n_test = 0;
    check(nerf_scene_write(dir, &so), "nerf_scene_write");
    nerf_dataset_options dopt;
    NERF_DATASET_OPTIONS_INIT(&dopt);
    nerf_dataset *ds = NULL;
    check(nerf_dataset_load(&ds, dir, &dopt), "nerf_dataset_load");
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_FAST);
    nerf_model *m = NULL;
    check(nerf_model_create(&m, &mo), "nerf_model_create");
    nerf_sampler_options sopt;
    NERF_SAMPLER_OPTIONS_INIT(&sopt);
    nerf_sampler_options_preset(&sopt, NERF_PRESET_FAST);
    nerf_sampler *s = NULL;
    check(nerf_sampler_create(&s, &sopt), "nerf_sampler_create");
    counter c;
    memset(&c, 0, sizeof c);
    nerf_trainer_options to;
    NERF_TRAINER_OPTIONS_INIT(&to);
    to.batch_rays = batch;
    to.precrop_steps = 0;
    to.random_background = 1;
    to.grad_hook = count_hook;
    to.hook_user = &c;
    nerf_trainer *t = NULL;
    check(nerf_trainer_create(&t, m, ds, s, &to), "nerf_trainer_create");
    for (int k = 1; k <= steps; k++) {
        nerf_train_stats st;
        memset(&st, 0, sizeof st);
        st.struct_size = sizeof st;
        check(nerf_trainer_step(t, &st), "nerf_trainer_step");
        if (k == 1) { /* the sizes are known after the first exchange */
            printf("fast preset on the built-in scene (%ux%u), %u rays a "
                   "step; the hash tables hold %llu of the parameters, the "
                   "layers %llu:\n  step  samples/ray  touched table "
                   "entries  of the table  pairs (8 B)   dense ring "
                   "(2x4 B)\n", width, width, batch,
                   (unsigned long long)c.span, (unsigned long long)c.dense);
        }
        if (k == 1 || k == steps || (k & (k - 1)) == 0) {
            printf("  %4d  %11.1f  %21llu  %11.2f%%  %8.2f MB  %8.2f MB\n",
                   k, st.samples_per_ray, (unsigned long long)c.nonzero,
                   100.0 * (double)c.nonzero / (double)c.span,
                   8e-6 * (double)c.nonzero, 8e-6 * (double)c.span);
        }
    }
    nerf_trainer_destroy(t);
    nerf_sampler_destroy(s);
    nerf_model_destroy(m);
    nerf_dataset_destroy(ds);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : 1;
}
