/*
 * bf16 layer products through oneDNN's matmul primitive (oneDNN 2.x C API).
 * gemm_bf16.h states what the backend promises; this file is how.
 *
 * Shapes.  oneDNN's fast bf16 matmul (brgemm) needs every dimension fixed
 * when the primitive is created; with a run-time row count it falls back
 * to a slower gemm kernel.  Batches change size all the time (marched
 * samples are packed), so products are cut into pieces of a few fixed
 * sizes, and the primitive of each size is created once and kept:
 *  - forward and input-gradient products go by rows, in pieces of
 *    ROW_BLOCK rows and then powers of two down to 2 rows.  A single last
 *    row runs as a 2-row piece over a padded copy, because oneDNN computes
 *    a 1-row product another way and its rounding would then depend on
 *    where the row fell;
 *  - weight gradients sum over samples, so they go by samples, in pieces
 *    of K_BLOCK and then powers of two down to 1, each added into the
 *    fp32 gradient by a sum post-op.
 * A product of n rows needs at most about log2(ROW_BLOCK) primitives per
 * layer shape, whatever n is.
 *
 * Threads.  Each product is split into one block per libnerf thread
 * (parallel.h), and every block calls oneDNN with OpenMP's thread count
 * set to 1 on its thread, so oneDNN never starts threads of its own.  The
 * primitives are created with that count too (oneDNN fixes a primitive's
 * thread count when it creates it).  They run with a scratchpad the caller
 * passes (user scratchpad mode), which is what makes one primitive safe
 * to run on several threads at once.
 */
#include "gemm_bf16.h"

#include <oneapi/dnnl/dnnl.h>
#include <oneapi/dnnl/dnnl_debug.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bf16.h"
#include "parallel.h"

#if DNNL_CPU_THREADING_RUNTIME == DNNL_RUNTIME_OMP
#include <omp.h>
#define USE_OMP 1
#elif DNNL_CPU_THREADING_RUNTIME == DNNL_RUNTIME_SEQ
#define USE_OMP 0
#else
#error "the bf16 backend needs oneDNN built with the OpenMP or sequential runtime"
#endif

#define ROW_LOG2 10
#define ROW_BLOCK ((size_t)1 << ROW_LOG2)
#define K_LOG2 12
#define K_BLOCK ((size_t)1 << K_LOG2)
#define BUCKETS 64
/* Two widths (floor and ceiling of the split) per weight-gradient call. */
#define WIDTHS 2

/* ---- process-wide: support check and engine ----------------------------- */

static struct {
    pthread_once_t once;
    int ok;
    const char *why;
    dnnl_engine_t engine; /* lives as long as the process, as oneDNN's own
                           * global state does: primitives of models the
                           * application never destroyed point at it */
} global = {.once = PTHREAD_ONCE_INIT};

/* oneDNN fixes a primitive's thread count at creation and uses the
 * calling thread's OpenMP count: make it 1 for the duration of a call,
 * and give the application its own setting back afterwards. */
static int threads_enter(void)
{
#if USE_OMP
    int saved = omp_get_max_threads();
    if (saved != 1) {
        omp_set_num_threads(1);
    }
    return saved;
#else
    return 1;
#endif
}

static void threads_leave(int saved)
{
#if USE_OMP
    if (saved != 1) {
        omp_set_num_threads(saved);
    }
#else
    (void)saved;
#endif
}

enum { F_BIAS = 1, F_RELU = 2, F_SUM = 4 };

/*
 * C[m, n] (+)= A[m, k] B[k, n] (+ bias, ReLU), A and B bf16 with the given
 * element strides, C fp32 rows of ldc.  All int64_t, so the struct has no
 * padding and compares with memcmp.
 */
typedef struct prim_key {
    int64_t m, n, k;
    int64_t sa0, sa1, sb0, sb1, ldc;
    int64_t flags;
} prim_key;

static dnnl_status_t make_pd(const prim_key *key, dnnl_primitive_desc_t *pd,
                             dnnl_memory_desc_t md[4])
{
    const dnnl_dims_t da = {key->m, key->k}, sa = {key->sa0, key->sa1};
    const dnnl_dims_t db = {key->k, key->n}, sb = {key->sb0, key->sb1};
    const dnnl_dims_t dc = {key->m, key->n}, sc = {key->ldc, 1};
    const dnnl_dims_t dbias = {1, key->n};
    dnnl_status_t st = dnnl_memory_desc_init_by_strides(&md[0], 2, da,
                                                        dnnl_bf16, sa);
    if (st == dnnl_success) {
        st = dnnl_memory_desc_init_by_strides(&md[1], 2, db, dnnl_bf16, sb);
    }
    if (st == dnnl_success) {
        st = dnnl_memory_desc_init_by_strides(&md[2], 2, dc, dnnl_f32, sc);
    }
    if (st == dnnl_success) {
        st = dnnl_memory_desc_init_by_tag(&md[3], 2, dbias, dnnl_f32, dnnl_ab);
    }
    dnnl_matmul_desc_t desc;
    if (st == dnnl_success) {
        st = dnnl_matmul_desc_init(&desc, &md[0], &md[1],
                                   (key->flags & F_BIAS) ? &md[3] : NULL,
                                   &md[2]);
    }
    if (st != dnnl_success) {
        return st;
    }
    dnnl_primitive_attr_t attr = NULL;
    dnnl_post_ops_t ops = NULL;
    st = dnnl_primitive_attr_create(&attr);
    if (st == dnnl_success) {
        st = dnnl_primitive_attr_set_scratchpad_mode(attr,
                                                     dnnl_scratchpad_mode_user);
    }
    if (st == dnnl_success) {
        st = dnnl_post_ops_create(&ops);
    }
    /* oneDNN applies the bias before the post-ops, which run in order. */
    if (st == dnnl_success && (key->flags & F_SUM)) {
        st = dnnl_post_ops_append_sum(ops, 1.0f);
    }
    if (st == dnnl_success && (key->flags & F_RELU)) {
        st = dnnl_post_ops_append_eltwise(ops, 1.0f, dnnl_eltwise_relu, 0.0f,
                                          0.0f);
    }
    if (st == dnnl_success) {
        st = dnnl_primitive_attr_set_post_ops(attr, ops);
    }
    if (st == dnnl_success) {
        st = dnnl_primitive_desc_create(pd, &desc, attr, global.engine, NULL);
    }
    dnnl_post_ops_destroy(ops);
    dnnl_primitive_attr_destroy(attr);
    return st;
}

static bool isa_has_bf16(void)
{
    const unsigned need = dnnl_cpu_isa_avx512_core_bf16;
    return ((unsigned)dnnl_get_effective_cpu_isa() & need) == need;
}

/*
 * AMX tiles round a bf16 dot product differently from AVX512-BF16, and
 * oneDNN picks one or the other per product shape (often by the row
 * count), so with AMX a row's result would depend on the size of the
 * piece it fell in, and images on chunk sizes and thread counts.  Capping
 * oneDNN's ISA is process-wide and only possible before its first use:
 * when the caller used oneDNN first and AMX is on, bf16 is refused rather
 * than non-deterministic.
 */
static bool cap_isa(void)
{
    /* oneDNN's call overrides its variables; a cap the user chose stays. */
    const char *chosen = getenv("ONEDNN_MAX_CPU_ISA");
    if (chosen == NULL || chosen[0] == '\0') {
        chosen = getenv("DNNL_MAX_CPU_ISA");
    }
    if ((chosen == NULL || chosen[0] == '\0') &&
        dnnl_set_max_cpu_isa(dnnl_cpu_isa_avx512_core_bf16) == dnnl_success) {
        return true;
    }
    const unsigned amx = dnnl_cpu_isa_avx512_core_amx;
    return ((unsigned)dnnl_get_effective_cpu_isa() & amx) != amx;
}

static void check_support(void)
{
    if (!cap_isa()) {
        global.why = "oneDNN runs AMX kernels (ONEDNN_MAX_CPU_ISA allows "
                     "them, or oneDNN was in use before libnerf), whose "
                     "rounding depends on the product shape; set "
                     "ONEDNN_MAX_CPU_ISA=AVX512_CORE_BF16";
        return;
    }
    /* Without native bf16 oneDNN emulates it, slower than fp32: that is
     * not what anyone asking for bf16 wants. */
    if (!isa_has_bf16()) {
        global.why = "oneDNN reports no AVX512-BF16 on this CPU (or "
                     "DNNL_MAX_CPU_ISA excludes it)";
        return;
    }
    if (dnnl_engine_create(&global.engine, dnnl_cpu, 0) != dnnl_success) {
        global.engine = NULL;
        global.why = "oneDNN could not create a CPU engine";
        return;
    }
    const prim_key key = {32, 32, 32, 32, 1, 1, 32, 32, F_BIAS | F_RELU};
    dnnl_primitive_desc_t pd = NULL;
    dnnl_memory_desc_t md[4];
    int saved = threads_enter();
    dnnl_status_t st = make_pd(&key, &pd, md);
    threads_leave(saved);
    const char *impl = NULL;
    if (st == dnnl_success) {
        st = dnnl_primitive_desc_query(pd, dnnl_query_impl_info_str, 0, &impl);
    }
    if (st != dnnl_success) {
        global.why = "oneDNN cannot create a bf16 matmul on this CPU";
    } else if (impl == NULL || strncmp(impl, "ref", 3) == 0) {
        global.why = "oneDNN has only its reference bf16 matmul on this CPU";
    } else {
        global.ok = 1;
    }
    dnnl_primitive_desc_destroy(pd);
}

int nerf__bf16_supported(const char **why)
{
    pthread_once(&global.once, check_support);
    if (why) {
        *why = global.ok ? NULL : global.why;
    }
    return global.ok;
}

/* ---- rounding ----------------------------------------------------------- */

NERF__BF16_WIDE void nerf__bf16_round(const float *x, size_t n,
                                      uint16_t *out)
{
    for (size_t i = 0; i < n; i++) {
        out[i] = nerf__bf16_from_float(x[i]);
    }
}

typedef struct round_job {
    const nerf__layer_part *parts;
    int n_parts;
    const float *flat;  /* or one flat range */
    uint16_t *out;
    size_t ldo;
} round_job;

static NERF__BF16_WIDE void round_rows(void *ctx, size_t begin, size_t end)
{
    const round_job *j = ctx;
    for (size_t i = begin; i < end; i++) {
        uint16_t *o = j->out + i * j->ldo;
        for (int p = 0; p < j->n_parts; p++) {
            const float *x = j->parts[p].x + i * j->parts[p].ldx;
            const uint32_t in = j->parts[p].in;
            for (uint32_t c = 0; c < in; c++) {
                o[c] = nerf__bf16_from_float(x[c]);
            }
            o += in;
        }
    }
}

/* The parts side by side into out [n, sum of their widths]. */
static void round_parts(const nerf__layer_part *parts, int n_parts, size_t n,
                        uint16_t *out, size_t ldo)
{
    round_job j = {.parts = parts, .n_parts = n_parts, .out = out, .ldo = ldo};
    nerf__parallel_for(n, 2 * ldo, round_rows, &j);
}

static void round_flat(void *ctx, size_t begin, size_t end)
{
    const round_job *j = ctx;
    nerf__bf16_round(j->flat + begin, end - begin, j->out + begin);
}

/* ---- the model's backend ------------------------------------------------ */

typedef struct prim_entry {
    prim_key key;
    dnnl_primitive_t prim;
    dnnl_memory_desc_t md[4]; /* A, B, C, bias */
    dnnl_memory_desc_t scratch_md;
    size_t scratch_size;
    struct prim_entry *next;
} prim_entry;

struct nerf__bf16 {
    nerf__env env;
    const float *params;
    nerf__bf16_region regions[NERF__BF16_MAX_REGIONS];
    size_t base[NERF__BF16_MAX_REGIONS]; /* each region's start in wb */
    int n_regions;
    uint16_t *wb;
    /* gen counts weight changes; synced is the gen wb was rounded at. */
    atomic_uint_fast64_t gen, synced;
    pthread_mutex_t sync_mu;
    pthread_mutex_t cache_mu;
    prim_entry *buckets[BUCKETS];
    size_t n_prims;
};

int nerf__bf16_create(const nerf__env *env, const float *params,
                      const nerf__bf16_region *regions, int n_regions,
                      nerf__bf16 **out)
{
    *out = NULL;
    const char *why;
    if (!nerf__bf16_supported(&why)) {
        return nerf__error(NERF_EINVAL, "bf16 products are not available: %s",
                           why);
    }
    nerf__bf16 *b = nerf__calloc(env, 1, sizeof *b);
    if (b == NULL) {
        return NERF_ENOMEM;
    }
    b->env = *env;
    b->params = params;
    size_t total = 0;
    for (int i = 0; i < n_regions && i < NERF__BF16_MAX_REGIONS; i++) {
        b->regions[i] = regions[i];
        b->base[i] = total;
        total += regions[i].count;
        b->n_regions = i + 1;
    }
    b->wb = nerf__alloc(env, (total ? total : 1) * sizeof(uint16_t));
    if (b->wb == NULL) {
        nerf__free(env, b);
        return NERF_ENOMEM;
    }
    atomic_init(&b->gen, 1);
    atomic_init(&b->synced, 0);
    pthread_mutex_init(&b->sync_mu, NULL);
    pthread_mutex_init(&b->cache_mu, NULL);
    *out = b;
    return NERF_OK;
}

void nerf__bf16_destroy(nerf__bf16 *b)
{
    if (b == NULL) {
        return;
    }
    for (int i = 0; i < BUCKETS; i++) {
        prim_entry *e = b->buckets[i];
        while (e) {
            prim_entry *next = e->next;
            dnnl_primitive_destroy(e->prim);
            nerf__free(&b->env, e);
            e = next;
        }
    }
    pthread_mutex_destroy(&b->sync_mu);
    pthread_mutex_destroy(&b->cache_mu);
    nerf__env env = b->env;
    nerf__free(&env, b->wb);
    nerf__free(&env, b);
}

void nerf__bf16_weights_changed(nerf__bf16 *b)
{
    if (b) {
        atomic_fetch_add_explicit(&b->gen, 1, memory_order_release);
    }
}

size_t nerf__bf16_primitives(nerf__bf16 *b)
{
    pthread_mutex_lock(&b->cache_mu);
    size_t n = b->n_prims;
    pthread_mutex_unlock(&b->cache_mu);
    return n;
}

/* Round the weights again if they changed since the last time.  Threads
 * that find the copy current pay one atomic load. */
static void sync_weights(nerf__bf16 *b)
{
    uint64_t want = atomic_load_explicit(&b->gen, memory_order_acquire);
    if (atomic_load_explicit(&b->synced, memory_order_acquire) == want) {
        return;
    }
    pthread_mutex_lock(&b->sync_mu);
    if (atomic_load_explicit(&b->synced, memory_order_acquire) != want) {
        for (int i = 0; i < b->n_regions; i++) {
            round_job j = {.flat = b->params + b->regions[i].offset,
                           .out = b->wb + b->base[i]};
            nerf__parallel_for(b->regions[i].count, 2, round_flat, &j);
        }
        atomic_store_explicit(&b->synced, want, memory_order_release);
    }
    pthread_mutex_unlock(&b->sync_mu);
}

/* The rounded copy of the weights at w (a pointer into params), or NULL
 * if w is not in a region (a caller's bug). */
static const uint16_t *rounded(const nerf__bf16 *b, const float *w,
                               size_t count)
{
    if (w < b->params) {
        return NULL;
    }
    size_t off = (size_t)(w - b->params);
    for (int i = 0; i < b->n_regions; i++) {
        const nerf__bf16_region *r = &b->regions[i];
        if (off >= r->offset && off - r->offset + count <= r->count) {
            return b->wb + b->base[i] + (off - r->offset);
        }
    }
    return NULL;
}

static size_t key_hash(const prim_key *k)
{
    uint64_t h = 1469598103934665603u;
    const unsigned char *p = (const unsigned char *)k;
    for (size_t i = 0; i < sizeof *k; i++) {
        h = (h ^ p[i]) * 1099511628211u;
    }
    return (size_t)(h % BUCKETS);
}

static int dnnl_failed(dnnl_status_t st, const char *what)
{
    return nerf__error(st == dnnl_out_of_memory ? NERF_ENOMEM : NERF_ERROR,
                       "bf16 products: oneDNN could not %s (%s)", what,
                       dnnl_status2str(st));
}

/* The primitive for key, created on first use.  Entries live as long as
 * the backend, so callers keep the pointer without holding the lock. */
static int get_prim(nerf__bf16 *b, const prim_key *key, prim_entry **out)
{
    size_t h = key_hash(key);
    pthread_mutex_lock(&b->cache_mu);
    for (prim_entry *e = b->buckets[h]; e; e = e->next) {
        if (memcmp(&e->key, key, sizeof *key) == 0) {
            pthread_mutex_unlock(&b->cache_mu);
            *out = e;
            return NERF_OK;
        }
    }
    prim_entry *e = nerf__calloc(&b->env, 1, sizeof *e);
    if (e == NULL) {
        pthread_mutex_unlock(&b->cache_mu);
        return NERF_ENOMEM;
    }
    e->key = *key;
    dnnl_primitive_desc_t pd = NULL;
    int saved = threads_enter();
    dnnl_status_t st = make_pd(key, &pd, e->md);
    if (st == dnnl_success) {
        st = dnnl_primitive_create(&e->prim, pd);
    }
    threads_leave(saved);
    if (st == dnnl_success) {
        const dnnl_memory_desc_t *smd =
            dnnl_primitive_desc_query_md(pd, dnnl_query_scratchpad_md, 0);
        e->scratch_md = *smd;
        e->scratch_size = dnnl_memory_desc_get_size(smd);
    }
    dnnl_primitive_desc_destroy(pd);
    if (st != dnnl_success) {
        pthread_mutex_unlock(&b->cache_mu);
        nerf__free(&b->env, e);
        char what[160];
        snprintf(what, sizeof what, "create a bf16 matmul [%lld x %lld] x "
                 "[%lld x %lld]", (long long)key->m, (long long)key->k,
                 (long long)key->k, (long long)key->n);
        return dnnl_failed(st, what);
    }
    e->next = b->buckets[h];
    b->buckets[h] = e;
    b->n_prims++;
    pthread_mutex_unlock(&b->cache_mu);
    nerf__log(&b->env, NERF_LOG_DEBUG, "bf16: primitive %zu: [%lld x %lld] x "
              "[%lld x %lld], flags %lld", b->n_prims, (long long)key->m,
              (long long)key->k, (long long)key->k, (long long)key->n,
              (long long)key->flags);
    *out = e;
    return NERF_OK;
}

/* ---- the caller's scratch ----------------------------------------------- */

/* What one block of a split product owns while it runs. */
typedef struct slot {
    dnnl_stream_t stream;
    void *block;       /* scratchpad, then the padded row buffers */
    size_t block_size;
} slot;

struct nerf__bf16_scratch {
    nerf__env env;
    uint16_t *a;   /* the left operand, rounded */
    size_t a_cap;
    uint16_t *x;   /* a weight gradient's inputs, rounded */
    size_t x_cap;
    unsigned n_slots;
    slot *slots;
};

void nerf__bf16_scratch_free(nerf__bf16_scratch *s)
{
    if (s == NULL) {
        return;
    }
    nerf__env env = s->env;
    for (unsigned i = 0; i < s->n_slots; i++) {
        if (s->slots[i].stream) {
            dnnl_stream_destroy(s->slots[i].stream);
        }
        nerf__free(&env, s->slots[i].block);
    }
    nerf__free(&env, s->slots);
    nerf__free(&env, s->a);
    nerf__free(&env, s->x);
    nerf__free(&env, s);
}

static int scratch_get(const nerf__layer_ctx *c, nerf__bf16_scratch **out)
{
    nerf__bf16_scratch *s = *c->scratch;
    if (s == NULL) {
        s = nerf__calloc(c->env, 1, sizeof *s);
        if (s == NULL) {
            return NERF_ENOMEM;
        }
        s->env = *c->env;
        s->n_slots = nerf__parallel_threads();
        s->slots = nerf__calloc(c->env, s->n_slots, sizeof *s->slots);
        if (s->slots == NULL) {
            nerf__free(c->env, s);
            return NERF_ENOMEM;
        }
        *c->scratch = s;
    }
    *out = s;
    return NERF_OK;
}

static int grow(const nerf__env *env, uint16_t **buf, size_t *cap,
                size_t rows, size_t cols)
{
    size_t need;
    if (nerf__mul_size(rows, cols, &need) != 0 ||
        nerf__mul_size(need, sizeof(uint16_t), &need) != 0) {
        return nerf__error(NERF_ENOMEM, "bf16 products: %zu x %zu operand "
                           "is too large", rows, cols);
    }
    if (need <= *cap) {
        return NERF_OK;
    }
    uint16_t *p = nerf__alloc(env, need);
    if (p == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(env, *buf);
    *buf = p;
    *cap = need;
    return NERF_OK;
}

/* Streams and per-block memory of at least `size` bytes for every slot. */
static int slots_ready(nerf__bf16_scratch *s, unsigned n, size_t size)
{
    for (unsigned i = 0; i < n; i++) {
        slot *sl = &s->slots[i];
        if (sl->stream == NULL) {
            dnnl_status_t st = dnnl_stream_create(&sl->stream, global.engine,
                                                  dnnl_stream_default_flags);
            if (st != dnnl_success) {
                sl->stream = NULL;
                return dnnl_failed(st, "create a stream");
            }
        }
        if (size > sl->block_size) {
            void *p = nerf__calloc(&s->env, 1, size);
            if (p == NULL) {
                return NERF_ENOMEM;
            }
            nerf__free(&s->env, sl->block);
            sl->block = p;
            sl->block_size = size;
        }
    }
    return NERF_OK;
}

static size_t round_up64(size_t bytes)
{
    return (bytes + 63) & ~(size_t)63;
}

/* ---- running pieces ----------------------------------------------------- */

static dnnl_status_t run_piece(const prim_entry *e, dnnl_stream_t stream,
                               const void *a, const void *bm, void *cm,
                               const float *bias, void *scratchpad)
{
    dnnl_memory_t mem[5] = {NULL, NULL, NULL, NULL, NULL};
    dnnl_exec_arg_t args[5];
    int n = 0;
    /* oneDNN takes non-const handles but only reads sources. */
    void *handles[4] = {(void *)a, (void *)bm, cm, (void *)bias};
    const int arg_ids[4] = {DNNL_ARG_SRC, DNNL_ARG_WEIGHTS, DNNL_ARG_DST,
                            DNNL_ARG_BIAS};
    dnnl_status_t st = dnnl_success;
    for (int i = 0; i < 4 && st == dnnl_success; i++) {
        if (i == 3 && !(e->key.flags & F_BIAS)) {
            break;
        }
        st = dnnl_memory_create(&mem[n], &e->md[i], global.engine, handles[i]);
        if (st == dnnl_success) {
            args[n] = (dnnl_exec_arg_t){arg_ids[i], mem[n]};
            n++;
        }
    }
    if (st == dnnl_success && e->scratch_size) {
        st = dnnl_memory_create(&mem[n], &e->scratch_md, global.engine,
                                scratchpad);
        if (st == dnnl_success) {
            args[n] = (dnnl_exec_arg_t){DNNL_ARG_SCRATCHPAD, mem[n]};
            n++;
        }
    }
    if (st == dnnl_success) {
        st = dnnl_primitive_execute(e->prim, stream, n, args);
    }
    for (int i = 0; i < n; i++) {
        dnnl_memory_destroy(mem[i]);
    }
    return st;
}

/* A row-wise product: C[r, :] = f(A[r, :] B) for r in [0, n). */
typedef struct rows_job {
    nerf__bf16_scratch *s;
    prim_entry *by_log2[ROW_LOG2 + 1]; /* pieces of 2^e rows, e >= 1 */
    size_t n;
    unsigned blocks;
    const uint16_t *a;
    size_t lda;
    const uint16_t *bm;
    float *c;
    size_t ldc;
    const float *bias;
    size_t k, cols;      /* A's columns, C's columns */
    size_t pad_offset;   /* of the padded rows in a slot's block */
    atomic_int status;
} rows_job;

static void block_range(size_t n, unsigned blocks, size_t t, size_t *lo,
                        size_t *hi)
{
    *lo = n * t / blocks;
    *hi = n * (t + 1) / blocks;
}

static void rows_block(void *ctx, size_t t)
{
    rows_job *j = ctx;
    slot *sl = &j->s->slots[t];
    size_t lo, hi;
    block_range(j->n, j->blocks, t, &lo, &hi);
    int saved = threads_enter();
    dnnl_status_t st = dnnl_success;
    size_t r = lo;
    for (int e = ROW_LOG2; e >= 1 && st == dnnl_success; e--) {
        const size_t m = (size_t)1 << e;
        while (hi - r >= m && st == dnnl_success) {
            st = run_piece(j->by_log2[e], sl->stream, j->a + r * j->lda, j->bm,
                           j->c + r * j->ldc, j->bias, sl->block);
            r += m;
            if (e < ROW_LOG2) {
                break; /* below the block size, each size at most once */
            }
        }
    }
    if (r < hi && st == dnnl_success) {
        /* The last row, as row 0 of a 2-row piece; row 1 is zeros. */
        uint16_t *pa = (uint16_t *)((char *)sl->block + j->pad_offset);
        float *pc = (float *)(pa + round_up64(2 * j->lda * sizeof *pa) /
                                       sizeof *pa);
        memcpy(pa, j->a + r * j->lda, j->k * sizeof *pa);
        memset(pa + j->lda, 0, j->k * sizeof *pa);
        st = run_piece(j->by_log2[1], sl->stream, pa, j->bm, pc, j->bias,
                       sl->block);
        if (st == dnnl_success) {
            memcpy(j->c + r * j->ldc, pc, j->cols * sizeof *pc);
        }
    }
    if (st == dnnl_success) {
        st = dnnl_stream_wait(sl->stream);
    }
    threads_leave(saved);
    if (st != dnnl_success) {
        int none = dnnl_success;
        atomic_compare_exchange_strong(&j->status, &none, (int)st);
    }
}

static unsigned blocks_for(const nerf__bf16_scratch *s, size_t units)
{
    unsigned t = s->n_slots;
    return units < t ? (unsigned)(units ? units : 1) : t;
}

/*
 * C[n, cols] = A[n, k] B (+ bias, ReLU per flags), A bf16 rows of lda, B
 * a [k, cols] bf16 matrix of strides sb0, sb1, C fp32 rows of ldc.
 */
static int row_product(nerf__bf16 *b, nerf__bf16_scratch *s, size_t n,
                       size_t k, size_t cols, const uint16_t *a, size_t lda,
                       const uint16_t *bm, size_t sb0, size_t sb1, float *c,
                       size_t ldc, const float *bias, int64_t flags)
{
    rows_job j;
    memset(&j, 0, sizeof j);
    j.s = s;
    j.n = n;
    j.blocks = blocks_for(s, n / 2);
    j.a = a;
    j.lda = lda;
    j.bm = bm;
    j.c = c;
    j.ldc = ldc;
    j.bias = bias;
    j.k = k;
    j.cols = cols;
    atomic_init(&j.status, dnnl_success);
    /* The piece sizes the blocks will use: every block's length in
     * ROW_BLOCKs and powers of two, and 2 for a last odd row. */
    bool need[ROW_LOG2 + 1] = {false};
    for (unsigned t = 0; t < j.blocks; t++) {
        size_t lo, hi;
        block_range(n, j.blocks, t, &lo, &hi);
        size_t len = hi - lo;
        if (len >= ROW_BLOCK) {
            need[ROW_LOG2] = true;
        }
        for (int e = 1; e < ROW_LOG2; e++) {
            need[e] = need[e] || ((len >> e) & 1u);
        }
        need[1] = need[1] || (len & 1u);
    }
    size_t scratch = 0;
    for (int e = 1; e <= ROW_LOG2; e++) {
        if (!need[e]) {
            continue;
        }
        const prim_key key = {(int64_t)1 << e, (int64_t)cols, (int64_t)k,
                              (int64_t)lda, 1, (int64_t)sb0, (int64_t)sb1,
                              (int64_t)ldc, flags};
        int rc = get_prim(b, &key, &j.by_log2[e]);
        if (rc != NERF_OK) {
            return rc;
        }
        if (j.by_log2[e]->scratch_size > scratch) {
            scratch = j.by_log2[e]->scratch_size;
        }
    }
    j.pad_offset = round_up64(scratch);
    size_t block = j.pad_offset + round_up64(2 * lda * sizeof(uint16_t)) +
                   round_up64(2 * ldc * sizeof(float));
    int rc = slots_ready(s, j.blocks, block);
    if (rc != NERF_OK) {
        return rc;
    }
    size_t cost = (n / j.blocks + 1) * k * cols / 16 + 1;
    nerf__parallel_blocks(j.blocks, cost, rows_block, &j);
    int st = atomic_load(&j.status);
    return st == dnnl_success
               ? NERF_OK
               : dnnl_failed((dnnl_status_t)st, "run a bf16 matmul");
}

/* dW[out, in] += dY^T X, cut along dW's longer side into one range per
 * block, each summing over all samples in K pieces, in sample order. */
typedef struct wgrad_job {
    nerf__bf16_scratch *s;
    prim_entry *by[WIDTHS][K_LOG2 + 1];
    size_t narrow;     /* the smaller of the two range widths */
    bool by_rows;      /* ranges of dW rows, else of columns */
    size_t span;       /* out or in: the side that is cut */
    unsigned blocks;
    size_t n;
    const uint16_t *dy; /* [n, out] */
    size_t out;
    const uint16_t *x;  /* [n, in] */
    size_t in;
    float *dw;
    size_t lddw;
    atomic_int status;
} wgrad_job;

static void wgrad_block(void *ctx, size_t t)
{
    wgrad_job *j = ctx;
    slot *sl = &j->s->slots[t];
    size_t lo, hi;
    block_range(j->span, j->blocks, t, &lo, &hi);
    if (hi == lo) {
        return;
    }
    prim_entry *const *by = j->by[hi - lo == j->narrow ? 0 : 1];
    const size_t mo = j->by_rows ? lo : 0, no = j->by_rows ? 0 : lo;
    int saved = threads_enter();
    dnnl_status_t st = dnnl_success;
    size_t r = 0;
    for (int e = K_LOG2; e >= 0 && st == dnnl_success; e--) {
        const size_t m = (size_t)1 << e;
        while (j->n - r >= m && st == dnnl_success) {
            st = run_piece(by[e], sl->stream, j->dy + r * j->out + mo,
                           j->x + r * j->in + no, j->dw + mo * j->lddw + no,
                           NULL, sl->block);
            r += m;
            if (e < K_LOG2) {
                break;
            }
        }
    }
    if (st == dnnl_success) {
        st = dnnl_stream_wait(sl->stream);
    }
    threads_leave(saved);
    if (st != dnnl_success) {
        int none = dnnl_success;
        atomic_compare_exchange_strong(&j->status, &none, (int)st);
    }
}

static int weight_product(nerf__bf16 *b, nerf__bf16_scratch *s, size_t n,
                          size_t out, size_t in, const uint16_t *dy,
                          const uint16_t *x, float *dw, size_t lddw)
{
    wgrad_job j;
    memset(&j, 0, sizeof j);
    j.s = s;
    j.by_rows = out >= in;
    j.span = j.by_rows ? out : in;
    j.blocks = blocks_for(s, j.span);
    j.narrow = j.span / j.blocks;
    j.n = n;
    j.dy = dy;
    j.out = out;
    j.x = x;
    j.in = in;
    j.dw = dw;
    j.lddw = lddw;
    atomic_init(&j.status, dnnl_success);
    size_t scratch = 0;
    for (int w = 0; w < WIDTHS; w++) {
        const size_t width = j.narrow + (size_t)w;
        if (width == 0 || (w == 1 && j.span % j.blocks == 0)) {
            continue;
        }
        const size_t m = j.by_rows ? width : out, cols = j.by_rows ? in : width;
        for (int e = 0; e <= K_LOG2; e++) {
            const size_t k = (size_t)1 << e;
            if (e < K_LOG2 ? !((n >> e) & 1u) : n < K_BLOCK) {
                continue;
            }
            const prim_key key = {(int64_t)m, (int64_t)cols, (int64_t)k,
                                  1, (int64_t)out, (int64_t)in, 1,
                                  (int64_t)lddw, F_SUM};
            int rc = get_prim(b, &key, &j.by[w][e]);
            if (rc != NERF_OK) {
                return rc;
            }
            if (j.by[w][e]->scratch_size > scratch) {
                scratch = j.by[w][e]->scratch_size;
            }
        }
    }
    int rc = slots_ready(s, j.blocks, round_up64(scratch));
    if (rc != NERF_OK) {
        return rc;
    }
    size_t cost = n * (out * in / j.blocks + 1) / 16 + 1;
    nerf__parallel_blocks(j.blocks, cost, wgrad_block, &j);
    int st = atomic_load(&j.status);
    return st == dnnl_success
               ? NERF_OK
               : dnnl_failed((dnnl_status_t)st, "run a bf16 matmul");
}

/* ---- the layer products ------------------------------------------------- */

static size_t parts_width(const nerf__layer_part *parts, int n_parts)
{
    size_t k = 0;
    for (int p = 0; p < n_parts; p++) {
        k += parts[p].in;
    }
    return k;
}

static int weights_for(nerf__bf16 *b, const float *w, size_t rows,
                       size_t ldw, size_t cols, const uint16_t **out)
{
    *out = rows ? rounded(b, w, (rows - 1) * ldw + cols) : NULL;
    if (*out == NULL) {
        return nerf__error(NERF_ERROR, "bf16 products: weights outside the "
                           "model's parameters");
    }
    return NERF_OK;
}

int nerf__bf16_forward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                       const nerf__layer_part *parts, int n_parts,
                       const float *w, size_t ldw, const float *b, int relu,
                       float *y, size_t ldy, uint16_t *kept)
{
    if (n == 0) {
        return NERF_OK;
    }
    nerf__bf16 *be = c->bf16;
    const size_t k = parts_width(parts, n_parts);
    nerf__bf16_scratch *s;
    const uint16_t *wb;
    int rc = scratch_get(c, &s);
    if (rc == NERF_OK && kept == NULL) {
        rc = grow(&s->env, &s->a, &s->a_cap, n, k);
    }
    if (rc == NERF_OK) {
        sync_weights(be);
        rc = weights_for(be, w, out, ldw, k, &wb);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    uint16_t *a = kept ? kept : s->a;
    round_parts(parts, n_parts, n, a, k);
    int64_t flags = (b ? F_BIAS : 0) | (relu ? F_RELU : 0);
    /* Y = X W^T: B = W^T, W [out, ldw] read by columns. */
    return row_product(be, s, n, k, out, a, k, wb, 1, ldw, y, ldy, b, flags);
}

int nerf__bf16_backward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                        const float *dy, size_t lddy, const uint16_t *dyb,
                        const nerf__layer_part *parts, int n_parts,
                        const uint16_t *kept, const float *w, size_t ldw,
                        float *dw, int dx_part, float *dx, size_t lddx)
{
    if (n == 0) {
        return NERF_OK;
    }
    nerf__bf16 *be = c->bf16;
    const size_t k = parts_width(parts, n_parts);
    nerf__bf16_scratch *s;
    int rc = scratch_get(c, &s);
    if (rc == NERF_OK && dyb == NULL) {
        rc = grow(&s->env, &s->a, &s->a_cap, n, out);
    }
    if (rc == NERF_OK && kept == NULL) {
        rc = grow(&s->env, &s->x, &s->x_cap, n, k);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    if (dyb == NULL) {
        const nerf__layer_part d = {dy, lddy, out};
        round_parts(&d, 1, n, s->a, out);
        dyb = s->a;
    }
    if (kept == NULL) {
        round_parts(parts, n_parts, n, s->x, k);
        kept = s->x;
    }
    /* One product serves every part: their columns are adjacent in dW. */
    rc = weight_product(be, s, n, out, k, dyb, kept, dw, ldw);
    if (rc != NERF_OK || dx == NULL) {
        return rc;
    }
    size_t col = 0;
    for (int p = 0; p < dx_part; p++) {
        col += parts[p].in;
    }
    const uint32_t in = parts[dx_part].in;
    const uint16_t *wb;
    sync_weights(be);
    rc = weights_for(be, w + col, out, ldw, in, &wb);
    if (rc != NERF_OK) {
        return rc;
    }
    /* dX = dY W_q: B is W's column block, [out, in] rows of ldw. */
    return row_product(be, s, n, out, in, dyb, out, wb, ldw, 1, dx, lddx,
                       NULL, 0);
}
