/*
 * bench_bf16: one 256 x 256 ReLU layer's products, fp32 against bf16, and
 * the threading choices of the bf16 backend.  Prints figures; asserts
 * nothing.  Built when meson finds oneDNN.
 *
 *   bench_bf16 [--seconds S] [--rows N]
 *
 * For each batch of rows it times, in GFLOP/s of the products:
 *  - fp32: lib/mlp/layer.c's fp32 path, cblas_sgemm then the fused bias
 *    + ReLU pass (forward), and the two backward products;
 *  - bf16: the same calls on a bf16 model (the input rounded in the call,
 *    cut over libnerf's threads, oneDNN on one thread per call);
 *  - oneDNN alone on its own OpenMP threads (one thread per core), the
 *    input already bf16: what the backend would get by leaving threads
 *    to oneDNN;
 *  - two threads at once each doing half the rows, as two renderer
 *    workers do: through the backend, and through oneDNN with its OpenMP
 *    threads (which then puts two threads per core);
 * and the process's thread count before and after, to show that the
 * backend starts no OpenMP threads.
 */
#include <cblas.h>
#include <omp.h>
#include <oneapi/dnnl/dnnl.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "nerf.h"
#include "nerf_internal.h"

#define WIDTH 256

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int threads_now(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    int n = -1;
    while (f && fgets(line, sizeof line, f)) {
        if (sscanf(line, "Threads: %d", &n) == 1) {
            break;
        }
    }
    if (f) {
        fclose(f);
    }
    return n;
}

static nerf_model *layer_model(int matmul)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.depth = 2;
    o.width = WIDTH;
    o.skip_layer = 0;
    o.use_fine = 0;
    o.matmul = (uint32_t)matmul;
    nerf_model *m = NULL;
    if (nerf_model_create(&m, &o) != NERF_OK) {
        fprintf(stderr, "bench_bf16: %s\n", nerf_last_error());
    }
    return m;
}

/* ---- the library's layer calls ------------------------------------------ */

typedef struct layer_run {
    nerf_model *m;
    nerf__workspace ws; /* holds the bf16 scratch */
    size_t n;
    const float *x, *dy;
    float *y, *dw, *dx;
    int rc;
} layer_run;

static const nerf__linear *the_layer(const nerf_model *m)
{
    return &m->nets[0].trunk[1]; /* 256 -> 256 */
}

static void forward(layer_run *r)
{
    const nerf__linear *l = the_layer(r->m);
    nerf__layer_ctx c = {r->m->nets[0].onednn, &r->ws.onednn, &r->m->env};
    nerf__layer_part p = {r->x, WIDTH, WIDTH};
    r->rc = nerf__layer_forward(&c, r->n, WIDTH, &p, 1, r->m->params + l->w,
                                WIDTH, r->m->params + l->b, true, r->y, WIDTH,
                                NULL);
}

static void backward(layer_run *r)
{
    const nerf__linear *l = the_layer(r->m);
    nerf__layer_ctx c = {r->m->nets[0].onednn, &r->ws.onednn, &r->m->env};
    nerf__layer_part p = {r->x, WIDTH, WIDTH};
    r->rc = nerf__layer_backward(&c, r->n, WIDTH, r->dy, WIDTH, NULL, &p, 1,
                                 NULL, r->m->params + l->w, WIDTH, r->dw, 0,
                                 r->dx, WIDTH);
}

/* Run fn until `budget` seconds have passed (after one untimed call). */
static double rate(void (*fn)(layer_run *), layer_run *r, double flops,
                   double budget)
{
    fn(r);
    int reps = 0;
    double t0 = now(), t;
    do {
        fn(r);
        reps++;
        t = now() - t0;
    } while (t < budget);
    return r->rc == NERF_OK ? reps * flops / t * 1e-9 : -1.0;
}

/* The forward's rounding of its input alone, over libnerf's threads as the
 * backend does it: what the products take is the forward less this. */
typedef struct round_job {
    const float *x;
    uint16_t *out;
} round_job;

static void round_range(void *ctx, size_t begin, size_t end)
{
    const round_job *j = ctx;
    nerf__bf16_round(j->x + begin * WIDTH, (end - begin) * WIDTH,
                     j->out + begin * WIDTH);
}

static double round_seconds(const float *x, uint16_t *out, size_t n,
                            double budget)
{
    round_job j = {x, out};
    nerf__parallel_for(n, 2 * WIDTH, round_range, &j);
    int reps = 0;
    double t0 = now(), t;
    do {
        nerf__parallel_for(n, 2 * WIDTH, round_range, &j);
        reps++;
        t = now() - t0;
    } while (t < budget);
    return t / reps;
}

/* ---- oneDNN on its own OpenMP threads ----------------------------------- */

typedef struct onednn_run {
    dnnl_engine_t engine;
    dnnl_primitive_t prim;
    dnnl_memory_desc_t md[4];
    size_t n;
    uint16_t *xb, *wb;
    float *y, *bias;
    int threads; /* OpenMP threads of the calls (and of the primitive) */
    dnnl_status_t st;
} onednn_run;

static dnnl_status_t onednn_make(onednn_run *r)
{
    const dnnl_dims_t dx = {(dnnl_dim_t)r->n, WIDTH}, sx = {WIDTH, 1};
    const dnnl_dims_t dw = {WIDTH, WIDTH}, sw = {1, WIDTH};
    const dnnl_dims_t dy = {(dnnl_dim_t)r->n, WIDTH}, sy = {WIDTH, 1};
    const dnnl_dims_t db = {1, WIDTH};
    dnnl_memory_desc_init_by_strides(&r->md[0], 2, dx, dnnl_bf16, sx);
    dnnl_memory_desc_init_by_strides(&r->md[1], 2, dw, dnnl_bf16, sw);
    dnnl_memory_desc_init_by_strides(&r->md[2], 2, dy, dnnl_f32, sy);
    dnnl_memory_desc_init_by_tag(&r->md[3], 2, db, dnnl_f32, dnnl_ab);
    dnnl_matmul_desc_t desc;
    dnnl_matmul_desc_init(&desc, &r->md[0], &r->md[1], &r->md[3], &r->md[2]);
    dnnl_primitive_attr_t attr;
    dnnl_post_ops_t ops;
    dnnl_primitive_attr_create(&attr);
    dnnl_post_ops_create(&ops);
    dnnl_post_ops_append_eltwise(ops, 1.0f, dnnl_eltwise_relu, 0.0f, 0.0f);
    dnnl_primitive_attr_set_post_ops(attr, ops);
    dnnl_primitive_desc_t pd = NULL;
    omp_set_num_threads(r->threads);
    dnnl_status_t st = dnnl_primitive_desc_create(&pd, &desc, attr, r->engine,
                                                  NULL);
    if (st == dnnl_success) {
        st = dnnl_primitive_create(&r->prim, pd);
    }
    dnnl_primitive_desc_destroy(pd);
    dnnl_post_ops_destroy(ops);
    dnnl_primitive_attr_destroy(attr);
    return st;
}

static void onednn_forward(onednn_run *r)
{
    omp_set_num_threads(r->threads);
    dnnl_stream_t stream;
    dnnl_memory_t mem[4];
    void *h[4] = {r->xb, r->wb, r->y, r->bias};
    const int ids[4] = {DNNL_ARG_SRC, DNNL_ARG_WEIGHTS, DNNL_ARG_DST,
                        DNNL_ARG_BIAS};
    dnnl_exec_arg_t args[4];
    dnnl_stream_create(&stream, r->engine, dnnl_stream_default_flags);
    for (int i = 0; i < 4; i++) {
        dnnl_memory_create(&mem[i], &r->md[i], r->engine, h[i]);
        args[i] = (dnnl_exec_arg_t){ids[i], mem[i]};
    }
    r->st = dnnl_primitive_execute(r->prim, stream, 4, args);
    dnnl_stream_wait(stream);
    for (int i = 0; i < 4; i++) {
        dnnl_memory_destroy(mem[i]);
    }
    dnnl_stream_destroy(stream);
}

/* ---- two callers at once ------------------------------------------------ */

typedef struct pair_job {
    layer_run *lr;
    onednn_run *dn;
    double budget;
    int reps;
} pair_job;

static void *pair_main(void *arg)
{
    pair_job *j = arg;
    double t0 = now();
    j->reps = 0;
    do {
        if (j->lr) {
            forward(j->lr);
        } else {
            onednn_forward(j->dn);
        }
        j->reps++;
    } while (now() - t0 < j->budget);
    return NULL;
}

/* Two threads, each on its own half of the rows; GFLOP/s of both. */
static double pair_rate(pair_job jobs[2], double flops_each, double budget)
{
    pthread_t th[2];
    double t0 = now();
    for (int i = 0; i < 2; i++) {
        jobs[i].budget = budget;
        pthread_create(&th[i], NULL, pair_main, &jobs[i]);
    }
    for (int i = 0; i < 2; i++) {
        pthread_join(th[i], NULL);
    }
    double t = now() - t0;
    return (jobs[0].reps + jobs[1].reps) * flops_each / t * 1e-9;
}

/* ---- main --------------------------------------------------------------- */

static float *filled(size_t count, float scale)
{
    float *p = malloc(count * sizeof(float));
    for (size_t i = 0; p && i < count; i++) {
        p[i] = scale * ((float)((i * 2654435761u) % 1000u) / 1000.0f - 0.5f);
    }
    return p;
}

static void bench_rows(size_t n, double budget, nerf_model *m32,
                       nerf_model *m16, dnnl_engine_t engine)
{
    const double flops = 2.0 * (double)n * WIDTH * WIDTH;
    float *x = filled(n * WIDTH, 2.0f), *dy = filled(n * WIDTH, 1.0f);
    float *y = malloc(n * WIDTH * sizeof(float));
    float *dx = malloc(n * WIDTH * sizeof(float));
    float *dw = calloc((size_t)WIDTH * WIDTH, sizeof(float));
    layer_run r32 = {.m = m32, .n = n, .x = x, .dy = dy, .y = y, .dw = dw,
                     .dx = dx};
    layer_run r16 = r32;
    r16.m = m16;
    double f32 = rate(forward, &r32, flops, budget);
    double b32 = rate(backward, &r32, 2 * flops, budget);
    int before = threads_now();
    double f16 = rate(forward, &r16, flops, budget);
    double b16 = rate(backward, &r16, 2 * flops, budget);
    int during = threads_now();

    /* oneDNN alone, on one OpenMP thread per core. */
    const int cores = (int)nerf__cpu_count();
    const int saved = omp_get_max_threads();
    uint16_t *xb = malloc(n * WIDTH * sizeof(uint16_t));
    uint16_t *wb = malloc((size_t)WIDTH * WIDTH * sizeof(uint16_t));
    const double t_round = round_seconds(x, xb, n, budget);
    nerf__bf16_round(m16->params + the_layer(m16)->w, (size_t)WIDTH * WIDTH,
                     wb);
    onednn_run o = {.engine = engine, .n = n, .xb = xb, .wb = wb, .y = y,
                    .bias = m16->params + the_layer(m16)->b,
                    .threads = cores};
    double omp = -1.0;
    if (onednn_make(&o) == dnnl_success) {
        onednn_forward(&o);
        int reps = 0;
        double t0 = now(), t;
        do {
            onednn_forward(&o);
            reps++;
            t = now() - t0;
        } while (t < budget);
        omp = o.st == dnnl_success ? reps * flops / t * 1e-9 : -1.0;
    }
    int after_omp = threads_now();

    /* Two callers, half the rows each. */
    const size_t h = n / 2;
    layer_run half[2] = {r16, r16};
    memset(&half[0].ws, 0, sizeof half[0].ws);
    memset(&half[1].ws, 0, sizeof half[1].ws);
    half[1].x = x + h * WIDTH;
    half[1].y = y + h * WIDTH;
    half[0].n = half[1].n = h;
    pair_job lib_pair[2] = {{.lr = &half[0]}, {.lr = &half[1]}};
    double pair_lib = pair_rate(lib_pair, 2.0 * h * WIDTH * WIDTH, budget);
    onednn_run oh[2] = {o, o};
    double pair_omp = -1.0;
    oh[0].n = oh[1].n = h;
    oh[0].prim = oh[1].prim = NULL;
    oh[1].xb = xb + h * WIDTH;
    oh[1].y = y + h * WIDTH;
    if (onednn_make(&oh[0]) == dnnl_success) {
        oh[1].prim = oh[0].prim;
        memcpy(oh[1].md, oh[0].md, sizeof oh[0].md);
        pair_job omp_pair[2] = {{.dn = &oh[0]}, {.dn = &oh[1]}};
        pair_omp = pair_rate(omp_pair, 2.0 * h * WIDTH * WIDTH, budget);
    }
    omp_set_num_threads(saved);

    printf("rows %zu:\n", n);
    printf("  fp32 forward (sgemm + bias/ReLU pass)  %7.1f GFLOP/s\n", f32);
    printf("  fp32 backward (dW + dX)                %7.1f GFLOP/s\n", b32);
    printf("  bf16 forward (libnerf, rounding in)    %7.1f GFLOP/s\n", f16);
    printf("    of which rounding the input, %.2f ms: the products alone "
           "%7.1f GFLOP/s\n", 1e3 * t_round,
           flops / (flops / (f16 * 1e9) - t_round) * 1e-9);
    printf("  bf16 backward (libnerf, rounding in)   %7.1f GFLOP/s\n", b16);
    printf("  bf16 forward, oneDNN on %d OpenMP threads, input already "
           "bf16 %7.1f GFLOP/s\n", cores, omp);
    printf("  two callers at once, half the rows each: libnerf %7.1f, "
           "oneDNN on %d OpenMP threads each %7.1f GFLOP/s\n", pair_lib,
           cores, pair_omp);
    printf("  process threads: %d before the bf16 calls, %d after them, %d "
           "after oneDNN's own OpenMP run\n", before, during, after_omp);
    nerf__workspace_release(&m16->env, &r16.ws);
    nerf__workspace_release(&m16->env, &half[0].ws);
    nerf__workspace_release(&m16->env, &half[1].ws);
    if (oh[0].prim) {
        dnnl_primitive_destroy(oh[0].prim);
    }
    if (o.prim) {
        dnnl_primitive_destroy(o.prim);
    }
    free(x);
    free(dy);
    free(y);
    free(dx);
    free(dw);
    free(xb);
    free(wb);
}

int main(int argc, char **argv)
{
    double budget = 2.0;
    size_t rows[4] = {16384, 65536};
    int n_rows = 2;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--seconds") == 0 && i + 1 < argc) {
            budget = atof(argv[++i]);
        } else if (strcmp(argv[i], "--rows") == 0 && i + 1 < argc) {
            rows[0] = (size_t)atol(argv[++i]);
            n_rows = 1;
        } else {
            fprintf(stderr, "usage: %s [--seconds S] [--rows N]\n", argv[0]);
            return 2;
        }
    }
    if (!nerf_matmul_supported(NERF_MATMUL_BF16)) {
        nerf_model *m = layer_model(NERF_MATMUL_BF16); /* prints why */
        nerf_model_destroy(m);
        return 1;
    }
    printf("%s\n", nerf_build_info());
    printf("%u cores; OpenBLAS %d thread(s) for fp32; %s layer\n",
           nerf__cpu_count(), nerf__blas_threads(), "256 x 256 ReLU");
    nerf_model *m32 = layer_model(NERF_MATMUL_FP32);
    nerf_model *m16 = layer_model(NERF_MATMUL_BF16);
    dnnl_engine_t engine = NULL;
    if (m32 == NULL || m16 == NULL ||
        dnnl_engine_create(&engine, dnnl_cpu, 0) != dnnl_success) {
        return 1;
    }
    for (int i = 0; i < n_rows; i++) {
        bench_rows(rows[i], budget, m32, m16, engine);
    }
    dnnl_engine_destroy(engine);
    nerf_model_destroy(m32);
    nerf_model_destroy(m16);
    return 0;
}
