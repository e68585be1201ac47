/*
 * What the parts of nerf-bench share: the run's settings, the presets it
 * measures and the figures each measurement fills in.  Each nerf-bench-*.c
 * file measures or reports one thing; nerf-bench.c runs them in order.
 * Private to nerf-bench.
 */
#ifndef NERF_BENCH_H
#define NERF_BENCH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "matmul_name.h"
#include "nerf.h"
#include "nerf_internal.h"

#define BATCH_RAYS 1024u
/* The side of the square products nerf-bench sets beside the step's. */
#define SQUARE_SIDE 256
#define MIN_TRAIN_STEPS 2
/* The fast preset's trainer refreshes every cell of the occupancy grid
 * every NERF__GRID_EVERY_WARMUP steps up to step NERF__GRID_WARMUP and a
 * fraction of the empty ones after (trainer.h): warming up past that, the
 * grid has carved the empty space and the timed steps are in the regime
 * a long run spends its time in. */
#define FAST_WARMUP_STEPS (NERF__GRID_WARMUP + 4 * NERF__GRID_EVERY)
/* A whole view rather than the top rows of one: with ray marching the
 * cost of a ray depends on what it meets.  The 800x800 view's camera at
 * 128x128 pixels (same field of view, so the same share of rays on the
 * objects). */
#define FAST_RENDER_SIDE 128u

/* ---- the run ------------------------------------------------------------ */

/* The command line's settings, and what the run found out about the
 * machine and its load. */
typedef struct run_info {
    double seconds;
    int threads_requested; /* 0: not given */
    uint32_t workers_requested;
    /* OpenBLAS threads while rendering (--render-blas-threads; 0:
     * unchanged).  Renderer workers each call the BLAS, so one worker per
     * core over a single-threaded BLAS is the other way to use the cores. */
    int render_blas_threads;
    int matmul; /* nerf_matmul of every model the bench creates */
    uint32_t fast_warmup;
    uint32_t cores;
    int blas_threads;
    uint32_t render_side, rss_rows;
    bool full, no_rss;
    uint32_t train_side, train_views;
    uint32_t train_height; /* --data: its images' height; else train_side */
    const char *data; /* --data: a scene's training split, else NULL */
    uint32_t downscale;
    double load_start[3], load_end[3];
    double total_seconds;
} run_info;

/* ---- the machine (nerf-bench-system.c) ---------------------------------- */

double now(void);
void load_average(double out[3]);
double vm_mb(const char *field);
int blas_threads(void);
void set_blas_threads(int n);
const char *blas_config(void);
const char *blas_corename(void);

/* ---- presets, views, datasets (nerf-bench-setup.c) ---------------------- */

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

/* ds: NULL for the preset as it is; a dataset (--data) to place the model
 * in its scene and sample it as nerf-train does. */
int preset_make(preset_setup *p, int id, int matmul, const nerf_dataset *ds);
void preset_release(preset_setup *p);
void view_camera(nerf_camera *c, uint32_t side);
/* The view renders are timed on, width pixels wide: with --data its first
 * training camera (at its aspect ratio), else view_camera()'s. */
int render_camera(nerf_camera *c, uint32_t width, const nerf_dataset *ds);
nerf_dataset *make_dataset(uint32_t side, uint32_t views);
nerf_dataset *load_dataset(run_info *ri);

/* ---- the sgemm bound (nerf-bench-sgemm.c) ------------------------------- */

typedef struct gemm_timing {
    double gflops_step;    /* forward + backward products */
    double gflops_forward; /* forward products alone */
    double seconds;        /* timed */
    int reps;
} gemm_timing;

/* ---- peak memory of a render (nerf-bench-memory.c) ---------------------- */

typedef struct rss_result {
    int ok;
    int full;
    uint32_t workers;
    double hwm_mb, maxrss_mb, outputs_mb, seconds;
    double model_mb; /* resident once the model exists, before the render */
    uint64_t rays_done, rays_total;
} rss_result;

void rss_in_child(int preset, bool full, const run_info *ri,
                  rss_result *res);
const char *rss_method(const rss_result *r, char *buf, size_t size);

/* ---- a marching step's parts (nerf-bench-breakdown.c) ------------------- */

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
    bool same_samples; /* the bench's march marched the step's samples */
    size_t rays, samples; /* samples: those kept up to opacity */
    size_t marched;
    size_t cut_evaluated; /* samples the density pass evaluated */
    int rounds;
    double march;        /* count + fill + sample points */
    double opacity_cut;  /* the density pass, in its rounds */
    double hash_fw, hash_bw, sh_fw;
    double net_fw, net_bw; /* whole network: encodings included */
    double composite_fw, composite_bw;
    double zero_grad, adam;
    double grid_update;  /* one refresh, one per NERF__GRID_EVERY steps */
    int grid_updates;
    size_t grid_cells_evaluated;
    /* What the step's backward touched (touched_params()), counted in the
     * untimed first round on the trained model: the timed rounds repeat
     * one step's update, which drives the model far from any real state
     * (after ten seconds of them, the backward gave no gradient at all). */
    size_t touched, touched_lines;
    size_t level_entries[NERF__HASHGRID_MAX_LEVELS];
} step_breakdown;

/* The categories the figures are reported in, seconds per step. */
typedef struct step_shares {
    double encoding, mlp, compositing, cut, optimiser, grid, sum;
} step_shares;

int time_breakdown(nerf_trainer *t, double budget, step_breakdown *bd);
step_shares shares_of(const step_breakdown *b);

/* ---- the fast step's floor (nerf-bench-floor.c, nerf-bench-peak.c) ------ */

/* What the step of the breakdown must cost at least, part by part, in
 * seconds per step (nerf-bench-floor.c says how each is measured). */
typedef struct fast_floor {
    bool ok;
    double peak_gflops; /* fp32 multiply-adds, all threads */
    const char *isa;    /* the kernel the peak was measured with */
    uint32_t threads, levels;
    double level_read_ns[NERF__HASHGRID_MAX_LEVELS];  /* per access, */
    double level_write_ns[NERF__HASHGRID_MAX_LEVELS]; /* all threads */
    double cached_read_ns, cached_write_ns; /* on entries in cache */
    double line_rmw_ns;   /* a random line update, all threads */
    /* The table's update: its touched lines alone (a random update in
     * each of table_arrays arrays), or those arrays streamed whole; the
     * floor takes the less. */
    int table_arrays;
    double table_lines, table_stream;
    double encoding, mlp, optimiser, grid, sum;
} fast_floor;

/* GFLOP/s of fp32 fused multiply-adds on every thread of the pool. */
double peak_gflops(const char **isa_out);
/* How the floor is measured, in one sentence, for the table and the
 * JSON. */
extern const char floor_method[];
/* After time_breakdown() on the same trainer; writes the model. */
int measure_floor(nerf_trainer *t, const step_breakdown *bd, fast_floor *fl);

/* A part of the step with a floor: its measured time beside that floor
 * (seconds per step). */
typedef struct floor_part {
    const char *name;
    double measured, floor;
} floor_part;
enum { FLOOR_ENCODING, FLOOR_MLP, FLOOR_OPTIMISER, FLOOR_GRID, FLOOR_PARTS };
/* The parts in the enum's order.  by_gap: furthest above its floor
 * (measured less floor) first, where a faster step has the most to win. */
void floor_parts(const step_breakdown *bd, const fast_floor *fl,
                 bool by_gap, floor_part parts[FLOOR_PARTS]);
/* Parameters of network 0 (a hash-grid one) with a gradient in m->grads:
 * every layer parameter, and each table float whose entry got one; in
 * *lines the 64-byte lines of the table that hold them, and in
 * level_entries the entries of each level that got one. */
size_t touched_params(const nerf_model *m, size_t *lines,
                      size_t level_entries[NERF__HASHGRID_MAX_LEVELS]);

/* ---- the figures of one preset ------------------------------------------ */

typedef struct figures {
    bool ran;
    /* shapes */
    double flops_sample_fw, flops_train_ray, flops_render_ray;
    size_t params;
    /* sgemm (not for marching presets) */
    gemm_timing gemm;    /* the better of the two runs, rate by rate */
    gemm_timing runs[2]; /* before training, after rendering */
    double gemm_square;  /* cblas_sgemm GFLOP/s at square SQUARE_SIDE */
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
    /* marching: where a training step's time goes, and its floor */
    step_breakdown bd;
    fast_floor floor;
    /* memory */
    rss_result rss;
    bool rss_skipped;
    /* bf16: oneDNN primitives the model created for everything above */
    size_t onednn_primitives;
} figures;

/* nerf-bench-sgemm.c: the FLOPs of the network's shapes (f's flops_*
 * fields), a timed run of a training step's products, and the rays/s
 * the better run's rates allow. */
int sgemm_flops(const preset_setup *p, figures *f);
int sgemm_time(const preset_setup *p, double budget, gemm_timing *out,
               int *calls);
double sgemm_square_gflops(int side, double budget);
double train_bound(const figures *f);
double render_bound(const figures *f);

/* nerf-bench-train.c; keep (marching presets): the trainer, for the
 * step's parts. */
int measure_training(preset_setup *p, const nerf_dataset *ds,
                     const run_info *ri, figures *f, nerf_trainer **keep);

/* nerf-bench-render.c; render_rays: rays per timed call without
 * marching. */
int measure_render(preset_setup *p, const run_info *ri,
                   const nerf_dataset *ds, figures *f);
unsigned render_rays(void);

/* ---- the report (nerf-bench-table.c, nerf-bench-json.c) ----------------- */

void print_table(FILE *out, const run_info *ri, const preset_setup *ps,
                 const figures *fs, int n);
void print_json(const run_info *ri, const preset_setup *ps,
                const figures *fs, int n_presets);

#endif
