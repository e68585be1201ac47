/*
 * nerf_model_save() and nerf_model_load(): libnerf's own checkpoint format.
 * docs/formats.md is the specification; this file follows it.  In short: a
 * 48-byte little-endian header with its own CRC, then a zlib stream whose
 * content is a list of tagged sections (u32 tag, u64 length, bytes).
 */
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <zlib.h>

#include "average.h"
#include "byteorder.h"
#include "deflate_bound.h"
#include "file_io.h"
#include "fingerprint.h"
#include "gemm_onednn.h"
#include "model.h"
#include "occupancy.h"
#include "schedule.h"

#define MAGIC "NERFCKPT"
#define MAGIC_LEN 8
/* 2 (libnerf 0.2): adds the options2 section; version 1 files still load,
 * with the reference values of the fields it holds. */
#define FORMAT_VERSION 2u
#define HEADER_SIZE 48u
/* The frame every version keeps: magic, version, header size and a final
 * CRC, so that any version's header can at least be verified. */
#define HEADER_FRAME 20u
#define HEADER_SIZE_MAX 4096u

/* Bit 31 of a tag: a reader that does not know the section must refuse the
 * file; without it, unknown sections are skipped. */
#define TAG_REQUIRED 0x80000000u
#define TAG_OPTIONS (TAG_REQUIRED | 1u)
#define TAG_TRAINING (TAG_REQUIRED | 2u)
#define TAG_PARAMS (TAG_REQUIRED | 3u)
#define TAG_ADAM_M (TAG_REQUIRED | 4u)
#define TAG_ADAM_V (TAG_REQUIRED | 5u)
#define TAG_OPTIONS2 (TAG_REQUIRED | 6u)
/* Optional: a reader that does not know it loads the model with a fresh
 * grid, which training refills within a few updates. */
#define TAG_OCCUPANCY 7u
/* Optional: hyperparameters added after the options section (weight
 * decay).  A reader that does not know it trains on without them. */
#define TAG_TRAINING2 8u
/* Optional: how the model computes its products (nerf_model_options.
 * matmul), written for bf16 models only.  The weights are fp32 either way,
 * so a reader that does not know it loads the model computing in fp32. */
#define TAG_MATMUL 9u
/* Required, written only for models whose space is not BOX: a reader that
 * does not know the section would lay the grids over the wrong space. */
#define TAG_SPACE (TAG_REQUIRED | 10u)
/* Optional: the sampler settings and background the model was trained
 * with, for a renderer that knows nothing of its scene.  A reader that does
 * not know it renders with settings of its own, as before. */
#define TAG_RENDER 12u
/* Required, empty: the file is a weights-only export without the Adam
 * moments.  A reader that does not know it must not take the missing
 * moments for a corrupt file, nor resume training from zeros. */
#define TAG_WEIGHTS_ONLY (TAG_REQUIRED | 13u)
/* Optional: what data the model was trained on (model/fingerprint.h), for
 * a warning when it is resumed on other data.  A reader that does not know
 * it resumes without the warning.  Its body is checked on its own, not
 * through the tables below, where its index stays empty. */
#define TAG_DATA 11u
/* Required, written only for a model trained under a time budget
 * (model/schedule.h): a reader that does not know it would resume on
 * another learning-rate schedule. */
#define TAG_SCHEDULE (TAG_REQUIRED | 14u)
/* Optional: the batch the model was trained with (nerf_model_training_
 * batch()), so that a resume can take it.  A reader that does not know it
 * resumes with its caller's batch, as before. */
#define TAG_BATCH 15u
/* Optional: the steps the weights are averaged over before the schedule's
 * end, and the average while it runs (model/average.h).  A reader that
 * does not know it resumes without averaging. */
#define TAG_AVERAGE 16u
/* Optional: each hash-table parameter's Adam corrections by its own count
 * of updates (model.h).  A reader that does not know it resumes correcting
 * by the step, as before 0.10. */
#define TAG_ADAM_CORRECTIONS 17u
#define N_REQUIRED_SECTIONS 6
#define N_SECTIONS 17
#define OCCUPANCY_INDEX 6
#define TRAINING2_INDEX 7
#define MATMUL_INDEX 8
#define SPACE_INDEX 9
#define RENDER_INDEX 11
#define WEIGHTS_ONLY_INDEX 12
#define SCHEDULE_INDEX 13
#define BATCH_INDEX 14
#define AVERAGE_INDEX 15
#define ADAM_CORRECTIONS_INDEX 16
#define ADAM_M_INDEX 3
#define ADAM_V_INDEX 4
#define WORD_SIZE 8u /* the matmul and space sections: u32 value, u32 0 */
#define N_CORE_SECTIONS 5 /* the ones every version has */
#define SECTION_HEAD 12u /* u32 tag, u64 length */
#define OPTIONS_SIZE 52u /* 11 u32 fields and the u64 seed */
#define TRAINING_SIZE 64u /* 6 f64 hyperparameters, u64 step, u64 count */
#define N_OPTION_U32 11
#define OPTIONS2_SIZE 48u /* the 12 u32 fields appended in 0.2 */
#define N_OPTION2_U32 11  /* and a reserved 0 */
#define OCCUPANCY_HEAD 16u /* u32 resolution, u32 reserved, u64 updates */
#define TRAINING2_SIZE 8u /* f64 weight decay */
#define RENDER_SIZE 64u /* 16 u32 words: see put_render */
#define BATCH_SIZE 8u   /* u32 batch_rays, u32 batch_samples */

/* Refuse files beyond 64 GiB before reading them. */
#define MAX_FILE ((uint64_t)1 << 36)

/* The fields of a header, decoded. */
typedef struct ckpt_header {
    uint32_t version, size, flags;
    uint64_t payload_size, packed_size;
    uint32_t packed_crc, payload_crc;
} ckpt_header;

/* ---- saving ------------------------------------------------------------- */

static unsigned char *put_section(unsigned char *p, uint32_t tag, uint64_t len)
{
    nerf__store_le32(p, tag);
    nerf__store_le64(p + 4, len);
    return p + SECTION_HEAD;
}

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

static void store_fields(unsigned char *p, const nerf_model_options *o,
                         const size_t *offsets, int n)
{
    for (int i = 0; i < n; i++) {
        uint32_t v;
        memcpy(&v, (const char *)o + offsets[i], sizeof v);
        nerf__store_le32(p + 4 * i, v);
    }
}

static void load_fields(const unsigned char *p, nerf_model_options *o,
                        const size_t *offsets, int n)
{
    for (int i = 0; i < n; i++) {
        uint32_t v = nerf__load_le32(p + 4 * i);
        memcpy((char *)o + offsets[i], &v, sizeof v);
    }
}

static unsigned char *put_options(unsigned char *p, const nerf_model_options *o)
{
    p = put_section(p, TAG_OPTIONS, OPTIONS_SIZE);
    store_fields(p, o, option_u32, N_OPTION_U32);
    nerf__store_le64(p + 4 * N_OPTION_U32, o->seed);
    return p + OPTIONS_SIZE;
}

static unsigned char *put_options2(unsigned char *p,
                                   const nerf_model_options *o)
{
    p = put_section(p, TAG_OPTIONS2, OPTIONS2_SIZE);
    store_fields(p, o, option2_u32, N_OPTION2_U32);
    /* The struct's reserved1 here, which matmul replaced there: matmul
     * has a section of its own (TAG_MATMUL) that old readers can skip. */
    nerf__store_le32(p + 4 * N_OPTION2_U32, 0);
    return p + OPTIONS2_SIZE;
}

/*
 * The sections that hold one option each (matmul, space): a u32 value and
 * a reserved u32 0, written only when the value is not the one every file
 * before the section implies.
 */
typedef struct word_section {
    uint32_t tag, index;
    size_t offset;      /* of the option in nerf_model_options */
    uint32_t implied;   /* the value of a file without the section */
    uint32_t max;       /* largest known value */
    const char *name;
} word_section;

static const word_section word_sections[2] = {
    {TAG_MATMUL, MATMUL_INDEX, offsetof(nerf_model_options, matmul),
     NERF_MATMUL_FP32, NERF_MATMUL_FP32_ONEDNN, "matmul"},
    {TAG_SPACE, SPACE_INDEX, offsetof(nerf_model_options, space),
     NERF_SPACE_BOX, NERF_SPACE_UNBOUNDED, "space"},
};

static uint32_t word_value(const word_section *w, const nerf_model_options *o)
{
    uint32_t v;
    memcpy(&v, (const char *)o + w->offset, sizeof v);
    return v;
}

static size_t word_sections_size(const nerf_model *m)
{
    size_t n = 0;
    for (int i = 0; i < 2; i++) {
        const word_section *w = &word_sections[i];
        n += word_value(w, &m->opts) != w->implied ? SECTION_HEAD + WORD_SIZE
                                                   : 0;
    }
    return n;
}

static unsigned char *put_word_sections(unsigned char *p, const nerf_model *m)
{
    for (int i = 0; i < 2; i++) {
        const word_section *w = &word_sections[i];
        const uint32_t v = word_value(w, &m->opts);
        if (v != w->implied) {
            p = put_section(p, w->tag, WORD_SIZE);
            nerf__store_le32(p, v);
            nerf__store_le32(p + 4, 0);
            p += WORD_SIZE;
        }
    }
    return p;
}

static unsigned char *put_training(unsigned char *p, const nerf_model *m)
{
    const nerf__adam *a = &m->adam;
    const double hp[6] = {a->lr, a->lr_final, a->decay_steps,
                          a->beta1, a->beta2, a->eps};
    p = put_section(p, TAG_TRAINING, TRAINING_SIZE);
    for (int i = 0; i < 6; i++) {
        nerf__store_lef64(p + 8 * i, hp[i]);
    }
    nerf__store_le64(p + 48, m->step);
    nerf__store_le64(p + 56, m->n_params);
    return p + TRAINING_SIZE;
}

static unsigned char *put_training2(unsigned char *p, const nerf_model *m)
{
    p = put_section(p, TAG_TRAINING2, TRAINING2_SIZE);
    nerf__store_lef64(p, m->adam.weight_decay);
    return p + TRAINING2_SIZE;
}

static unsigned char *store_floats(unsigned char *p, const float *x,
                                   size_t n)
{
    for (size_t i = 0; i < n; i++) {
        nerf__store_lef32(p + 4 * i, x[i]);
    }
    return p + 4 * n;
}

static unsigned char *put_floats(unsigned char *p, uint32_t tag,
                                 const float *x, size_t n)
{
    p = put_section(p, tag, (uint64_t)n * 4);
    return store_floats(p, x, n);
}

/* The occupancy grid: its EMA and update counter, from which loading
 * rebuilds the bits exactly as the last update set them. */
static size_t occupancy_size(const nerf_model *m)
{
    return m->grid ? SECTION_HEAD + OCCUPANCY_HEAD + 4 * m->grid->cells : 0;
}

static unsigned char *put_occupancy(unsigned char *p, const nerf_model *m)
{
    const nerf__occupancy *g = m->grid;
    p = put_section(p, TAG_OCCUPANCY, OCCUPANCY_HEAD + 4 * (uint64_t)g->cells);
    nerf__store_le32(p, g->res);
    nerf__store_le32(p + 4, 0);
    nerf__store_le64(p + 8, g->updates);
    p += OCCUPANCY_HEAD;
    for (size_t i = 0; i < g->cells; i++) {
        nerf__store_lef32(p + 4 * i, g->ema[i]);
    }
    return p + 4 * g->cells;
}

static size_t data_size(const nerf_model *m)
{
    return m->data.known ? SECTION_HEAD + NERF__FINGERPRINT_SIZE : 0;
}

static unsigned char *put_data(unsigned char *p, const nerf_model *m)
{
    p = put_section(p, TAG_DATA, NERF__FINGERPRINT_SIZE);
    nerf__fingerprint_store(p, &m->data);
    return p + NERF__FINGERPRINT_SIZE;
}

/*
 * The render settings: u32 n_coarse, n_fine, lindisp, paper_bins, ndc,
 * march_steps, max_samples, white_background; f32 t_near, t_far,
 * ndc_focal; u32 ndc_width, ndc_height; three reserved u32 0.
 */
static unsigned char *put_render(unsigned char *p, const nerf_model *m)
{
    const nerf_sampler_options *o = &m->render_sampler;
    const uint32_t words[8] = {o->n_coarse, o->n_fine, o->lindisp,
                               o->paper_bins, o->ndc, o->march_steps,
                               o->max_samples, m->render_white};
    p = put_section(p, TAG_RENDER, RENDER_SIZE);
    for (int i = 0; i < 8; i++) {
        nerf__store_le32(p + 4 * i, words[i]);
    }
    nerf__store_lef32(p + 32, o->t_near);
    nerf__store_lef32(p + 36, o->t_far);
    nerf__store_lef32(p + 40, o->ndc_focal);
    nerf__store_le32(p + 44, o->ndc_width);
    nerf__store_le32(p + 48, o->ndc_height);
    memset(p + 52, 0, RENDER_SIZE - 52);
    return p + RENDER_SIZE;
}

static bool has_schedule(const nerf_model *m)
{
    return nerf__schedule_saved(&m->schedule, m->adam.decay_start);
}

static unsigned char *put_schedule(unsigned char *p, const nerf_model *m)
{
    p = put_section(p, TAG_SCHEDULE, NERF__SCHEDULE_SIZE);
    nerf__schedule_store(p, &m->schedule, m->adam.decay_start);
    return p + NERF__SCHEDULE_SIZE;
}

static unsigned char *put_batch(unsigned char *p, const nerf_model *m)
{
    p = put_section(p, TAG_BATCH, BATCH_SIZE);
    nerf__store_le32(p, m->batch_rays);
    nerf__store_le32(p + 4, m->batch_samples);
    return p + BATCH_SIZE;
}

/* A weights-only file trains no further, and leaves the average out. */
static bool has_average(const nerf_model *m, bool weights_only)
{
    return !weights_only && nerf__average_saved(m);
}

/* A weights-only file trains no further, and leaves the corrections out;
 * so does a model that corrects by the step (corrected implies a
 * table). */
static bool has_corrections(const nerf_model *m, bool weights_only)
{
    return !weights_only && m->corrected;
}

/* The head, then the running average's floats. */
static unsigned char *put_average(unsigned char *p, const nerf_model *m)
{
    p = put_section(p, TAG_AVERAGE, nerf__average_size(m));
    nerf__average_store_head(p, m);
    p += NERF__AVERAGE_HEAD;
    return m->averaging ? store_floats(p, m->average, m->n_params) : p;
}

static size_t payload_size(const nerf_model *m, bool weights_only)
{
    /* A weights-only file trades the two moment sections for its empty
     * marker. */
    const size_t moments = weights_only ? 0 : 2 * (SECTION_HEAD +
                                                   4 * m->n_params);
    return (N_REQUIRED_SECTIONS - 2) * SECTION_HEAD + OPTIONS_SIZE +
           OPTIONS2_SIZE + TRAINING_SIZE + 4 * m->n_params + moments +
           SECTION_HEAD + TRAINING2_SIZE + occupancy_size(m) +
           word_sections_size(m) +
           (m->has_render ? SECTION_HEAD + RENDER_SIZE : 0) +
           (weights_only ? SECTION_HEAD : 0) + data_size(m) +
           (has_schedule(m) ? SECTION_HEAD + NERF__SCHEDULE_SIZE : 0) +
           (m->batch_rays > 0 ? SECTION_HEAD + BATCH_SIZE : 0) +
           (has_average(m, weights_only)
                ? SECTION_HEAD + nerf__average_size(m) : 0) +
           (has_corrections(m, weights_only)
                ? SECTION_HEAD + 8 * m->n_table : 0);
}

/*
 * Stretches of a payload that zlib is to copy rather than compress:
 * trained weights and moments are noisy floats, which level 1 shrinks by
 * a tenth at about 40 MB/s (a fast-preset save took 6 s), while the rest
 * (the corrections, mostly zeros, the occupancy grid) shrinks many times.
 */
#define MAX_STORED 2

typedef struct stored_spans {
    size_t begin[MAX_STORED], end[MAX_STORED];
    int n;
} stored_spans;

static void add_stored(stored_spans *st, const unsigned char *base,
                       const unsigned char *begin, const unsigned char *end)
{
    st->begin[st->n] = (size_t)(begin - base);
    st->end[st->n] = (size_t)(end - base);
    st->n++;
}

static void build_payload(const nerf_model *m, bool weights_only,
                          unsigned char *p, stored_spans *st)
{
    unsigned char *const base = p;
    st->n = 0;
    p = put_options(p, &m->opts);
    p = put_training(p, m);
    unsigned char *weights = p;
    p = put_floats(p, TAG_PARAMS, m->params, m->n_params);
    if (!weights_only) {
        p = put_floats(p, TAG_ADAM_M, m->adam_m, m->n_params);
        p = put_floats(p, TAG_ADAM_V, m->adam_v, m->n_params);
    }
    add_stored(st, base, weights, p);
    p = put_options2(p, &m->opts);
    p = put_training2(p, m);
    if (m->grid) {
        p = put_occupancy(p, m);
    }
    p = put_word_sections(p, m);
    if (m->has_render) {
        p = put_render(p, m);
    }
    if (weights_only) {
        p = put_section(p, TAG_WEIGHTS_ONLY, 0);
    }
    if (m->data.known) {
        p = put_data(p, m);
    }
    if (has_schedule(m)) {
        p = put_schedule(p, m);
    }
    if (m->batch_rays > 0) {
        p = put_batch(p, m);
    }
    if (has_average(m, weights_only)) {
        unsigned char *average = p;
        p = put_average(p, m);
        add_stored(st, base, average, p);
    }
    if (has_corrections(m, weights_only)) {
        put_floats(p, TAG_ADAM_CORRECTIONS, m->adam_r, 2 * m->n_table);
    }
}

static void put_header(unsigned char *h, const ckpt_header *hd)
{
    memcpy(h, MAGIC, MAGIC_LEN);
    nerf__store_le32(h + 8, hd->version);
    nerf__store_le32(h + 12, hd->size);
    nerf__store_le64(h + 16, hd->payload_size);
    nerf__store_le64(h + 24, hd->packed_size);
    nerf__store_le32(h + 32, hd->packed_crc);
    nerf__store_le32(h + 36, hd->payload_crc);
    nerf__store_le32(h + 40, hd->flags);
    nerf__store_le32(h + 44, (uint32_t)crc32_z(0L, h, HEADER_SIZE - 4));
}

/* A zlib stream into a buffer of bound bytes, which can be larger than
 * one call's count (uInt): each call is given what is left of it. */
typedef struct packer {
    z_stream z;
    unsigned char *out;
    uLong bound;
} packer;

static void give_room(packer *pk)
{
    const uLong left = pk->bound - pk->z.total_out;
    pk->z.next_out = pk->out + pk->z.total_out;
    pk->z.avail_out = left > UINT_MAX ? UINT_MAX : (uInt)left;
}

/* src[0, n) into the stream at level (0: copied as stored blocks). */
static int pack_span(packer *pk, const unsigned char *src, size_t n,
                     int level)
{
    give_room(pk);
    int zr = deflateParams(&pk->z, level, Z_DEFAULT_STRATEGY);
    size_t done = 0;
    while (zr == Z_OK && done < n) {
        const size_t piece = n - done > UINT_MAX ? UINT_MAX : n - done;
        /* zlib reads next_in only; it is not const unless ZLIB_CONST. */
        pk->z.next_in = (Bytef *)(uintptr_t)(src + done);
        pk->z.avail_in = (uInt)piece;
        while (zr == Z_OK && pk->z.avail_in > 0) {
            give_room(pk);
            if (pk->z.avail_out == 0) {
                return Z_BUF_ERROR;
            }
            zr = deflate(&pk->z, Z_NO_FLUSH);
        }
        done += piece;
    }
    return zr;
}

/*
 * Compress payload into a new buffer, one zlib stream: st's spans copied,
 * the rest at level 1, which higher levels barely improve on at several
 * times the cost.  A reader inflates it as any other stream.
 */
static int pack(const nerf__env *env, const char *path,
                const unsigned char *payload, size_t size,
                const stored_spans *st, unsigned char **packed_out,
                size_t *packed_size)
{
    uLong bound = compressBound((uLong)size);
    /* Each change of level ends a block: a few bytes, with room to spare. */
    const uLong switches = 64u * (2u * MAX_STORED + 1u);
    if ((size_t)(uLong)size != size || bound < (uLong)size ||
        bound + switches < bound) {
        return nerf__error(NERF_ENOMEM, "%s: checkpoint of %zu bytes is too "
                           "large for zlib on this platform", path, size);
    }
    packer pk = {.out = nerf__alloc(env, bound + switches),
                 .bound = bound + switches};
    if (pk.out == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    int zr = deflateInit(&pk.z, 1);
    size_t at = 0;
    for (int i = 0; i <= st->n && zr == Z_OK; i++) {
        const size_t to = i < st->n ? st->begin[i] : size;
        zr = pack_span(&pk, payload + at, to - at, 1);
        if (zr == Z_OK && i < st->n) {
            zr = pack_span(&pk, payload + to, st->end[i] - to, 0);
            at = st->end[i];
        }
    }
    while (zr == Z_OK) {
        give_room(&pk);
        zr = pk.z.avail_out > 0 ? deflate(&pk.z, Z_FINISH) : Z_BUF_ERROR;
    }
    const size_t len = (size_t)pk.z.total_out;
    deflateEnd(&pk.z);
    if (zr != Z_STREAM_END) {
        nerf__free(env, pk.out);
        return nerf__error(zr == Z_MEM_ERROR ? NERF_ENOMEM : NERF_ERROR,
                           "%s: zlib could not compress the checkpoint "
                           "(error %d)", path, zr);
    }
    *packed_out = pk.out;
    *packed_size = len;
    return NERF_OK;
}

static int write_checkpoint(const nerf_model *m, const char *path,
                            bool weights_only, const unsigned char *payload,
                            size_t size, const stored_spans *st)
{
    unsigned char *packed = NULL;
    size_t packed_size = 0;
    int rc = pack(&m->env, path, payload, size, st, &packed, &packed_size);
    if (rc != NERF_OK) {
        return rc;
    }
    ckpt_header hd = {FORMAT_VERSION, HEADER_SIZE, 0, size, packed_size,
                      (uint32_t)crc32_z(0L, packed, packed_size),
                      (uint32_t)crc32_z(0L, payload, size)};
    unsigned char header[HEADER_SIZE];
    put_header(header, &hd);
    const nerf__span parts[2] = {{header, sizeof header},
                                 {packed, packed_size}};
    /* Saves killed mid-write (kill -9) leave their temporary files; a
     * checkpoint is saved again and again, so this is where they go. */
    unsigned stale = nerf__file_remove_stale_temps(&m->env, path);
    if (stale > 0) {
        nerf__log(&m->env, NERF_LOG_INFO, "%s: removed %u temporary file(s) "
                  "left by saves that did not finish", path, stale);
    }
    rc = nerf__file_write_atomic(&m->env, path, parts, 2);
    nerf__free(&m->env, packed);
    if (rc == NERF_OK) {
        nerf__log(&m->env, NERF_LOG_DEBUG, "%s: saved %s (format %u): "
                  "%zu parameters, step %llu, %zu bytes", path,
                  weights_only ? "weights-only export" : "checkpoint",
                  FORMAT_VERSION, m->n_params, (unsigned long long)m->step,
                  HEADER_SIZE + packed_size);
    }
    return rc;
}

static int save(const nerf_model *model, const char *path, bool weights_only,
                const char *fn)
{
    if (model == NULL || path == NULL) {
        return nerf__error(NERF_EINVAL, "%s: NULL %s", fn,
                           model ? "path" : "model");
    }
    if (!nerf__model_finite(model)) {
        /* No program can use such a file, and a trainer saving a run that
         * diverged would replace its last good checkpoint with it. */
        char text[320];
        nerf__model_nonfinite_text(model, text, sizeof text);
        return nerf__error(NERF_EINVAL, "%s: %s: not written: the model's "
                           "weights are not finite (%s): its training "
                           "diverged", fn, path, text);
    }
    /* A model that has no moments must not gain zeros that a later run
     * would take for its optimiser's state. */
    weights_only = weights_only || model->weights_only;
    size_t size = payload_size(model, weights_only);
    unsigned char *payload = nerf__alloc(&model->env, size);
    if (payload == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    stored_spans st;
    build_payload(model, weights_only, payload, &st);
    int rc = write_checkpoint(model, path, weights_only, payload, size, &st);
    nerf__free(&model->env, payload);
    return rc;
}

NERF_API int nerf_model_save(const nerf_model *model, const char *path)
{
    return save(model, path, false, "nerf_model_save");
}

NERF_API int nerf_model_export(const nerf_model *model, const char *path)
{
    return save(model, path, true, "nerf_model_export");
}

/* ---- loading: the header ------------------------------------------------ */

static int truncated(const char *path, size_t size, uint64_t need)
{
    return nerf__error(NERF_EFORMAT, "%s: truncated checkpoint (%zu bytes, "
                       "expected %llu)", path, size, (unsigned long long)need);
}

/* Magic, header size and header CRC: the frame common to all versions. */
static int check_frame(const char *path, const unsigned char *b, size_t size)
{
    size_t cmp = size < MAGIC_LEN ? size : MAGIC_LEN;
    if (memcmp(b, MAGIC, cmp) != 0) {
        return nerf__error(NERF_EUNRECOGNISED, "%s: not a libnerf "
                           "checkpoint (a model file)", path);
    }
    if (size < HEADER_FRAME) {
        return truncated(path, size, HEADER_SIZE);
    }
    uint32_t hsize = nerf__load_le32(b + 12);
    if (hsize < HEADER_FRAME || hsize > HEADER_SIZE_MAX || hsize % 4 != 0) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint header "
                           "(header size %lu)", path, (unsigned long)hsize);
    }
    if (size < hsize) {
        return truncated(path, size, hsize);
    }
    uint32_t stored = nerf__load_le32(b + hsize - 4);
    if ((uint32_t)crc32_z(0L, b, hsize - 4) != stored) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (header "
                           "CRC mismatch)", path);
    }
    return NERF_OK;
}

static int read_header(const char *path, const unsigned char *b, size_t size,
                       ckpt_header *hd)
{
    int rc = check_frame(path, b, size);
    if (rc != NERF_OK) {
        return rc;
    }
    hd->version = nerf__load_le32(b + 8);
    hd->size = nerf__load_le32(b + 12);
    if (hd->version > FORMAT_VERSION) {
        return nerf__error(NERF_EVERSION, "%s: checkpoint format version %lu "
                           "is newer than this libnerf supports (version %u)",
                           path, (unsigned long)hd->version, FORMAT_VERSION);
    }
    if (hd->version == 0 || hd->size != HEADER_SIZE) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint header "
                           "(format version %lu, header size %lu)", path,
                           (unsigned long)hd->version, (unsigned long)hd->size);
    }
    hd->payload_size = nerf__load_le64(b + 16);
    hd->packed_size = nerf__load_le64(b + 24);
    hd->packed_crc = nerf__load_le32(b + 32);
    hd->payload_crc = nerf__load_le32(b + 36);
    hd->flags = nerf__load_le32(b + 40);
    if (hd->flags != 0) {
        return nerf__error(NERF_EVERSION, "%s: checkpoint uses features this "
                           "libnerf does not know (flags 0x%lx)", path,
                           (unsigned long)hd->flags);
    }
    uint64_t body = size - HEADER_SIZE;
    if (body < hd->packed_size) {
        return truncated(path, size, HEADER_SIZE + hd->packed_size);
    }
    if (body > hd->packed_size) {
        return nerf__error(NERF_EFORMAT, "%s: %llu unexpected bytes after the "
                           "checkpoint payload", path,
                           (unsigned long long)(body - hd->packed_size));
    }
    return NERF_OK;
}

/* ---- loading: the payload ----------------------------------------------- */

static int unpack(const nerf__env *env, const char *path,
                  const unsigned char *packed, const ckpt_header *hd,
                  unsigned char **out)
{
    size_t n_in = (size_t)hd->packed_size;
    if ((uint32_t)crc32_z(0L, packed, n_in) != hd->packed_crc) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (payload "
                           "CRC mismatch)", path);
    }
    uint64_t n_out = hd->payload_size;
    uLong src_len = (uLong)n_in;
    uLongf dst_len = (uLongf)n_out;
    if (n_out / NERF__DEFLATE_MAX_RATIO > n_in || n_out >= SIZE_MAX ||
        src_len != n_in || dst_len != n_out) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint header "
                           "(%llu bytes cannot decompress to %llu)", path,
                           (unsigned long long)n_in,
                           (unsigned long long)n_out);
    }
    unsigned char *payload = nerf__alloc(env, n_out ? (size_t)n_out : 1);
    if (payload == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    int zr = uncompress2(payload, &dst_len, packed, &src_len);
    int rc = NERF_OK;
    if (zr == Z_MEM_ERROR) {
        rc = nerf__error(NERF_ENOMEM, "%s: zlib ran out of memory", path);
    } else if (zr != Z_OK || dst_len != n_out || src_len != n_in) {
        rc = nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (payload "
                         "does not decompress to its recorded size)", path);
    } else if ((uint32_t)crc32_z(0L, payload, n_out) != hd->payload_crc) {
        rc = nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                         "(decompressed payload CRC mismatch)", path);
    }
    if (rc != NERF_OK) {
        nerf__free(env, payload);
        return rc;
    }
    *out = payload;
    return NERF_OK;
}

/* The known sections of a payload, in the order of their tags. */
typedef struct sections {
    const unsigned char *body[N_SECTIONS];
    uint64_t len[N_SECTIONS];
    const unsigned char *data; /* TAG_DATA's body, or NULL */
    uint64_t data_len;
} sections;

static const char *const section_names[N_SECTIONS] = {
    "options", "training state", "parameters", "Adam first moments",
    "Adam second moments", "options (0.2)", "occupancy grid",
    "training state (0.2)", "matmul", "space", "data", "render settings",
    "weights-only marker", "schedule", "batch", "average",
    "Adam corrections"};

static int take_section(const nerf__env *env, const char *path, sections *s,
                        uint32_t tag, const unsigned char *body, uint64_t len)
{
    if (tag == TAG_DATA) {
        if (s->data != NULL) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (two "
                               "data sections)", path);
        }
        s->data = body;
        s->data_len = len;
        return NERF_OK;
    }
    uint32_t index = (tag & ~TAG_REQUIRED) - 1;
    bool known = (tag & TAG_REQUIRED) ? index < N_REQUIRED_SECTIONS ||
                                            tag == TAG_SPACE ||
                                            tag == TAG_WEIGHTS_ONLY ||
                                            tag == TAG_SCHEDULE
                                      : tag == TAG_OCCUPANCY ||
                                            tag == TAG_TRAINING2 ||
                                            tag == TAG_MATMUL ||
                                            tag == TAG_RENDER ||
                                            tag == TAG_BATCH ||
                                            tag == TAG_AVERAGE ||
                                            tag == TAG_ADAM_CORRECTIONS;
    if (known) {
        if (s->body[index] != NULL) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (two "
                               "%s sections)", path, section_names[index]);
        }
        s->body[index] = body;
        s->len[index] = len;
        return NERF_OK;
    }
    if (tag & TAG_REQUIRED) {
        return nerf__error(NERF_EVERSION, "%s: checkpoint has a required "
                           "section 0x%08lx unknown to this libnerf (format "
                           "version %u)", path, (unsigned long)tag,
                           FORMAT_VERSION);
    }
    nerf__log(env, NERF_LOG_DEBUG, "%s: skipping checkpoint section 0x%08lx "
              "(%llu bytes)", path, (unsigned long)tag,
              (unsigned long long)len);
    return NERF_OK;
}

static int split_sections(const nerf__env *env, const char *path,
                          const unsigned char *p, size_t n, sections *s)
{
    memset(s, 0, sizeof *s);
    size_t at = 0;
    while (at < n) {
        if (n - at < SECTION_HEAD) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                               "(section header cut at payload byte %zu)",
                               path, at);
        }
        uint32_t tag = nerf__load_le32(p + at);
        uint64_t len = nerf__load_le64(p + at + 4);
        at += SECTION_HEAD;
        if (len > n - at) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                               "(section 0x%08lx runs past the payload)",
                               path, (unsigned long)tag);
        }
        int rc = take_section(env, path, s, tag, p + at, len);
        if (rc != NERF_OK) {
            return rc;
        }
        at += (size_t)len;
    }
    const bool weights_only = s->body[WEIGHTS_ONLY_INDEX] != NULL;
    for (int i = 0; i < N_CORE_SECTIONS; i++) {
        const bool moment = i == ADAM_M_INDEX || i == ADAM_V_INDEX;
        if (s->body[i] == NULL && !(weights_only && moment)) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (no "
                               "%s section)", path, section_names[i]);
        }
        if (s->body[i] != NULL && weights_only && moment) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (a "
                               "weights-only file with %s)", path,
                               section_names[i]);
        }
    }
    if (weights_only && s->body[ADAM_CORRECTIONS_INDEX] != NULL) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (a "
                           "weights-only file with %s)", path,
                           section_names[ADAM_CORRECTIONS_INDEX]);
    }
    if (weights_only && s->len[WEIGHTS_ONLY_INDEX] != 0) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the "
                           "weights-only marker is not empty)", path);
    }
    return NERF_OK;
}

static void get_options(const unsigned char *p, nerf_model_options *o)
{
    nerf_model_options_init(o, sizeof *o);
    load_fields(p, o, option_u32, N_OPTION_U32);
    o->seed = nerf__load_le64(p + 4 * N_OPTION_U32);
    o->hooks = NULL;
}

static void get_options2(const unsigned char *p, nerf_model_options *o)
{
    load_fields(p, o, option2_u32, N_OPTION2_U32);
}

/* The one-option sections: what they hold, or why one is corrupt (NULL:
 * fine); a section absent leaves the value every file before it had. */
static const char *get_word_sections(const sections *s, nerf_model_options *o,
                                     char *why, size_t why_size)
{
    for (int i = 0; i < 2; i++) {
        const word_section *w = &word_sections[i];
        const unsigned char *b = s->body[w->index];
        if (b == NULL) {
            continue;
        }
        const uint32_t v = nerf__load_le32(b);
        if (s->len[w->index] != WORD_SIZE || nerf__load_le32(b + 4) != 0) {
            snprintf(why, why_size, "the %s section has the wrong size or a "
                     "non-zero reserved field", w->name);
            return why;
        }
        if (v > w->max) {
            snprintf(why, why_size, "the %s section holds %u, no known "
                     "value", w->name, (unsigned)v);
            return why;
        }
        memcpy((char *)o + w->offset, &v, sizeof v);
    }
    return NULL;
}

/*
 * A checkpoint of a oneDNN model holds fp32 weights like any other, so
 * where its products are not available it still loads, computing in fp32
 * through cblas (and saying so), rather than leaving its weights unusable
 * on this machine.
 */
static void matmul_here(const nerf__env *env, const char *path,
                        nerf_model_options *o)
{
    const char *why;
    if (o->matmul != NERF_MATMUL_FP32 &&
        !nerf__onednn_supported(o->matmul, &why)) {
        nerf__log(env, NERF_LOG_WARN, "%s: the model was saved with %s "
                  "products, which are not available here (%s): it computes "
                  "in fp32 through cblas", path,
                  o->matmul == NERF_MATMUL_BF16 ? "bf16" : "oneDNN fp32", why);
        o->matmul = NERF_MATMUL_FP32;
    }
}

/* Options and sizes: everything that can be checked before allocating. */
static int check_shapes(const nerf__env *env, const char *path,
                        const sections *s, nerf_model_options *o,
                        uint64_t *n_params)
{
    if (s->len[0] != OPTIONS_SIZE || s->len[1] != TRAINING_SIZE) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (%s "
                           "section has the wrong size)", path,
                           section_names[s->len[0] != OPTIONS_SIZE ? 0 : 1]);
    }
    const int sized[2] = {5, TRAINING2_INDEX};
    const uint64_t sizes[2] = {OPTIONS2_SIZE, TRAINING2_SIZE};
    for (int i = 0; i < 2; i++) {
        if (s->body[sized[i]] != NULL && s->len[sized[i]] != sizes[i]) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (%s "
                               "section has the wrong size)", path,
                               section_names[sized[i]]);
        }
    }
    get_options(s->body[0], o);
    if (s->body[5] != NULL) {
        get_options2(s->body[5], o);
        if (nerf__load_le32(s->body[5] + 4 * N_OPTION2_U32) != 0) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the "
                               "reserved field of options (0.2) is not 0)",
                               path);
        }
    }
    char why_word[128];
    const char *bad = get_word_sections(s, o, why_word, sizeof why_word);
    if (bad) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (%s)", path,
                           bad);
    }
    matmul_here(env, path, o);
    if (nerf__model_check_options(o) != NERF_OK) {
        char why[512];
        snprintf(why, sizeof why, "%s", nerf_last_error());
        return nerf__error(NERF_EFORMAT, "%s: checkpoint holds invalid model "
                           "options (%s)", path, why);
    }
    uint64_t n = nerf__load_le64(s->body[1] + 56);
    uint64_t need = nerf__model_options_param_count(o);
    if (n != need) {
        return nerf__error(NERF_EFORMAT, "%s: checkpoint holds %llu "
                           "parameters but its options need %llu", path,
                           (unsigned long long)n, (unsigned long long)need);
    }
    for (int i = 2; i < N_CORE_SECTIONS; i++) {
        if (s->body[i] != NULL && (s->len[i] / 4 != n || s->len[i] % 4 != 0)) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (%s "
                               "section holds %llu bytes, expected %llu)",
                               path, section_names[i],
                               (unsigned long long)s->len[i],
                               (unsigned long long)(4 * n));
        }
    }
    if (s->body[OCCUPANCY_INDEX] != NULL) {
        /* Only a grid of the size this libnerf gives the model fits. */
        const uint64_t R = NERF__MODEL_GRID_RESOLUTION;
        const uint64_t len = s->len[OCCUPANCY_INDEX];
        const unsigned char *b = s->body[OCCUPANCY_INDEX];
        if (o->encoding != NERF_ENCODING_HASHGRID ||
            len != OCCUPANCY_HEAD + 4 * R * R * R ||
            nerf__load_le32(b) != R || nerf__load_le32(b + 4) != 0) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the "
                               "occupancy grid section does not fit the "
                               "model)", path);
        }
    }
    *n_params = n;
    return NERF_OK;
}

/* The saved EMA into the model's fresh grid.  A genuine EMA is a finite
 * density >= 0 in every cell. */
static int set_occupancy(const char *path, nerf_model *m,
                         const unsigned char *b)
{
    nerf__occupancy *g = m->grid;
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

/* training2 may be NULL: a file from before weight decay trained without
 * it, so resuming it goes on without. */
static int set_training(const char *path, nerf_model *m, const unsigned char *p,
                        const unsigned char *training2)
{
    static const int keys[6] = {
        NERF_PARAM_LEARNING_RATE, NERF_PARAM_LEARNING_RATE_FINAL,
        NERF_PARAM_DECAY_STEPS, NERF_PARAM_ADAM_BETA1, NERF_PARAM_ADAM_BETA2,
        NERF_PARAM_ADAM_EPS};
    static const int keys2[1] = {NERF_PARAM_WEIGHT_DECAY};
    int rc = set_params(path, m, keys, 6, p);
    m->adam.weight_decay = 0.0;
    if (rc == NERF_OK && training2 != NULL) {
        rc = set_params(path, m, keys2, 1, training2);
    }
    m->step = nerf__load_le64(p + 48);
    return rc;
}

static void get_floats(const unsigned char *p, float *x, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        x[i] = nerf__load_lef32(p + 4 * i);
    }
}

/* The corrections into m.  A file with moments but without them was
 * trained correcting by the step, and goes on so. */
static int get_corrections(const char *path, nerf_model *m,
                           const sections *s)
{
    const unsigned char *b = s->body[ADAM_CORRECTIONS_INDEX];
    if (b == NULL) {
        if (s->body[WEIGHTS_ONLY_INDEX] == NULL) {
            m->corrected = false;
        }
        return NERF_OK;
    }
    const uint64_t len = s->len[ADAM_CORRECTIONS_INDEX];
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

/*
 * The render settings into the model.  Only what the file format decides
 * is checked here; the sampler's own checks run when a sampler is made of
 * them (nerf_model_render_settings()).
 */
static int get_render(const char *path, nerf_model *m, const unsigned char *b,
                      uint64_t len)
{
    if (len != RENDER_SIZE) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the "
                           "render settings section has the wrong size)",
                           path);
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
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the "
                           "render settings section holds values no "
                           "sampler has)", path);
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

/* A batch no trainer takes would be refused by the one a resume makes. */
static int get_batch(const char *path, nerf_model *m, const unsigned char *b,
                     uint64_t len)
{
    const uint32_t rays = len == BATCH_SIZE ? nerf__load_le32(b) : 0;
    const uint32_t samples = len == BATCH_SIZE ? nerf__load_le32(b + 4) : 0;
    if (rays < 1 || rays > NERF__BATCH_RAYS_MAX ||
        samples > NERF__BATCH_SAMPLES_MAX) {
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the "
                           "batch section has the wrong size or holds a "
                           "batch no trainer takes)", path);
    }
    m->batch_rays = rays;
    m->batch_samples = samples;
    return NERF_OK;
}

static int build_model(const nerf__env *env, const char *path,
                       const unsigned char *payload, size_t size,
                       nerf_model **out)
{
    sections s;
    nerf_model_options o;
    uint64_t n = 0;
    int rc = split_sections(env, path, payload, size, &s);
    if (rc == NERF_OK) {
        rc = check_shapes(env, path, &s, &o, &n);
    }
    nerf_model *m = NULL;
    if (rc == NERF_OK) {
        rc = nerf__model_alloc(&m, &o, env);
        if (rc != NERF_OK) {
            return nerf__error_prefix(rc, path);
        }
        rc = set_training(path, m, s.body[1], s.body[TRAINING2_INDEX]);
    }
    if (rc != NERF_OK) {
        nerf_model_destroy(m);
        return rc;
    }
    if (s.body[OCCUPANCY_INDEX] != NULL) {
        rc = set_occupancy(path, m, s.body[OCCUPANCY_INDEX]);
        if (rc != NERF_OK) {
            nerf_model_destroy(m);
            return rc;
        }
    }
    if (s.body[RENDER_INDEX] != NULL) {
        rc = get_render(path, m, s.body[RENDER_INDEX], s.len[RENDER_INDEX]);
        if (rc != NERF_OK) {
            nerf_model_destroy(m);
            return rc;
        }
    }
    if (s.body[BATCH_INDEX] != NULL) {
        rc = get_batch(path, m, s.body[BATCH_INDEX], s.len[BATCH_INDEX]);
        if (rc != NERF_OK) {
            nerf_model_destroy(m);
            return rc;
        }
    }
    /* A file without the section was made before averaging, or without
     * it: it goes on without. */
    m->adam.average_steps = 0.0;
    if (s.body[AVERAGE_INDEX] != NULL) {
        bool oom = false;
        const char *bad = nerf__average_parse(
            s.body[AVERAGE_INDEX], s.len[AVERAGE_INDEX], m, &oom);
        if (bad != NULL) {
            nerf_model_destroy(m);
            return oom ? nerf__error(NERF_ENOMEM, "%s: %s", path, bad)
                       : nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                                     "(%s)", path, bad);
        }
        if (m->averaging) {
            get_floats(s.body[AVERAGE_INDEX] + NERF__AVERAGE_HEAD,
                       m->average, m->n_params);
        }
    }
    if (s.body[SCHEDULE_INDEX] != NULL) {
        const char *bad = nerf__schedule_parse(
            s.body[SCHEDULE_INDEX], s.len[SCHEDULE_INDEX], &m->schedule,
            &m->adam.decay_start);
        if (bad != NULL) {
            nerf_model_destroy(m);
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (%s)",
                               path, bad);
        }
    }
    if (s.data != NULL && !nerf__fingerprint_parse(s.data, s.data_len,
                                                   &m->data)) {
        nerf_model_destroy(m);
        return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the data "
                           "section is too short or holds a value that is "
                           "not a number)", path);
    }
    rc = get_corrections(path, m, &s);
    if (rc != NERF_OK) {
        nerf_model_destroy(m);
        return rc;
    }
    get_floats(s.body[2], m->params, m->n_params);
    m->weights_only = s.body[WEIGHTS_ONLY_INDEX] != NULL;
    if (!m->weights_only) {
        get_floats(s.body[ADAM_M_INDEX], m->adam_m, m->n_params);
        get_floats(s.body[ADAM_V_INDEX], m->adam_v, m->n_params);
    }
    nerf__model_weights_changed(m);
    size_t len = strlen(path) + 1;
    m->source = nerf__alloc(env, len);
    if (m->source == NULL) {
        nerf_model_destroy(m);
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    memcpy(m->source, path, len);
    /* Loaded all the same, for inspection: a diverged run's checkpoint
     * is said to be one here, where it is first seen, and refused by
     * whatever would make something of it (finite.c). */
    nerf__model_warn_nonfinite(m, path);
    *out = m;
    return NERF_OK;
}

int nerf__checkpoint_parse(const nerf__env *env, const char *path,
                           const unsigned char *data, size_t size,
                           nerf_model **out)
{
    *out = NULL;
    ckpt_header hd;
    memset(&hd, 0, sizeof hd);
    unsigned char *payload = NULL;
    int rc = read_header(path, data, size, &hd);
    if (rc == NERF_OK) {
        rc = unpack(env, path, data + HEADER_SIZE, &hd, &payload);
    }
    if (rc == NERF_OK) {
        rc = build_model(env, path, payload, (size_t)hd.payload_size, out);
    }
    nerf__free(env, payload);
    if (rc == NERF_OK) {
        nerf__log(env, NERF_LOG_DEBUG, "%s: loaded checkpoint (format %lu): "
                  "%zu parameters, step %llu", path,
                  (unsigned long)hd.version, (*out)->n_params,
                  (unsigned long long)(*out)->step);
    }
    return rc;
}

NERF_API int nerf_model_load(nerf_model **out, const char *path,
                             const nerf_hooks *hooks)
{
    if (out == NULL || path == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_load: NULL %s",
                           out ? "path" : "out");
    }
    *out = NULL;
    nerf__env env;
    int rc = nerf__env_from_hooks(&env, hooks);
    unsigned char *file = NULL;
    size_t size = 0;
    if (rc == NERF_OK) {
        rc = nerf__file_read(&env, path, MAX_FILE, &file, &size);
    }
    if (rc == NERF_OK) {
        rc = nerf__checkpoint_parse(&env, path, file, size, out);
    }
    nerf__free(&env, file);
    return rc;
}
