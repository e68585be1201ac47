/*
 * nerf_model_save() and nerf_model_load(): libnerf's own checkpoint format.
 * docs/formats.md is the specification; this file follows it.  In short: a
 * 48-byte little-endian header with its own CRC, then a zlib stream whose
 * content is a list of tagged sections (u32 tag, u64 length, bytes), which
 * checkpoint_sections.c lists, writes and reads.
 */
#include <limits.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <zlib.h>

#include "byte_buf.h"
#include "byteorder.h"
#include "checkpoint_sections.h"
#include "deflate_bound.h"
#include "file_io.h"
#include "gemm_onednn.h"
#include "model.h"
#include "occupancy.h"

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
#define SECTION_HEAD NERF__CKPT_SECTION_HEAD
#define N_SECTIONS NERF__CKPT_N_SECTIONS

/* Refuse files beyond 64 GiB before reading them. */
#define MAX_FILE ((uint64_t)1 << 36)

/* The fields of a header, decoded. */
typedef struct ckpt_header {
    uint32_t version, size, flags;
    uint64_t payload_size, packed_size;
    uint32_t packed_crc, payload_crc;
} ckpt_header;

/* ---- saving ------------------------------------------------------------- */

/*
 * Stretches of a payload that zlib is to copy rather than compress:
 * trained weights and moments are noisy floats, which level 1 barely
 * shrinks and spends most of a save's time on (docs/perf-log/
 * 2026-11-29-0.10.5-to-0.10.8.md, "0.10.7"), while the rest (the
 * corrections, mostly zeros, the occupancy grid) shrinks many times.
 * Neighbouring stored sections make one stretch.
 */
#define MAX_STORED N_SECTIONS

typedef struct stored_spans {
    size_t begin[MAX_STORED], end[MAX_STORED];
    int n;
} stored_spans;

static void add_stored(stored_spans *st, size_t begin, size_t end)
{
    if (st->n > 0 && st->end[st->n - 1] == begin) {
        st->end[st->n - 1] = end;
        return;
    }
    st->begin[st->n] = begin;
    st->end[st->n] = end;
    st->n++;
}

/* Each section a file of s has, in the table's order, appended to b. */
static void build_payload(const nerf__ckpt_save *s, nerf__buf *b,
                          stored_spans *st)
{
    st->n = 0;
    for (int i = 0; i < N_SECTIONS && !b->failed; i++) {
        const nerf__ckpt_section *k = &nerf__ckpt_sections[i];
        if (!nerf__ckpt_written(k, s)) {
            continue;
        }
        const size_t head = b->size;
        nerf__buf_grow(b, SECTION_HEAD);
        k->write(b, s);
        if (!b->failed) {
            /* The length is what the body took: nothing sums it apart. */
            nerf__store_le32(b->data + head, k->tag);
            nerf__store_le64(b->data + head + 4, b->size - head - SECTION_HEAD);
            if (k->flags & NERF__CKPT_STORED) {
                add_stored(st, head, b->size);
            }
        }
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
    const nerf__ckpt_save s = {model, weights_only || model->weights_only};
    nerf__buf b = {.env = &model->env};
    /* The float arrays at once: a model of 140 MB would otherwise be
     * copied as it grows, and held twice while it is. */
    const size_t arrays = s.weights_only ? 1 : 3 + (model->averaging ? 1 : 0);
    nerf__buf_reserve(&b, 4 * (arrays * model->n_params + 2 * model->n_table +
                               (model->grid ? model->grid->cells : 0)) +
                              4096);
    stored_spans st;
    build_payload(&s, &b, &st);
    int rc = b.failed ? nerf__error_prefix(NERF_ENOMEM, path)
                      : write_checkpoint(model, path, s.weights_only, b.data,
                                         b.size, &st);
    nerf__free(&model->env, b.data);
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
/* The payload's known sections into v; a required one unknown here refuses
 * the file, an optional one is skipped. */
static int split_sections(const nerf__env *env, const char *path,
                          const unsigned char *p, size_t n, nerf__ckpt_view *v)
{
    memset(v, 0, sizeof *v);
    size_t at = 0;
    while (at < n) {
        if (n - at < SECTION_HEAD) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                               "(section header cut at payload byte %zu)",
                               path, at);
        }
        const uint32_t tag = nerf__load_le32(p + at);
        const uint64_t len = nerf__load_le64(p + at + 4);
        at += SECTION_HEAD;
        if (len > n - at) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint "
                               "(section 0x%08lx runs past the payload)",
                               path, (unsigned long)tag);
        }
        int i = 0;
        while (i < N_SECTIONS && nerf__ckpt_sections[i].tag != tag) {
            i++;
        }
        if (i < N_SECTIONS && v->body[i] != NULL) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (two "
                               "%s sections)", path,
                               nerf__ckpt_sections[i].name);
        }
        if (i < N_SECTIONS) {
            v->body[i] = p + at;
            v->len[i] = len;
        } else if (tag & NERF__CKPT_TAG_REQUIRED) {
            return nerf__error(NERF_EVERSION, "%s: checkpoint has a required "
                               "section 0x%08lx unknown to this libnerf "
                               "(format version %u)", path,
                               (unsigned long)tag, FORMAT_VERSION);
        } else {
            nerf__log(env, NERF_LOG_DEBUG, "%s: skipping checkpoint section "
                      "0x%08lx (%llu bytes)", path, (unsigned long)tag,
                      (unsigned long long)len);
        }
        at += (size_t)len;
    }
    return NERF_OK;
}

/* Which sections a file must have, may not have, and their fixed sizes. */
static int check_presence(const char *path, const nerf__ckpt_view *v)
{
    const bool weights_only = v->body[NERF__CKPT_WEIGHTS_ONLY] != NULL;
    for (int i = 0; i < N_SECTIONS; i++) {
        const nerf__ckpt_section *k = &nerf__ckpt_sections[i];
        const bool has = v->body[i] != NULL;
        const bool excused = weights_only && (k->flags & NERF__CKPT_OPTIMISER);
        if ((k->flags & NERF__CKPT_CORE) && !has && !excused) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (no "
                               "%s section)", path, k->name);
        }
        if (has && excused) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (a "
                               "weights-only file with %s)", path, k->name);
        }
        if (has && (k->flags & NERF__CKPT_FIXED) && v->len[i] != k->size) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (the "
                               "%s section has the wrong size)", path,
                               k->name);
        }
    }
    return NERF_OK;
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

/* The options, and the sizes that follow from them: everything that can
 * be checked before the model is allocated.  The options section comes
 * first in the table and every file has it, so that o starts from it. */
static int read_options(const nerf__env *env, const char *path,
                        const nerf__ckpt_view *v, nerf_model_options *o)
{
    for (int i = 0; i < N_SECTIONS; i++) {
        const nerf__ckpt_section *k = &nerf__ckpt_sections[i];
        if (k->read_options != NULL && v->body[i] != NULL) {
            int rc = k->read_options(path, k, v->body[i], o);
            if (rc != NERF_OK) {
                return rc;
            }
        }
    }
    matmul_here(env, path, o);
    if (nerf__model_check_options(o) != NERF_OK) {
        char why[512];
        snprintf(why, sizeof why, "%s", nerf_last_error());
        return nerf__error(NERF_EFORMAT, "%s: checkpoint holds invalid model "
                           "options (%s)", path, why);
    }
    const uint64_t n = nerf__load_le64(v->body[NERF__CKPT_TRAINING] + 56);
    const uint64_t need = nerf__model_options_param_count(o);
    if (n != need) {
        return nerf__error(NERF_EFORMAT, "%s: checkpoint holds %llu "
                           "parameters but its options need %llu", path,
                           (unsigned long long)n, (unsigned long long)need);
    }
    for (int i = 0; i < N_SECTIONS; i++) {
        const nerf__ckpt_section *k = &nerf__ckpt_sections[i];
        if ((k->flags & NERF__CKPT_PER_PARAM) && v->body[i] != NULL &&
            (v->len[i] / 4 != n || v->len[i] % 4 != 0)) {
            return nerf__error(NERF_EFORMAT, "%s: corrupted checkpoint (%s "
                               "section holds %llu bytes, expected %llu)",
                               path, k->name, (unsigned long long)v->len[i],
                               (unsigned long long)(4 * n));
        }
    }
    return NERF_OK;
}

/* Every section's read, present or not, into the model made of the
 * options. */
static int fill_model(const char *path, nerf_model *m,
                      const nerf__ckpt_view *v)
{
    for (int i = 0; i < N_SECTIONS; i++) {
        const nerf__ckpt_section *k = &nerf__ckpt_sections[i];
        if (k->read != NULL) {
            int rc = k->read(path, m, v->body[i], v->len[i], v);
            if (rc != NERF_OK) {
                return rc;
            }
        }
    }
    nerf__model_weights_changed(m);
    const size_t len = strlen(path) + 1;
    m->source = nerf__alloc(&m->env, len);
    if (m->source == NULL) {
        return nerf__error_prefix(NERF_ENOMEM, path);
    }
    memcpy(m->source, path, len);
    return NERF_OK;
}

static int build_model(const nerf__env *env, const char *path,
                       const unsigned char *payload, size_t size,
                       nerf_model **out)
{
    nerf__ckpt_view v;
    nerf_model_options o;
    nerf_model *m = NULL;
    int rc = split_sections(env, path, payload, size, &v);
    if (rc == NERF_OK) {
        rc = check_presence(path, &v);
    }
    if (rc == NERF_OK) {
        rc = read_options(env, path, &v, &o);
    }
    if (rc == NERF_OK) {
        rc = nerf__model_alloc(&m, &o, env);
        if (rc != NERF_OK) {
            rc = nerf__error_prefix(rc, path);
        }
    }
    if (rc == NERF_OK) {
        rc = fill_model(path, m, &v);
    }
    if (rc != NERF_OK) {
        nerf_model_destroy(m);
        return rc;
    }
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
