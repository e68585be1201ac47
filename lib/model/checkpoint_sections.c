/*
 * Each section of a checkpoint's payload: its body written from a model
 * and read back into one.  docs/formats.md is the specification; the
 * table at the end is the one list of sections.
 */
#include "checkpoint_sections.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "average.h"
#include "byteorder.h"
#include "fingerprint.h"
#include "occupancy.h"
#include "schedule.h"

#define TAG_REQUIRED NERF__CKPT_TAG_REQUIRED
#define N_OPTION_U32 11
#define OPTIONS_SIZE 52u  /* 11 u32 fields and the u64 seed */
#define N_OPTION2_U32 11  /* and a reserved 0 */
#define OPTIONS2_SIZE 48u /* the 12 u32 fields appended in 0.2 */
#define TRAINING_SIZE 64u /* 6 f64 hyperparameters, u64 step, u64 count */
#define TRAINING2_SIZE 8u /* f64 weight decay */
#define WORD_SIZE 8u      /* u32 value, u32 0 */
#define OCCUPANCY_HEAD 16u /* u32 resolution, u32 reserved, u64 updates */
#define RENDER_SIZE 64u   /* 16 u32 words: see write_render */
#define BATCH_SIZE 8u     /* u32 batch_rays, u32 batch_samples */

static int corrupt(const char *path, const char *what)
{
    return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (%s)", path,
                       what);
}

/* ---- floats ------------------------------------------------------------- */

static void put_floats(nerf__buf *b, const float *x, size_t n)
{
    unsigned char *p = nerf__buf_grow(b, 4 * n);
    for (size_t i = 0; p != NULL && i < n; i++) {
        nerf__store_lef32(p + 4 * i, x[i]);
    }
}

static void get_floats(const unsigned char *p, float *x, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        x[i] = nerf__load_lef32(p + 4 * i);
    }
}

/* ---- options ------------------------------------------------------------ */

/*
 * The 32-bit fields of nerf_model_options in file order: the options
 * section's (the u64 seed follows them) and the options2 section's.  One
 * table serves writing and reading; bound, a float, travels as its bits.
 */
static const size_t option_u32[N_OPTION_U32] = {
    offsetof(nerf_model_options, encoding),
    offsetof(nerf_model_options, pos_frequencies),
    offsetof(nerf_model_options, dir_frequencies),
    offsetof(nerf_model_options, encoding_flags),
    offsetof(nerf_model_options, depth),
    offsetof(nerf_model_options, width),
    offsetof(nerf_model_options, skip_layer),
    offsetof(nerf_model_options, view_width),
    offsetof(nerf_model_options, use_viewdirs),
    offsetof(nerf_model_options, use_fine),
    offsetof(nerf_model_options, reserved0),
};

_Static_assert(sizeof(float) == sizeof(uint32_t), "bound travels as 32 bits");

static const size_t option2_u32[N_OPTION2_U32] = {
    offsetof(nerf_model_options, dir_encoding),
    offsetof(nerf_model_options, sh_degree),
    offsetof(nerf_model_options, hash_levels),
    offsetof(nerf_model_options, hash_features),
    offsetof(nerf_model_options, hash_log2_size),
    offsetof(nerf_model_options, hash_min_resolution),
    offsetof(nerf_model_options, hash_max_resolution),
    offsetof(nerf_model_options, bound),
    offsetof(nerf_model_options, geo_features),
    offsetof(nerf_model_options, view_depth),
    offsetof(nerf_model_options, density_activation),
};

static uint32_t option_at(const nerf_model_options *o, size_t offset)
{
    uint32_t v;
    memcpy(&v, (const char *)o + offset, sizeof v);
    return v;
}

static void put_fields(unsigned char *p, const nerf_model_options *o,
                       const size_t *offsets, int n)
{
    for (int i = 0; i < n; i++) {
        nerf__store_le32(p + 4 * i, option_at(o, offsets[i]));
    }
}

static void get_fields(const unsigned char *p, nerf_model_options *o,
                       const size_t *offsets, int n)
{
    for (int i = 0; i < n; i++) {
        uint32_t v = nerf__load_le32(p + 4 * i);
        memcpy((char *)o + offsets[i], &v, sizeof v);
    }
}

static void write_options(nerf__buf *b, const nerf__ckpt_save *s)
{
    unsigned char *p = nerf__buf_grow(b, OPTIONS_SIZE);
    if (p != NULL) {
        put_fields(p, &s->m->opts, option_u32, N_OPTION_U32);
        nerf__store_le64(p + 4 * N_OPTION_U32, s->m->opts.seed);
    }
}

/* The first of the options sections: every field not in the file keeps
 * nerf_model_options_init()'s value. */
static int read_options1(const char *path, const nerf__ckpt_section *k,
                         const unsigned char *b, nerf_model_options *o)
{
    (void)path;
    (void)k;
    nerf_model_options_init(o, sizeof *o);
    get_fields(b, o, option_u32, N_OPTION_U32);
    o->seed = nerf__load_le64(b + 4 * N_OPTION_U32);
    o->hooks = NULL;
    return NERF_OK;
}

static void write_options2(nerf__buf *b, const nerf__ckpt_save *s)
{
    unsigned char *p = nerf__buf_grow(b, OPTIONS2_SIZE);
    if (p != NULL) {
        put_fields(p, &s->m->opts, option2_u32, N_OPTION2_U32);
        /* The struct's reserved1 here, which matmul replaced there:
         * matmul has a section of its own that old readers can skip. */
        nerf__store_le32(p + 4 * N_OPTION2_U32, 0);
    }
}

static int read_options2(const char *path, const nerf__ckpt_section *k,
                         const unsigned char *b, nerf_model_options *o)
{
    (void)k;
    get_fields(b, o, option2_u32, N_OPTION2_U32);
    if (nerf__load_le32(b + 4 * N_OPTION2_U32) != 0) {
        return corrupt(path, "the reserved field of options (0.2) is not 0");
    }
    return NERF_OK;
}

/*
 * The sections that hold one option each (matmul, space): a u32 value and
 * a reserved u32 0, written only when the value is not the one every file
 * before the section implies.
 */
static bool word_wanted(const nerf__ckpt_save *s, const nerf__ckpt_section *k)
{
    return option_at(&s->m->opts, k->option) != k->implied;
}

static const nerf__ckpt_section *const matmul_kind =
    &nerf__ckpt_sections[NERF__CKPT_MATMUL];
static const nerf__ckpt_section *const space_kind =
    &nerf__ckpt_sections[NERF__CKPT_SPACE];

static bool has_matmul(const nerf__ckpt_save *s)
{
    return word_wanted(s, matmul_kind);
}

static bool has_space(const nerf__ckpt_save *s)
{
    return word_wanted(s, space_kind);
}

static void write_word(nerf__buf *b, const nerf__ckpt_save *s,
                       const nerf__ckpt_section *k)
{
    unsigned char *p = nerf__buf_grow(b, WORD_SIZE);
    if (p != NULL) {
        nerf__store_le32(p, option_at(&s->m->opts, k->option));
        nerf__store_le32(p + 4, 0);
    }
}

static void write_matmul(nerf__buf *b, const nerf__ckpt_save *s)
{
    write_word(b, s, matmul_kind);
}

static void write_space(nerf__buf *b, const nerf__ckpt_save *s)
{
    write_word(b, s, space_kind);
}

static int read_word(const char *path, const nerf__ckpt_section *k,
                     const unsigned char *b, nerf_model_options *o)
{
    const uint32_t v = nerf__load_le32(b);
    char why[128];
    if (nerf__load_le32(b + 4) != 0) {
        snprintf(why, sizeof why, "the %s section has a non-zero reserved "
                 "field", k->name);
        return corrupt(path, why);
    }
    if (v > k->max) {
        snprintf(why, sizeof why, "the %s section holds %u, no known value",
                 k->name, (unsigned)v);
        return corrupt(path, why);
    }
    memcpy((char *)o + k->option, &v, sizeof v);
    return NERF_OK;
}

/* ---- training state ----------------------------------------------------- */

static void write_training(nerf__buf *b, const nerf__ckpt_save *s)
{
    const nerf__adam *a = &s->m->adam;
    const double hp[6] = {a->lr, a->lr_final, a->decay_steps,
                          a->beta1, a->beta2, a->eps};
    unsigned char *p = nerf__buf_grow(b, TRAINING_SIZE);
    if (p != NULL) {
        for (int i = 0; i < 6; i++) {
            nerf__store_lef64(p + 8 * i, hp[i]);
        }
        nerf__store_le64(p + 48, s->m->step);
        nerf__store_le64(p + 56, s->m->n_params);
    }
}

/* Hyperparameters go through the public setter, which checks their range. */
static int set_params(const char *path, nerf_model *m, const int *keys, int n,
                      const unsigned char *p)
{
    for (int i = 0; i < n; i++) {
        if (nerf_model_set_param(m, keys[i], nerf__load_lef64(p + 8 * i)) !=
            NERF_OK) {
            char why[512];
            snprintf(why, sizeof why, "%s", nerf_last_error());
            return nerf__error(NERF_EFORMAT, "%s: checkpoint holds an invalid "
                               "hyperparameter (%s)", path, why);
        }
    }
    return NERF_OK;
}

static int read_training(const char *path, nerf_model *m,
                         const unsigned char *b, uint64_t len,
                         const nerf__ckpt_view *v)
{
    (void)len;
    (void)v;
    static const int keys[6] = {
        NERF_PARAM_LEARNING_RATE, NERF_PARAM_LEARNING_RATE_FINAL,
        NERF_PARAM_DECAY_STEPS, NERF_PARAM_ADAM_BETA1, NERF_PARAM_ADAM_BETA2,
        NERF_PARAM_ADAM_EPS};
    m->step = nerf__load_le64(b + 48);
    return set_params(path, m, keys, 6, b);
}

static void write_training2(nerf__buf *b, const nerf__ckpt_save *s)
{
    unsigned char *p = nerf__buf_grow(b, TRAINING2_SIZE);
    if (p != NULL) {
        nerf__store_lef64(p, s->m->adam.weight_decay);
    }
}

/* A file from before weight decay trained without it, so resuming it goes
 * on without. */
static int read_training2(const char *path, nerf_model *m,
                          const unsigned char *b, uint64_t len,
                          const nerf__ckpt_view *v)
{
    (void)len;
    (void)v;
    static const int keys[1] = {NERF_PARAM_WEIGHT_DECAY};
    m->adam.weight_decay = 0.0;
    return b != NULL ? set_params(path, m, keys, 1, b) : NERF_OK;
}

/* ---- weights and moments ------------------------------------------------ */

static void write_params(nerf__buf *b, const nerf__ckpt_save *s)
{
    put_floats(b, s->m->params, s->m->n_params);
}

static void write_adam_m(nerf__buf *b, const nerf__ckpt_save *s)
{
    put_floats(b, s->m->adam_m, s->m->n_params);
}

static void write_adam_v(nerf__buf *b, const nerf__ckpt_save *s)
{
    put_floats(b, s->m->adam_v, s->m->n_params);
}

/* The lengths were checked against the options (NERF__CKPT_PER_PARAM); a
 * weights-only file has no moments. */
static int read_array(float *x, size_t n, const unsigned char *b)
{
    if (b != NULL) {
        get_floats(b, x, n);
    }
    return NERF_OK;
}

static int read_params(const char *path, nerf_model *m,
                       const unsigned char *b, uint64_t len,
                       const nerf__ckpt_view *v)
{
    return read_array(m->params, m->n_params, b);
}

static int read_adam_m(const char *path, nerf_model *m,
                       const unsigned char *b, uint64_t len,
                       const nerf__ckpt_view *v)
{
    return read_array(m->adam_m, m->n_params, b);
}

static int read_adam_v(const char *path, nerf_model *m,
                       const unsigned char *b, uint64_t len,
                       const nerf__ckpt_view *v)
{
    return read_array(m->adam_v, m->n_params, b);
}

/* A weights-only file trains no further: it is marked by an empty section,
 * so that a reader that does not know it neither takes the missing
 * moments for a corrupt file nor resumes training from zeros. */
static bool has_marker(const nerf__ckpt_save *s)
{
    return s->weights_only;
}

static void write_nothing(nerf__buf *b, const nerf__ckpt_save *s)
{
    (void)b;
    (void)s;
}

static int read_marker(const char *path, nerf_model *m,
                       const unsigned char *b, uint64_t len,
                       const nerf__ckpt_view *v)
{
    (void)path;
    (void)len;
    (void)v;
    m->weights_only = b != NULL;
    return NERF_OK;
}

/* ---- occupancy grid ----------------------------------------------------- */

/* Its EMA and update counter, from which loading rebuilds the bits exactly
 * as the last update set them. */
static bool has_grid(const nerf__ckpt_save *s)
{
    return s->m->grid != NULL;
}

static void write_occupancy(nerf__buf *b, const nerf__ckpt_save *s)
{
    const nerf__occupancy *g = s->m->grid;
    unsigned char *p = nerf__buf_grow(b, OCCUPANCY_HEAD);
    if (p != NULL) {
        nerf__store_le32(p, g->res);
        nerf__store_le32(p + 4, 0);
        nerf__store_le64(p + 8, g->updates);
    }
    put_floats(b, g->ema, g->cells);
}

/* Only a grid of the size this libnerf gives the model fits; a genuine EMA
 * is a finite density >= 0 in every cell.  A file without the section
 * leaves the model its fresh grid, which training refills within a few
 * updates. */
static int read_occupancy(const char *path, nerf_model *m,
                          const unsigned char *b, uint64_t len,
                          const nerf__ckpt_view *v)
{
    (void)v;
    if (b == NULL) {
        return NERF_OK;
    }
    const uint64_t R = NERF__MODEL_GRID_RESOLUTION;
    nerf__occupancy *g = m->grid;
    if (g == NULL || len != OCCUPANCY_HEAD + 4 * R * R * R ||
        nerf__load_le32(b) != R || nerf__load_le32(b + 4) != 0) {
        return corrupt(path, "the occupancy grid section does not fit the "
                       "model");
    }
    const unsigned char *p = b + OCCUPANCY_HEAD;
    for (size_t i = 0; i < g->cells; i++) {
        float e = nerf__load_lef32(p + 4 * i);
        if (!(e >= 0.0f) || !isfinite(e)) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                               "(occupancy grid cell %zu holds %g)", path, i,
                               (double)e);
        }
        g->ema[i] = e;
    }
    /* The bits, mean and threshold follow from the EMA as the last update
     * computed them (see nerf__occupancy_rebuild_bits). */
    g->updates = nerf__load_le64(b + 8);
    nerf__occupancy_rebuild_bits(g);
    return NERF_OK;
}

/* ---- render settings ---------------------------------------------------- */

/*
 * The sampler settings and background the model was trained with, for a
 * renderer that knows nothing of its scene: u32 n_coarse, n_fine, lindisp,
 * paper_bins, ndc, march_steps, max_samples, white_background; f32 t_near,
 * t_far, ndc_focal; u32 ndc_width, ndc_height; three reserved u32 0.
 */
static bool has_render(const nerf__ckpt_save *s)
{
    return s->m->has_render;
}

static void write_render(nerf__buf *b, const nerf__ckpt_save *s)
{
    const nerf_sampler_options *o = &s->m->render_sampler;
    const uint32_t words[8] = {o->n_coarse, o->n_fine, o->lindisp,
                               o->paper_bins, o->ndc, o->march_steps,
                               o->max_samples, s->m->render_white};
    unsigned char *p = nerf__buf_grow(b, RENDER_SIZE);
    if (p == NULL) {
        return;
    }
    for (int i = 0; i < 8; i++) {
        nerf__store_le32(p + 4 * i, words[i]);
    }
    nerf__store_lef32(p + 32, o->t_near);
    nerf__store_lef32(p + 36, o->t_far);
    nerf__store_lef32(p + 40, o->ndc_focal);
    nerf__store_le32(p + 44, o->ndc_width);
    nerf__store_le32(p + 48, o->ndc_height);
    memset(p + 52, 0, RENDER_SIZE - 52);
}

/* Only what the file format decides is checked here; the sampler's own
 * checks run when a sampler is made of them (nerf_model_render_settings()).
 * A file without the section renders with its caller's settings. */
static int read_render(const char *path, nerf_model *m,
                       const unsigned char *b, uint64_t len,
                       const nerf__ckpt_view *v)
{
    (void)len;
    (void)v;
    if (b == NULL) {
        return NERF_OK;
    }
    uint32_t w[8];
    for (int i = 0; i < 8; i++) {
        w[i] = nerf__load_le32(b + 4 * i);
    }
    const float t_near = nerf__load_lef32(b + 32);
    const float t_far = nerf__load_lef32(b + 36);
    const float focal = nerf__load_lef32(b + 40);
    bool reserved = true;
    for (uint32_t at = 52; at < RENDER_SIZE; at += 4) {
        reserved = reserved && nerf__load_le32(b + at) == 0;
    }
    if (!reserved || w[2] > 1 || w[3] > 1 || w[4] > 1 || w[7] > 1 ||
        !isfinite(t_near) || !isfinite(t_far) || !isfinite(focal)) {
        return corrupt(path, "the render settings section holds values no "
                       "sampler has");
    }
    nerf_sampler_options *o = &m->render_sampler;
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->n_coarse = w[0];
    o->n_fine = w[1];
    o->lindisp = w[2];
    o->paper_bins = w[3];
    o->ndc = w[4];
    o->march_steps = w[5];
    o->max_samples = w[6];
    o->t_near = t_near;
    o->t_far = t_far;
    o->ndc_focal = focal;
    o->ndc_width = nerf__load_le32(b + 44);
    o->ndc_height = nerf__load_le32(b + 48);
    m->render_white = w[7];
    m->has_render = true;
    return NERF_OK;
}

/* ---- what the model was trained on and how ------------------------------ */

/* The data (model/fingerprint.h), for a warning when the model is resumed
 * on other data. */
static bool has_data(const nerf__ckpt_save *s)
{
    return s->m->data.known;
}

static void write_data(nerf__buf *b, const nerf__ckpt_save *s)
{
    unsigned char *p = nerf__buf_grow(b, NERF__FINGERPRINT_SIZE);
    if (p != NULL) {
        nerf__fingerprint_store(p, &s->m->data);
    }
}

static int read_data(const char *path, nerf_model *m, const unsigned char *b,
                     uint64_t len, const nerf__ckpt_view *v)
{
    (void)v;
    if (b != NULL && !nerf__fingerprint_parse(b, len, &m->data)) {
        return corrupt(path, "the data section is too short or holds a value "
                       "that is not a number");
    }
    return NERF_OK;
}

/* A time budget's schedule (model/schedule.h). */
static bool has_schedule(const nerf__ckpt_save *s)
{
    return nerf__schedule_saved(&s->m->schedule, s->m->adam.decay_start);
}

static void write_schedule(nerf__buf *b, const nerf__ckpt_save *s)
{
    unsigned char *p = nerf__buf_grow(b, NERF__SCHEDULE_SIZE);
    if (p != NULL) {
        nerf__schedule_store(p, &s->m->schedule, s->m->adam.decay_start);
    }
}

static int read_schedule(const char *path, nerf_model *m,
                         const unsigned char *b, uint64_t len,
                         const nerf__ckpt_view *v)
{
    (void)v;
    const char *bad = b != NULL ? nerf__schedule_parse(b, len, &m->schedule,
                                                       &m->adam.decay_start)
                                : NULL;
    return bad != NULL ? corrupt(path, bad) : NERF_OK;
}

/* The batch the trainer took (nerf_model_training_batch()), for a resume
 * to take it. */
static bool has_batch(const nerf__ckpt_save *s)
{
    return s->m->batch_rays > 0;
}

static void write_batch(nerf__buf *b, const nerf__ckpt_save *s)
{
    unsigned char *p = nerf__buf_grow(b, BATCH_SIZE);
    if (p != NULL) {
        nerf__store_le32(p, s->m->batch_rays);
        nerf__store_le32(p + 4, s->m->batch_samples);
    }
}

/* A batch no trainer takes would be refused by the one a resume makes. */
static int read_batch(const char *path, nerf_model *m, const unsigned char *b,
                      uint64_t len, const nerf__ckpt_view *v)
{
    (void)len;
    (void)v;
    if (b == NULL) {
        return NERF_OK;
    }
    const uint32_t rays = nerf__load_le32(b);
    const uint32_t samples = nerf__load_le32(b + 4);
    if (rays < 1 || rays > NERF__BATCH_RAYS_MAX ||
        samples > NERF__BATCH_SAMPLES_MAX) {
        return corrupt(path, "the batch section holds a batch no trainer "
                       "takes");
    }
    m->batch_rays = rays;
    m->batch_samples = samples;
    return NERF_OK;
}

/* The steps the weights are averaged over before the schedule's end, and
 * the average while it runs (model/average.h): its head, then its floats.
 * A weights-only file trains no further, and leaves it out. */
static bool has_average(const nerf__ckpt_save *s)
{
    return !s->weights_only && nerf__average_saved(s->m);
}

static void write_average(nerf__buf *b, const nerf__ckpt_save *s)
{
    unsigned char *p = nerf__buf_grow(b, NERF__AVERAGE_HEAD);
    if (p != NULL) {
        nerf__average_store_head(p, s->m);
    }
    if (s->m->averaging) {
        put_floats(b, s->m->average, s->m->n_params);
    }
}

/* A file without the section was made before averaging, or without it: it
 * goes on without. */
static int read_average(const char *path, nerf_model *m,
                        const unsigned char *b, uint64_t len,
                        const nerf__ckpt_view *v)
{
    (void)v;
    m->adam.average_steps = 0.0;
    if (b == NULL) {
        return NERF_OK;
    }
    bool oom = false;
    const char *bad = nerf__average_parse(b, len, m, &oom);
    if (bad != NULL) {
        return oom ? nerf__error(NERF_ENOMEM, "%s: %s", path, bad)
                   : corrupt(path, bad);
    }
    if (m->averaging) {
        get_floats(b + NERF__AVERAGE_HEAD, m->average, m->n_params);
    }
    return NERF_OK;
}

/* Each hash-table parameter's Adam corrections by its own count of
 * updates (model.h), for a model that keeps them (corrected implies a
 * table). */
static bool has_corrections(const nerf__ckpt_save *s)
{
    return s->m->corrected;
}

static void write_corrections(nerf__buf *b, const nerf__ckpt_save *s)
{
    put_floats(b, s->m->adam_r, 2 * s->m->n_table);
}

/* A file with moments but without corrections was trained correcting by
 * the step, and goes on so. */
static int read_corrections(const char *path, nerf_model *m,
                            const unsigned char *b, uint64_t len,
                            const nerf__ckpt_view *v)
{
    if (b == NULL) {
        if (v->body[NERF__CKPT_WEIGHTS_ONLY] == NULL) {
            m->corrected = false;
        }
        return NERF_OK;
    }
    if (m->n_table == 0 || len != 8 * (uint64_t)m->n_table) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the Adam "
                           "corrections are %llu bytes for a hash table of "
                           "%zu parameters)", path, (unsigned long long)len,
                           m->n_table);
    }
    get_floats(b, m->adam_r, 2 * m->n_table);
    for (size_t i = 0; i < 2 * m->n_table; i++) {
        /* beta^k for k from 0 on; the negation catches NaN. */
        if (!(m->adam_r[i] >= 0.0f && m->adam_r[i] <= 1.0f)) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (Adam "
                               "correction %zu is %g, not within 0 to 1)",
                               path, i, (double)m->adam_r[i]);
        }
    }
    m->corrected = true;
    return NERF_OK;
}

/* The per-image appearance codes (appearance.h): u32 count, u32 floats
 * per code, the codes, then (but in a weights-only file) the running
 * means of their slopes and curvatures.  libnerf 0.13.0 wrote the same
 * layout under tag 18 with Adam's moments in place of the means. */
static bool has_appearance(const nerf__ckpt_save *s)
{
    return s->m->appearance.n > 0;
}

static void write_appearance(nerf__buf *b, const nerf__ckpt_save *s)
{
    const nerf__appearance *a = &s->m->appearance;
    unsigned char *p = nerf__buf_grow(b, 8);
    if (p != NULL) {
        nerf__store_le32(p, a->n);
        nerf__store_le32(p + 4, NERF__CODE_FLOATS);
    }
    const size_t n = (size_t)a->n * NERF__CODE_FLOATS;
    put_floats(b, a->code, n);
    if (!s->weights_only) {
        put_floats(b, a->mean_grad, n);
        put_floats(b, a->mean_curv, n);
    }
}

/* The codes of a section of either tag; the state after them is read
 * when keep_state, else left at its start (zero means). */
static int read_codes(const char *path, nerf_model *m,
                      const unsigned char *b, uint64_t len,
                      const nerf__ckpt_view *v, bool keep_state)
{
    if (len < 8) {
        return corrupt(path, "the appearance codes section is shorter than "
                       "its head");
    }
    if (m->appearance.n != 0) {
        return corrupt(path, "the appearance codes are there twice, under "
                       "tags 18 and 19");
    }
    const uint32_t n = nerf__load_le32(b);
    const uint32_t floats = nerf__load_le32(b + 4);
    const uint64_t arrays = v->body[NERF__CKPT_WEIGHTS_ONLY] ? 1 : 3;
    if (n == 0 || n > NERF__CODES_MAX || floats != NERF__CODE_FLOATS ||
        len != 8 + arrays * 4 * (uint64_t)n * floats) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (an "
                           "appearance codes section of %llu bytes for %u "
                           "codes of %u floats; expected 1 to %u codes of "
                           "%u)", path, (unsigned long long)len,
                           (unsigned)n, (unsigned)floats,
                           (unsigned)NERF__CODES_MAX,
                           (unsigned)NERF__CODE_FLOATS);
    }
    int rc = nerf__appearance_create(m, n);
    if (rc != NERF_OK) {
        return rc;
    }
    nerf__appearance *a = &m->appearance;
    const size_t k = (size_t)n * NERF__CODE_FLOATS;
    get_floats(b + 8, a->code, k);
    if (arrays == 3 && keep_state) {
        get_floats(b + 8 + 4 * k, a->mean_grad, k);
        get_floats(b + 8 + 8 * k, a->mean_curv, k);
    }
    for (size_t i = 0; i < k; i++) {
        /* The negations catch NaN. */
        if (!isfinite(a->code[i]) || !isfinite(a->mean_grad[i]) ||
            !(a->mean_curv[i] >= 0.0f && isfinite(a->mean_curv[i]))) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                               "(appearance code %zu holds a value that is "
                               "not finite, or a negative curvature)",
                               path, i / NERF__CODE_FLOATS);
        }
    }
    return NERF_OK;
}

/* A file without the section holds a model without codes. */
static int read_appearance(const char *path, nerf_model *m,
                           const unsigned char *b, uint64_t len,
                           const nerf__ckpt_view *v)
{
    return b ? read_codes(path, m, b, len, v, true) : NERF_OK;
}

/* 0.13.0's codes: their Adam moments mean nothing to the codes' steps
 * since, which start their means afresh, as a model's first steps do. */
static int read_appearance_0_13(const char *path, nerf_model *m,
                                const unsigned char *b, uint64_t len,
                                const nerf__ckpt_view *v)
{
    return b ? read_codes(path, m, b, len, v, false) : NERF_OK;
}

static bool never(const nerf__ckpt_save *s)
{
    (void)s;
    return false;
}

/* ---- the table ---------------------------------------------------------- */

bool nerf__ckpt_written(const nerf__ckpt_section *k, const nerf__ckpt_save *s)
{
    if (s->weights_only && (k->flags & NERF__CKPT_OPTIMISER)) {
        return false;
    }
    return k->wanted == NULL || k->wanted(s);
}

/*
 * Tags 1 to 6 are libnerf 0.2's core, all required.  Every later section is
 * optional (bit 31 clear) when a reader that does not know it can still
 * make a correct model of the file, and required when it cannot: space
 * (grids laid over the wrong space), the weights-only marker, the schedule
 * (another learning-rate schedule on resume).
 */
const nerf__ckpt_section nerf__ckpt_sections[NERF__CKPT_N_SECTIONS] = {
    [NERF__CKPT_OPTIONS] = {
        .tag = TAG_REQUIRED | 1u, .name = "options",
        .flags = NERF__CKPT_CORE | NERF__CKPT_FIXED, .size = OPTIONS_SIZE,
        .write = write_options, .read_options = read_options1},
    [NERF__CKPT_TRAINING] = {
        .tag = TAG_REQUIRED | 2u, .name = "training state",
        .flags = NERF__CKPT_CORE | NERF__CKPT_FIXED, .size = TRAINING_SIZE,
        .write = write_training, .read = read_training},
    [NERF__CKPT_PARAMS] = {
        .tag = TAG_REQUIRED | 3u, .name = "parameters",
        .flags = NERF__CKPT_CORE | NERF__CKPT_STORED | NERF__CKPT_PER_PARAM,
        .write = write_params, .read = read_params},
    [NERF__CKPT_ADAM_M] = {
        .tag = TAG_REQUIRED | 4u, .name = "Adam first moments",
        .flags = NERF__CKPT_CORE | NERF__CKPT_OPTIMISER | NERF__CKPT_STORED |
                 NERF__CKPT_PER_PARAM,
        .write = write_adam_m, .read = read_adam_m},
    [NERF__CKPT_ADAM_V] = {
        .tag = TAG_REQUIRED | 5u, .name = "Adam second moments",
        .flags = NERF__CKPT_CORE | NERF__CKPT_OPTIMISER | NERF__CKPT_STORED |
                 NERF__CKPT_PER_PARAM,
        .write = write_adam_v, .read = read_adam_v},
    /* Version 1 files lack the two 0.2 sections: they load with the
     * reference values of the fields these hold. */
    [NERF__CKPT_OPTIONS2] = {
        .tag = TAG_REQUIRED | 6u, .name = "options (0.2)",
        .flags = NERF__CKPT_FIXED, .size = OPTIONS2_SIZE,
        .write = write_options2, .read_options = read_options2},
    [NERF__CKPT_TRAINING2] = {
        .tag = 8u, .name = "training state (0.2)",
        .flags = NERF__CKPT_FIXED, .size = TRAINING2_SIZE,
        .write = write_training2, .read = read_training2},
    [NERF__CKPT_OCCUPANCY] = {
        .tag = 7u, .name = "occupancy grid", .wanted = has_grid,
        .write = write_occupancy, .read = read_occupancy},
    /* Written for bf16 and oneDNN models only: the weights are fp32
     * either way, so a reader that does not know it computes in fp32. */
    [NERF__CKPT_MATMUL] = {
        .tag = 9u, .name = "matmul", .flags = NERF__CKPT_FIXED,
        .size = WORD_SIZE, .wanted = has_matmul, .write = write_matmul,
        .read_options = read_word,
        .option = offsetof(nerf_model_options, matmul),
        .implied = NERF_MATMUL_FP32, .max = NERF_MATMUL_FP32_ONEDNN},
    [NERF__CKPT_SPACE] = {
        .tag = TAG_REQUIRED | 10u, .name = "space", .flags = NERF__CKPT_FIXED,
        .size = WORD_SIZE, .wanted = has_space, .write = write_space,
        .read_options = read_word,
        .option = offsetof(nerf_model_options, space),
        .implied = NERF_SPACE_BOX, .max = NERF_SPACE_UNBOUNDED},
    [NERF__CKPT_RENDER] = {
        .tag = 12u, .name = "render settings", .flags = NERF__CKPT_FIXED,
        .size = RENDER_SIZE, .wanted = has_render, .write = write_render,
        .read = read_render},
    [NERF__CKPT_WEIGHTS_ONLY] = {
        .tag = TAG_REQUIRED | 13u, .name = "weights-only marker",
        .flags = NERF__CKPT_FIXED, .size = 0, .wanted = has_marker,
        .write = write_nothing, .read = read_marker},
    /* Longer bodies are for fields a later writer may add (formats.md). */
    [NERF__CKPT_DATA] = {
        .tag = 11u, .name = "data", .wanted = has_data,
        .write = write_data, .read = read_data},
    [NERF__CKPT_SCHEDULE] = {
        .tag = TAG_REQUIRED | 14u, .name = "schedule",
        .flags = NERF__CKPT_FIXED, .size = NERF__SCHEDULE_SIZE,
        .wanted = has_schedule, .write = write_schedule,
        .read = read_schedule},
    [NERF__CKPT_BATCH] = {
        .tag = 15u, .name = "batch", .flags = NERF__CKPT_FIXED,
        .size = BATCH_SIZE, .wanted = has_batch, .write = write_batch,
        .read = read_batch},
    /* Left out of weights-only files by has_average() rather than by
     * OPTIMISER, so that a reader does not refuse one that holds it. */
    [NERF__CKPT_AVERAGE] = {
        .tag = 16u, .name = "average", .flags = NERF__CKPT_STORED,
        .wanted = has_average, .write = write_average,
        .read = read_average},
    [NERF__CKPT_CORRECTIONS] = {
        .tag = 17u, .name = "Adam corrections",
        .flags = NERF__CKPT_OPTIMISER, .wanted = has_corrections,
        .write = write_corrections, .read = read_corrections},
    /* Optional: a reader that skips it renders the networks' own colours,
     * the look of no photo in particular (model/appearance.h). */
    [NERF__CKPT_APPEARANCE] = {
        .tag = 19u, .name = "appearance codes", .flags = NERF__CKPT_STORED,
        .wanted = has_appearance, .write = write_appearance,
        .read = read_appearance},
    /* Read, never written: 0.13.0's codes, whose optimiser state
     * (Adam's moments) the codes' steps no longer use. */
    [NERF__CKPT_APPEARANCE_0_13] = {
        .tag = 18u, .name = "appearance codes (0.13.0)",
        .flags = NERF__CKPT_STORED, .wanted = never, .write = write_nothing,
        .read = read_appearance_0_13},
};
