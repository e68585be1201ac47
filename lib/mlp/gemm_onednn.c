/*
 * Layer products through oneDNN's matmul primitive (oneDNN 2.x C API), in
 * bf16 or fp32.  gemm_onednn.h states what the backend promises; this
 * file is how.
 *
 * Shapes.  oneDNN's fast matmul (brgemm) needs every dimension fixed when
 * the primitive is created; with a run-time row count it falls back to a
 * slower gemm kernel.  Batches change size all the time (marched samples
 * are packed), so products are cut into pieces of a few fixed sizes, and
 * the primitive of each size is created once and kept:
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
 * Operands.  bf16 products read a rounded copy of their inputs, built with
 * the parts of a concatenated input side by side, so one product serves a
 * layer.  fp32 products read the inputs where they are, one product per
 * part: the first part's writes the output, the others add to it (a sum
 * post-op), and the last applies the bias and the ReLU.
 *
 * Threads.  Each product is split into one block per libnerf thread
 * (parallel.h), and every block calls oneDNN with OpenMP's thread count
 * set to 1 on its thread, so oneDNN never starts threads of its own.  The
 * primitives are created with that count too (oneDNN fixes a primitive's
 * thread count when it creates it).  They run with a scratchpad the caller
 * passes (user scratchpad mode), which is what makes one primitive safe
 * to run on several threads at once.
 */
#include "gemm_onednn.h"

#include <oneapi/dnnl/dnnl.h>
#include <oneapi/dnnl/dnnl_debug.h>
#include <pthread.h>
#include <signal.h>
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
#error "libnerf needs oneDNN built with the OpenMP or sequential runtime"
#endif

#define ROW_LOG2 10
#define ROW_BLOCK ((size_t)1 << ROW_LOG2)
#define K_LOG2 12
#define K_BLOCK ((size_t)1 << K_LOG2)
#define BUCKETS 64
/* Two widths (floor and ceiling of the split) per weight-gradient call. */
#define WIDTHS 2

/* ---- process-wide: support check and engine ----------------------------- */

enum { KIND_BF16, KIND_F32, KINDS };

static struct {
    pthread_once_t once;
    int ok[KINDS];
    const char *why[KINDS];
    dnnl_engine_t engine; /* lives as long as the process, as oneDNN's own
                           * global state does: primitives of models the
                           * application never destroyed point at it */
} global = {.once = PTHREAD_ONCE_INIT};

/* What a thread changes about itself while it calls oneDNN, to give back
 * afterwards. */
typedef struct thread_state {
    int omp_threads;
    sigset_t signals;
} thread_state;

/*
 * oneDNN fixes a primitive's thread count at creation and uses the
 * calling thread's OpenMP count: make it 1 for the duration of a call.
 *
 * And hold back the signals a handler could catch: the generated gemm
 * kernels of oneDNN 2.x (jit_avx512_common_gemm_f32, which some fp32
 * products get) point the stack pointer into a heap buffer while they
 * run, so a signal handled on the thread then writes its frame over the
 * heap (oneDNN issue 4845, fixed in 2026).  nerf-train's Ctrl-C corrupted
 * the heap about one time in ten that way.  A signal held back is handled
 * by another thread of the process, or here once the call is over.
 * Faults are left alone: a fault inside a kernel is not a frame to save.
 */
static void threads_enter(thread_state *ts)
{
    sigset_t all;
    sigfillset(&all);
    const int faults[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL};
    for (size_t i = 0; i < sizeof faults / sizeof faults[0]; i++) {
        sigdelset(&all, faults[i]);
    }
    pthread_sigmask(SIG_BLOCK, &all, &ts->signals);
#if USE_OMP
    ts->omp_threads = omp_get_max_threads();
    if (ts->omp_threads != 1) {
        omp_set_num_threads(1);
    }
#else
    ts->omp_threads = 1;
#endif
}

static void threads_leave(const thread_state *ts)
{
#if USE_OMP
    if (ts->omp_threads != 1) {
        omp_set_num_threads(ts->omp_threads);
    }
#endif
    pthread_sigmask(SIG_SETMASK, &ts->signals, NULL);
}

enum { F_BIAS = 1, F_RELU = 2, F_SUM = 4 };

/*
 * C[m, n] (+)= A[m, k] B[k, n] (+ bias, ReLU), A and B of type dt with the
 * given element strides, C fp32 rows of ldc.  All int64_t, so the struct
 * has no padding and compares with memcmp.
 */
typedef struct prim_key {
    int64_t m, n, k;
    int64_t sa0, sa1, sb0, sb1, ldc;
    int64_t flags;
    int64_t dt; /* dnnl_data_type_t */
} prim_key;

static dnnl_status_t make_pd(const prim_key *key, dnnl_primitive_desc_t *pd,
                             dnnl_memory_desc_t md[4])
{
    const dnnl_dims_t da = {key->m, key->k}, sa = {key->sa0, key->sa1};
    const dnnl_dims_t db = {key->k, key->n}, sb = {key->sb0, key->sb1};
    const dnnl_dims_t dc = {key->m, key->n}, sc = {key->ldc, 1};
    const dnnl_dims_t dbias = {1, key->n};
    const dnnl_data_type_t dt = (dnnl_data_type_t)key->dt;
    dnnl_status_t st = dnnl_memory_desc_init_by_strides(&md[0], 2, da, dt,
                                                        sa);
    if (st == dnnl_success) {
        st = dnnl_memory_desc_init_by_strides(&md[1], 2, db, dt, sb);
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

/* Whether oneDNN makes an optimised (not reference) matmul of type dt,
 * and if `brgemm_only`, one of its brgemm kernels; NULL if so, else why
 * not (`cannot`, `ref_only` or `no_brgemm`). */
static const char *matmul_made(dnnl_data_type_t dt, const char *cannot,
                               const char *ref_only, bool brgemm_only,
                               const char *no_brgemm)
{
    const prim_key key = {32, 32, 32, 32, 1, 1, 32, 32, F_BIAS | F_RELU, dt};
    dnnl_primitive_desc_t pd = NULL;
    dnnl_memory_desc_t md[4];
    thread_state ts;
    threads_enter(&ts);
    dnnl_status_t st = make_pd(&key, &pd, md);
    threads_leave(&ts);
    const char *impl = NULL;
    if (st == dnnl_success) {
        st = dnnl_primitive_desc_query(pd, dnnl_query_impl_info_str, 0, &impl);
    }
    const char *why = NULL;
    if (st != dnnl_success) {
        why = cannot;
    } else if (impl == NULL || strncmp(impl, "ref", 3) == 0) {
        why = ref_only;
    } else if (brgemm_only && strncmp(impl, "brg", 3) != 0) {
        why = no_brgemm;
    }
    dnnl_primitive_desc_destroy(pd);
    return why;
}

static void check_support(void)
{
    /* Before anything else: the cap only takes before oneDNN's first use. */
    const bool capped = cap_isa();
    if (dnnl_engine_create(&global.engine, dnnl_cpu, 0) != dnnl_success) {
        global.engine = NULL;
        global.why[KIND_BF16] = global.why[KIND_F32] =
            "oneDNN could not create a CPU engine";
        return;
    }
    /* AMX has no fp32 products: the cap does not concern them.  Only the
     * brgemm kernels (AVX-512 in oneDNN 2.x) compute a row the same way
     * whatever the row count; the gemm fallback orders its sums by it,
     * which would make images depend on chunk sizes and thread counts. */
    global.why[KIND_F32] = matmul_made(
        dnnl_f32, "oneDNN cannot create an fp32 matmul",
        "oneDNN has only its reference fp32 matmul on this CPU", true,
        "oneDNN has no brgemm fp32 matmul on this CPU (it needs AVX-512, "
        "or DNNL_MAX_CPU_ISA excludes it)");
    if (!capped) {
        global.why[KIND_BF16] =
            "oneDNN runs AMX kernels (ONEDNN_MAX_CPU_ISA allows them, or "
            "oneDNN was in use before libnerf), whose rounding depends on "
            "the product shape; set ONEDNN_MAX_CPU_ISA=AVX512_CORE_BF16";
    } else if (!isa_has_bf16()) {
        /* Without native bf16 oneDNN emulates it, slower than fp32: that
         * is not what anyone asking for bf16 wants. */
        global.why[KIND_BF16] = "oneDNN reports no AVX512-BF16 on this CPU "
                                "(or DNNL_MAX_CPU_ISA excludes it)";
    } else {
        global.why[KIND_BF16] = matmul_made(
            dnnl_bf16, "oneDNN cannot create a bf16 matmul on this CPU",
            "oneDNN has only its reference bf16 matmul on this CPU", false,
            NULL);
    }
    for (int k = 0; k < KINDS; k++) {
        global.ok[k] = global.why[k] == NULL;
    }
}

static int kind_of(uint32_t matmul)
{
    return matmul == NERF_MATMUL_BF16 ? KIND_BF16
           : matmul == NERF_MATMUL_FP32_ONEDNN ? KIND_F32
                                               : -1;
}

int nerf__onednn_supported(uint32_t matmul, const char **why)
{
    const int k = kind_of(matmul);
    if (k < 0) {
        if (why) {
            *why = "not a oneDNN kind of products";
        }
        return 0;
    }
    pthread_once(&global.once, check_support);
    if (why) {
        *why = global.ok[k] ? NULL : global.why[k];
    }
    return global.ok[k];
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

struct nerf__onednn {
    nerf__env env;
    bool bf16;            /* rounds its operands; else fp32 in place */
    dnnl_data_type_t dt;  /* of the operands */
    size_t esize;         /* their size in bytes */
    const char *name;     /* for messages */
    const float *params;
    nerf__onednn_region regions[NERF__ONEDNN_MAX_REGIONS];
    size_t base[NERF__ONEDNN_MAX_REGIONS]; /* each region's start in wb */
    int n_regions;
    uint16_t *wb; /* bf16: the rounded weights */
    /* gen counts weight changes; synced is the gen wb was rounded at. */
    atomic_uint_fast64_t gen, synced;
    pthread_mutex_t sync_mu;
    pthread_mutex_t cache_mu;
    prim_entry *buckets[BUCKETS];
    size_t n_prims;
    size_t n_not_brgemm; /* of n_prims: see nerf__onednn_rows_alone() */
};

int nerf__onednn_create(const nerf__env *env, uint32_t matmul,
                        const float *params,
                        const nerf__onednn_region *regions, int n_regions,
                        nerf__onednn **out)
{
    *out = NULL;
    const char *why;
    const bool bf16 = matmul == NERF_MATMUL_BF16;
    const char *name = bf16 ? "bf16 products" : "oneDNN fp32 products";
    if (!nerf__onednn_supported(matmul, &why)) {
        return nerf__error(NERF_EINVAL, "%s are not available: %s", name,
                           why);
    }
    nerf__onednn *b = nerf__calloc(env, 1, sizeof *b);
    if (b == NULL) {
        return NERF_ENOMEM;
    }
    b->env = *env;
    b->bf16 = bf16;
    b->dt = bf16 ? dnnl_bf16 : dnnl_f32;
    b->esize = bf16 ? sizeof(uint16_t) : sizeof(float);
    b->name = name;
    b->params = params;
    size_t total = 0;
    for (int i = 0; i < n_regions && i < NERF__ONEDNN_MAX_REGIONS; i++) {
        b->regions[i] = regions[i];
        b->base[i] = total;
        total += regions[i].count;
        b->n_regions = i + 1;
    }
    if (bf16) {
        b->wb = nerf__alloc(env, (total ? total : 1) * sizeof(uint16_t));
    }
    if (bf16 && b->wb == NULL) {
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

void nerf__onednn_destroy(nerf__onednn *b)
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

int nerf__onednn_rounds(const nerf__onednn *b)
{
    return b != NULL && b->bf16;
}

void nerf__onednn_weights_changed(nerf__onednn *b)
{
    if (b) {
        atomic_fetch_add_explicit(&b->gen, 1, memory_order_release);
    }
}

size_t nerf__onednn_primitives(nerf__onednn *b)
{
    pthread_mutex_lock(&b->cache_mu);
    size_t n = b->n_prims;
    pthread_mutex_unlock(&b->cache_mu);
    return n;
}

int nerf__onednn_rows_alone(nerf__onednn *b)
{
    pthread_mutex_lock(&b->cache_mu);
    int alone = b->n_not_brgemm == 0;
    pthread_mutex_unlock(&b->cache_mu);
    return alone;
}

/* Round the weights again if they changed since the last time.  Threads
 * that find the copy current pay one atomic load. */
static void sync_weights(nerf__onednn *b)
{
    if (!b->bf16) {
        return;
    }
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

/* The weights at w (a pointer into params) as the products read them:
 * their rounded copy for bf16, or NULL if w is not in a region (a
 * caller's bug). */
static const void *operand_weights(const nerf__onednn *b, const float *w,
                                   size_t count)
{
    if (w < b->params) {
        return NULL;
    }
    size_t off = (size_t)(w - b->params);
    for (int i = 0; i < b->n_regions; i++) {
        const nerf__onednn_region *r = &b->regions[i];
        if (off >= r->offset && off - r->offset + count <= r->count) {
            return b->bf16 ? (const void *)(b->wb + b->base[i] +
                                            (off - r->offset))
                           : (const void *)w;
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

static int dnnl_failed(const nerf__onednn *b, dnnl_status_t st,
                       const char *what)
{
    return nerf__error(st == dnnl_out_of_memory ? NERF_ENOMEM : NERF_ERROR,
                       "%s: oneDNN could not %s (%s)", b->name, what,
                       dnnl_status2str(st));
}

/* The primitive for key, created on first use.  Entries live as long as
 * the backend, so callers keep the pointer without holding the lock. */
static int get_prim(nerf__onednn *b, const prim_key *key, prim_entry **out)
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
    thread_state ts;
    threads_enter(&ts);
    dnnl_status_t st = make_pd(key, &pd, e->md);
    if (st == dnnl_success) {
        st = dnnl_primitive_create(&e->prim, pd);
    }
    threads_leave(&ts);
    const char *impl = NULL;
    if (st == dnnl_success) {
        const dnnl_memory_desc_t *smd =
            dnnl_primitive_desc_query_md(pd, dnnl_query_scratchpad_md, 0);
        e->scratch_md = *smd;
        e->scratch_size = dnnl_memory_desc_get_size(smd);
        if (dnnl_primitive_desc_query(pd, dnnl_query_impl_info_str, 0,
                                      &impl) != dnnl_success) {
            impl = NULL;
        }
        b->n_not_brgemm += impl == NULL || strncmp(impl, "brg", 3) != 0;
    }
    dnnl_primitive_desc_destroy(pd);
    if (st != dnnl_success) {
        pthread_mutex_unlock(&b->cache_mu);
        nerf__free(&b->env, e);
        char what[160];
        snprintf(what, sizeof what, "create a matmul [%lld x %lld] x "
                 "[%lld x %lld]", (long long)key->m, (long long)key->k,
                 (long long)key->k, (long long)key->n);
        return dnnl_failed(b, st, what);
    }
    e->next = b->buckets[h];
    b->buckets[h] = e;
    b->n_prims++;
    pthread_mutex_unlock(&b->cache_mu);
    nerf__log(&b->env, NERF_LOG_DEBUG, "%s: primitive %zu: [%lld x %lld] x "
              "[%lld x %lld], flags %lld, %s", b->name, b->n_prims,
              (long long)key->m,
              (long long)key->k, (long long)key->k, (long long)key->n,
              (long long)key->flags, impl ? impl : "(implementation unknown)");
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

struct nerf__onednn_scratch {
    nerf__env env;
    /* Untyped so that one grow() serves them all. */
    void *a;       /* bf16: the left operand, rounded */
    size_t a_cap;
    void *x;       /* bf16: a weight gradient's inputs, rounded */
    size_t x_cap;
    void *w;       /* fp32: a block of weights made dense */
    size_t w_cap;
    unsigned n_slots;
    slot *slots;
};

void nerf__onednn_scratch_free(nerf__onednn_scratch *s)
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
    nerf__free(&env, s->w);
    nerf__free(&env, s);
}

static int scratch_get(const nerf__layer_ctx *c, nerf__onednn_scratch **out)
{
    nerf__onednn_scratch *s = *c->scratch;
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

/* *buf holds at least rows x cols elements of esize bytes. */
static int grow(const nerf__env *env, void **buf, size_t *cap, size_t rows,
                size_t cols, size_t esize)
{
    size_t need;
    if (nerf__mul_size(rows, cols, &need) != 0 ||
        nerf__mul_size(need, esize, &need) != 0) {
        return nerf__error(NERF_ENOMEM, "oneDNN products: %zu x %zu operand "
                           "is too large", rows, cols);
    }
    if (need <= *cap) {
        return NERF_OK;
    }
    void *p = nerf__alloc(env, need);
    if (p == NULL) {
        return NERF_ENOMEM;
    }
    nerf__free(env, *buf);
    *buf = p;
    *cap = need;
    return NERF_OK;
}

/* Streams and per-block memory of at least `size` bytes for every slot. */
static int slots_ready(const nerf__onednn *b, nerf__onednn_scratch *s,
                       unsigned n, size_t size)
{
    for (unsigned i = 0; i < n; i++) {
        slot *sl = &s->slots[i];
        if (sl->stream == NULL) {
            dnnl_status_t st = dnnl_stream_create(&sl->stream, global.engine,
                                                  dnnl_stream_default_flags);
            if (st != dnnl_success) {
                sl->stream = NULL;
                return dnnl_failed(b, st, "create a stream");
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

/* The end of a block's pieces: wait for them, give back the thread's
 * OpenMP setting and signals, and keep the first failure of any block in
 * *status. */
static void block_done(slot *sl, dnnl_status_t st, const thread_state *ts,
                       atomic_int *status)
{
    if (st == dnnl_success) {
        st = dnnl_stream_wait(sl->stream);
    }
    threads_leave(ts);
    if (st != dnnl_success) {
        int none = dnnl_success;
        atomic_compare_exchange_strong(status, &none, (int)st);
    }
}

/* A row-wise product: C[r, :] = f(A[r, :] B) for r in [0, n). */
typedef struct rows_job {
    nerf__onednn_scratch *s;
    prim_entry *by_log2[ROW_LOG2 + 1]; /* pieces of 2^e rows, e >= 1 */
    size_t n;
    unsigned blocks;
    const char *a;       /* elements of esize bytes */
    size_t lda;          /* above k: pieces copy their rows dense */
    size_t dense_offset; /* of that copy in a slot's block */
    const void *bm;
    float *c;
    size_t ldc;
    const float *bias;
    size_t esize;
    size_t k, cols;      /* A's columns, C's columns */
    bool sum;            /* C is added to, not written */
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
    thread_state ts;
    threads_enter(&ts);
    dnnl_status_t st = dnnl_success;
    size_t r = lo;
    for (int e = ROW_LOG2; e >= 1 && st == dnnl_success; e--) {
        const size_t m = (size_t)1 << e;
        while (hi - r >= m && st == dnnl_success) {
            const char *a = j->a + r * j->lda * j->esize;
            if (j->lda != j->k) {
                char *d = (char *)sl->block + j->dense_offset;
                for (size_t i = 0; i < m; i++) {
                    memcpy(d + i * j->k * j->esize,
                           a + i * j->lda * j->esize, j->k * j->esize);
                }
                a = d;
            }
            st = run_piece(j->by_log2[e], sl->stream, a, j->bm,
                           j->c + r * j->ldc, j->bias, sl->block);
            r += m;
            if (e < ROW_LOG2) {
                break; /* below the block size, each size at most once */
            }
        }
    }
    if (r < hi && st == dnnl_success) {
        /* The last row, as row 0 of a 2-row piece; row 1 is zeros. */
        char *pa = (char *)sl->block + j->pad_offset;
        float *pc = (float *)(pa + round_up64(2 * j->k * j->esize));
        memcpy(pa, j->a + r * j->lda * j->esize, j->k * j->esize);
        memset(pa + j->k * j->esize, 0, j->k * j->esize);
        if (j->sum) {
            memcpy(pc, j->c + r * j->ldc, j->cols * sizeof *pc);
        }
        st = run_piece(j->by_log2[1], sl->stream, pa, j->bm, pc, j->bias,
                       sl->block);
        if (st == dnnl_success) {
            memcpy(j->c + r * j->ldc, pc, j->cols * sizeof *pc);
        }
    }
    block_done(sl, st, &ts, &j->status);
}

static unsigned blocks_for(const nerf__onednn_scratch *s, size_t units)
{
    unsigned t = s->n_slots;
    return units < t ? (unsigned)(units ? units : 1) : t;
}

/*
 * C[n, cols] = A[n, k] B (+ bias, ReLU, sum into C per flags), A rows of
 * lda, B a [k, cols] matrix of strides sb0, sb1 (both of the backend's
 * operand type), C fp32 rows of ldc.  Rows of A wider than k (a part of a
 * wider matrix) are copied dense piece by piece, for the reason
 * dense_block() gives.
 */
static int row_product(nerf__onednn *b, nerf__onednn_scratch *s, size_t n,
                       size_t k, size_t cols, const void *a, size_t lda,
                       const void *bm, size_t sb0, size_t sb1, float *c,
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
    j.esize = b->esize;
    j.k = k;
    j.cols = cols;
    j.sum = (flags & F_SUM) != 0;
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
                              (int64_t)k, 1, (int64_t)sb0, (int64_t)sb1,
                              (int64_t)ldc, flags, (int64_t)b->dt};
        int rc = get_prim(b, &key, &j.by_log2[e]);
        if (rc != NERF_OK) {
            return rc;
        }
        if (j.by_log2[e]->scratch_size > scratch) {
            scratch = j.by_log2[e]->scratch_size;
        }
    }
    j.pad_offset = round_up64(scratch);
    j.dense_offset = j.pad_offset + round_up64(2 * k * b->esize) +
                     round_up64(2 * ldc * sizeof(float));
    size_t block = j.dense_offset +
                   (lda != k ? round_up64(ROW_BLOCK * k * b->esize) : 0);
    int rc = slots_ready(b, s, j.blocks, block);
    if (rc != NERF_OK) {
        return rc;
    }
    size_t cost = (n / j.blocks + 1) * k * cols / 16 + 1;
    nerf__parallel_blocks(j.blocks, cost, rows_block, &j);
    int st = atomic_load(&j.status);
    return st == dnnl_success
               ? NERF_OK
               : dnnl_failed(b, (dnnl_status_t)st, "run a matmul");
}

/* dW[out, in] += dY^T X, cut along dW's longer side into one range per
 * block, each summing over all samples in K pieces, in sample order. */
typedef struct wgrad_job {
    nerf__onednn_scratch *s;
    prim_entry *by[WIDTHS][K_LOG2 + 1];
    size_t narrow;     /* the smaller of the two range widths */
    bool by_rows;      /* ranges of dW rows, else of columns */
    size_t span;       /* out or in: the side that is cut */
    unsigned blocks;
    size_t n;
    size_t esize;
    const char *dy;    /* [n, out], rows of lddy */
    size_t lddy;
    const char *x;     /* [n, in], rows of ldx */
    size_t ldx;
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
    thread_state ts;
    threads_enter(&ts);
    dnnl_status_t st = dnnl_success;
    size_t r = 0;
    for (int e = K_LOG2; e >= 0 && st == dnnl_success; e--) {
        const size_t m = (size_t)1 << e;
        while (j->n - r >= m && st == dnnl_success) {
            st = run_piece(by[e], sl->stream,
                           j->dy + (r * j->lddy + mo) * j->esize,
                           j->x + (r * j->ldx + no) * j->esize,
                           j->dw + mo * j->lddw + no, NULL, sl->block);
            r += m;
            if (e < K_LOG2) {
                break;
            }
        }
    }
    block_done(sl, st, &ts, &j->status);
}

static int weight_product(nerf__onednn *b, nerf__onednn_scratch *s, size_t n,
                          size_t out, size_t in, const void *dy, size_t lddy,
                          const void *x, size_t ldx, float *dw, size_t lddw)
{
    wgrad_job j;
    memset(&j, 0, sizeof j);
    j.s = s;
    j.by_rows = out >= in;
    j.span = j.by_rows ? out : in;
    j.blocks = blocks_for(s, j.span);
    j.narrow = j.span / j.blocks;
    j.n = n;
    j.esize = b->esize;
    j.dy = dy;
    j.lddy = lddy;
    j.x = x;
    j.ldx = ldx;
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
                                  1, (int64_t)lddy, (int64_t)ldx, 1,
                                  (int64_t)lddw, F_SUM, (int64_t)b->dt};
            int rc = get_prim(b, &key, &j.by[w][e]);
            if (rc != NERF_OK) {
                return rc;
            }
            if (j.by[w][e]->scratch_size > scratch) {
                scratch = j.by[w][e]->scratch_size;
            }
        }
    }
    int rc = slots_ready(b, s, j.blocks, round_up64(scratch));
    if (rc != NERF_OK) {
        return rc;
    }
    size_t cost = n * (out * in / j.blocks + 1) / 16 + 1;
    nerf__parallel_blocks(j.blocks, cost, wgrad_block, &j);
    int st = atomic_load(&j.status);
    return st == dnnl_success
               ? NERF_OK
               : dnnl_failed(b, (dnnl_status_t)st, "run a matmul");
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

static int weights_for(nerf__onednn *b, const float *w, size_t rows,
                       size_t ldw, size_t cols, const void **out)
{
    sync_weights(b);
    *out = rows ? operand_weights(b, w, (rows - 1) * ldw + cols) : NULL;
    if (*out == NULL) {
        return nerf__error(NERF_ERROR, "%s: weights outside the model's "
                           "parameters", b->name);
    }
    return NERF_OK;
}

/*
 * W's column block [out, in] from rows of ldw, copied dense into the
 * scratch, or w itself when it already is.  oneDNN runs its brgemm kernels
 * only on dense weights; on a block of a wider matrix it falls back to a
 * gemm whose sums are ordered by the row count, so a row's result would
 * depend on the piece it fell in.  A block is at most a layer's weights,
 * small beside the products that read it.
 */
static int dense_block(nerf__onednn_scratch *s, const float *w, size_t out,
                       size_t in, size_t ldw, const float **dense)
{
    if (ldw == in) {
        *dense = w;
        return NERF_OK;
    }
    int rc = grow(&s->env, &s->w, &s->w_cap, out, in, sizeof(float));
    if (rc != NERF_OK) {
        return rc;
    }
    float *d = s->w;
    for (size_t r = 0; r < out; r++) {
        memcpy(d + r * in, w + r * ldw, in * sizeof(float));
    }
    *dense = d;
    return NERF_OK;
}

/* fp32: one product per part, read in place, each after the first adding
 * to Y; the last one applies the bias and the ReLU. */
static int forward_f32(nerf__onednn *be, nerf__onednn_scratch *s, size_t n,
                       uint32_t out, const nerf__layer_part *parts,
                       int n_parts, const float *w, size_t ldw,
                       const float *b, int relu, float *y, size_t ldy)
{
    size_t col = 0;
    for (int p = 0; p < n_parts; p++) {
        const bool last = p == n_parts - 1;
        const void *wp;
        const float *wd = NULL;
        int rc = weights_for(be, w + col, out, ldw, parts[p].in, &wp);
        if (rc == NERF_OK) {
            rc = dense_block(s, wp, out, parts[p].in, ldw, &wd);
        }
        if (rc != NERF_OK) {
            return rc;
        }
        const size_t ld = wd == wp ? ldw : parts[p].in;
        int64_t flags = (p > 0 ? F_SUM : 0) | (last && b ? F_BIAS : 0) |
                        (last && relu ? F_RELU : 0);
        rc = row_product(be, s, n, parts[p].in, out, parts[p].x,
                         parts[p].ldx, wd, 1, ld, y, ldy, last ? b : NULL,
                         flags);
        if (rc != NERF_OK) {
            return rc;
        }
        col += parts[p].in;
    }
    return NERF_OK;
}

int nerf__onednn_forward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                         const nerf__layer_part *parts, int n_parts,
                         const float *w, size_t ldw, const float *b, int relu,
                         float *y, size_t ldy, uint16_t *kept)
{
    if (n == 0) {
        return NERF_OK;
    }
    nerf__onednn *be = c->onednn;
    nerf__onednn_scratch *s;
    int rc = scratch_get(c, &s);
    if (rc != NERF_OK) {
        return rc;
    }
    if (!be->bf16) {
        return forward_f32(be, s, n, out, parts, n_parts, w, ldw, b, relu, y,
                           ldy);
    }
    const size_t k = parts_width(parts, n_parts);
    const void *wb;
    if (kept == NULL) {
        rc = grow(&s->env, &s->a, &s->a_cap, n, k, sizeof(uint16_t));
    }
    if (rc == NERF_OK) {
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

/* dX = dY W_q: B is W's column block of part dx_part, [out, in] rows of
 * ldw. */
static int input_grad(nerf__onednn *be, nerf__onednn_scratch *s, size_t n,
                      uint32_t out, const void *dy, size_t lddy,
                      const nerf__layer_part *parts, int dx_part,
                      const float *w, size_t ldw, float *dx, size_t lddx)
{
    size_t col = 0;
    for (int p = 0; p < dx_part; p++) {
        col += parts[p].in;
    }
    const uint32_t in = parts[dx_part].in;
    const void *wb;
    int rc = weights_for(be, w + col, out, ldw, in, &wb);
    size_t ld = ldw;
    if (rc == NERF_OK && !be->bf16) {
        const float *wd;
        rc = dense_block(s, wb, out, in, ldw, &wd);
        ld = wd == wb ? ldw : in;
        wb = wd;
    }
    if (rc != NERF_OK) {
        return rc;
    }
    return row_product(be, s, n, out, in, dy, lddy, wb, ld, 1, dx, lddx,
                       NULL, 0);
}

/* fp32: a weight gradient per part, each reading its part in place. */
static int backward_f32(nerf__onednn *be, nerf__onednn_scratch *s, size_t n,
                        uint32_t out, const float *dy, size_t lddy,
                        const nerf__layer_part *parts, int n_parts,
                        const float *w, size_t ldw, float *dw, int dx_part,
                        float *dx, size_t lddx)
{
    int rc = NERF_OK;
    size_t col = 0;
    for (int p = 0; p < n_parts && rc == NERF_OK; p++) {
        rc = weight_product(be, s, n, out, parts[p].in, dy, lddy, parts[p].x,
                            parts[p].ldx, dw + col, ldw);
        col += parts[p].in;
    }
    if (rc != NERF_OK || dx == NULL) {
        return rc;
    }
    return input_grad(be, s, n, out, dy, lddy, parts, dx_part, w, ldw, dx,
                      lddx);
}

int nerf__onednn_backward(const nerf__layer_ctx *c, size_t n, uint32_t out,
                          const float *dy, size_t lddy, const uint16_t *dyb,
                          const nerf__layer_part *parts, int n_parts,
                          const uint16_t *kept, const float *w, size_t ldw,
                          float *dw, int dx_part, float *dx, size_t lddx)
{
    if (n == 0) {
        return NERF_OK;
    }
    nerf__onednn *be = c->onednn;
    nerf__onednn_scratch *s;
    int rc = scratch_get(c, &s);
    if (rc != NERF_OK) {
        return rc;
    }
    if (!be->bf16) {
        return backward_f32(be, s, n, out, dy, lddy, parts, n_parts, w, ldw,
                            dw, dx_part, dx, lddx);
    }
    const size_t k = parts_width(parts, n_parts);
    if (dyb == NULL) {
        rc = grow(&s->env, &s->a, &s->a_cap, n, out, sizeof(uint16_t));
    }
    if (rc == NERF_OK && kept == NULL) {
        rc = grow(&s->env, &s->x, &s->x_cap, n, k, sizeof(uint16_t));
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
    rc = weight_product(be, s, n, out, k, dyb, out, kept, k, dw, ldw);
    if (rc != NERF_OK || dx == NULL) {
        return rc;
    }
    return input_grad(be, s, n, out, dyb, out, parts, dx_part, w, ldw, dx,
                      lddx);
}
