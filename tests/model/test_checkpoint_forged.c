/*
 * Checkpoints forged with valid CRCs: the payload is decoded, edited and
 * re-encoded from the layout in docs/formats.md (so these tests also check
 * that document), and the loader must judge the content itself: section
 * framing, required and optional tags, sizes, options and parameters.
 */
#include "../harness.h"
#include "ckpt_fixture.h"
#include "dispatch.h"
#include "small_grid.h"

/* ---- forged payloads with valid CRCs ------------------------------------ */

typedef struct section {
    uint32_t tag;
    size_t len;
    unsigned char *data;
} section;

typedef struct payload {
    section s[16];
    int n;
} payload;

static void split_payload(const unsigned char *file, size_t size, payload *p)
{
    uLongf n = (uLongf)le64(file + 16);
    unsigned char *raw = malloc(n);
    CHECK(uncompress(raw, &n, file + HEADER, size - HEADER) == Z_OK);
    p->n = 0;
    for (size_t at = 0; at + 12 <= n && p->n < 16; p->n++) {
        section *s = &p->s[p->n];
        s->tag = le32(raw + at);
        s->len = (size_t)le64(raw + at + 4);
        s->data = malloc(s->len + 1);
        memcpy(s->data, raw + at + 12, s->len);
        at += 12 + s->len;
    }
    free(raw);
}

/* Write p as a checkpoint with correct sizes and CRCs. */
static void write_payload(const char *path, const payload *p,
                          const char *raw_tail, size_t tail_len)
{
    size_t n = tail_len;
    for (int i = 0; i < p->n; i++) {
        n += 12 + p->s[i].len;
    }
    unsigned char *raw = malloc(n), *at = raw;
    for (int i = 0; i < p->n; i++) {
        put32(at, p->s[i].tag);
        put64(at + 4, p->s[i].len);
        memcpy(at + 12, p->s[i].data, p->s[i].len);
        at += 12 + p->s[i].len;
    }
    if (tail_len > 0) {
        memcpy(at, raw_tail, tail_len);
    }
    /* Stored blocks: a valid stream as any other, and the forged files
     * of the hash-grid models are written in a fraction of the time that
     * compressing their floats takes (most of all under an emulator). */
    uLongf packed_len = compressBound(n);
    unsigned char *file = malloc(HEADER + packed_len);
    CHECK(compress2(file + HEADER, &packed_len, raw, n, Z_NO_COMPRESSION) ==
          Z_OK);
    memcpy(file, "NERFCKPT", 8);
    put32(file + 8, 1);
    put32(file + 12, HEADER);
    put64(file + 16, n);
    put64(file + 24, packed_len);
    put32(file + 32, (uint32_t)crc32(0L, file + HEADER, packed_len));
    put32(file + 36, (uint32_t)crc32(0L, raw, n));
    put32(file + 40, 0);
    fix_header_crc(file);
    spit(path, file, HEADER + packed_len);
    free(file);
    free(raw);
}

static void free_payload(payload *p)
{
    for (int i = 0; i < p->n; i++) {
        free(p->s[i].data);
    }
    p->n = 0;
}

static void add_section(payload *p, uint32_t tag, const void *data, size_t len)
{
    section *s = &p->s[p->n++];
    s->tag = tag;
    s->len = len;
    s->data = malloc(len + 1);
    memcpy(s->data, data, len);
}

/* The little-endian f32 at b. */
static float f32_at(const unsigned char *b)
{
    uint32_t u = le32(b);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Remove the sections tagged tag. */
static void drop_tag(payload *p, uint32_t tag)
{
    for (int i = 0; i < p->n;) {
        if (p->s[i].tag == tag) {
            free(p->s[i].data);
            memmove(&p->s[i], &p->s[i + 1],
                    (size_t)(p->n - i - 1) * sizeof p->s[0]);
            p->n--;
        } else {
            i++;
        }
    }
}

/* The tests of the occupancy grid take it for its file's last section, as
 * a hash-grid model's files had it before the Adam corrections (tag 17,
 * which forged_corrections_sections covers) came after it. */
static void split_grid_payload(const unsigned char *file, size_t size,
                               payload *p)
{
    split_payload(file, size, p);
    drop_tag(p, 17u);
}

/* A section of two u32 words, cut or padded with zeros to len (<= 12). */
static void add_two_words(payload *p, uint32_t tag, uint32_t a, uint32_t b,
                          size_t len)
{
    unsigned char body[12] = {0};
    put32(body, a);
    put32(body + 4, b);
    add_section(p, tag, body, len);
}

TEST(payload_layout_is_as_documented)
{
    size_t size = 0;
    unsigned char *file = good_file(&size);
    payload p;
    split_payload(file, size, &p);
    CHECK_EQ_INT(p.n, 7);
    const uint32_t tags[7] = {0x80000001u, 0x80000002u, 0x80000003u,
                              0x80000004u, 0x80000005u, 0x80000006u,
                              0x00000008u};
    for (int i = 0; i < 7 && i < p.n; i++) {
        CHECK_EQ_INT(p.s[i].tag, tags[i]);
    }
    if (p.n == 7) {
        /* training state (0.2): the weight decay, 0 for this model. */
        CHECK_EQ_INT(p.s[6].len, 8);
        CHECK_EQ_INT(le64(p.s[6].data), 0);
        CHECK_EQ_INT(p.s[5].len, 48);
        CHECK_EQ_INT(le32(p.s[5].data + 1 * 4), 4);   /* sh_degree */
        CHECK_EQ_INT(le32(p.s[5].data + 9 * 4), 1);   /* view_depth */
        CHECK_EQ_INT(p.s[0].len, 52);
        CHECK_EQ_INT(le32(p.s[0].data + 4 * 4), 4);   /* depth */
        CHECK_EQ_INT(le32(p.s[0].data + 5 * 4), 64);  /* width */
        CHECK_EQ_INT(le64(p.s[0].data + 44), 4242);   /* seed */
        CHECK_EQ_INT(p.s[1].len, 64);
        double lr;
        uint64_t bits = le64(p.s[1].data);
        memcpy(&lr, &bits, sizeof lr);
        CHECK(lr == 1.25e-3);
        CHECK_EQ_INT(le64(p.s[1].data + 48), 3);      /* step */
        uint64_t n = le64(p.s[1].data + 56);
        CHECK_EQ_INT(p.s[2].len, 4 * n);
        CHECK_EQ_INT(p.s[4].len, 4 * n);
    }
    free_payload(&p);
    free(file);
}

/* Each forgery: what it does to the sections, and the status it earns. */
static void forge(const char *name, void (*edit)(payload *), int want)
{
    size_t size = 0;
    unsigned char *file = good_file(&size);
    payload p;
    split_payload(file, size, &p);
    edit(&p);
    char path[128];
    path_in(path, sizeof path, "forged.ckpt");
    write_payload(path, &p, NULL, 0);
    if (want == NERF_OK) {
        nerf_model *m = NULL, *ref = trained_model(true);
        CHECK_OK(nerf_model_load(&m, path, NULL));
        if (m && ref) {
            check_same_model(m, ref);
        }
        nerf_model_destroy(m);
        nerf_model_destroy(ref);
    } else {
        expect_load_fails(path, want, name);
    }
    free_payload(&p);
    free(file);
}

static void edit_width(payload *p)
{
    put32(p->s[0].data + 5 * 4, 65);
}

static void edit_depth_zero(payload *p)
{
    put32(p->s[0].data + 4 * 4, 0);
}

static void edit_beta1(payload *p)
{
    double v = 2.0;
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    put64(p->s[1].data + 3 * 8, bits);
}

static void edit_params_count(payload *p)
{
    put64(p->s[1].data + 56, le64(p->s[1].data + 56) + 1);
}

static void edit_add_optional(payload *p)
{
    add_section(p, 0x00000100u, "trainer", 7);
}

static void edit_add_optional_first(payload *p)
{
    memmove(&p->s[1], &p->s[0], (size_t)p->n * sizeof p->s[0]);
    p->n++;
    p->s[0].tag = 0x00000123u;
    p->s[0].len = 0;
    p->s[0].data = malloc(1);
}

static void edit_add_required(payload *p)
{
    add_section(p, 0x80000100u, "needed", 6);
}

static void edit_duplicate(payload *p)
{
    add_section(p, p->s[0].tag, p->s[0].data, p->s[0].len);
}

/* The Adam second moments, a section every version has. */
static void edit_drop_last(payload *p)
{
    free(p->s[4].data);
    p->s[4] = p->s[--p->n];
}

/* A version 1 file: no options2 or training2 section, which read as the
 * reference values of their fields. */
static void edit_drop_options2(payload *p)
{
    for (int k = 0; k < 2; k++) {
        free(p->s[5].data);
        memmove(&p->s[5], &p->s[6], (size_t)(p->n - 6) * sizeof p->s[0]);
        p->n--;
    }
}

static void edit_short_training2(payload *p)
{
    p->s[6].len -= 1;
}

static void edit_weight_decay_negative(payload *p)
{
    put64(p->s[6].data, 0xbff0000000000000u); /* -1.0 */
}

static void edit_short_options2(payload *p)
{
    p->s[5].len -= 4;
}

static void edit_short_array(payload *p)
{
    p->s[3].len -= 4;
}

static void edit_shuffle(payload *p)
{
    section t = p->s[0];
    p->s[0] = p->s[4];
    p->s[4] = t;
}

/* Weights-only files (tag 0x8000000d, empty) have no moment sections. */
static void edit_marker_with_moments(payload *p)
{
    add_section(p, 0x8000000du, "", 0);
}

static void drop_moments(payload *p)
{
    for (int k = 0; k < 2; k++) {
        free(p->s[3].data);
        for (int i = 3; i + 1 < p->n; i++) {
            p->s[i] = p->s[i + 1];
        }
        p->n--;
    }
}

static void edit_marker_not_empty(payload *p)
{
    drop_moments(p);
    add_section(p, 0x8000000du, "x", 1);
}

/* The render settings (tag 12): 64 bytes, of which the last 12 are 0. */
static unsigned char render_section[64];

static void fill_render_section(void)
{
    memset(render_section, 0, sizeof render_section);
    put32(render_section, 32);      /* n_coarse */
    put32(render_section + 4, 64);  /* n_fine */
    put32(render_section + 28, 1);  /* white_background */
    const float t[2] = {2.0f, 6.0f};
    memcpy(render_section + 32, t, sizeof t); /* little-endian hosts */
}

static void edit_render_good(payload *p)
{
    fill_render_section();
    add_section(p, 12u, render_section, sizeof render_section);
}

static void edit_render_short(payload *p)
{
    fill_render_section();
    add_section(p, 12u, render_section, sizeof render_section - 4);
}

static void edit_render_reserved(payload *p)
{
    fill_render_section();
    render_section[60] = 1;
    add_section(p, 12u, render_section, sizeof render_section);
}

static void edit_render_white_2(payload *p)
{
    fill_render_section();
    put32(render_section + 28, 2);
    add_section(p, 12u, render_section, sizeof render_section);
}

/* The schedule (required tag 14): u32 state, u32 0, f64 decay start,
 * f64 budget, f64 rate, u64 fit step, u64 total. */
static unsigned char schedule_section[48];

static void fill_schedule_section(uint32_t state, double start,
                                  uint64_t fit, uint64_t total)
{
    memset(schedule_section, 0, sizeof schedule_section);
    put32(schedule_section, state);
    const double f[3] = {start, 600.0, 25.0};
    memcpy(schedule_section + 8, f, sizeof f); /* little-endian hosts */
    memcpy(schedule_section + 32, &fit, 8);
    memcpy(schedule_section + 40, &total, 8);
}

static void edit_schedule_short(payload *p)
{
    fill_schedule_section(2, 10.0, 10, 100);
    add_section(p, 0x8000000eu, schedule_section, 40);
}

static void edit_schedule_state_3(payload *p)
{
    fill_schedule_section(3, 10.0, 10, 100);
    add_section(p, 0x8000000eu, schedule_section, sizeof schedule_section);
}

static void edit_schedule_fit_past_total(payload *p)
{
    fill_schedule_section(2, 10.0, 200, 100);
    add_section(p, 0x8000000eu, schedule_section, sizeof schedule_section);
}

static void edit_schedule_nan_start(payload *p)
{
    fill_schedule_section(2, NAN, 10, 100);
    add_section(p, 0x8000000eu, schedule_section, sizeof schedule_section);
}

static void edit_schedule_twice(payload *p)
{
    fill_schedule_section(1, 0.0, 0, 0);
    add_section(p, 0x8000000eu, schedule_section, sizeof schedule_section);
    add_section(p, 0x8000000eu, schedule_section, sizeof schedule_section);
}

/* The batch (optional tag 15): u32 rays, u32 samples. */
static uint32_t batch_rays, batch_samples, batch_len = 8;

static void edit_add_batch(payload *p)
{
    add_two_words(p, 15u, batch_rays, batch_samples, batch_len);
}

static void edit_add_two_batches(payload *p)
{
    edit_add_batch(p);
    edit_add_batch(p);
}

TEST(forged_batch_sections)
{
    batch_rays = 4096;
    batch_samples = 1u << 18;
    forge("batch of 4096 rays", edit_add_batch, NERF_OK);
    char path[128];
    path_in(path, sizeof path, "forged.ckpt");
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    uint32_t rays = 0, samples = 0;
    CHECK_OK(nerf_model_training_batch(m, &rays, &samples));
    CHECK_EQ_INT((int)rays, 4096);
    CHECK_EQ_INT((int)samples, 1 << 18);
    CHECK(nerf_model_contents(m) & NERF_MODEL_HAS_BATCH_RECORD);
    nerf_model_destroy(m);
    batch_len = 12;
    forge("batch section of 12 bytes", edit_add_batch, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "batch section") != NULL);
    batch_len = 8;
    batch_rays = 0;
    forge("batch of 0 rays", edit_add_batch, NERF_EFORMAT);
    batch_rays = (1u << 20) + 1;
    forge("batch past the trainer's limit", edit_add_batch, NERF_EFORMAT);
    batch_rays = 64;
    batch_samples = (1u << 26) + 1;
    forge("sample budget past the limit", edit_add_batch, NERF_EFORMAT);
    batch_samples = 0;
    forge("two batch sections", edit_add_two_batches, NERF_EFORMAT);
}

/* The appearance codes (optional tag 19; 0.13.0's tag 18): u32 count,
 * u32 floats a code, then the codes and the two means of their steps
 * (0.13.0: Adam's moments). */
static uint32_t codes_n = 2, codes_floats = 3, codes_bad = 0, codes_tag = 19;
static size_t codes_len_delta = 0;

static void edit_add_codes(payload *p)
{
    unsigned char b[8 + 3 * 4 * 2 * 3 + 4];
    put32(b, codes_n);
    put32(b + 4, codes_floats);
    for (uint32_t i = 0; i < 18; i++) {
        float v = i < 6 ? 0.1f * (float)i : 0.01f; /* codes, m, v */
        if (codes_bad == 1 && i == 2) {
            v = NAN;
        }
        if (codes_bad == 2 && i == 15) {
            v = -1.0f;
        }
        memcpy(b + 8 + 4 * i, &v, 4); /* little-endian hosts */
    }
    add_section(p, codes_tag, b, 8 + 4 * 18 + codes_len_delta);
}

static void edit_add_two_codes(payload *p)
{
    edit_add_codes(p);
    edit_add_codes(p);
}

static void edit_add_codes_of_both_tags(payload *p)
{
    codes_tag = 18;
    edit_add_codes(p);
    codes_tag = 19;
    edit_add_codes(p);
}

/* The codes' state as the model holds it: whether every mean is v. */
static bool code_means_are(const nerf_model *m, float v)
{
    const nerf__appearance *a = &m->appearance;
    for (size_t i = 0; i < (size_t)a->n * NERF__CODE_FLOATS; i++) {
        if (a->mean_grad[i] != v || a->mean_curv[i] != v) {
            return false;
        }
    }
    return a->n > 0;
}

TEST(forged_appearance_sections)
{
    forge("two appearance codes", edit_add_codes, NERF_OK);
    char path[128];
    path_in(path, sizeof path, "forged.ckpt");
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    uint32_t n = 0;
    CHECK_OK(nerf_model_appearance_count(m, &n));
    CHECK_EQ_INT((int)n, 2);
    float c[NERF_APPEARANCE_CODE_FLOATS];
    CHECK_OK(nerf_model_appearance_code(m, NERF_APPEARANCE_OF(1), c));
    CHECK(c[0] == 0.3f && c[2] == 0.5f);
    CHECK_OK(nerf_model_appearance_code(m, NERF_APPEARANCE_NEUTRAL, c));
    CHECK_NEAR(c[0], 0.15, 1e-6);
    CHECK(nerf_model_contents(m) & NERF_MODEL_HAS_APPEARANCE);
    CHECK(code_means_are(m, 0.01f));
    nerf_model_destroy(m);
    /* 0.13.0's section: the codes, and Adam's moments left behind. */
    codes_tag = 18;
    codes_bad = 2;
    forge("0.13.0's appearance codes", edit_add_codes, NERF_OK);
    codes_bad = 0;
    codes_tag = 19;
    m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    CHECK_OK(nerf_model_appearance_code(m, NERF_APPEARANCE_OF(1), c));
    CHECK(c[0] == 0.3f && c[2] == 0.5f);
    CHECK(code_means_are(m, 0.0f));
    nerf_model_destroy(m);
    codes_len_delta = 4;
    forge("appearance codes 4 bytes long", edit_add_codes, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "appearance codes section") != NULL);
    codes_len_delta = 0;
    codes_n = 0;
    forge("no appearance codes", edit_add_codes, NERF_EFORMAT);
    codes_n = 2;
    codes_floats = 12;
    forge("codes of 12 floats", edit_add_codes, NERF_EFORMAT);
    codes_floats = 3;
    codes_bad = 1;
    forge("a NaN code", edit_add_codes, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "appearance code 0") != NULL);
    codes_bad = 2;
    forge("a negative mean curvature", edit_add_codes, NERF_EFORMAT);
    codes_bad = 0;
    forge("two appearance sections", edit_add_two_codes, NERF_EFORMAT);
    forge("codes under tags 18 and 19", edit_add_codes_of_both_tags,
          NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "twice") != NULL);
}

/* The average (optional tag 16): f64 steps, u32 running, u32 reserved,
 * then the running average's n floats. */
static double average_steps;
static uint32_t average_running, average_reserved;
static size_t average_floats; /* floats to append */
static int average_copies = 1;

static void edit_add_average(payload *p)
{
    const uint64_t n = le64(p->s[1].data + 56);
    if (average_floats == SIZE_MAX) {
        average_floats = (size_t)n;
    }
    size_t len = 16 + 4 * average_floats;
    unsigned char *body = calloc(1, len);
    uint64_t bits;
    memcpy(&bits, &average_steps, sizeof bits);
    put32(body, (uint32_t)bits);
    put32(body + 4, (uint32_t)(bits >> 32));
    put32(body + 8, average_running);
    put32(body + 12, average_reserved);
    for (size_t i = 0; i < average_floats; i++) {
        const float f = 0.5f + (float)i;
        uint32_t w;
        memcpy(&w, &f, sizeof w);
        put32(body + 16 + 4 * i, w);
    }
    for (int c = 0; c < average_copies; c++) {
        add_section(p, 16u, body, len);
    }
    free(body);
}

static void forge_average(const char *name, double steps, uint32_t running,
                          size_t floats, int want)
{
    average_steps = steps;
    average_running = running;
    average_floats = floats;
    forge(name, edit_add_average, want);
}

TEST(forged_average_sections)
{
    forge_average("average over 50 steps", 50.0, 0, 0, NERF_OK);
    char path[128];
    path_in(path, sizeof path, "forged.ckpt");
    nerf_model *m = NULL;
    double k = -1.0;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    CHECK_OK(nerf_model_get_param(m, NERF_PARAM_AVERAGE_STEPS, &k));
    CHECK(k == 50.0);
    CHECK(m && !m->averaging);
    nerf_model_destroy(m);
    /* A running average comes back as it was saved. */
    forge_average("running average", 50.0, 1, SIZE_MAX, NERF_OK);
    m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    CHECK(m && m->averaging && m->average != NULL);
    if (m && m->average) {
        CHECK(m->average[0] == 0.5f && m->average[3] == 3.5f);
    }
    nerf_model_destroy(m);
    forge_average("running flag without the average", 50.0, 1, 0,
                  NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "average section") != NULL);
    forge_average("an average not running", 50.0, 0, SIZE_MAX, NERF_EFORMAT);
    forge_average("running flag 2", 50.0, 2, 0, NERF_EFORMAT);
    forge_average("negative steps", -1.0, 0, 0, NERF_EFORMAT);
    forge_average("NaN steps", NAN, 0, 0, NERF_EFORMAT);
    forge_average("steps past 10^15", 2e15, 0, 0, NERF_EFORMAT);
    average_reserved = 1;
    forge_average("reserved field set", 50.0, 0, 0, NERF_EFORMAT);
    average_reserved = 0;
    average_copies = 2;
    forge_average("two average sections", 50.0, 0, 0, NERF_EFORMAT);
    average_copies = 1;
}

TEST(forged_schedule_sections)
{
    forge("schedule cut short", edit_schedule_short, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "schedule") != NULL);
    forge("schedule state 3", edit_schedule_state_3, NERF_EFORMAT);
    forge("schedule fit past its total", edit_schedule_fit_past_total,
          NERF_EFORMAT);
    forge("schedule NaN start", edit_schedule_nan_start, NERF_EFORMAT);
    forge("two schedules", edit_schedule_twice, NERF_EFORMAT);
}

TEST(forged_weights_only_and_render_sections)
{
    forge("weights-only marker with moments", edit_marker_with_moments,
          NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "weights-only") != NULL);
    forge("weights-only marker not empty", edit_marker_not_empty,
          NERF_EFORMAT);
    forge("no moments, no marker", drop_moments, NERF_EFORMAT);
    forge("render settings", edit_render_good, NERF_OK);
    forge("render settings cut short", edit_render_short, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "render settings") != NULL);
    forge("render settings reserved 1", edit_render_reserved, NERF_EFORMAT);
    forge("render settings white 2", edit_render_white_2, NERF_EFORMAT);
}

TEST(forged_payloads)
{
    forge("width changed", edit_width, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "parameters") != NULL);
    forge("depth 0", edit_depth_zero, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "depth") != NULL);
    forge("beta1 2.0", edit_beta1, NERF_EFORMAT);
    forge("n_params + 1", edit_params_count, NERF_EFORMAT);
    forge("unknown required section", edit_add_required, NERF_EVERSION);
    forge("duplicate options", edit_duplicate, NERF_EFORMAT);
    forge("no adam_v", edit_drop_last, NERF_EFORMAT);
    forge("short adam_m", edit_short_array, NERF_EFORMAT);
    forge("short options2", edit_short_options2, NERF_EFORMAT);
    forge("version 1, no options2", edit_drop_options2, NERF_OK);
    forge("short training2", edit_short_training2, NERF_EFORMAT);
    forge("negative weight decay", edit_weight_decay_negative, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "106") != NULL);
    forge("unknown optional section", edit_add_optional, NERF_OK);
    forge("unknown optional section first", edit_add_optional_first, NERF_OK);
    forge("sections reordered", edit_shuffle, NERF_OK);
}

TEST(forged_section_framing)
{
    size_t size = 0;
    unsigned char *file = good_file(&size);
    payload p;
    split_payload(file, size, &p);
    char path[128];
    path_in(path, sizeof path, "framing.ckpt");
    /* A section header cut short, then a length running past the end. */
    write_payload(path, &p, "\1\0\0\0\7", 5);
    expect_load_fails(path, NERF_EFORMAT, "cut section header");
    unsigned char tail[12];
    put32(tail, 0x00000100u);
    put64(tail + 4, UINT64_MAX - 3);
    write_payload(path, &p, (const char *)tail, sizeof tail);
    expect_load_fails(path, NERF_EFORMAT, "section past the end");
    free_payload(&p);
    free(file);
}

/* ---- the occupancy grid of hash-grid models ---------------------------- */

static int ball_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    (void)ctx;
    for (size_t i = 0; i < n; i++) {
        const float *p = xyz + 3 * i;
        float r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        sigma[i] = r2 < 0.25f ? 40.0f : 0.1f * r2;
    }
    return 0;
}

/* A small hash-grid model whose grid has been updated twice. */
static nerf_model *grid_model(void)
{
    nerf_model_options o;
    small_grid_options(&o);
    o.seed = 77;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m) {
        CHECK(m->grid != NULL && m->grid->res == 128);
        CHECK_OK(nerf__occupancy_update(m->grid, ball_density, NULL,
                                        m->grid->cells));
        CHECK_OK(nerf__occupancy_update(m->grid, ball_density, NULL, 1000));
        /* Without averaging, the grid is its file's last section, as the
         * tests below take it (forged_average_sections covers that
         * section). */
        CHECK_OK(nerf_model_set_param(m, NERF_PARAM_AVERAGE_STEPS, 0.0));
    }
    return m;
}

static void forge_grid(const char *name, void (*edit)(payload *), int want,
                       bool fresh)
{
    char path[128];
    path_in(path, sizeof path, "grid.ckpt");
    nerf_model *ref = grid_model();
    CHECK_OK(nerf_model_save(ref, path));
    size_t size = 0;
    unsigned char *file = fx_slurp(path, &size);
    payload p;
    split_grid_payload(file, size, &p);
    if (edit) {
        edit(&p);
    }
    write_payload(path, &p, NULL, 0);
    nerf_model *m = NULL;
    if (want != NERF_OK) {
        expect_load_fails(path, want, name);
    } else {
        CHECK_OK(nerf_model_load(&m, path, NULL));
    }
    if (m && fresh) {
        /* A file without the grid: the model with a fresh one. */
        CHECK(m->grid->updates == 0 && m->grid->occupied == m->grid->cells);
        nerf__occupancy_reset(ref->grid);
    }
    if (m) {
        check_same_model(m, ref);
    }
    nerf_model_destroy(m);
    nerf_model_destroy(ref);
    free_payload(&p);
    free(file);
}

static void edit_drop_grid(payload *p)
{
    free(p->s[--p->n].data);
}

static void edit_grid_resolution(payload *p)
{
    put32(p->s[7].data, 64);
}

static void edit_grid_short(payload *p)
{
    p->s[7].len -= 4;
}

static void edit_grid_negative(payload *p)
{
    put32(p->s[7].data + 16 + 4 * 1000, 0xbf800000u); /* -1.0f */
}

static void edit_grid_nan(payload *p)
{
    put32(p->s[7].data + 16 + 4 * 5, 0x7fc00000u);
}

TEST(occupancy_grid_section)
{
    char path[128];
    path_in(path, sizeof path, "grid.ckpt");
    nerf_model *m = grid_model();
    CHECK_OK(nerf_model_save(m, path));
    size_t size = 0;
    unsigned char *file = fx_slurp(path, &size);
    payload p;
    split_grid_payload(file, size, &p);
    /* Optional tag 7, last: u32 resolution, u32 0, u64 updates, then the
     * EMA of every cell as f32, x fastest. */
    CHECK_EQ_INT(p.n, 8);
    if (p.n == 8 && m) {
        const nerf__occupancy *g = m->grid;
        /* Before it, training2 with the hash-grid default decay. */
        double wd;
        uint64_t wd_bits = le64(p.s[6].data);
        memcpy(&wd, &wd_bits, sizeof wd);
        CHECK(wd == 1e-6);
        CHECK_EQ_INT(p.s[7].tag, 0x00000007u);
        CHECK_EQ_INT(p.s[7].len, 16 + 4 * 128 * 128 * 128);
        CHECK_EQ_INT(le32(p.s[7].data), 128);
        CHECK_EQ_INT(le32(p.s[7].data + 4), 0);
        CHECK_EQ_INT(le64(p.s[7].data + 8), 2);
        const size_t cell = 70 + 128 * (64 + 128 * 60);
        const float v = f32_at(p.s[7].data + 16 + 4 * cell);
        CHECK(v == g->ema[cell] && v > 30.0f);
    }
    free_payload(&p);
    free(file);
    nerf_model *back = NULL;
    CHECK_OK(nerf_model_load(&back, path, NULL));
    if (back && m) {
        check_same_model(back, m);
    }
    nerf_model_destroy(back);
    /* A frequency-encoding model has no grid and saves none. */
    nerf_model *tiny = trained_model(true);
    CHECK(tiny && tiny->grid == NULL);
    CHECK_OK(nerf_model_save(tiny, path));
    file = fx_slurp(path, &size);
    split_payload(file, size, &p);
    CHECK_EQ_INT(p.n, 7);
    /* ... and refuses one forged into its file. */
    if (m) {
        size_t gsize = 0;
        char gpath[128];
        path_in(gpath, sizeof gpath, "grid2.ckpt");
        CHECK_OK(nerf_model_save(m, gpath));
        unsigned char *gfile = fx_slurp(gpath, &gsize);
        payload gp;
        split_grid_payload(gfile, gsize, &gp);
        if (gp.n == 8) {
            add_section(&p, gp.s[7].tag, gp.s[7].data, gp.s[7].len);
            write_payload(path, &p, NULL, 0);
            expect_load_fails(path, NERF_EFORMAT, "grid of a tiny model");
        }
        free_payload(&gp);
        free(gfile);
    }
    free_payload(&p);
    free(file);
    nerf_model_destroy(tiny);
    nerf_model_destroy(m);

    forge_grid("no grid section", edit_drop_grid, NERF_OK, true);
    forge_grid("grid of resolution 64", edit_grid_resolution, NERF_EFORMAT,
               false);
    forge_grid("short grid", edit_grid_short, NERF_EFORMAT, false);
    forge_grid("negative EMA", edit_grid_negative, NERF_EFORMAT, false);
    CHECK(strstr(nerf_last_error(), "occupancy grid cell 1000") != NULL);
    forge_grid("NaN EMA", edit_grid_nan, NERF_EFORMAT, false);
    /* A file from before weight decay resumes without it. */
    nerf_model *old = NULL;
    path_in(path, sizeof path, "grid.ckpt");
    m = grid_model();
    CHECK_OK(nerf_model_save(m, path));
    file = fx_slurp(path, &size);
    split_grid_payload(file, size, &p);
    free(p.s[6].data);
    p.s[6] = p.s[7];
    p.n--;
    write_payload(path, &p, NULL, 0);
    CHECK_OK(nerf_model_load(&old, path, NULL));
    double wd = 1.0;
    CHECK_OK(nerf_model_get_param(old, NERF_PARAM_WEIGHT_DECAY, &wd));
    CHECK(wd == 0.0);
    nerf_model_destroy(old);
    nerf_model_destroy(m);
    free_payload(&p);
    free(file);
    forge_grid("sections as saved", NULL, NERF_OK, false);
}

/*
 * A hash-grid model's Adam corrections: optional tag 17, last, t f32
 * beta1^k then t f32 beta2^k for its t table parameters, k each one's
 * count of updates.  Without it a file with
 * moments resumes correcting by the step (a file from before 0.10); a
 * wrong size, a value outside 0 to 1, corrections for a model without a
 * table, or in a weights-only file are refused.
 */
static void save_corrected(const char *path, payload *p,
                           unsigned char **file)
{
    nerf_model *m = grid_model();
    if (m == NULL) {
        p->n = 0;
        *file = NULL;
        return;
    }
    for (int step = 0; step < 3; step++) {
        nerf__model_zero_grad(m);
        for (size_t i = 0; i <= (size_t)step; i++) {
            m->grads[m->nets[0].pos_params + 5 * i] = 0.25f;
        }
        CHECK_OK(nerf__model_adam_step(m));
    }
    CHECK_OK(nerf_model_save(m, path));
    nerf_model_destroy(m);
    size_t size = 0;
    *file = fx_slurp(path, &size);
    split_payload(*file, size, p);
}

static void load_corrected(const char *path, const payload *p, int want,
                           const char *what)
{
    write_payload(path, p, NULL, 0);
    if (want != NERF_OK) {
        expect_load_fails(path, want, what);
        return;
    }
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    nerf_model_destroy(m);
}

TEST(forged_corrections_sections)
{
    char path[128];
    path_in(path, sizeof path, "corrections.ckpt");
    payload p;
    unsigned char *file = NULL;
    save_corrected(path, &p, &file);
    section *c = p.n > 0 ? &p.s[p.n - 1] : NULL;
    CHECK(c && c->tag == 17u);
    if (c == NULL || c->tag != 17u) {
        free_payload(&p);
        free(file);
        return;
    }
    /* Parameters 0, 5 and 10 were touched by 3, 2 and 1 of the steps. */
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    CHECK(m && m->corrected && c->len == 8 * m->n_table);
    CHECK(nerf_model_contents(m) & NERF_MODEL_HAS_ADAM_CORRECTIONS);
    const size_t t = m ? m->n_table : 0;
    if (m && c->len == 8 * t) {
        for (int i = 0; i < 3; i++) {
            const double k = 3 - i;
            CHECK_NEAR(f32_at(c->data + 20 * i), pow(0.9, k), 1e-6);
            CHECK_NEAR(f32_at(c->data + 4 * t + 20 * i), pow(0.99, k), 1e-6);
            CHECK(m->adam_r[5 * i] == f32_at(c->data + 20 * i));
        }
        CHECK(m->adam_r[1] == 1.0f && m->adam_r[t + 1] == 1.0f);
    }
    nerf_model_destroy(m);

    /* Without the section: corrected by the step, as it was trained. */
    section kept = *c;
    p.n--;
    write_payload(path, &p, NULL, 0);
    m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    CHECK(m && !m->corrected);
    CHECK(!(nerf_model_contents(m) & NERF_MODEL_HAS_ADAM_CORRECTIONS));
    nerf_model_destroy(m);

    p.s[p.n++] = kept;
    c = &p.s[p.n - 1];
    c->len -= 4;
    load_corrected(path, &p, NERF_EFORMAT, "corrections cut short");
    CHECK(strstr(nerf_last_error(), "Adam corrections") != NULL);
    c->len += 4;
    const uint32_t bad[3] = {0xbf800000u /* -1 */, 0x3f800001u /* 1+ */,
                             0x7fc00000u /* NaN */};
    for (int i = 0; i < 3; i++) {
        const uint32_t was = le32(c->data + 8);
        put32(c->data + 8, bad[i]);
        load_corrected(path, &p, NERF_EFORMAT, "a correction out of range");
        CHECK(strstr(nerf_last_error(), "Adam correction 2 ") != NULL);
        put32(c->data + 8, was);
    }
    load_corrected(path, &p, NERF_OK, "corrections as saved");
    add_section(&p, kept.tag, kept.data, kept.len);
    load_corrected(path, &p, NERF_EFORMAT, "two corrections sections");
    free(p.s[--p.n].data);

    /* A weights-only file keeps no optimiser state. */
    drop_tag(&p, 0x80000004u);
    drop_tag(&p, 0x80000005u);
    add_section(&p, 0x8000000Du, "", 0);
    load_corrected(path, &p, NERF_EFORMAT,
                   "weights-only file with corrections");
    CHECK(strstr(nerf_last_error(), "weights-only") != NULL);

    /* A frequency-encoding model has no table to correct. */
    size_t size = 0;
    unsigned char *tiny_file = good_file(&size);
    payload tiny;
    split_payload(tiny_file, size, &tiny);
    add_section(&tiny, kept.tag, kept.data, 8);
    load_corrected(path, &tiny, NERF_EFORMAT, "corrections for a tiny model");
    free_payload(&tiny);
    free(tiny_file);
    free_payload(&p);
    free(file);
}

/*
 * nerf_model_options.matmul travels in an optional section of its own
 * (tag 9: u32 matmul, u32 reserved), written for oneDNN models only, so
 * that readers that predate it load such a file computing in fp32 (readers
 * of 0.2 to 0.6 know the section but not the value 2, FP32_ONEDNN, and
 * refuse it as unknown).  A bf16
 * checkpoint loads as bf16 where bf16 products are available, and as fp32,
 * with a warning, where they are not (test_checkpoint_forged_no_bf16 runs
 * this file with oneDNN's ISA capped below AVX512-BF16).  The options2
 * slot that held reserved1 stays reserved.
 */
static uint32_t matmul_value, matmul_reserved;
static size_t matmul_len;

static void edit_add_matmul(payload *p)
{
    add_two_words(p, 0x00000009u, matmul_value, matmul_reserved, matmul_len);
}

static void edit_options2_reserved(payload *p)
{
    put32(p->s[5].data + 11 * 4, 1);
}

static char warning[2048];

/* Every warning, one a line: NERF_FP32_PRODUCTS=onednn where oneDNN has
 * no fp32 products adds one of its own to the loader's. */
static void keep_warning(int level, const char *msg, void *user)
{
    (void)user;
    const size_t at = strlen(warning);
    if (level == NERF_LOG_WARN && at < sizeof warning) {
        snprintf(warning + at, sizeof warning - at, "%s\n", msg);
    }
}

/* Load path, the warnings logged on the way kept in `warning`. */
static nerf_model *load_keeping_warnings(const char *path)
{
    nerf_hooks h;
    NERF_HOOKS_INIT(&h);
    h.log_cb = keep_warning;
    h.log_level = NERF_LOG_WARN;
    warning[0] = '\0';
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_load(&m, path, &h));
    return m;
}

/* A file of the good model with a matmul section of `kind` loads with
 * that kind where it is available, else as fp32 with a warning. */
static void load_matmul_section(uint32_t kind)
{
    size_t size = 0;
    unsigned char *file = good_file(&size);
    payload p;
    split_payload(file, size, &p);
    matmul_value = kind;
    matmul_reserved = 0;
    matmul_len = 8;
    edit_add_matmul(&p);
    char path[128];
    path_in(path, sizeof path, kind == NERF_MATMUL_BF16 ? "bf16.ckpt"
                                                        : "onednn.ckpt");
    write_payload(path, &p, NULL, 0);
    nerf_model *ref = trained_model(true);
    nerf_model *m = load_keeping_warnings(path);
    if (m && ref) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        CHECK_OK(nerf_model_get_options(m, &o));
        CHECK(memcmp(m->params, ref->params, m->n_params * sizeof(float)) == 0);
        if (nerf_matmul_supported((int)kind)) {
            CHECK_EQ_INT(o.matmul, kind);
            CHECK(m->onednn != NULL);
            CHECK(warning[0] == '\0');
        } else {
            /* An fp32 model, which NERF_FP32_PRODUCTS=onednn sends
             * through oneDNN's fp32 products where oneDNN has them. */
            CHECK_EQ_INT(o.matmul, NERF_MATMUL_FP32);
            CHECK((m->onednn != NULL) ==
                  (nerf__fp32_onednn_override() &&
                   nerf_matmul_supported(NERF_MATMUL_FP32_ONEDNN)));
            CHECK(strstr(warning, path) != NULL);
            CHECK(strstr(warning, "fp32") != NULL);
            printf("  loaded as fp32: %s", warning);
        }
    }
    nerf_model_destroy(m);
    nerf_model_destroy(ref);
    free_payload(&p);
    free(file);
}

TEST(matmul_section)
{
    /* As saved: present for bf16 models only, as documented. */
    if (nerf_matmul_supported(NERF_MATMUL_BF16)) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        nerf_model_options_preset(&o, NERF_PRESET_TINY);
        o.matmul = NERF_MATMUL_BF16;
        nerf_model *b = NULL;
        char path[128];
        path_in(path, sizeof path, "saved-bf16.ckpt");
        CHECK_OK(nerf_model_create(&b, &o));
        CHECK_OK(nerf_model_save(b, path));
        nerf_model_destroy(b);
        size_t size = 0;
        unsigned char *file = fx_slurp(path, &size);
        payload p;
        split_payload(file, size, &p);
        CHECK_EQ_INT(p.n, 8);
        if (p.n == 8) {
            /* After training2, the last section. */
            CHECK_EQ_INT(p.s[6].tag, 0x00000008u);
            CHECK_EQ_INT(p.s[7].tag, 0x00000009u);
            CHECK_EQ_INT(p.s[7].len, 8);
            CHECK_EQ_INT(le32(p.s[7].data), NERF_MATMUL_BF16);
            CHECK_EQ_INT(le32(p.s[5].data + 11 * 4), 0);
        }
        free_payload(&p);
        free(file);
    }

    const uint32_t kinds[2] = {NERF_MATMUL_BF16, NERF_MATMUL_FP32_ONEDNN};
    for (int k = 0; k < 2; k++) {
        load_matmul_section(kinds[k]);
    }

    matmul_value = NERF_MATMUL_FP32; /* allowed, though never written */
    forge("matmul section, fp32", edit_add_matmul, NERF_OK);
    matmul_value = 3;
    forge("matmul 3", edit_add_matmul, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "matmul") != NULL);
    matmul_value = NERF_MATMUL_BF16;
    matmul_reserved = 1;
    forge("matmul reserved 1", edit_add_matmul, NERF_EFORMAT);
    matmul_reserved = 0;
    matmul_len = 12;
    forge("matmul section of 12 bytes", edit_add_matmul, NERF_EFORMAT);
    matmul_len = 8;
    forge("options2 reserved 1", edit_options2_reserved, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "reserved") != NULL);
}


/* ---- the data section: what the model was trained on -------------------- */

static unsigned char data_body[64];
static size_t data_len = 48;

static void edit_add_data(payload *p)
{
    add_section(p, 0x0000000Bu, data_body, data_len);
}

static void edit_add_two_data(payload *p)
{
    add_section(p, 0x0000000Bu, data_body, data_len);
    add_section(p, 0x0000000Bu, data_body, data_len);
}

static const nerf__fingerprint some_data = {
    true, 100, 400, 300, 800, 600, 2, 1, {0.25f, 0.5f, 0.75f}, 0.0f, 1.0f};

static void check_same_data(const nerf__fingerprint *a,
                            const nerf__fingerprint *b)
{
    CHECK(a->known == b->known);
    CHECK_EQ_INT(a->count, b->count);
    CHECK_EQ_INT(a->width, b->width);
    CHECK_EQ_INT(a->height, b->height);
    CHECK_EQ_INT(a->src_width, b->src_width);
    CHECK_EQ_INT(a->src_height, b->src_height);
    CHECK_EQ_INT(a->kind, b->kind);
    CHECK_EQ_INT(a->flags, b->flags);
    CHECK(memcmp(a->mean_rgb, b->mean_rgb, sizeof a->mean_rgb) == 0);
    CHECK(a->near_bound == b->near_bound && a->far_bound == b->far_bound);
}

TEST(data_section)
{
    /* A model without a record (never trained by a trainer, or from an
     * older file) has no section, and loads without one. */
    size_t size = 0;
    unsigned char *file = good_file(&size);
    payload p;
    split_payload(file, size, &p);
    for (int i = 0; i < p.n; i++) {
        CHECK(p.s[i].tag != 0x0000000Bu);
    }
    free_payload(&p);
    free(file);
    char path[128];
    path_in(path, sizeof path, "good.ckpt");
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    CHECK(m && !m->data.known);
    nerf_model_destroy(m);

    /* With a record: the last section, laid out as documented, and read
     * back as it was. */
    m = trained_model(true);
    m->data = some_data;
    path_in(path, sizeof path, "data.ckpt");
    CHECK_OK(nerf_model_save(m, path));
    nerf_model_destroy(m);
    file = fx_slurp(path, &size);
    split_payload(file, size, &p);
    const section *d = &p.s[p.n - 1];
    CHECK_EQ_INT(d->tag, 0x0000000Bu);
    CHECK_EQ_INT(d->len, 48);
    if (d->tag == 0x0000000Bu && d->len == 48) {
        const uint32_t u[7] = {100, 400, 300, 800, 600, 2, 1};
        for (int i = 0; i < 7; i++) {
            CHECK_EQ_INT(le32(d->data + 4 * i), u[i]);
        }
        const float x[5] = {0.25f, 0.5f, 0.75f, 0.0f, 1.0f};
        for (int i = 0; i < 5; i++) {
            uint32_t bits;
            memcpy(&bits, &x[i], 4);
            CHECK_EQ_INT(le32(d->data + 28 + 4 * i), bits);
        }
        memcpy(data_body, d->data, 48);
    }
    free_payload(&p);
    free(file);
    m = NULL;
    CHECK_OK(nerf_model_load(&m, path, NULL));
    if (m) {
        check_same_data(&m->data, &some_data);
    }
    nerf_model_destroy(m);

    /* A later writer may append fields: they are skipped. */
    data_len = 52;
    forge("data section of 52 bytes", edit_add_data, NERF_OK);
    data_len = 40;
    forge("data section of 40 bytes", edit_add_data, NERF_EFORMAT);
    CHECK(strstr(nerf_last_error(), "data section") != NULL);
    data_len = 48;
    forge("two data sections", edit_add_two_data, NERF_EFORMAT);
    put32(data_body + 28, 0x7fc00000u); /* a NaN mean colour */
    forge("data section with a NaN", edit_add_data, NERF_EFORMAT);
}

/* ---- weights that are not finite: a run that diverged ------------------- */

/* The good file with value at the parameters idx[0..n). */
static void forge_weights(const char *path, const size_t *idx, int n,
                          float value)
{
    size_t size = 0;
    unsigned char *file = good_file(&size);
    payload p;
    split_payload(file, size, &p);
    CHECK_EQ_INT(p.s[2].tag, 0x80000003u);
    for (int k = 0; k < n; k++) {
        memcpy(p.s[2].data + 4 * idx[k], &value, sizeof value);
    }
    write_payload(path, &p, NULL, 0);
    free_payload(&p);
    free(file);
}

static void check_mentions(const char *text, const char *part,
                           const char *what)
{
    if (strstr(text, part) == NULL) {
        FAILF("%s: '%s' lacks '%s'", what, text, part);
    }
}

/* Such a checkpoint loads, for inspection, saying at load what it is and
 * where the first such weight is; nothing else takes it. */
TEST(nonfinite_weights_load_for_inspection)
{
    nerf_model *ref = trained_model(true);
    if (ref == NULL) {
        return;
    }
    const nerf__network *coarse = &ref->nets[0], *fine = &ref->nets[1];
    const size_t in1 = coarse->trunk[1].in;
    struct {
        size_t idx[2];
        int n;
        float value;
        const char *where;
    } cases[] = {
        {{coarse->trunk[1].w + 3 * in1 + 5}, 1, NAN,
         "1 of %zu weights are NaN or infinite, the first in the coarse "
         "network's trunk layer 1 weights [row 3, column 5]"},
        {{fine->rgb.b + 2, fine->view[0].w}, 2, INFINITY,
         "2 of %zu weights are NaN or infinite, the first in the fine "
         "network's colour layer 0 weights [row 0, column 0]"},
        {{fine->rgb.b + 2}, 1, -INFINITY,
         "the first in the fine network's rgb layer bias [2]"},
        {{coarse->head.b + 1}, 1, NAN,
         "the first in the coarse network's density head bias [1]"},
    };
    char path[128], out[128], where[256];
    path_in(path, sizeof path, "diverged.ckpt");
    path_in(out, sizeof out, "diverged-copy.ckpt");
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        forge_weights(path, cases[c].idx, cases[c].n, cases[c].value);
        snprintf(where, sizeof where, cases[c].where, ref->n_params);
        nerf_model *m = load_keeping_warnings(path);
        if (m == NULL) {
            continue;
        }
        check_mentions(warning, path, "the load's warning");
        check_mentions(warning, where, "the load's warning");
        check_mentions(warning, "diverged", "the load's warning");
        CHECK(nerf_model_contents(m) & NERF_MODEL_HAS_NONFINITE_WEIGHTS);
        /* Inspection: a query runs, whatever it gives. */
        float rgb[3 * 37], sigma[37];
        query(m, NERF_NETWORK_COARSE, rgb, sigma);
        /* Nothing is made of it, and nothing written. */
        CHECK_EQ_INT(nerf_model_save(m, out), NERF_EINVAL);
        check_mentions(nerf_last_error(), out, "nerf_model_save");
        check_mentions(nerf_last_error(), where, "nerf_model_save");
        CHECK_EQ_INT(nerf_model_export(m, out), NERF_EINVAL);
        CHECK(access(out, F_OK) != 0);
        nerf_renderer *r = NULL;
        CHECK_EQ_INT(nerf_renderer_create(&r, m, NULL, NULL), NERF_EINVAL);
        CHECK(r == NULL);
        check_mentions(nerf_last_error(), path, "nerf_renderer_create");
        check_mentions(nerf_last_error(), "not finite",
                       "nerf_renderer_create");
        nerf_mesh *mesh = NULL;
        CHECK_EQ_INT(nerf_mesh_extract(&mesh, m, NULL), NERF_EINVAL);
        check_mentions(nerf_last_error(), path, "nerf_mesh_extract");
        nerf_model_destroy(m);
    }
    /* A good file still says nothing and has finite weights. */
    size_t size = 0;
    unsigned char *file = good_file(&size);
    spit(path, file, size);
    free(file);
    nerf_model *m = load_keeping_warnings(path);
    /* (NERF_FP32_PRODUCTS=onednn, where oneDNN has no fp32 products, may
     * warn of its own.) */
    CHECK(strstr(warning, "NaN or infinite") == NULL &&
          strstr(warning, "diverged") == NULL);
    CHECK(!(nerf_model_contents(m) & NERF_MODEL_HAS_NONFINITE_WEIGHTS));
    nerf_model_destroy(m);
    nerf_model_destroy(ref);
}

/* In a hash-grid model the first such weight may lie in a level of the
 * hash table; the answer follows the weights as they change. */
TEST(nonfinite_weights_in_a_hash_table)
{
    nerf_model_options o;
    small_grid_options(&o);
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    if (m == NULL) {
        return;
    }
    const nerf__hashgrid *hg = &m->nets[0].pos_enc.u.hash;
    CHECK(!(nerf_model_contents(m) & NERF_MODEL_HAS_NONFINITE_WEIGHTS));
    const size_t i = m->nets[0].pos_params + hg->offset[1] + 7;
    const float was = m->params[i];
    m->params[i] = NAN;
    nerf__model_weights_changed(m);
    CHECK(nerf_model_contents(m) & NERF_MODEL_HAS_NONFINITE_WEIGHTS);
    char text[320], want[128];
    nerf__model_nonfinite_text(m, text, sizeof text);
    snprintf(want, sizeof want, "the coarse network's hash table, level 1 "
             "[entry %zu of the table]", hg->offset[1] + 7);
    check_mentions(text, want, "a hash table's weight");
    m->params[i] = was;
    nerf__model_weights_changed(m);
    CHECK(!(nerf_model_contents(m) & NERF_MODEL_HAS_NONFINITE_WEIGHTS));
    nerf_model_destroy(m);
}

int main(void)
{
    make_tmpdir();
    RUN(payload_layout_is_as_documented);
    RUN(forged_payloads);
    RUN(forged_weights_only_and_render_sections);
    RUN(forged_average_sections);
    RUN(forged_schedule_sections);
    RUN(forged_batch_sections);
    RUN(forged_appearance_sections);
    RUN(forged_section_framing);
    RUN(occupancy_grid_section);
    RUN(forged_corrections_sections);
    RUN(matmul_section);
    RUN(data_section);
    RUN(nonfinite_weights_load_for_inspection);
    RUN(nonfinite_weights_in_a_hash_table);
    remove_tree(tmpdir);
    HARNESS_EXIT();
}
