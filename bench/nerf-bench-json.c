/*
 * The report as one JSON object on stdout (--json): the run's settings,
 * the machine and its load, and each preset's figures under its name.
 * bench/torch_peer.py reads these keys from the file bench/run.sh saves.
 */
#include <cJSON.h>
#include <stdio.h>
#include <stdlib.h>

#include "nerf-bench.h"

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

/* The step's floor, part by part (seconds per step). */
static cJSON *floor_json(const figures *f)
{
    const fast_floor *fl = &f->floor;
    if (!fl->ok) {
        return cJSON_CreateNull();
    }
    cJSON *o = cJSON_CreateObject();
    char method[1024];
    snprintf(method, sizeof method, "%s; share = sum / mean step",
             floor_method);
    cJSON_AddStringToObject(o, "method", method);
    cJSON_AddNumberToObject(o, "peak_gflops", fl->peak_gflops);
    cJSON_AddStringToObject(o, "peak_isa", fl->isa);
    cJSON_AddNumberToObject(o, "threads", fl->threads);
    cJSON *r = cJSON_AddArrayToObject(o, "level_read_ns");
    cJSON *w = cJSON_AddArrayToObject(o, "level_add_ns");
    for (uint32_t l = 0; l < fl->levels; l++) {
        cJSON_AddItemToArray(r, cJSON_CreateNumber(fl->level_read_ns[l]));
        cJSON_AddItemToArray(w, cJSON_CreateNumber(fl->level_write_ns[l]));
    }
    cJSON_AddNumberToObject(o, "cached_read_ns", fl->cached_read_ns);
    cJSON_AddNumberToObject(o, "cached_add_ns", fl->cached_write_ns);
    cJSON *e = cJSON_AddArrayToObject(o, "level_corners");
    for (uint32_t l = 0; l < fl->levels; l++) {
        const double corners = (double)f->bd.level_entries[l];
        cJSON_AddItemToArray(e, cJSON_CreateNumber(corners));
    }
    cJSON_AddNumberToObject(o, "touched_params", (double)f->bd.touched);
    cJSON_AddNumberToObject(o, "touched_lines", (double)f->bd.touched_lines);
    cJSON_AddNumberToObject(o, "line_update_ns", fl->line_rmw_ns);
    cJSON_AddNumberToObject(o, "table_arrays", fl->table_arrays);
    cJSON_AddNumberToObject(o, "table_lines_seconds", fl->table_lines);
    cJSON_AddNumberToObject(o, "table_stream_seconds", fl->table_stream);
    cJSON *sec = cJSON_AddObjectToObject(o, "seconds");
    cJSON_AddNumberToObject(sec, "encoding", fl->encoding);
    cJSON_AddNumberToObject(sec, "mlp", fl->mlp);
    cJSON_AddNumberToObject(sec, "optimiser", fl->optimiser);
    cJSON_AddNumberToObject(sec, "grid", fl->grid);
    cJSON_AddNumberToObject(sec, "sum", fl->sum);
    cJSON_AddNumberToObject(o, "fast_floor_share",
                            fl->sum / (f->train_seconds / f->train_steps));
    /* Furthest above its floor first. */
    floor_part g[FLOOR_PARTS];
    floor_parts(&f->bd, fl, true, g);
    cJSON *gaps = cJSON_AddArrayToObject(o, "above_floor");
    for (int i = 0; i < FLOOR_PARTS; i++) {
        cJSON *part = cJSON_CreateObject();
        cJSON_AddStringToObject(part, "part", g[i].name);
        cJSON_AddNumberToObject(part, "measured_seconds", g[i].measured);
        cJSON_AddNumberToObject(part, "floor_seconds", g[i].floor);
        cJSON_AddNumberToObject(part, "over_seconds",
                                g[i].measured - g[i].floor);
        cJSON_AddItemToArray(gaps, part);
    }
    return o;
}

/* Seconds per step of each part, and shares of their sum. */
static cJSON *breakdown_json(const figures *f)
{
    const step_breakdown *b = &f->bd;
    if (!b->ok) {
        return cJSON_CreateNull();
    }
    const step_shares sh = shares_of(b);
    cJSON *o = cJSON_CreateObject();
    char method[1024];
    snprintf(method, sizeof method,
             "the library's building blocks timed one by one in the bench, "
             "each called as the training step calls it, on the packed "
             "samples of the last timed step, in interleaved rounds (mean "
             "per call); shares are of the sum of the parts; mlp = network "
             "forward + backward less the encoding; opacity_cut share = "
             "the density pass, in rounds of a few samples a ray "
             "(cut_evaluated_samples), less the hash "
             "forward of those kept up to opacity, on which the other "
             "parts run and whose encodings the forward reuses; grid = one "
             "occupancy-grid refresh / %u; the rest of the step is "
             "step_seconds - sum_seconds",
             NERF__GRID_EVERY);
    cJSON_AddStringToObject(o, "method", method);
    cJSON_AddNumberToObject(o, "rays", (double)b->rays);
    cJSON_AddNumberToObject(o, "samples", (double)b->samples);
    cJSON_AddNumberToObject(o, "marched_samples", (double)b->marched);
    cJSON_AddNumberToObject(o, "cut_evaluated_samples",
                            (double)b->cut_evaluated);
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
    cJSON_AddNumberToObject(sec, "opacity_cut", b->opacity_cut);
    cJSON_AddNumberToObject(sec, "zero_grad", b->zero_grad);
    cJSON_AddNumberToObject(sec, "adam", b->adam);
    cJSON_AddNumberToObject(sec, "grid_refresh", b->grid_update);
    cJSON_AddNumberToObject(sec, "grid_refresh_cells",
                            (double)b->grid_cells_evaluated);
    cJSON *shares = cJSON_AddObjectToObject(o, "shares");
    cJSON_AddNumberToObject(shares, "encoding", sh.encoding / sh.sum);
    cJSON_AddNumberToObject(shares, "mlp", sh.mlp / sh.sum);
    cJSON_AddNumberToObject(shares, "compositing", sh.compositing / sh.sum);
    cJSON_AddNumberToObject(shares, "opacity_cut", sh.cut / sh.sum);
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
        cJSON_AddNumberToObject(n, "sh_degree", net->dir_enc.u.sh_degree);
        const nerf__hashgrid *hg = &net->pos_enc.u.hash;
        cJSON *h = cJSON_AddObjectToObject(n, "hash_grid");
        cJSON_AddNumberToObject(h, "levels", hg->levels);
        cJSON_AddNumberToObject(h, "features", hg->features);
        cJSON_AddNumberToObject(h, "log2_table", hg->log2_table);
        cJSON_AddNumberToObject(h, "min_resolution", hg->min_resolution);
        cJSON_AddNumberToObject(h, "max_resolution", hg->max_resolution);
        cJSON_AddNumberToObject(h, "table_params", (double)hg->count);
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
    cJSON_AddNumberToObject(o, "train_image_height", ri->train_height);
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
    /* oneDNN's primitives, bf16 or fp32; the first name is kept for
     * readers of the output from before fp32 through oneDNN existed. */
    const double prims = (double)f->onednn_primitives;
    cJSON_AddNumberToObject(o, "onednn_primitives", prims);
    cJSON_AddNumberToObject(o, "bf16_primitives", prims);

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
            ri->data ? "nerf_renderer_render_rays on every pixel of the "
                       "data's first training camera at render_image_side "
                       "pixels wide, the model as trained; samples counted "
                       "by replaying the call in the renderer's blocks"
                     : "nerf_renderer_render_rays on every pixel of the "
                       "800x800 view's camera at render_image_side pixels, "
                       "the model as trained; samples counted by replaying "
                       "the call in the renderer's blocks");
        cJSON_AddItemToObject(o, "train_step_breakdown",
                              breakdown_json(f));
        cJSON_AddItemToObject(o, "train_step_floor", floor_json(f));
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
    cJSON_AddNumberToObject(o, "sgemm_square_gflops", f->gemm_square);
    cJSON_AddNumberToObject(o, "sgemm_square_side", SQUARE_SIDE);
    cJSON_AddNumberToObject(o, "train_square_share",
                            f->train_rays_per_s * f->flops_train_ray * 1e-9 /
                                f->gemm_square);
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

static cJSON *load_json(const double l[3])
{
    if (l[0] < 0.0) {
        return cJSON_CreateNull();
    }
    const double v[3] = {l[0], l[1], l[2]};
    return cJSON_CreateDoubleArray(v, 3);
}

void print_json(const run_info *ri, const preset_setup *ps,
                       const figures *fs, int n_presets)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "tool", "nerf-bench");
    cJSON_AddStringToObject(root, "libnerf_version", nerf_version_string());
    cJSON_AddStringToObject(root, "build_info", nerf_build_info());
    cJSON_AddStringToObject(root, "matmul",
                            matmul_name((uint32_t)ri->matmul));
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
