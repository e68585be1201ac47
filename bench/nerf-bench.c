/*
 * nerf-bench: the figures libnerf's speed is judged by, in one run, for
 * the reference, tiny and fast presets:
 *
 *  - training rays/s and network samples/s in steady state (1024-ray
 *    steps on the built-in scene, warm-up steps excluded);
 *  - rendering rays/s and samples/s (nerf_renderer_render_rays,
 *    evaluation);
 *  - reference and tiny: cblas_sgemm GFLOP/s measured in the same run on
 *    the products of one training step, the FLOPs per ray from the
 *    network's shapes, hence the sgemm-bound rays/s and the share of it
 *    the library reaches;
 *  - fast (hash grid, occupancy grid, ray marching): samples per ray in
 *    training and rendering, and where a training step's time goes
 *    (encoding, MLP, compositing, optimiser, grid update), from the
 *    library's internal building blocks timed one by one on the packed
 *    samples of a real step;
 *  - peak resident memory of an 800x800 render, in a child process;
 *  - thread counts and the BLAS build.
 *
 * With --matmul bf16 the models compute their products in bf16 through
 * oneDNN (NERF_MATMUL_BF16); the bound stays the fp32 cblas_sgemm one, so
 * the shares then say how far bf16 goes past what fp32 products allow.
 *
 *   nerf-bench [--json] [--preset reference|tiny|fast|all] [--seconds S]
 *              [--threads N] [--workers W] [--size S] [--render-size S]
 *              [--rss-rows K] [--full] [--no-800] [--fast-warmup N]
 *              [--matmul fp32|bf16]
 *
 * With --json, stdout holds exactly one JSON object and the table goes to
 * stderr.  Run `nerf-bench --help` for what each option does.
 */
#include <cJSON.h>
#include <cblas.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "composite_packed.h"
#include "cpu.h"
#include "gemm_bf16.h"
#include "hashgrid.h"
#include "march.h"
#include "model.h"
#include "occupancy.h"
#include "parallel.h"
#include "renderer.h"
#include "sampler.h"
#include "sh.h"
#include "trainer.h"

#define BATCH_RAYS 1024u
/* Rays per timed render call: a few seconds of the reference preset on
 * two cores, a whole number of the renderer's 512-ray chunks. */
#define RENDER_RAYS 2048u
#define MIN_TRAIN_STEPS 2
#define MAX_CALLS 512
/* The fast preset's trainer refreshes every cell of the occupancy grid
 * every 16 steps up to step 256 and a sixteenth of the empty ones after:
 * warming up past that, the grid has carved the empty space and the
 * timed steps are in the regime a long run spends its time in. */
#define FAST_WARMUP_STEPS 320u
/* A whole view rather than the top rows of one: with ray marching the
 * cost of a ray depends on what it meets.  The 800x800 view's camera at
 * 128x128 pixels (same field of view, so the same share of rays on the
 * objects). */
#define FAST_RENDER_SIDE 128u

/* ---- clock, load, memory ------------------------------------------------ */

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The 1, 5 and 15 minute load averages, or -1s off Linux: the figures are
 * only comparable between runs on an otherwise idle machine. */
static void load_average(double out[3])
{
    out[0] = out[1] = out[2] = -1.0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf %lf %lf", &out[0], &out[1], &out[2]) != 3) {
            out[0] = out[1] = out[2] = -1.0;
        }
        fclose(f);
    }
}

/* A Vm* figure of this process ("VmHWM", "VmRSS") in MB, or -1 where
 * /proc is missing. */
static double vm_mb(const char *field)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (f == NULL) {
        return -1.0;
    }
    char line[256];
    double mb = -1.0;
    size_t len = strlen(field);
    while (fgets(line, sizeof line, f)) {
        long kb;
        if (strncmp(line, field, len) == 0 && line[len] == ':' &&
            sscanf(line + len + 1, "%ld", &kb) == 1) {
            mb = kb / 1024.0;
            break;
        }
    }
    fclose(f);
    return mb;
}

/* ---- the BLAS ----------------------------------------------------------- */

static int blas_threads(void)
{
#ifdef HAVE_OPENBLAS_GET_NUM_THREADS
    return openblas_get_num_threads();
#else
    return -1;
#endif
}

static void set_blas_threads(int n)
{
#ifdef HAVE_OPENBLAS_SET_NUM_THREADS
    if (n > 0) {
        openblas_set_num_threads(n);
    }
#else
    (void)n;
#endif
}

/* OpenBLAS threads while rendering (--render-blas-threads; 0: unchanged).
 * Renderer workers each call the BLAS, so one worker per core over a
 * single-threaded BLAS is the other way to use the cores. */
static int render_blas_threads;
/* nerf_matmul of every model the bench creates (--matmul). */
static int bench_matmul = NERF_MATMUL_FP32;

static const char *blas_config(void)
{
#ifdef HAVE_OPENBLAS_GET_CONFIG
    return openblas_get_config();
#else
    return NULL;
#endif
}

static const char *blas_corename(void)
{
#ifdef HAVE_OPENBLAS_GET_CORENAME
    return openblas_get_corename();
#else
    return NULL;
#endif
}

/* ---- the network's matrix products -------------------------------------- */

/*
 * One cblas_sgemm, row-major.  The list below is the natural
 * one-product-per-layer form of the network (samples as rows), with
 * the leading dimensions and betas of lib/mlp/network.c as written when
 * this bench was: the bound it gives belongs to the network's shapes, not
 * to however the library happens to call the BLAS.
 */
typedef struct gemm_call {
    bool ta, tb;
    int m, n, k;
    int lda, ldb, ldc;
    float beta;
    bool backward;
} gemm_call;

typedef struct gemm_list {
    gemm_call c[MAX_CALLS];
    int count;
} gemm_list;

static void push(gemm_list *l, gemm_call g)
{
    if (l->count < MAX_CALLS) {
        l->c[l->count++] = g;
    }
}

/* Y[n, out] = X[n, in] W^T, W a column block of rows of ldw floats. */
static void fwd(gemm_list *l, int n, int out, int in, int ldx, int ldw,
                float beta, int ldy)
{
    push(l, (gemm_call){false, true, n, out, in, ldx, ldw, ldy, beta, false});
}

/* dW[out, in] += dY[n, out]^T X[n, in]. */
static void wgrad(gemm_list *l, int n, int out, int in, int lddy, int ldx,
                  int lddw)
{
    push(l, (gemm_call){true, false, out, in, n, lddy, ldx, lddw, 1.0f, true});
}

/* dX[n, in] = dY[n, out] W. */
static void igrad(gemm_list *l, int n, int out, int in, int lddy, int ldw,
                  int lddx)
{
    push(l, (gemm_call){false, false, n, in, out, lddy, ldw, lddx, 0.0f, true});
}

static void network_forward(gemm_list *l, const nerf__network *net, int n)
{
    const int W = (int)net->width, Ep = (int)net->pos_width;
    const int HW = (int)nerf__network_head_width(net);
    for (uint32_t i = 0; i < net->depth; i++) {
        const int in = (int)net->trunk[i].in;
        if (i > 0 && i == net->skip) {
            /* [gamma(x), h]: one product per column block, never copied. */
            fwd(l, n, W, Ep, Ep, in, 0.0f, W);
            fwd(l, n, W, W, W, in, 1.0f, W);
        } else {
            fwd(l, n, W, in, i == 0 ? Ep : W, in, 0.0f, W);
        }
    }
    fwd(l, n, HW, W, W, W, 0.0f, HW);
    if (net->use_viewdirs) {
        const int V = (int)net->view_width, Ed = (int)net->dir_width;
        fwd(l, n, V, W, HW, W + Ed, 0.0f, V);
        fwd(l, n, V, Ed, Ed, W + Ed, 1.0f, V);
        fwd(l, n, 3, V, V, V, 0.0f, 3);
    }
}

/* Inputs that are encodings get no dX: nothing upstream learns. */
static void network_backward(gemm_list *l, const nerf__network *net, int n)
{
    const int W = (int)net->width, Ep = (int)net->pos_width;
    const int HW = (int)nerf__network_head_width(net);
    if (net->use_viewdirs) {
        const int V = (int)net->view_width, Ed = (int)net->dir_width;
        wgrad(l, n, 3, V, 3, V, V);
        igrad(l, n, 3, V, 3, V, V);
        wgrad(l, n, V, W, V, HW, W + Ed);
        wgrad(l, n, V, Ed, V, Ed, W + Ed);
        igrad(l, n, V, W, V, W + Ed, HW);
    }
    wgrad(l, n, HW, W, HW, W, W);
    igrad(l, n, HW, W, HW, W, W);
    for (uint32_t i = net->depth; i-- > 0;) {
        const int in = (int)net->trunk[i].in;
        if (i == 0) {
            wgrad(l, n, W, in, W, Ep, in);
            break;
        }
        if (i == net->skip) {
            wgrad(l, n, W, Ep, W, Ep, in);
        }
        wgrad(l, n, W, W, W, W, in);
        igrad(l, n, W, W, W, in, W);
    }
}

/*
 * The products of one training step of `rays` rays: the coarse network on
 * n_coarse samples per ray and the fine one on all samples, forward then
 * backward.  Rendering runs the same forward products.
 */
static void step_products(gemm_list *l, const nerf_model *m, int passes,
                          const int samples[2], int rays)
{
    const nerf__network *net[2] = {&m->nets[0], &m->nets[m->n_nets - 1]};
    l->count = 0;
    for (int p = 0; p < passes; p++) {
        network_forward(l, net[p], rays * samples[p]);
    }
    for (int p = passes; p-- > 0;) {
        network_backward(l, net[p], rays * samples[p]);
    }
}

static double list_flops(const gemm_list *l, bool forward, bool backward)
{
    double f = 0.0;
    for (int i = 0; i < l->count; i++) {
        const gemm_call *g = &l->c[i];
        if (g->backward ? backward : forward) {
            f += 2.0 * g->m * g->n * (double)g->k;
        }
    }
    return f;
}

typedef struct gemm_timing {
    double gflops_step;    /* forward + backward products */
    double gflops_forward; /* forward products alone */
    double seconds;        /* timed */
    int reps;
} gemm_timing;

static size_t elems(size_t rows, int ld)
{
    return rows * (size_t)ld;
}

/*
 * Run the list until `budget` seconds have passed (at least once), timing
 * each call so that forward and backward rates come from the same runs.
 */
static int time_products(const gemm_list *l, double budget, gemm_timing *out)
{
    size_t na = 0, nb = 0, nc = 0;
    for (int i = 0; i < l->count; i++) {
        const gemm_call *g = &l->c[i];
        size_t a = elems((size_t)(g->ta ? g->k : g->m), g->lda);
        size_t b = elems((size_t)(g->tb ? g->n : g->k), g->ldb);
        size_t c = elems((size_t)g->m, g->ldc);
        na = a > na ? a : na;
        nb = b > nb ? b : nb;
        nc = c > nc ? c : nc;
    }
    float *a = malloc(na * sizeof(float));
    float *b = malloc(nb * sizeof(float));
    float *c = calloc(nc, sizeof(float));
    if (!a || !b || !c) {
        free(a);
        free(b);
        free(c);
        return -1;
    }
    /* Written, not calloc'd zeros: untouched pages all map to one zero page
     * and would make the inputs look cache-resident. */
    for (size_t i = 0; i < na; i++) {
        a[i] = (float)(i % 251) * 1e-4f;
    }
    for (size_t i = 0; i < nb; i++) {
        b[i] = (float)(i % 241) * 1e-4f;
    }
    /* Wakes OpenBLAS's threads before the clock starts. */
    for (int i = 0; i < l->count && i < 2; i++) {
        const gemm_call *g = &l->c[i];
        cblas_sgemm(CblasRowMajor, g->ta ? CblasTrans : CblasNoTrans,
                    g->tb ? CblasTrans : CblasNoTrans, g->m, g->n, g->k, 1.0f,
                    a, g->lda, b, g->ldb, g->beta, c, g->ldc);
    }
    double t_fw = 0.0, t_bw = 0.0;
    int reps = 0;
    do {
        for (int i = 0; i < l->count; i++) {
            const gemm_call *g = &l->c[i];
            double t0 = now();
            cblas_sgemm(CblasRowMajor, g->ta ? CblasTrans : CblasNoTrans,
                        g->tb ? CblasTrans : CblasNoTrans, g->m, g->n, g->k,
                        1.0f, a, g->lda, b, g->ldb, g->beta, c, g->ldc);
            double t = now() - t0;
            if (g->backward) {
                t_bw += t;
            } else {
                t_fw += t;
            }
        }
        reps++;
    } while (t_fw + t_bw < budget);
    free(a);
    free(b);
    free(c);
    double f_fw = list_flops(l, true, false), f_bw = list_flops(l, false, true);
    out->reps = reps;
    out->seconds = t_fw + t_bw;
    out->gflops_step = reps * (f_fw + f_bw) / (t_fw + t_bw) * 1e-9;
    out->gflops_forward = reps * f_fw / t_fw * 1e-9;
    return 0;
}

/* ---- presets ------------------------------------------------------------ */

typedef struct preset_setup {
    int id;
    const char *name;
    bool march; /* samples marched through the occupancy grid */
    nerf_model *model;
    nerf_sampler *train_sampler; /* perturb set: training draws */
    nerf_sampler *eval_sampler;
    int passes;
    int samples[2]; /* network samples per ray of each pass */
    uint32_t n_coarse, n_fine;
} preset_setup;

static int preset_make(preset_setup *p, int id)
{
    memset(p, 0, sizeof *p);
    p->id = id;
    p->name = id == NERF_PRESET_TINY   ? "tiny"
              : id == NERF_PRESET_FAST ? "fast"
                                       : "reference";
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, id);
    mo.matmul = (uint32_t)bench_matmul;
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, id);
    if (nerf_model_create(&p->model, &mo) != NERF_OK ||
        nerf_sampler_create(&p->train_sampler, &so) != NERF_OK) {
        return -1;
    }
    so.perturb = 0;
    if (nerf_sampler_create(&p->eval_sampler, &so) != NERF_OK) {
        return -1;
    }
    p->march = so.march_steps > 0;
    p->n_coarse = so.n_coarse;
    p->n_fine = so.n_fine;
    p->passes = so.n_fine > 0 ? 2 : 1;
    p->samples[0] = (int)so.n_coarse;
    p->samples[1] = (int)(so.n_coarse + so.n_fine);
    return 0;
}

static void preset_release(preset_setup *p)
{
    nerf_sampler_destroy(p->eval_sampler);
    nerf_sampler_destroy(p->train_sampler);
    nerf_model_destroy(p->model);
}

/* A Blender-like view of the built-in scene: 4 units from the origin,
 * 0.69 rad field of view. */
static void view_camera(nerf_camera *c, uint32_t side)
{
    NERF_CAMERA_INIT(c);
    c->width = c->height = side;
    c->fx = c->fy = 0.5f * (float)side / tanf(0.5f * 0.6911112f);
    c->cx = c->cy = 0.5f * (float)side;
    const float eye[3] = {0.0f, -3.5777088f, 1.7888544f};
    const float target[3] = {0.0f, 0.0f, 0.0f}, up[3] = {0.0f, 0.0f, 1.0f};
    nerf_camera_look_at(c, eye, target, up);
}

/* ---- peak memory of a render, in a child process ------------------------ */

typedef struct rss_result {
    int ok;
    int full;
    uint32_t workers;
    double hwm_mb, maxrss_mb, outputs_mb, seconds;
    double model_mb; /* resident once the model exists, before the render */
    uint64_t rays_done, rays_total;
} rss_result;

typedef struct rss_stop {
    uint64_t limit; /* 0: never stop */
    uint64_t done;
} rss_stop;

static int rss_progress(const nerf_progress *p, void *user)
{
    rss_stop *s = user;
    s->done = p->done;
    return s->limit && p->done >= s->limit;
}

static void rss_measure(int preset, uint32_t side, uint32_t rows, bool full,
                        uint32_t workers, rss_result *res)
{
    preset_setup p;
    memset(res, 0, sizeof *res);
    if (preset_make(&p, preset) != 0) {
        fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        return;
    }
    res->model_mb = vm_mb("VmRSS");
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = workers;
    ro.white_background = 1;
    nerf_renderer *r = NULL;
    size_t pixels = (size_t)side * side;
    /* A caller of a full render holds full-size outputs: touch them all
     * up front so that a stopped render counts them too. */
    float *rgb = malloc(pixels * 3 * sizeof(float));
    float *depth = malloc(pixels * sizeof(float));
    float *opacity = malloc(pixels * sizeof(float));
    if (rgb && depth && opacity &&
        nerf_renderer_create(&r, p.model, p.eval_sampler, &ro) == NERF_OK) {
        memset(rgb, 0, pixels * 3 * sizeof(float));
        memset(depth, 0, pixels * sizeof(float));
        memset(opacity, 0, pixels * sizeof(float));
        rss_stop stop = {full ? 0 : (uint64_t)rows * side, 0};
        nerf_renderer_set_progress(r, rss_progress, &stop);
        nerf_camera cam;
        view_camera(&cam, side);
        double t0 = now();
        int rc =
            nerf_renderer_render_image(r, &cam, rgb, depth, opacity, pixels);
        res->seconds = now() - t0;
        if (rc == NERF_OK || (rc == NERF_ECANCELLED && !full)) {
            struct rusage ru;
            getrusage(RUSAGE_SELF, &ru);
            res->ok = 1;
            res->full = rc == NERF_OK;
            res->workers = r->threads;
            res->hwm_mb = vm_mb("VmHWM");
            res->maxrss_mb = ru.ru_maxrss / 1024.0;
            res->outputs_mb = pixels * 5 * sizeof(float) / 1048576.0;
            res->rays_done = rc == NERF_OK ? pixels : stop.done;
            res->rays_total = pixels;
        } else {
            fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        }
    } else {
        fprintf(stderr, "nerf-bench: cannot set up the %ux%u render\n", side,
                side);
    }
    nerf_renderer_destroy(r);
    free(rgb);
    free(depth);
    free(opacity);
    preset_release(&p);
}

/*
 * Forked while this process is still small, so the figure is the render's
 * own and not inflated by the training buffers measured later.
 */
static void rss_in_child(int preset, uint32_t side, uint32_t rows, bool full,
                         uint32_t workers, rss_result *res)
{
    memset(res, 0, sizeof *res);
    int fd[2];
    if (pipe(fd) != 0) {
        return;
    }
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        rss_result r;
        rss_measure(preset, side, rows, full, workers, &r);
        ssize_t w = write(fd[1], &r, sizeof r);
        _exit(w == (ssize_t)sizeof r ? 0 : 1);
    }
    close(fd[1]);
    if (pid > 0) {
        size_t got = 0;
        while (got < sizeof *res) {
            ssize_t n = read(fd[0], (char *)res + got, sizeof *res - got);
            if (n < 0 && errno == EINTR) {
                continue;
            }
            if (n <= 0) {
                break;
            }
            got += (size_t)n;
        }
        int status = 0;
        waitpid(pid, &status, 0);
        if (got != sizeof *res || !WIFEXITED(status) ||
            WEXITSTATUS(status) != 0) {
            memset(res, 0, sizeof *res);
        }
    }
    close(fd[0]);
}

/* ---- the dataset: the built-in scene in a temporary folder -------------- */

static void remove_tree(const char *path)
{
    struct stat st;
    if (lstat(path, &st) != 0) {
        return;
    }
    if (S_ISDIR(st.st_mode)) {
        DIR *d = opendir(path);
        if (d) {
            struct dirent *e;
            while ((e = readdir(d)) != NULL) {
                if (strcmp(e->d_name, ".") == 0 ||
                    strcmp(e->d_name, "..") == 0) {
                    continue;
                }
                size_t len = strlen(path) + strlen(e->d_name) + 2;
                char *child = malloc(len);
                if (child) {
                    snprintf(child, len, "%s/%s", path, e->d_name);
                    remove_tree(child);
                    free(child);
                }
            }
            closedir(d);
        }
        rmdir(path);
    } else {
        unlink(path);
    }
}

static nerf_dataset *make_dataset(uint32_t side, uint32_t views)
{
    const char *tmp = getenv("TMPDIR");
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/nerf-bench-XXXXXX",
             tmp && *tmp ? tmp : "/tmp");
    if (mkdtemp(dir) == NULL) {
        perror("nerf-bench: mkdtemp");
        return NULL;
    }
    nerf_scene_options so;
    NERF_SCENE_OPTIONS_INIT(&so);
    so.width = so.height = side;
    so.n_train = views;
    so.n_val = 0;
    so.n_test = 0;
    nerf_dataset *ds = NULL;
    if (nerf_scene_write(dir, &so) != NERF_OK ||
        nerf_dataset_load(&ds, dir, NULL) != NERF_OK) {
        fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        ds = NULL;
    }
    /* The images are in memory now. */
    remove_tree(dir);
    return ds;
}

/* ---- the measurements of one preset ------------------------------------- */

/*
 * Where a training step of a marching preset goes.  Timers inside the
 * library's loops would cost every user time in every step, so instead
 * the bench times the library's own building blocks one at a time, each
 * called as the step calls it, on the packed samples of a real step (the
 * last timed one, still held by its trainer), and sets their sum beside
 * the measured step time; the difference is what no block covers
 * (drawing the rays, the loss, view directions copied to the samples).
 * Seconds are means per call.
 */
typedef struct step_breakdown {
    bool ok;
    bool same_samples; /* the bench's march reproduced the step's samples */
    size_t rays, samples;
    int rounds;
    double march;        /* count + fill + sample points */
    double hash_fw, hash_bw, sh_fw;
    double net_fw, net_bw; /* whole network: encodings included */
    double composite_fw, composite_bw;
    double zero_grad, adam;
    double grid_update;  /* one refresh; the trainer does one per 16 steps */
    int grid_updates;
    size_t grid_cells_evaluated;
} step_breakdown;

/* The categories the figures are reported in, seconds per step. */
typedef struct step_shares {
    double encoding, mlp, compositing, optimiser, grid, sum;
} step_shares;

static step_shares shares_of(const step_breakdown *b)
{
    step_shares s;
    s.encoding = b->hash_fw + b->hash_bw + b->sh_fw;
    /* The network's own calls encode first: what remains is the products
     * and the element-wise passes between them. */
    s.mlp = fmax(0.0, b->net_fw + b->net_bw - s.encoding);
    s.compositing = b->march + b->composite_fw + b->composite_bw;
    s.optimiser = b->zero_grad + b->adam;
    s.grid = b->grid_update / NERF__GRID_EVERY;
    s.sum = s.encoding + s.mlp + s.compositing + s.optimiser + s.grid;
    return s;
}

typedef struct figures {
    bool ran;
    /* shapes */
    double flops_sample_fw, flops_train_ray, flops_render_ray;
    size_t params;
    /* sgemm (not for marching presets) */
    gemm_timing gemm;    /* the better of the two runs, rate by rate */
    gemm_timing runs[2]; /* before training, after rendering */
    int gemm_calls;
    /* training */
    int train_ok, warmup_steps, train_steps;
    double warmup_seconds, warmup_psnr;
    double train_seconds, train_rays_per_s, train_loss, train_psnr;
    double train_fastest_step; /* seconds: the load's least disturbed step */
    /* network evaluations per ray, and per second */
    double train_samples_per_ray, train_samples_per_s;
    uint64_t train_last_step;
    double grid_occupied; /* marching: share of the grid's cells, at the end */
    /* rendering */
    int render_ok;
    uint32_t render_workers;
    int render_blas_threads;
    uint32_t render_side; /* marching: a whole view of this side */
    uint64_t render_rays;
    double render_seconds, render_rays_per_s;
    double render_samples_per_ray, render_samples_per_s;
    /* marching: where a training step's time goes */
    step_breakdown bd;
    /* memory */
    rss_result rss;
    bool rss_skipped;
    /* bf16: oneDNN primitives the model created for everything above */
    size_t bf16_primitives;
} figures;

static int measure_training(preset_setup *p, const nerf_dataset *ds,
                            double budget, uint32_t fast_warmup, figures *f,
                            nerf_trainer **keep)
{
    nerf_trainer_options to;
    NERF_TRAINER_OPTIONS_INIT(&to);
    to.batch_rays = BATCH_RAYS;
    /* The central crop only changes which pixels are drawn; the steady
     * state of a run is past it. */
    to.precrop_steps = 0;
    /* As nerf-train trains a hash-grid model (images without alpha
     * ignore it). */
    to.random_background = p->march ? 1 : 0;
    nerf_trainer *t = NULL;
    if (nerf_trainer_create(&t, p->model, ds, p->train_sampler, &to) !=
        NERF_OK) {
        return -1;
    }
    nerf_train_stats s;
    memset(&s, 0, sizeof s);
    s.struct_size = sizeof s;
    /* The first step allocates every buffer; the tiny preset's steps are
     * short enough that a few more cost nothing and settle the caches.
     * A marching preset's cost depends on what the model has learnt (the
     * grid it has carved, where rays become opaque), so it trains first. */
    f->warmup_steps = p->march                  ? (int)fast_warmup
                      : p->id == NERF_PRESET_TINY ? 3
                                                  : 1;
    int rc = NERF_OK;
    double w0 = now();
    for (int i = 0; i < f->warmup_steps && rc == NERF_OK; i++) {
        rc = nerf_trainer_step(t, &s);
    }
    f->warmup_seconds = now() - w0;
    f->warmup_psnr = s.psnr;
    /* Marching: whole cycles of NERF__GRID_EVERY steps, so that the grid
     * refreshes weigh in the mean as often as in a long run. */
    const int cycle = p->march ? (int)NERF__GRID_EVERY : 1;
    const int min_steps = p->march ? cycle : MIN_TRAIN_STEPS;
    int steps = 0;
    double samples = 0.0;
    double t0 = now(), elapsed = 0.0, fastest = INFINITY;
    while (rc == NERF_OK &&
           (elapsed < budget || steps < min_steps || steps % cycle != 0)) {
        double before = elapsed;
        rc = nerf_trainer_step(t, &s);
        steps++;
        elapsed = now() - t0;
        fastest = fmin(fastest, elapsed - before);
        samples += s.samples_per_ray * BATCH_RAYS;
    }
    if (rc == NERF_OK && p->model->grid) {
        const nerf__occupancy *g = p->model->grid;
        f->grid_occupied = (double)g->occupied / (double)g->cells;
    }
    if (rc == NERF_OK && keep) {
        *keep = t;
    } else {
        nerf_trainer_destroy(t);
    }
    if (rc != NERF_OK) {
        return -1;
    }
    f->train_ok = 1;
    f->train_steps = steps;
    f->train_seconds = elapsed;
    f->train_rays_per_s = steps * (double)BATCH_RAYS / elapsed;
    f->train_samples_per_ray = samples / (steps * (double)BATCH_RAYS);
    f->train_samples_per_s = samples / elapsed;
    f->train_loss = s.loss;
    f->train_psnr = s.psnr;
    f->train_last_step = s.step;
    f->train_fastest_step = fastest;
    return 0;
}

/*
 * Network samples of rendering n rays.  Rendering is deterministic, so
 * replaying the call in the blocks its workers use (NERF__RENDER_BLOCK
 * rays from the first ray) evaluates exactly the samples the timed calls
 * did, and the batch counts them.
 */
static int count_render_samples(const nerf_renderer *r, size_t n,
                                const float *o, const float *d,
                                uint64_t *total)
{
    nerf__batch b;
    nerf__batch_init(&b, &r->env);
    nerf__render_setup s;
    nerf__renderer_eval_setup(r, &s);
    float rgb[3 * NERF__RENDER_BLOCK];
    nerf__pass_out out[NERF__PASSES];
    memset(out, 0, sizeof out);
    out[nerf__sampler_last_pass(r->sampler)].rgb = rgb;
    int rc = NERF_OK;
    *total = 0;
    for (size_t at = 0; at < n && rc == NERF_OK; at += NERF__RENDER_BLOCK) {
        size_t k = n - at < NERF__RENDER_BLOCK ? n - at : NERF__RENDER_BLOCK;
        s.first_ray = at;
        rc = nerf__render_batch(&b, &s, k, o + 3 * at, d + 3 * at, out);
        *total += b.n_evaluated;
    }
    nerf__batch_release(&b);
    return rc;
}

static int measure_render(preset_setup *p, uint32_t workers, double budget,
                          figures *f)
{
    nerf_renderer_options ro;
    NERF_RENDERER_OPTIONS_INIT(&ro);
    ro.threads = workers;
    ro.white_background = 1;
    const int blas_before = blas_threads();
    set_blas_threads(render_blas_threads);
    nerf_renderer *r = NULL;
    if (nerf_renderer_create(&r, p->model, p->eval_sampler, &ro) != NERF_OK) {
        set_blas_threads(blas_before);
        return -1;
    }
    /* Without marching, the top rows of an 800x800 view: cost does not
     * depend on where rays go, as nothing stops a ray early.  Marching:
     * a whole view (FAST_RENDER_SIDE). */
    nerf_camera cam;
    size_t n = RENDER_RAYS, warm = RENDER_RAYS / 2;
    if (p->march) {
        f->render_side = FAST_RENDER_SIDE;
        n = warm = (size_t)FAST_RENDER_SIDE * FAST_RENDER_SIDE;
        view_camera(&cam, FAST_RENDER_SIDE);
    } else {
        view_camera(&cam, 800);
    }
    float *o = malloc(n * 3 * sizeof(float));
    float *d = malloc(n * 3 * sizeof(float));
    float *rgb = malloc(n * 3 * sizeof(float));
    int rc = o && d && rgb ? nerf_camera_rays(&cam, 0, n, o, d) : NERF_ENOMEM;
    /* Warm-up: the workers allocate their scratch on their first block. */
    if (rc == NERF_OK) {
        rc = nerf_renderer_render_rays(r, warm, o, d, rgb, NULL, NULL);
    }
    uint64_t rays = 0;
    double t0 = now(), elapsed = 0.0;
    while (rc == NERF_OK && (elapsed < budget || rays == 0)) {
        rc = nerf_renderer_render_rays(r, n, o, d, rgb, NULL, NULL);
        rays += n;
        elapsed = now() - t0;
    }
    double per_ray = 0.0;
    if (rc == NERF_OK && p->march) {
        uint64_t total = 0;
        rc = count_render_samples(r, n, o, d, &total);
        per_ray = (double)total / (double)n;
    } else {
        per_ray = p->samples[0] + (p->passes > 1 ? p->samples[1] : 0);
    }
    f->render_workers = r->threads;
    f->render_blas_threads = blas_threads();
    nerf_renderer_destroy(r);
    set_blas_threads(blas_before);
    free(o);
    free(d);
    free(rgb);
    if (rc != NERF_OK) {
        return -1;
    }
    f->render_ok = 1;
    f->render_rays = rays;
    f->render_seconds = elapsed;
    f->render_rays_per_s = rays / elapsed;
    f->render_samples_per_ray = per_ray;
    f->render_samples_per_s = per_ray * f->render_rays_per_s;
    return 0;
}

/* ---- the building blocks of a marching training step -------------------- */

/* The encodings as lib/mlp/network.c runs them over the thread pool (same
 * splits and cost hints), outside the network. */
typedef struct enc_job {
    const nerf__network *net;
    const float *table, *in, *d_out;
    float *out, *grad;
    size_t n;
} enc_job;

static void hash_fw_rows(void *ctx, size_t begin, size_t end)
{
    const enc_job *j = ctx;
    nerf__hashgrid_forward_range(&j->net->hash, j->table, begin, end, j->in,
                                 3, j->out, j->net->pos_width);
}

/* Levels paired fine with coarse, as the network pairs them, so that
 * contiguous blocks cost about the same. */
static void hash_bw_level(void *ctx, size_t block)
{
    const enc_job *j = ctx;
    const uint32_t L = j->net->hash.levels;
    uint32_t level = block % 2 ? L - 1 - (uint32_t)(block / 2)
                               : (uint32_t)(block / 2);
    nerf__hashgrid_backward_level(&j->net->hash, level, j->n, j->in, 3,
                                  j->d_out, j->net->pos_width, j->grad);
}

static void sh_rows(void *ctx, size_t begin, size_t end)
{
    const enc_job *j = ctx;
    const size_t w = j->net->dir_width;
    nerf__sh_forward(j->net->sh_degree, end - begin, j->in + 3 * begin, 3,
                     j->out + begin * w, w);
}

typedef struct grid_ctx {
    nerf_model *m;
    nerf__workspace *ws;
} grid_ctx;

static int grid_density(void *ctx, size_t n, const float *xyz, float *sigma)
{
    grid_ctx *g = ctx;
    return nerf__model_density(g->m, 0, g->ws, n, xyz, sigma);
}

/*
 * Time the blocks of the trainer's last step in rounds until `budget`
 * seconds (at least three), then two grid refreshes.  Everything here
 * writes the model (gradients, Adam, the grid): it runs after every other
 * measurement of the preset.
 */
static int time_breakdown(nerf_trainer *t, double budget, step_breakdown *bd)
{
    nerf_model *m = t->model;
    nerf__batch *b = &t->batch;
    const nerf__network *net = &m->nets[0];
    nerf__occupancy *g = m->grid;
    memset(bd, 0, sizeof *bd);
    if (!b->marched || !b->kept || b->march.total == 0 || g == NULL ||
        !nerf__network_has_table(net) || !net->use_viewdirs ||
        net->dir_enc.kind != NERF_ENCODING_SPHERICAL_HARMONICS) {
        return -1;
    }
    const size_t n = b->march.total, B = b->n_rays;
    const uint64_t step = m->step; /* the Adam rounds below advance it */
    bd->rays = B;
    bd->samples = n;

    /* The step's march: render_march.c's training settings, the step's
     * rays and numbering. */
    const nerf_sampler_options *so = &t->sampler->opts;
    nerf__march_options mo;
    nerf__march_defaults(&mo, g);
    mo.step = nerf__march_step(g->lo, g->hi, so->march_steps);
    mo.max_samples = so->max_samples;
    mo.skip_empty = true;
    mo.jitter = so->perturb != 0;
    mo.seed = so->seed + UINT64_C(0xd1b54a32d192ed03) * NERF__STREAM_MARCH;
    mo.iteration = 0;
    nerf__march_rays rays = {.n = B, .origins = t->origins,
                             .dirs = t->directions, .near_all = so->t_near,
                             .far_all = so->t_far,
                             .first_ray = t->setup.first_ray};
    nerf__march_samples ms;
    nerf__march_samples_init(&ms, &m->env);
    int rc = nerf__march_run(g, &mo, &rays, &ms);
    const size_t n_march = ms.total > n ? ms.total : n;
    float *points = malloc(3 * n_march * sizeof(float));
    float *enc = malloc(n * net->pos_width * sizeof(float));
    float *d_enc = malloc(n * net->pos_width * sizeof(float));
    float *sh = malloc(n * net->dir_width * sizeof(float));
    float *rgb = malloc(3 * B * sizeof(float));
    if (rc != NERF_OK || !points || !enc || !d_enc || !sh || !rgb) {
        rc = -1;
        goto done;
    }
    const bool same =
        ms.total == n &&
        memcmp(ms.offsets, b->march.offsets, (B + 1) * sizeof(size_t)) == 0 &&
        memcmp(ms.t, b->march.t, n * sizeof(float)) == 0;
    for (size_t i = 0; i < n * net->pos_width; i++) {
        d_enc[i] = 1e-3f * (float)(i % 7);
    }
    enc_job hj = {.net = net, .table = m->params + net->table,
                  .in = b->march_points, .d_out = d_enc, .out = enc,
                  .grad = m->grads + net->table, .n = n};
    enc_job sj = {.net = net, .in = b->m_dirs, .out = sh, .n = n};
    nerf__packed_out po = {.rgb = rgb};

    /* Round 0 is untimed: it faults in the bench's own buffers, which the
     * step has long had. */
    double t0 = now();
    for (int round = 0;; round++) {
        if (round == 1) {
            memset(bd, 0, sizeof *bd);
            bd->rays = B;
            bd->samples = n;
            bd->same_samples = same;
            t0 = now();
        } else if (round > 1 && now() - t0 >= budget && bd->rounds >= 3) {
            break;
        }
        double a = now();
        rc = nerf__march_run(g, &mo, &rays, &ms);
        if (rc != NERF_OK) {
            goto done;
        }
        nerf__march_points(&rays, ms.offsets, ms.t, points);
        double c = now();
        bd->march += c - a;
        a = c;
        nerf__parallel_for(n, 200 * net->hash.levels, hash_fw_rows, &hj);
        c = now();
        bd->hash_fw += c - a;
        a = c;
        nerf__parallel_blocks(net->hash.levels, 200 * n, hash_bw_level, &hj);
        c = now();
        bd->hash_bw += c - a;
        a = c;
        nerf__parallel_for(n, 40, sh_rows, &sj);
        c = now();
        bd->sh_fw += c - a;
        /* The step itself, block by block. */
        a = c;
        /* As the step: a no-op after an Adam step, which zeroes them. */
        nerf__model_clear_grad(m);
        c = now();
        bd->zero_grad += c - a;
        a = c;
        rc = nerf__model_forward(m, 0, &b->ws[0], n, b->march_points,
                                 b->m_dirs, b->m_rgb, b->m_sigma);
        if (rc != NERF_OK) {
            goto done;
        }
        c = now();
        bd->net_fw += c - a;
        a = c;
        nerf__composite_packed(&b->packed, &po);
        c = now();
        bd->composite_fw += c - a;
        a = c;
        nerf__composite_packed_backward(&b->packed, t->d_rgb[0], NULL, NULL,
                                        b->m_d_rgb, b->m_d_sigma);
        c = now();
        bd->composite_bw += c - a;
        a = c;
        nerf__model_backward(m, 0, &b->ws[0], b->m_d_rgb, b->m_d_sigma);
        c = now();
        bd->net_bw += c - a;
        a = c;
        nerf__model_adam_step(m);
        c = now();
        bd->adam += c - a;
        bd->rounds += round > 0;
    }

    /* The refresh rule of the timed steps' regime. */
    const size_t n_random = nerf__grid_random_cells(step, g->cells);
    grid_ctx gc = {m, &t->density_ws};
    for (int i = 0; i < 2 && rc == NERF_OK; i++) {
        double a = now();
        rc = nerf__occupancy_update(g, grid_density, &gc, n_random);
        bd->grid_update += now() - a;
        bd->grid_updates++;
        bd->grid_cells_evaluated += g->evaluated;
    }
    if (rc != NERF_OK) {
        goto done;
    }
    const double r = bd->rounds;
    bd->march /= r;
    bd->hash_fw /= r;
    bd->hash_bw /= r;
    bd->sh_fw /= r;
    bd->zero_grad /= r;
    bd->net_fw /= r;
    bd->composite_fw /= r;
    bd->composite_bw /= r;
    bd->net_bw /= r;
    bd->adam /= r;
    bd->grid_update /= bd->grid_updates;
    bd->grid_cells_evaluated /= (size_t)bd->grid_updates;
    bd->ok = true;
done:
    nerf__march_samples_release(&ms);
    free(points);
    free(enc);
    free(d_enc);
    free(sh);
    free(rgb);
    return rc == NERF_OK ? 0 : -1;
}

static int measure(preset_setup *p, const nerf_dataset *ds, double budget,
                   uint32_t workers, uint32_t fast_warmup, figures *f)
{
    /* FLOPs per ray: the products of a one-ray step. */
    gemm_list *l = malloc(sizeof *l);
    if (l == NULL) {
        return -1;
    }
    double lib_fw = nerf__network_flops_per_sample(&p->model->nets[0]);
    if (p->march) {
        /* A variable number of samples per ray, and products far from
         * the step's main cost: no sgemm bound, the step's breakdown
         * instead. */
        f->flops_sample_fw = lib_fw;
    } else {
        step_products(l, p->model, p->passes, p->samples, 1);
        f->flops_train_ray = list_flops(l, true, true);
        f->flops_render_ray = list_flops(l, true, false);
        f->flops_sample_fw =
            list_flops(l, true, false) /
            (p->samples[0] + (p->passes > 1 ? p->samples[1] : 0));
        if (fabs(lib_fw - f->flops_sample_fw) > 0.5) {
            fprintf(stderr,
                    "nerf-bench: warning: %s: %.0f forward FLOPs per "
                    "sample from the shapes, the library counts %.0f\n",
                    p->name, f->flops_sample_fw, lib_fw);
        }
    }
    f->params = nerf_model_param_count(p->model);

    /* The sgemm rate is taken before training and again after rendering,
     * and the better of the two kept: on a shared machine the load
     * changes between measurements, and the bound is what the machine
     * can do, so a disturbed run should not lower it. */
    const char *failed = NULL;
    if (!p->march) {
        step_products(l, p->model, p->passes, p->samples, (int)BATCH_RAYS);
        f->gemm_calls = l->count;
        fprintf(stderr,
                "nerf-bench: %s: sgemm on a training step's products...\n",
                p->name);
        if (time_products(l, budget, &f->runs[0]) != 0) {
            failed = "sgemm: out of memory";
        }
    }
    nerf_trainer *kept = NULL;
    if (!failed) {
        if (p->march) {
            fprintf(stderr, "nerf-bench: %s: training (%u warm-up steps)...\n",
                    p->name, fast_warmup);
        } else {
            fprintf(stderr, "nerf-bench: %s: training...\n", p->name);
        }
        if (measure_training(p, ds, budget, fast_warmup, f,
                             p->march ? &kept : NULL) != 0) {
            failed = "training";
        }
    }
    if (!failed) {
        fprintf(stderr, "nerf-bench: %s: rendering...\n", p->name);
        if (measure_render(p, workers, budget, f) != 0) {
            failed = "rendering";
        }
    }
    if (!failed && !p->march) {
        fprintf(stderr, "nerf-bench: %s: sgemm again...\n", p->name);
        if (time_products(l, budget, &f->runs[1]) != 0) {
            failed = "sgemm: out of memory";
        }
    }
    if (!failed && p->march) {
        fprintf(stderr,
                "nerf-bench: %s: timing a training step's parts...\n",
                p->name);
        if (time_breakdown(kept, budget, &f->bd) != 0) {
            failed = "the step's parts";
        } else if (!f->bd.same_samples) {
            fprintf(stderr,
                    "nerf-bench: warning: %s: the bench's march did not "
                    "reproduce the step's samples; the compositing figure "
                    "is for a different sample set\n",
                    p->name);
        }
    }
    nerf_trainer_destroy(kept);
    free(l);
    f->bf16_primitives = p->model->bf16 ? nerf__bf16_primitives(p->model->bf16)
                                        : 0;
    if (failed) {
        fprintf(stderr, "nerf-bench: %s: %s: %s\n", p->name, failed,
                nerf_last_error());
        return -1;
    }
    f->gemm.gflops_step = fmax(f->runs[0].gflops_step, f->runs[1].gflops_step);
    f->gemm.gflops_forward =
        fmax(f->runs[0].gflops_forward, f->runs[1].gflops_forward);
    f->gemm.reps = f->runs[0].reps + f->runs[1].reps;
    f->gemm.seconds = f->runs[0].seconds + f->runs[1].seconds;
    f->ran = true;
    return 0;
}

/* ---- derived figures ---------------------------------------------------- */

static double train_bound(const figures *f)
{
    return f->gemm.gflops_step * 1e9 / f->flops_train_ray;
}

static double render_bound(const figures *f)
{
    return f->gemm.gflops_forward * 1e9 / f->flops_render_ray;
}

/* ---- output ------------------------------------------------------------- */

typedef struct run_info {
    double seconds;
    int threads_requested; /* 0: not given */
    uint32_t workers_requested;
    uint32_t cores;
    int blas_threads;
    uint32_t render_side, rss_rows;
    bool full, no_rss;
    uint32_t train_side, train_views;
    const char *data; /* --data: a scene's training split, else NULL */
    uint32_t downscale;
    double load_start[3], load_end[3];
    double total_seconds;
} run_info;

static const char *rss_method(const rss_result *r, char *buf, size_t size)
{
    if (r->full) {
        snprintf(buf, size,
                 "whole %ux%u nerf_renderer_render_image in a "
                 "forked child, %u worker(s); VmHWM at the end",
                 (unsigned)sqrt((double)r->rays_total),
                 (unsigned)sqrt((double)r->rays_total), r->workers);
    } else {
        snprintf(buf, size,
                 "%ux%u nerf_renderer_render_image in a forked "
                 "child, %u worker(s), full-size outputs touched up front, "
                 "cancelled by its progress callback after %llu of %llu rays "
                 "(the first rows); VmHWM at that point (scratch is allocated "
                 "on each worker's first block and does not grow)",
                 (unsigned)sqrt((double)r->rays_total),
                 (unsigned)sqrt((double)r->rays_total), r->workers,
                 (unsigned long long)r->rays_done,
                 (unsigned long long)r->rays_total);
    }
    return buf;
}

static void add_memory(cJSON *o, const figures *f, const run_info *ri);

/* Seconds per step of each part, and shares of their sum. */
static cJSON *breakdown_json(const figures *f)
{
    const step_breakdown *b = &f->bd;
    if (!b->ok) {
        return cJSON_CreateNull();
    }
    const step_shares sh = shares_of(b);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(
        o, "method",
        "the library's building blocks timed one by one in the bench, each "
        "called as the training step calls it, on the packed samples of "
        "the last timed step, in interleaved rounds (mean per call); "
        "shares are of the sum of the parts; mlp = network forward + "
        "backward less the encoding; grid = one occupancy-grid refresh / "
        "16; the rest of the step is step_seconds - sum_seconds");
    cJSON_AddNumberToObject(o, "rays", (double)b->rays);
    cJSON_AddNumberToObject(o, "samples", (double)b->samples);
    cJSON_AddNumberToObject(o, "rounds", b->rounds);
    cJSON_AddBoolToObject(o, "march_reproduced_step", b->same_samples);
    cJSON_AddNumberToObject(o, "step_seconds",
                            f->train_seconds / f->train_steps);
    cJSON_AddNumberToObject(o, "sum_seconds", sh.sum);
    cJSON *sec = cJSON_AddObjectToObject(o, "seconds");
    cJSON_AddNumberToObject(sec, "march", b->march);
    cJSON_AddNumberToObject(sec, "hash_forward", b->hash_fw);
    cJSON_AddNumberToObject(sec, "hash_backward", b->hash_bw);
    cJSON_AddNumberToObject(sec, "sh_forward", b->sh_fw);
    cJSON_AddNumberToObject(sec, "network_forward", b->net_fw);
    cJSON_AddNumberToObject(sec, "network_backward", b->net_bw);
    cJSON_AddNumberToObject(sec, "composite_forward", b->composite_fw);
    cJSON_AddNumberToObject(sec, "composite_backward", b->composite_bw);
    cJSON_AddNumberToObject(sec, "zero_grad", b->zero_grad);
    cJSON_AddNumberToObject(sec, "adam", b->adam);
    cJSON_AddNumberToObject(sec, "grid_refresh", b->grid_update);
    cJSON_AddNumberToObject(sec, "grid_refresh_cells",
                            (double)b->grid_cells_evaluated);
    cJSON *shares = cJSON_AddObjectToObject(o, "shares");
    cJSON_AddNumberToObject(shares, "encoding", sh.encoding / sh.sum);
    cJSON_AddNumberToObject(shares, "mlp", sh.mlp / sh.sum);
    cJSON_AddNumberToObject(shares, "compositing", sh.compositing / sh.sum);
    cJSON_AddNumberToObject(shares, "optimiser", sh.optimiser / sh.sum);
    cJSON_AddNumberToObject(shares, "grid", sh.grid / sh.sum);
    return o;
}

static cJSON *preset_json(const preset_setup *p, const figures *f,
                          const run_info *ri)
{
    const nerf__network *net = &p->model->nets[0];
    cJSON *o = cJSON_CreateObject();
    cJSON *n = cJSON_AddObjectToObject(o, "network");
    cJSON_AddNumberToObject(n, "depth", net->depth);
    cJSON_AddNumberToObject(n, "width", net->width);
    cJSON_AddNumberToObject(n, "skip_layer", net->skip);
    cJSON_AddNumberToObject(n, "view_width", net->view_width);
    cJSON_AddNumberToObject(n, "pos_encoded_width", net->pos_width);
    cJSON_AddNumberToObject(n, "dir_encoded_width", net->dir_width);
    cJSON_AddNumberToObject(n, "networks", p->model->n_nets);
    cJSON_AddNumberToObject(n, "params", (double)f->params);
    if (p->march) {
        cJSON_AddNumberToObject(n, "view_depth", net->view_depth);
        cJSON_AddNumberToObject(n, "geo_features", net->geo_features);
        cJSON_AddNumberToObject(n, "sh_degree", net->sh_degree);
        cJSON *h = cJSON_AddObjectToObject(n, "hash_grid");
        cJSON_AddNumberToObject(h, "levels", net->hash.levels);
        cJSON_AddNumberToObject(h, "features", net->hash.features);
        cJSON_AddNumberToObject(h, "log2_table", net->hash.log2_table);
        cJSON_AddNumberToObject(h, "min_resolution", net->hash.min_resolution);
        cJSON_AddNumberToObject(h, "max_resolution", net->hash.max_resolution);
        cJSON_AddNumberToObject(h, "table_params", (double)net->hash.count);
        const nerf_sampler_options *so = &p->train_sampler->opts;
        cJSON_AddNumberToObject(o, "march_steps", so->march_steps);
        cJSON_AddNumberToObject(o, "max_samples", so->max_samples);
        /* Measured, not fixed: the marched samples per ray. */
        cJSON_AddNumberToObject(o, "network_samples_per_ray",
                                f->train_samples_per_ray);
    } else {
        cJSON_AddNumberToObject(o, "n_coarse", p->n_coarse);
        cJSON_AddNumberToObject(o, "n_fine", p->n_fine);
        cJSON_AddNumberToObject(o, "network_samples_per_ray",
                                p->samples[0] +
                                    (p->passes > 1 ? p->samples[1] : 0));
    }

    cJSON_AddNumberToObject(o, "train_rays_per_s", f->train_rays_per_s);
    cJSON_AddNumberToObject(o, "render_rays_per_s", f->render_rays_per_s);
    cJSON_AddNumberToObject(o, "train_samples_per_s", f->train_samples_per_s);
    cJSON_AddNumberToObject(o, "render_samples_per_s",
                            f->render_samples_per_s);
    cJSON_AddNumberToObject(o, "train_samples_per_ray",
                            f->train_samples_per_ray);
    cJSON_AddNumberToObject(o, "render_samples_per_ray",
                            f->render_samples_per_ray);

    cJSON_AddNumberToObject(o, "batch_rays", BATCH_RAYS);
    cJSON_AddNumberToObject(o, "train_image_size", ri->train_side);
    cJSON_AddNumberToObject(o, "train_views", ri->train_views);
    if (ri->data) {
        cJSON_AddStringToObject(o, "train_data", ri->data);
        cJSON_AddNumberToObject(o, "train_downscale", ri->downscale);
    }
    cJSON_AddNumberToObject(o, "train_warmup_steps", f->warmup_steps);
    cJSON_AddNumberToObject(o, "train_steps_timed", f->train_steps);
    cJSON_AddNumberToObject(o, "train_seconds_timed", f->train_seconds);
    cJSON_AddNumberToObject(o, "train_seconds_per_step",
                            f->train_seconds / f->train_steps);
    cJSON_AddNumberToObject(o, "train_fastest_step_seconds",
                            f->train_fastest_step);
    cJSON_AddNumberToObject(o, "train_last_loss", f->train_loss);
    cJSON_AddNumberToObject(o, "render_rays_timed", (double)f->render_rays);
    cJSON_AddNumberToObject(o, "render_seconds_timed", f->render_seconds);
    cJSON_AddNumberToObject(o, "render_workers", f->render_workers);
    cJSON_AddNumberToObject(o, "render_blas_threads", f->render_blas_threads);
    cJSON_AddNumberToObject(o, "bf16_primitives", (double)f->bf16_primitives);

    cJSON_AddNumberToObject(o, "flops_per_sample_forward", f->flops_sample_fw);
    if (p->march) {
        cJSON_AddNumberToObject(o, "train_warmup_seconds", f->warmup_seconds);
        cJSON_AddNumberToObject(o, "train_warmup_psnr", f->warmup_psnr);
        cJSON_AddNumberToObject(o, "train_last_psnr", f->train_psnr);
        cJSON_AddNumberToObject(o, "train_last_step",
                                (double)f->train_last_step);
        cJSON_AddNumberToObject(o, "grid_occupied_fraction", f->grid_occupied);
        cJSON_AddNumberToObject(o, "render_image_side", f->render_side);
        cJSON_AddStringToObject(
            o, "render_method",
            "nerf_renderer_render_rays on every pixel of the 800x800 view's "
            "camera at render_image_side pixels, the model as trained; "
            "samples counted by replaying the call in the renderer's "
            "blocks");
        cJSON_AddItemToObject(o, "train_step_breakdown",
                              breakdown_json(f));
        add_memory(o, f, ri);
        return o;
    }
    cJSON_AddNumberToObject(o, "flops_per_train_ray", f->flops_train_ray);
    cJSON_AddNumberToObject(o, "flops_per_render_ray", f->flops_render_ray);
    cJSON_AddNumberToObject(o, "sgemm_gflops", f->gemm.gflops_step);
    cJSON_AddNumberToObject(o, "sgemm_forward_gflops", f->gemm.gflops_forward);
    cJSON_AddNumberToObject(o, "sgemm_calls_per_step", f->gemm_calls);
    cJSON_AddNumberToObject(o, "sgemm_steps_timed", f->gemm.reps);
    cJSON_AddNumberToObject(o, "sgemm_seconds_timed", f->gemm.seconds);
    const double runs[2] = {f->runs[0].gflops_step, f->runs[1].gflops_step};
    cJSON_AddItemToObject(o, "sgemm_gflops_runs",
                          cJSON_CreateDoubleArray(runs, 2));
    cJSON_AddNumberToObject(o, "train_sgemm_bound_rays_per_s", train_bound(f));
    cJSON_AddNumberToObject(o, "render_sgemm_bound_rays_per_s",
                            render_bound(f));
    cJSON_AddNumberToObject(o, "train_sgemm_share",
                            f->train_rays_per_s / train_bound(f));
    cJSON_AddNumberToObject(o, "render_sgemm_share",
                            f->render_rays_per_s / render_bound(f));
    cJSON_AddNumberToObject(o, "train_gflops",
                            f->train_rays_per_s * f->flops_train_ray * 1e-9);
    cJSON_AddNumberToObject(o, "render_gflops",
                            f->render_rays_per_s * f->flops_render_ray * 1e-9);

    add_memory(o, f, ri);
    return o;
}

static void add_memory(cJSON *o, const figures *f, const run_info *ri)
{
    if (f->rss_skipped || !f->rss.ok) {
        cJSON_AddNullToObject(o, "peak_rss_mb");
    } else {
        const rss_result *r = &f->rss;
        char buf[512];
        cJSON_AddNumberToObject(o, "peak_rss_mb",
                                r->hwm_mb > 0 ? r->hwm_mb : r->maxrss_mb);
        cJSON *m = cJSON_AddObjectToObject(o, "peak_rss");
        cJSON_AddNumberToObject(m, "vm_hwm_mb", r->hwm_mb);
        cJSON_AddNumberToObject(m, "ru_maxrss_mb", r->maxrss_mb);
        cJSON_AddNumberToObject(m, "outputs_mb", r->outputs_mb);
        cJSON_AddNumberToObject(m, "before_render_mb", r->model_mb);
        cJSON_AddNumberToObject(m, "image_side", ri->render_side);
        cJSON_AddBoolToObject(m, "whole_image", r->full);
        cJSON_AddNumberToObject(m, "rays_rendered", (double)r->rays_done);
        cJSON_AddNumberToObject(m, "rays_total", (double)r->rays_total);
        cJSON_AddNumberToObject(m, "seconds", r->seconds);
        cJSON_AddNumberToObject(m, "workers", r->workers);
        cJSON_AddStringToObject(m, "method", rss_method(r, buf, sizeof buf));
    }
}

static cJSON *load_json(const double l[3])
{
    if (l[0] < 0.0) {
        return cJSON_CreateNull();
    }
    const double v[3] = {l[0], l[1], l[2]};
    return cJSON_CreateDoubleArray(v, 3);
}

static void print_json(const run_info *ri, const preset_setup *ps,
                       const figures *fs, int n_presets)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "tool", "nerf-bench");
    cJSON_AddStringToObject(root, "libnerf_version", nerf_version_string());
    cJSON_AddStringToObject(root, "build_info", nerf_build_info());
    cJSON_AddStringToObject(root, "matmul",
                            bench_matmul == NERF_MATMUL_BF16 ? "bf16" : "fp32");
    const char *cfg = blas_config(), *core = blas_corename();
    const char *coretype = getenv("OPENBLAS_CORETYPE");
    if (cfg) {
        cJSON_AddStringToObject(root, "blas_config", cfg);
    } else {
        cJSON_AddNullToObject(root, "blas_config");
    }
    if (core) {
        cJSON_AddStringToObject(root, "blas_corename", core);
    } else {
        cJSON_AddNullToObject(root, "blas_corename");
    }
    if (coretype) {
        cJSON_AddStringToObject(root, "openblas_coretype_env", coretype);
    } else {
        cJSON_AddNullToObject(root, "openblas_coretype_env");
    }
    cJSON *th = cJSON_AddObjectToObject(root, "threads");
    cJSON_AddNumberToObject(th, "cores", ri->cores);
    cJSON_AddNumberToObject(th, "openblas", ri->blas_threads);
    if (ri->threads_requested > 0) {
        cJSON_AddNumberToObject(th, "requested", ri->threads_requested);
    } else {
        cJSON_AddNullToObject(th, "requested");
    }
    cJSON_AddNumberToObject(th, "render_workers_requested",
                            ri->workers_requested);
    cJSON_AddStringToObject(th, "training",
                            "one calling thread; the products run on "
                            "OpenBLAS's threads");
    cJSON_AddNumberToObject(root, "seconds_per_measurement", ri->seconds);
    cJSON_AddItemToObject(root, "load_average_start",
                          load_json(ri->load_start));
    cJSON_AddItemToObject(root, "load_average_end", load_json(ri->load_end));
    cJSON_AddNumberToObject(root, "total_seconds", ri->total_seconds);
    for (int i = 0; i < n_presets; i++) {
        if (fs[i].ran) {
            cJSON_AddItemToObject(root, ps[i].name,
                                  preset_json(&ps[i], &fs[i], ri));
        }
    }
    char *text = cJSON_Print(root);
    if (text) {
        fputs(text, stdout);
        fputc('\n', stdout);
        cJSON_free(text);
    }
    cJSON_Delete(root);
}

/* A row of the table: one label, one figure per preset that ran. */
typedef void (*cell_fn)(char *buf, size_t size, const preset_setup *p,
                        const figures *f);

static void row(FILE *out, const char *label, cell_fn cell,
                const preset_setup *ps, const figures *fs, int n)
{
    fprintf(out, "%-38s", label);
    for (int i = 0; i < n; i++) {
        if (fs[i].ran) {
            char buf[64];
            cell(buf, sizeof buf, &ps[i], &fs[i]);
            fprintf(out, " %26s", buf);
        }
    }
    fputc('\n', out);
}

/* Thousands separated by commas, for figures read by people. */
static void grouped(char *buf, size_t size, double v)
{
    char digits[32];
    snprintf(digits, sizeof digits, "%.0f", v);
    size_t len = strlen(digits), o = 0;
    for (size_t i = 0; i < len && o + 2 < size; i++) {
        if (i > 0 && digits[i - 1] != '-' && (len - i) % 3 == 0) {
            buf[o++] = ',';
        }
        buf[o++] = digits[i];
    }
    buf[o] = '\0';
}

/* The figures a marching preset has not: no fixed sample count, no sgemm
 * bound. */
static bool no_bound(char *b, size_t s, const preset_setup *p)
{
    if (p->march) {
        snprintf(b, s, "-");
    }
    return p->march;
}

static void c_net(char *b, size_t s, const preset_setup *p, const figures *f)
{
    const nerf__network *n = &p->model->nets[0];
    if (nerf__network_has_table(n)) {
        snprintf(b, s, "hash %ux%u, %ux%u, view %ux%u", n->hash.levels,
                 n->hash.features, n->depth, n->width, n->view_depth,
                 n->view_width);
    } else {
        snprintf(b, s, "%ux%u, view %u", n->depth, n->width, n->view_width);
    }
}
static void c_samples(char *b, size_t s, const preset_setup *p,
                      const figures *f)
{
    if (p->march) {
        snprintf(b, s, "marched, <= %u",
                 p->train_sampler->opts.max_samples);
    } else {
        snprintf(b, s, "%u + %u", p->n_coarse, p->n_fine);
    }
}
static void c_fl_sample(char *b, size_t s, const preset_setup *p,
                        const figures *f)
{
    grouped(b, s, f->flops_sample_fw);
}
static void c_fl_train(char *b, size_t s, const preset_setup *p,
                       const figures *f)
{
    if (!no_bound(b, s, p)) {
        grouped(b, s, f->flops_train_ray);
    }
}
static void c_fl_render(char *b, size_t s, const preset_setup *p,
                        const figures *f)
{
    if (!no_bound(b, s, p)) {
        grouped(b, s, f->flops_render_ray);
    }
}
static void c_gemm(char *b, size_t s, const preset_setup *p, const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f", f->gemm.gflops_step);
    }
}
static void c_gemm_runs(char *b, size_t s, const preset_setup *p,
                        const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f, %.1f", f->runs[0].gflops_step,
                 f->runs[1].gflops_step);
    }
}
static void c_gemm_fw(char *b, size_t s, const preset_setup *p,
                      const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f", f->gemm.gflops_forward);
    }
}
static void c_warmup(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    snprintf(b, s, "%d in %.1f s", f->warmup_steps, f->warmup_seconds);
}
static void c_warmup_psnr(char *b, size_t s, const preset_setup *p,
                          const figures *f)
{
    snprintf(b, s, "%.1f / %.1f dB", f->warmup_psnr, f->train_psnr);
}
static void c_grid(char *b, size_t s, const preset_setup *p, const figures *f)
{
    if (p->march) {
        snprintf(b, s, "%.2f%%", 100.0 * f->grid_occupied);
    } else {
        snprintf(b, s, "-");
    }
}
static void c_train(char *b, size_t s, const preset_setup *p, const figures *f)
{
    grouped(b, s, f->train_rays_per_s);
}
static void c_train_spr(char *b, size_t s, const preset_setup *p,
                        const figures *f)
{
    snprintf(b, s, "%.1f", f->train_samples_per_ray);
}
static void c_train_sps(char *b, size_t s, const preset_setup *p,
                        const figures *f)
{
    grouped(b, s, f->train_samples_per_s);
}
static void c_step(char *b, size_t s, const preset_setup *p, const figures *f)
{
    snprintf(b, s, "%.1f ms", 1e3 * f->train_seconds / f->train_steps);
}
static void c_train_steps(char *b, size_t s, const preset_setup *p,
                          const figures *f)
{
    snprintf(b, s, "%d in %.1f s", f->train_steps, f->train_seconds);
}
static void c_train_fastest(char *b, size_t s, const preset_setup *p,
                            const figures *f)
{
    snprintf(b, s, "%.2f s", f->train_fastest_step);
}
static void c_train_bound(char *b, size_t s, const preset_setup *p,
                          const figures *f)
{
    if (!no_bound(b, s, p)) {
        grouped(b, s, train_bound(f));
    }
}
static void c_train_share(char *b, size_t s, const preset_setup *p,
                          const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f%%",
                 100.0 * f->train_rays_per_s / train_bound(f));
    }
}
static void c_train_gf(char *b, size_t s, const preset_setup *p,
                       const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f",
                 f->train_rays_per_s * f->flops_train_ray * 1e-9);
    }
}
static void c_render(char *b, size_t s, const preset_setup *p, const figures *f)
{
    grouped(b, s, f->render_rays_per_s);
}
static void c_render_spr(char *b, size_t s, const preset_setup *p,
                         const figures *f)
{
    snprintf(b, s, "%.1f", f->render_samples_per_ray);
}
static void c_render_sps(char *b, size_t s, const preset_setup *p,
                         const figures *f)
{
    grouped(b, s, f->render_samples_per_s);
}
static void c_render_rays(char *b, size_t s, const preset_setup *p,
                          const figures *f)
{
    snprintf(b, s, "%llu in %.1f s", (unsigned long long)f->render_rays,
             f->render_seconds);
}
static void c_render_bound(char *b, size_t s, const preset_setup *p,
                           const figures *f)
{
    if (!no_bound(b, s, p)) {
        grouped(b, s, render_bound(f));
    }
}
static void c_render_share(char *b, size_t s, const preset_setup *p,
                           const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f%%",
                 100.0 * f->render_rays_per_s / render_bound(f));
    }
}
static void c_render_gf(char *b, size_t s, const preset_setup *p,
                        const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f",
                 f->render_rays_per_s * f->flops_render_ray * 1e-9);
    }
}

/* A category of a marching step's breakdown: its share of the blocks' sum
 * and its milliseconds per step. */
static void share_cell(char *b, size_t s, const figures *f, double part)
{
    if (!f->bd.ok) {
        snprintf(b, s, "-");
        return;
    }
    snprintf(b, s, "%.1f%% (%.1f ms)", 100.0 * part / shares_of(&f->bd).sum,
             1e3 * part);
}
static void c_enc(char *b, size_t s, const preset_setup *p, const figures *f)
{
    share_cell(b, s, f, shares_of(&f->bd).encoding);
}
static void c_mlp(char *b, size_t s, const preset_setup *p, const figures *f)
{
    share_cell(b, s, f, shares_of(&f->bd).mlp);
}
static void c_comp(char *b, size_t s, const preset_setup *p, const figures *f)
{
    share_cell(b, s, f, shares_of(&f->bd).compositing);
}
static void c_opt(char *b, size_t s, const preset_setup *p, const figures *f)
{
    share_cell(b, s, f, shares_of(&f->bd).optimiser);
}
static void c_gridup(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    share_cell(b, s, f, shares_of(&f->bd).grid);
}
static void c_bd_sum(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    if (!f->bd.ok) {
        snprintf(b, s, "-");
        return;
    }
    const double step = f->train_seconds / f->train_steps;
    snprintf(b, s, "%.1f ms (%.0f%% of step)", 1e3 * shares_of(&f->bd).sum,
             100.0 * shares_of(&f->bd).sum / step);
}
static void c_bd_samples(char *b, size_t s, const preset_setup *p,
                         const figures *f)
{
    if (!f->bd.ok) {
        snprintf(b, s, "-");
        return;
    }
    snprintf(b, s, "%zu, %d rounds", f->bd.samples, f->bd.rounds);
}
static void c_prims(char *b, size_t s, const preset_setup *p,
                    const figures *f)
{
    snprintf(b, s, "%zu", f->bf16_primitives);
}
static void c_workers(char *b, size_t s, const preset_setup *p,
                      const figures *f)
{
    snprintf(b, s, "%u x %d BLAS", f->render_workers, f->render_blas_threads);
}
static void c_rss(char *b, size_t s, const preset_setup *p, const figures *f)
{
    if (f->rss_skipped) {
        snprintf(b, s, "skipped");
    } else if (!f->rss.ok) {
        snprintf(b, s, "failed");
    } else {
        snprintf(b, s, "%.1f MB",
                 f->rss.hwm_mb > 0 ? f->rss.hwm_mb : f->rss.maxrss_mb);
    }
}
static void c_rss_rays(char *b, size_t s, const preset_setup *p,
                       const figures *f)
{
    if (f->rss_skipped || !f->rss.ok) {
        snprintf(b, s, "-");
    } else if (f->rss.full) {
        snprintf(b, s, "all, %.0f s", f->rss.seconds);
    } else {
        snprintf(b, s, "%llu, %.0f s", (unsigned long long)f->rss.rays_done,
                 f->rss.seconds);
    }
}

static void print_table(FILE *out, const run_info *ri, const preset_setup *ps,
                        const figures *fs, int n)
{
    const char *cfg = blas_config(), *core = blas_corename();
    const char *coretype = getenv("OPENBLAS_CORETYPE");
    fprintf(out, "nerf-bench: %s\n", nerf_build_info());
    fprintf(out, "BLAS: %s%s%s%s%s\n", cfg ? cfg : "(not OpenBLAS)",
            core ? ", core " : "", core ? core : "",
            coretype ? ", OPENBLAS_CORETYPE=" : "", coretype ? coretype : "");
    fprintf(out,
            "threads: %u cores online; OpenBLAS %d thread(s)%s; "
            "training: one calling thread\n",
            ri->cores, ri->blas_threads,
            ri->threads_requested > 0 ? " (--threads)" : "");
    if (bench_matmul == NERF_MATMUL_BF16) {
        fprintf(out, "matmul: bf16 (oneDNN, cut over libnerf's %u "
                "threads); the sgemm rows are fp32 cblas_sgemm, so a share "
                "is bf16 rays/s over the fp32 bound\n",
                nerf__parallel_threads());
    } else {
        fprintf(out, "matmul: fp32 (cblas_sgemm)\n");
    }
    if (ri->load_start[0] >= 0.0) {
        fprintf(out,
                "load average: %.2f %.2f %.2f at the start, %.2f %.2f "
                "%.2f at the end\n",
                ri->load_start[0], ri->load_start[1], ri->load_start[2],
                ri->load_end[0], ri->load_end[1], ri->load_end[2]);
    }
    fprintf(out, "%.1f s per measurement, %.0f s in all\n\n", ri->seconds,
            ri->total_seconds);

    fprintf(out, "%-38s", "");
    for (int i = 0; i < n; i++) {
        if (fs[i].ran) {
            fprintf(out, " %26s", ps[i].name);
        }
    }
    fputc('\n', out);
    bool any_march = false;
    for (int i = 0; i < n; i++) {
        any_march = any_march || (fs[i].ran && ps[i].march);
    }
    row(out, "network (trunk, view branch)", c_net, ps, fs, n);
    row(out, "samples per ray (coarse + fine)", c_samples, ps, fs, n);
    row(out, "FLOPs per sample, forward", c_fl_sample, ps, fs, n);
    row(out, "FLOPs per training ray (fwd+bwd)", c_fl_train, ps, fs, n);
    row(out, "FLOPs per rendered ray", c_fl_render, ps, fs, n);
    row(out, "sgemm GFLOP/s, step products", c_gemm, ps, fs, n);
    row(out, "  the two runs", c_gemm_runs, ps, fs, n);
    row(out, "sgemm GFLOP/s, forward products", c_gemm_fw, ps, fs, n);
    row(out, "train rays/s (1024-ray steps)", c_train, ps, fs, n);
    row(out, "  train samples/s", c_train_sps, ps, fs, n);
    row(out, "  network samples per ray", c_train_spr, ps, fs, n);
    row(out, "  timed steps", c_train_steps, ps, fs, n);
    row(out, "  mean step", c_step, ps, fs, n);
    row(out, "  fastest step", c_train_fastest, ps, fs, n);
    if (any_march) {
        row(out, "  warm-up steps", c_warmup, ps, fs, n);
        row(out, "  PSNR after warm-up / at end", c_warmup_psnr, ps, fs, n);
        row(out, "  occupancy grid cells occupied", c_grid, ps, fs, n);
    }
    row(out, "  GFLOP/s", c_train_gf, ps, fs, n);
    row(out, "  sgemm-bound rays/s", c_train_bound, ps, fs, n);
    row(out, "  train_sgemm_share", c_train_share, ps, fs, n);
    row(out, "render rays/s", c_render, ps, fs, n);
    row(out, "  render samples/s", c_render_sps, ps, fs, n);
    row(out, "  network samples per ray", c_render_spr, ps, fs, n);
    row(out, "  timed rays", c_render_rays, ps, fs, n);
    row(out, "  renderer workers x BLAS threads", c_workers, ps, fs, n);
    row(out, "  GFLOP/s", c_render_gf, ps, fs, n);
    row(out, "  sgemm-bound rays/s", c_render_bound, ps, fs, n);
    row(out, "  render_sgemm_share", c_render_share, ps, fs, n);
    if (bench_matmul == NERF_MATMUL_BF16) {
        row(out, "oneDNN primitives (bf16)", c_prims, ps, fs, n);
    }
    char label[64];
    snprintf(label, sizeof label, "peak RSS, %ux%u render", ri->render_side,
             ri->render_side);
    row(out, label, c_rss, ps, fs, n);
    row(out, "  rays rendered for it", c_rss_rays, ps, fs, n);
    if (any_march) {
        row(out, "training step: encoding", c_enc, ps, fs, n);
        row(out, "  MLP", c_mlp, ps, fs, n);
        row(out, "  compositing (march, fwd, bwd)", c_comp, ps, fs, n);
        row(out, "  optimiser (zero grads, Adam)", c_opt, ps, fs, n);
        row(out, "  grid refresh (1/16 per step)", c_gridup, ps, fs, n);
        row(out, "  sum of the parts", c_bd_sum, ps, fs, n);
        row(out, "  timed on samples", c_bd_samples, ps, fs, n);
    }

    if (ri->data) {
        fprintf(out, "\nTraining: %u-ray steps on the training split of "
                "%s (%u views of %ux%u)", BATCH_RAYS, ri->data,
                ri->train_views, ri->train_side, ri->train_side);
    } else {
        fprintf(out, "\nTraining: %u-ray steps on the built-in scene (%u "
                "views of %ux%u)", BATCH_RAYS, ri->train_views,
                ri->train_side, ri->train_side);
    }
    fprintf(out,
            ", after the warm-up steps.  Rendering: "
            "nerf_renderer_render_rays on %u rays of an 800x800 view per "
            "call, after a warm-up call.\n",
            RENDER_RAYS);
    fprintf(out, "sgemm: the products of one training step (per layer "
                 "Y = X W^T, dW = dY^T X, dX = dY W; coarse net on 1024 x "
                 "n_coarse samples, fine net on 1024 x (n_coarse + n_fine)), "
                 "timed call by call before training and again after "
                 "rendering, the better rate kept; the render bound uses the "
                 "forward products' rate.\n");
    if (any_march) {
        fprintf(out,
                "fast: training timed in whole cycles of %u steps (one "
                "occupancy-grid refresh each) after the warm-up steps "
                "(grid fully refreshed every %u steps before step %u, "
                "occupied cells and a sixteenth of the others after).  "
                "Samples: network evaluations (stats.samples_per_ray in "
                "training; rendering: counted by replaying the timed call "
                "in the renderer's blocks of %u rays).  Rendering: "
                "nerf_renderer_render_rays on every pixel of the 800x800 "
                "view's camera at %ux%u, model as trained, after a "
                "warm-up call.\n",
                NERF__GRID_EVERY, NERF__GRID_EVERY, NERF__GRID_WARMUP,
                NERF__RENDER_BLOCK, FAST_RENDER_SIDE, FAST_RENDER_SIDE);
        fprintf(out,
                "fast, training step: the library's building blocks timed "
                "one by one in the bench (no timers in the library) on the "
                "packed samples of the last timed step, each called as the "
                "step calls it; percentages of their sum, which is set "
                "beside the mean step.  encoding = hash grid forward + "
                "backward + SH; MLP = the network's forward + backward "
                "less the encoding; compositing = march + points, "
                "composite forward + backward; optimiser = Adam (which "
                "zeroes the gradients as it reads them); grid refresh = "
                "one refresh / %u.  The "
                "rest of the step (ray drawing, loss, direction copies) is "
                "the gap to 100%%.\n",
                NERF__GRID_EVERY);
    }
    for (int i = 0; i < n; i++) {
        if (fs[i].ran && !fs[i].rss_skipped && fs[i].rss.ok) {
            char buf[512];
            fprintf(out, "peak RSS, %s: %s.\n", ps[i].name,
                    rss_method(&fs[i].rss, buf, sizeof buf));
        }
    }
}

/* ---- main --------------------------------------------------------------- */

/* --data: a real scene's training images; the run records their size. */
static nerf_dataset *load_dataset(run_info *ri)
{
    nerf_dataset_options o;
    NERF_DATASET_OPTIONS_INIT(&o);
    o.downscale = ri->downscale;
    nerf_dataset *ds = NULL;
    if (nerf_dataset_load(&ds, ri->data, &o) != NERF_OK) {
        fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
        return NULL;
    }
    uint32_t w = 0, h = 0;
    nerf_dataset_image_size(ds, &w, &h);
    ri->train_side = w;
    ri->train_views = nerf_dataset_count(ds);
    return ds;
}

static void usage(FILE *out, const char *argv0)
{
    fprintf(
        out,
        "usage: %s [--json] [--preset reference|tiny|fast|all]\n"
        "       [--seconds S] [--threads N] [--workers W] [--size S]\n"
        "       [--render-size S] [--rss-rows K] [--full] [--no-800]\n"
        "       [--fast-warmup N] [--data DIR [--downscale K]]\n"
        "       [--matmul fp32|bf16]\n"
        "\n"
        "  --json          print one JSON object on stdout (the table goes\n"
        "                  to stderr)\n"
        "  --preset P      reference, tiny, fast or all (default all)\n"
        "  --seconds S     time budget of each measurement (default 5); at\n"
        "                  least %d training steps, one render call and one\n"
        "                  run of the step's products are always timed (the\n"
        "                  products twice: before training, after rendering)\n"
        "  --threads N     set OpenBLAS to N threads and render with one\n"
        "                  worker (default: OpenBLAS's own count and the\n"
        "                  renderer's default workers)\n"
        "  --workers W     renderer worker threads (0: library default)\n"
        "  --render-blas-threads K  OpenBLAS threads while rendering; with\n"
        "                  --threads N, N/K workers (default: as training)\n"
        "  --size S        side of the training images (default 64)\n"
        "  --data DIR      train on the training split of the scene in DIR\n"
        "                  (Blender or LLFF) instead of the built-in scene\n"
        "  --downscale K   with --data: images reduced K times (default 1)\n"
        "  --render-size S side of the memory-measuring render (default 800)\n"
        "  --rss-rows K    rows rendered for the reference and fast presets'\n"
        "                  memory figure unless --full (default 4)\n"
        "  --full          render the whole image for every preset's memory\n"
        "                  figure (reference: about half an hour on 2 cores)\n"
        "  --no-800        skip the memory measurement\n"
        "  --fast-warmup N training steps of the fast preset before the\n"
        "                  timed ones (default %u: past the grid's warm-up\n"
        "                  refreshes, which end at step %u); its steps are\n"
        "                  timed in whole cycles of %u, at least one\n"
        "  --matmul M      the models' products: fp32 (default, cblas) or\n"
        "                  bf16 (oneDNN; see nerf_matmul_supported); the\n"
        "                  sgemm bound is fp32 either way\n",
        argv0, MIN_TRAIN_STEPS, FAST_WARMUP_STEPS, NERF__GRID_WARMUP,
        NERF__GRID_EVERY);
}

int main(int argc, char **argv)
{
    bool json = false;
    bool want[3] = {true, true, true}; /* reference, tiny, fast */
    uint32_t fast_warmup = FAST_WARMUP_STEPS;
    run_info ri;
    memset(&ri, 0, sizeof ri);
    ri.seconds = 5.0;
    ri.render_side = 800;
    ri.rss_rows = 4;
    ri.train_side = 64;
    ri.train_views = 20;
    ri.downscale = 1;
    bool workers_given = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has_value = i + 1 < argc;
        if (strcmp(a, "--json") == 0) {
            json = true;
        } else if (strcmp(a, "--preset") == 0 && has_value) {
            const char *v = argv[++i];
            const bool all = strcmp(v, "all") == 0;
            want[0] = all || strcmp(v, "reference") == 0;
            want[1] = all || strcmp(v, "tiny") == 0;
            want[2] = all || strcmp(v, "fast") == 0;
            if (!want[0] && !want[1] && !want[2]) {
                usage(stderr, argv[0]);
                return 2;
            }
        } else if (strcmp(a, "--seconds") == 0 && has_value) {
            ri.seconds = atof(argv[++i]);
        } else if (strcmp(a, "--threads") == 0 && has_value) {
            ri.threads_requested = atoi(argv[++i]);
            if (ri.threads_requested < 1) {
                usage(stderr, argv[0]);
                return 2;
            }
        } else if (strcmp(a, "--render-blas-threads") == 0 && has_value) {
            render_blas_threads = atoi(argv[++i]);
            if (render_blas_threads < 1) {
                usage(stderr, argv[0]);
                return 2;
            }
        } else if (strcmp(a, "--workers") == 0 && has_value) {
            ri.workers_requested = (uint32_t)atoi(argv[++i]);
            workers_given = true;
        } else if (strcmp(a, "--size") == 0 && has_value) {
            ri.train_side = (uint32_t)atoi(argv[++i]);
        } else if (strcmp(a, "--data") == 0 && has_value) {
            ri.data = argv[++i];
        } else if (strcmp(a, "--downscale") == 0 && has_value) {
            ri.downscale = (uint32_t)atoi(argv[++i]);
        } else if (strcmp(a, "--render-size") == 0 && has_value) {
            ri.render_side = (uint32_t)atoi(argv[++i]);
        } else if (strcmp(a, "--rss-rows") == 0 && has_value) {
            ri.rss_rows = (uint32_t)atoi(argv[++i]);
        } else if (strcmp(a, "--full") == 0) {
            ri.full = true;
        } else if (strcmp(a, "--no-800") == 0) {
            ri.no_rss = true;
        } else if (strcmp(a, "--matmul") == 0 && has_value) {
            const char *v = argv[++i];
            if (strcmp(v, "fp32") == 0) {
                bench_matmul = NERF_MATMUL_FP32;
            } else if (strcmp(v, "bf16") == 0) {
                bench_matmul = NERF_MATMUL_BF16;
            } else {
                usage(stderr, argv[0]);
                return 2;
            }
        } else if (strcmp(a, "--fast-warmup") == 0 && has_value) {
            int w = atoi(argv[++i]);
            if (w < 0) {
                usage(stderr, argv[0]);
                return 2;
            }
            fast_warmup = (uint32_t)w;
        } else if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout, argv[0]);
            return 0;
        } else {
            usage(stderr, argv[0]);
            return 2;
        }
    }
    if (ri.seconds < 0.0 || ri.train_side < 8 || ri.render_side < 1 ||
        ri.rss_rows < 1 || ri.downscale < 1) {
        usage(stderr, argv[0]);
        return 2;
    }
    if (ri.threads_requested > 0) {
#ifdef HAVE_OPENBLAS_SET_NUM_THREADS
        openblas_set_num_threads(ri.threads_requested);
#else
        fprintf(stderr,
                "nerf-bench: warning: this BLAS cannot be told its "
                "thread count; --threads only sets the renderer's workers\n");
#endif
        /* N threads in all, as a peer given N threads would use. */
        if (!workers_given) {
            ri.workers_requested =
                render_blas_threads > 0 && render_blas_threads < ri.threads_requested
                    ? (uint32_t)(ri.threads_requested / render_blas_threads)
                    : 1;
        }
    }
    if (!nerf_matmul_supported(bench_matmul)) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        o.matmul = (uint32_t)bench_matmul;
        nerf_model *m = NULL;
        nerf_model_create(&m, &o); /* fails, and says why */
        fprintf(stderr, "nerf-bench: --matmul bf16: %s\n", nerf_last_error());
        return 2;
    }
    ri.cores = nerf__cpu_count();
    ri.blas_threads = blas_threads();
    load_average(ri.load_start);
    double t_start = now();

    enum { N_PRESETS = 3 };
    static const int ids[N_PRESETS] = {NERF_PRESET_REFERENCE,
                                       NERF_PRESET_TINY, NERF_PRESET_FAST};
    static const char *const names[N_PRESETS] = {"reference", "tiny",
                                                 "fast"};
    preset_setup ps[N_PRESETS];
    figures fs[N_PRESETS];
    memset(ps, 0, sizeof ps);
    memset(fs, 0, sizeof fs);

    /* Memory first, while this process holds nothing that a fork would
     * carry into the child's resident set. */
    for (int i = 0; i < N_PRESETS; i++) {
        if (!want[i]) {
            continue;
        }
        if (ri.no_rss) {
            fs[i].rss_skipped = true;
            continue;
        }
        /* The fast preset's model is untrained here: its fresh grid is
         * all occupied and nothing stops its rays early, so a whole image
         * would take long; its workers' scratch is sized by the first
         * blocks all the same. */
        bool full = ri.full || ids[i] == NERF_PRESET_TINY;
        fprintf(stderr, "nerf-bench: %s: peak memory of a %ux%u render%s...\n",
                names[i], ri.render_side, ri.render_side,
                full ? "" : " (first rows)");
        rss_in_child(ids[i], ri.render_side, ri.rss_rows, full,
                     ri.workers_requested, &fs[i].rss);
    }

    nerf_dataset *ds = ri.data ? load_dataset(&ri)
                               : make_dataset(ri.train_side, ri.train_views);
    if (ds == NULL) {
        return 1;
    }
    int status = 0;
    for (int i = 0; i < N_PRESETS; i++) {
        if (!want[i]) {
            continue;
        }
        if (preset_make(&ps[i], ids[i]) != 0) {
            fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
            status = 1;
            break;
        }
        if (measure(&ps[i], ds, ri.seconds, ri.workers_requested, fast_warmup,
                    &fs[i]) != 0) {
            status = 1;
        }
    }
    nerf_dataset_destroy(ds);
    ri.total_seconds = now() - t_start;
    load_average(ri.load_end);

    print_table(json ? stderr : stdout, &ri, ps, fs, N_PRESETS);
    if (json) {
        print_json(&ri, ps, fs, N_PRESETS);
    }
    for (int i = 0; i < N_PRESETS; i++) {
        if (ps[i].model) {
            preset_release(&ps[i]);
        }
    }
    return status;
}
