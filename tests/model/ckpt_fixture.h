/*
 * Shared pieces of the checkpoint tests: a scratch directory, a model with
 * non-trivial optimiser state, exact model comparison, allocation
 * accounting through hooks, and little-endian access to raw files laid out
 * as docs/formats.md describes.  Include after harness.h.
 */
#ifndef NERF_TEST_CKPT_FIXTURE_H
#define NERF_TEST_CKPT_FIXTURE_H

#include <dirent.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "../data/data_fixtures.h"
#include "model.h"
#include "nerf.h"
#include "occupancy.h"

#define HEADER 48

static char tmpdir[64];

static inline void make_tmpdir(void)
{
    snprintf(tmpdir, sizeof tmpdir, "/tmp/nerf-ckpt-XXXXXX");
    if (mkdtemp(tmpdir) == NULL) {
        printf("cannot create a temporary directory\n");
        exit(1);
    }
}

/* ---- files -------------------------------------------------------------- */

static inline void path_in(char *buf, size_t size, const char *name)
{
    snprintf(buf, size, "%s/%s", tmpdir, name);
}

static inline void spit(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        FAILF("cannot write %s", path);
        return;
    }
    fwrite(data, 1, size, f);
    fclose(f);
}

/* Names in dir that look like a leftover temporary file. */
static inline int count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d)) != NULL;) {
        n += strstr(e->d_name, ".tmp.") != NULL;
    }
    if (d) {
        closedir(d);
    }
    return n;
}

static inline void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d)) != NULL;) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) {
            continue;
        }
        char p[512];
        if (snprintf(p, sizeof p, "%s/%s", dir, e->d_name) >= (int)sizeof p) {
            continue;
        }
        struct stat st;
        if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode)) {
            remove_tree(p);
        } else {
            unlink(p);
        }
    }
    if (d) {
        closedir(d);
    }
    rmdir(dir);
}

/* ---- models ------------------------------------------------------------- */

/* A model with non-default hyperparameters and non-zero Adam moments. */
static inline nerf_model *trained_model(bool full)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    o.seed = 4242;
    if (!full) {
        o.use_fine = 0;
        o.use_viewdirs = 0;
        o.skip_layer = 0;
        o.encoding_flags = NERF_ENCODING_SCALE_PI;
        o.pos_frequencies = 6;
    }
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m == NULL) {
        return NULL;
    }
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE, 1.25e-3));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_LEARNING_RATE_FINAL, 3e-5));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_DECAY_STEPS, 777));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_ADAM_BETA1, 0.85));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_ADAM_BETA2, 0.995));
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_ADAM_EPS, 1e-8));
    for (int step = 0; step < 3; step++) {
        nerf__model_zero_grad(m);
        for (size_t i = 0; i < m->n_params; i++) {
            m->grads[i] = (float)sin(0.37 * (double)i + step);
        }
        nerf__model_adam_step(m);
    }
    return m;
}

static inline void query(const nerf_model *m, int network, float *rgb,
                         float *sigma)
{
    float pos[3 * 37], dir[3 * 37];
    for (int i = 0; i < 37; i++) {
        double a = 0.3 * i, b = 0.11 * i;
        pos[3 * i] = (float)cos(a);
        pos[3 * i + 1] = (float)sin(1.7 * a);
        pos[3 * i + 2] = (float)(0.05 * i - 0.9);
        dir[3 * i] = (float)(cos(a) * sin(b + 0.2));
        dir[3 * i + 1] = (float)(sin(a) * sin(b + 0.2));
        dir[3 * i + 2] = (float)cos(b + 0.2);
    }
    CHECK_OK(nerf_model_query(m, network, 37, pos, dir, rgb, sigma));
}

/* Grids in the same state: EMA, bits (coarse level included) and the
 * update counter that keys the next update. */
static inline void check_same_grid(const nerf__occupancy *a,
                                   const nerf__occupancy *b)
{
    CHECK((a == NULL) == (b == NULL));
    if (a == NULL || b == NULL || a->cells != b->cells) {
        CHECK(a == b);
        return;
    }
    size_t n = 0;
    CHECK(memcmp(a->ema, b->ema, a->cells * sizeof(float)) == 0);
    CHECK(memcmp(a->bits, b->bits, a->words * sizeof(uint64_t)) == 0);
    n = ((size_t)a->coarse_res * a->coarse_res * a->coarse_res + 63) / 64;
    CHECK(memcmp(a->coarse, b->coarse, n * sizeof(uint64_t)) == 0);
    CHECK(a->updates == b->updates);
    CHECK(a->occupied == b->occupied);
    CHECK(memcmp(&a->threshold, &b->threshold, sizeof a->threshold) == 0);
}

static inline void check_same_model(const nerf_model *a,
                                    const nerf_model *b)
{
    CHECK_EQ_INT(a->n_params, b->n_params);
    CHECK(a->step == b->step);
    if (a->n_params != b->n_params) {
        return;
    }
    size_t bytes = a->n_params * sizeof(float);
    CHECK(memcmp(a->params, b->params, bytes) == 0);
    CHECK(memcmp(a->adam_m, b->adam_m, bytes) == 0);
    CHECK(memcmp(a->adam_v, b->adam_v, bytes) == 0);
    check_same_grid(a->grid, b->grid);
    nerf_model_options oa, ob;
    NERF_MODEL_OPTIONS_INIT(&oa);
    NERF_MODEL_OPTIONS_INIT(&ob);
    CHECK_OK(nerf_model_get_options(a, &oa));
    CHECK_OK(nerf_model_get_options(b, &ob));
    CHECK(memcmp(&oa, &ob, sizeof oa) == 0);
    for (int p = NERF_PARAM_LEARNING_RATE; p <= NERF_PARAM_WEIGHT_DECAY; p++) {
        double va = 0, vb = 1;
        CHECK_OK(nerf_model_get_param(a, p, &va));
        CHECK_OK(nerf_model_get_param(b, p, &vb));
        CHECK(memcmp(&va, &vb, sizeof va) == 0);
    }
    for (int net = 0; net < (int)a->n_nets; net++) {
        float rgb_a[3 * 37], rgb_b[3 * 37], s_a[37], s_b[37];
        query(a, net, rgb_a, s_a);
        query(b, net, rgb_b, s_b);
        CHECK(memcmp(rgb_a, rgb_b, sizeof rgb_a) == 0);
        CHECK(memcmp(s_a, s_b, sizeof s_a) == 0);
    }
}

/* ---- allocation accounting through hooks -------------------------------- */

static long live_blocks;

static inline void *count_alloc(size_t size, void *user)
{
    (void)user;
    live_blocks++;
    return malloc(size);
}

static inline void count_free(void *p, void *user)
{
    (void)user;
    live_blocks--;
    free(p);
}

static char last_log[1024];

static inline void keep_log(int level, const char *msg, void *user)
{
    (void)level;
    (void)user;
    snprintf(last_log, sizeof last_log, "%s", msg);
}

static inline nerf_hooks counting_hooks(void)
{
    nerf_hooks h;
    NERF_HOOKS_INIT(&h);
    h.alloc = count_alloc;
    h.free = count_free;
    h.log_cb = keep_log;
    h.log_level = NERF_LOG_DEBUG;
    return h;
}

/* Load a damaged file: it must fail with `want`, name the file, return no
 * model and free everything it allocated. */
static inline void expect_load_fails(const char *path, int want,
                                     const char *what)
{
    nerf_hooks h = counting_hooks();
    nerf_model *m = (nerf_model *)&h; /* must be reset to NULL */
    live_blocks = 0;
    int rc = nerf_model_load(&m, path, &h);
    if (rc != want || m != NULL || live_blocks != 0 ||
        strstr(nerf_last_error(), path) != nerf_last_error()) {
        FAILF("%s: status %d (want %d), model %p, %ld blocks live, "
              "message '%s'", what, rc, want, (void *)m, live_blocks,
              nerf_last_error());
    }
    if (rc == NERF_OK) {
        nerf_model_destroy(m);
    }
}

/* ---- raw file access ---------------------------------------------------- */


/* Save the reference checkpoint and return its bytes. */
static inline unsigned char *good_file(size_t *size)
{
    char path[128];
    path_in(path, sizeof path, "good.ckpt");
    nerf_model *m = trained_model(true);
    CHECK_OK(nerf_model_save(m, path));
    nerf_model_destroy(m);
    unsigned char *b = fx_slurp(path, size);
    CHECK(b != NULL && *size > 200);
    return b;
}

static inline uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
           (uint32_t)p[3] << 24;
}

static inline uint64_t le64(const unsigned char *p)
{
    return le32(p) | (uint64_t)le32(p + 4) << 32;
}

static inline void put32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = (unsigned char)(v >> (8 * i));
    }
}

static inline void put64(unsigned char *p, uint64_t v)
{
    put32(p, (uint32_t)v);
    put32(p + 4, (uint32_t)(v >> 32));
}

static inline void fix_header_crc(unsigned char *b)
{
    put32(b + 44, (uint32_t)crc32(0L, b, 44));
}

#endif
