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
 *              [--matmul fp32|bf16|fp32-onednn]
 *
 * With --json, stdout holds exactly one JSON object and the table goes to
 * stderr.  Run `nerf-bench --help` for what each option does.
 *
 * This file reads the command line and runs the measurements in order;
 * each is in a file of its own, named after what it measures:
 * nerf-bench-memory.c (the 800x800 render's memory), nerf-bench-sgemm.c
 * (the bound), nerf-bench-train.c, nerf-bench-render.c,
 * nerf-bench-breakdown.c (the fast preset's step by parts), and the
 * report in nerf-bench-table.c and nerf-bench-json.c.  What they share
 * is in nerf-bench.h; nerf-bench-setup.c makes the presets and datasets,
 * nerf-bench-system.c asks the machine.  The library's internals come
 * through lib/nerf_internal.h only, and what the library decides (march
 * settings, seeds, schedules, how a step encodes) is called, not written
 * out again; the sgemm bound's own list of products is the one deliberate
 * exception, for the reason nerf-bench-sgemm.c gives.
 */
#include <cblas.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nerf-bench.h"

/*
 * The measurements of one preset, in an order that keeps them apart: the
 * sgemm rate, training, rendering, the sgemm rate again, and (marching)
 * the step's parts, which write the model and so come last.
 */
static int measure(preset_setup *p, const nerf_dataset *ds,
                   const run_info *ri, figures *f)
{
    const double budget = ri->seconds;
    if (sgemm_flops(p, f) != 0) {
        return -1;
    }
    f->params = nerf_model_param_count(p->model);

    /* The sgemm rate is taken before training and again after rendering,
     * and the better of the two kept: on a shared machine the load
     * changes between measurements, and the bound is what the machine
     * can do, so a disturbed run should not lower it. */
    const char *failed = NULL;
    if (!p->march) {
        fprintf(stderr,
                "nerf-bench: %s: sgemm on a training step's products...\n",
                p->name);
        if (sgemm_time(p, budget, &f->runs[0], &f->gemm_calls) != 0) {
            failed = "sgemm: out of memory";
        }
    }
    nerf_trainer *kept = NULL;
    if (!failed) {
        if (p->march) {
            fprintf(stderr, "nerf-bench: %s: training (%u warm-up steps)...\n",
                    p->name, ri->fast_warmup);
        } else {
            fprintf(stderr, "nerf-bench: %s: training...\n", p->name);
        }
        if (measure_training(p, ds, ri, f, p->march ? &kept : NULL) != 0) {
            failed = "training";
        }
    }
    if (!failed) {
        fprintf(stderr, "nerf-bench: %s: rendering...\n", p->name);
        if (measure_render(p, ri, ri->data ? ds : NULL, f) != 0) {
            failed = "rendering";
        }
    }
    if (!failed && !p->march) {
        fprintf(stderr, "nerf-bench: %s: sgemm again...\n", p->name);
        if (sgemm_time(p, budget, &f->runs[1], &f->gemm_calls) != 0) {
            failed = "sgemm: out of memory";
        }
        f->gemm_square = sgemm_square_gflops(SQUARE_SIDE, budget / 2.0);
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
    if (!failed && p->march) {
        fprintf(stderr, "nerf-bench: %s: measuring the step's floor...\n",
                p->name);
        if (measure_floor(kept, &f->bd, &f->floor) != 0) {
            failed = "the step's floor";
        }
    }
    nerf_trainer_destroy(kept);
    f->onednn_primitives =
        p->model->onednn ? nerf__onednn_primitives(p->model->onednn) : 0;
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

/* ---- main --------------------------------------------------------------- */

static void usage(FILE *out, const char *argv0)
{
    fprintf(
        out,
        "usage: %s [--json] [--preset reference|tiny|fast|all]\n"
        "       [--seconds S] [--threads N] [--workers W] [--size S]\n"
        "       [--render-size S] [--rss-rows K] [--full] [--no-800]\n"
        "       [--fast-warmup N] [--data DIR [--downscale K]]\n"
        "       [--matmul " MATMUL_CHOICES "]\n"
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
    run_info ri;
    memset(&ri, 0, sizeof ri);
    ri.matmul = NERF_MATMUL_FP32;
    ri.fast_warmup = FAST_WARMUP_STEPS;
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
            ri.render_blas_threads = atoi(argv[++i]);
            if (ri.render_blas_threads < 1) {
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
            ri.matmul = matmul_parse(argv[++i]);
            if (ri.matmul < 0) {
                usage(stderr, argv[0]);
                return 2;
            }
        } else if (strcmp(a, "--fast-warmup") == 0 && has_value) {
            int w = atoi(argv[++i]);
            if (w < 0) {
                usage(stderr, argv[0]);
                return 2;
            }
            ri.fast_warmup = (uint32_t)w;
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
    ri.train_height = ri.train_side;
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
                ri.render_blas_threads > 0 &&
                        ri.render_blas_threads < ri.threads_requested
                    ? (uint32_t)(ri.threads_requested /
                                 ri.render_blas_threads)
                    : 1;
        }
    }
    if (!nerf_matmul_supported(ri.matmul)) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        o.matmul = (uint32_t)ri.matmul;
        nerf_model *m = NULL;
        nerf_model_create(&m, &o); /* fails, and says why */
        fprintf(stderr, "nerf-bench: --matmul %s: %s\n",
                matmul_name((uint32_t)ri.matmul), nerf_last_error());
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
        rss_in_child(ids[i], full, &ri, &fs[i].rss);
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
        if (preset_make(&ps[i], ids[i], ri.matmul, ri.data ? ds : NULL) !=
            0) {
            fprintf(stderr, "nerf-bench: %s\n", nerf_last_error());
            status = 1;
            break;
        }
        if (measure(&ps[i], ds, &ri, &fs[i]) != 0) {
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
