/*
 * The report as a table for people: one column per preset that ran, one
 * row per figure, then a paragraph on how each figure was taken.  It goes
 * to stdout, or to stderr when --json has stdout.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nerf-bench.h"

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
    if (n->pos_enc.kind == NERF_ENCODING_HASHGRID) {
        const nerf__hashgrid *hg = &n->pos_enc.u.hash;
        snprintf(b, s, "hash %ux%u, %ux%u, view %ux%u", hg->levels,
                 hg->features, n->depth, n->width, n->view_depth,
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
static void c_gemm_square(char *b, size_t s, const preset_setup *p,
                          const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f", f->gemm_square);
    }
}
static void c_square_share(char *b, size_t s, const preset_setup *p,
                           const figures *f)
{
    if (!no_bound(b, s, p)) {
        snprintf(b, s, "%.1f%%", 100.0 * f->train_rays_per_s *
                                     f->flops_train_ray * 1e-9 /
                                     f->gemm_square);
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
static void c_cut(char *b, size_t s, const preset_setup *p, const figures *f)
{
    share_cell(b, s, f, shares_of(&f->bd).cut);
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
    snprintf(b, s, "%zu of %zu marched (%zu density), %d rounds",
             f->bd.samples, f->bd.marched, f->bd.cut_evaluated,
             f->bd.rounds);
}
/* The floor of a marching step's part, and the measured part's share of
 * it (100%: the part runs at its floor). */
static void floor_cell(char *b, size_t s, const figures *f, double floor,
                       double measured)
{
    if (!f->floor.ok) {
        snprintf(b, s, "-");
        return;
    }
    snprintf(b, s, "%.2f ms (%.0f%%)", 1e3 * floor,
             measured > 0.0 ? 100.0 * floor / measured : 0.0);
}
static void c_peak(char *b, size_t s, const preset_setup *p, const figures *f)
{
    if (!f->floor.ok) {
        snprintf(b, s, "-");
        return;
    }
    snprintf(b, s, "%.0f GFLOP/s, %s x %u", f->floor.peak_gflops,
             f->floor.isa, f->floor.threads);
}
static void c_access(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    const fast_floor *fl = &f->floor;
    if (!fl->ok || fl->levels == 0) {
        snprintf(b, s, "-");
        return;
    }
    const uint32_t last = fl->levels - 1;
    snprintf(b, s, "%.2f/%.2f .. %.2f/%.2f ns", fl->level_read_ns[0],
             fl->level_write_ns[0], fl->level_read_ns[last],
             fl->level_write_ns[last]);
}
static void c_cached(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    const fast_floor *fl = &f->floor;
    if (!fl->ok) {
        snprintf(b, s, "-");
        return;
    }
    size_t corners = 0;
    for (uint32_t l = 0; l < fl->levels; l++) {
        corners += f->bd.level_entries[l];
    }
    snprintf(b, s, "%zu of %zu; %.2f/%.2f ns", corners,
             (size_t)8 * fl->levels * f->bd.samples, fl->cached_read_ns,
             fl->cached_write_ns);
}
/* One part's floor and its share of the measured part. */
static void part_cell(char *b, size_t s, const figures *f, int which)
{
    floor_part parts[FLOOR_PARTS];
    floor_parts(&f->bd, &f->floor, false, parts);
    floor_cell(b, s, f, parts[which].floor, parts[which].measured);
}
static void c_fl_enc(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    part_cell(b, s, f, FLOOR_ENCODING);
}
static void c_fl_mlp(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    part_cell(b, s, f, FLOOR_MLP);
}
static void c_fl_opt(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    part_cell(b, s, f, FLOOR_OPTIMISER);
}
static void c_fl_grid(char *b, size_t s, const preset_setup *p,
                      const figures *f)
{
    part_cell(b, s, f, FLOOR_GRID);
}
static void c_fl_sum(char *b, size_t s, const preset_setup *p,
                     const figures *f)
{
    floor_cell(b, s, f, f->floor.sum, f->train_seconds / f->train_steps);
}
/* The two parts furthest above their floor, by how much. */
static void c_fl_furthest(char *b, size_t s, const preset_setup *p,
                          const figures *f)
{
    if (!f->floor.ok) {
        snprintf(b, s, "-");
        return;
    }
    floor_part g[FLOOR_PARTS];
    floor_parts(&f->bd, &f->floor, true, g);
    snprintf(b, s, "%s +%.1f, %s +%.1f ms", g[0].name,
             1e3 * (g[0].measured - g[0].floor), g[1].name,
             1e3 * (g[1].measured - g[1].floor));
}
static void c_fl_touched(char *b, size_t s, const preset_setup *p,
                         const figures *f)
{
    if (!f->floor.ok) {
        snprintf(b, s, "-");
        return;
    }
    snprintf(b, s, "%zu", f->bd.touched);
}
static void c_fl_lines(char *b, size_t s, const preset_setup *p,
                       const figures *f)
{
    if (!f->floor.ok) {
        snprintf(b, s, "-");
        return;
    }
    snprintf(b, s, "%zu, %.2f ns each", f->bd.touched_lines,
             f->floor.line_rmw_ns);
}
static void c_fl_table(char *b, size_t s, const preset_setup *p,
                       const figures *f)
{
    if (!f->floor.ok) {
        snprintf(b, s, "-");
        return;
    }
    snprintf(b, s, "%d: %.2f / %.2f ms", f->floor.table_arrays,
             1e3 * f->floor.table_lines, 1e3 * f->floor.table_stream);
}
static void c_prims(char *b, size_t s, const preset_setup *p,
                    const figures *f)
{
    snprintf(b, s, "%zu", f->onednn_primitives);
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

/* The notes under the table name the share of the empty cells that a
 * grid refresh after the warm-up evaluates in words. */
_Static_assert(NERF__GRID_RANDOM_DIV == 16,
               "the fast preset's note says \"a sixteenth\"");

void print_table(FILE *out, const run_info *ri, const preset_setup *ps,
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
    if (ri->matmul == NERF_MATMUL_BF16) {
        fprintf(out, "matmul: bf16 (oneDNN, cut over libnerf's %u "
                "threads); the sgemm rows are fp32 cblas_sgemm, so a share "
                "is bf16 rays/s over the fp32 bound\n",
                nerf__parallel_threads());
    } else if (ri->matmul == NERF_MATMUL_FP32_ONEDNN) {
        fprintf(out, "matmul: fp32 through oneDNN (cut over libnerf's %u "
                "threads); the sgemm rows are cblas_sgemm's\n",
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
    char label[64];
    row(out, "network (trunk, view branch)", c_net, ps, fs, n);
    row(out, "samples per ray (coarse + fine)", c_samples, ps, fs, n);
    row(out, "FLOPs per sample, forward", c_fl_sample, ps, fs, n);
    row(out, "FLOPs per training ray (fwd+bwd)", c_fl_train, ps, fs, n);
    row(out, "FLOPs per rendered ray", c_fl_render, ps, fs, n);
    row(out, "sgemm GFLOP/s, step products", c_gemm, ps, fs, n);
    row(out, "  the two runs", c_gemm_runs, ps, fs, n);
    row(out, "sgemm GFLOP/s, forward products", c_gemm_fw, ps, fs, n);
    snprintf(label, sizeof label, "sgemm GFLOP/s, square %d", SQUARE_SIDE);
    row(out, label, c_gemm_square, ps, fs, n);
    snprintf(label, sizeof label, "train rays/s (%u-ray steps)", BATCH_RAYS);
    row(out, label, c_train, ps, fs, n);
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
    row(out, "  train_square_share", c_square_share, ps, fs, n);
    row(out, "render rays/s", c_render, ps, fs, n);
    row(out, "  render samples/s", c_render_sps, ps, fs, n);
    row(out, "  network samples per ray", c_render_spr, ps, fs, n);
    row(out, "  timed rays", c_render_rays, ps, fs, n);
    row(out, "  renderer workers x BLAS threads", c_workers, ps, fs, n);
    row(out, "  GFLOP/s", c_render_gf, ps, fs, n);
    row(out, "  sgemm-bound rays/s", c_render_bound, ps, fs, n);
    row(out, "  render_sgemm_share", c_render_share, ps, fs, n);
    if (ri->matmul != NERF_MATMUL_FP32) {
        row(out, "oneDNN primitives", c_prims, ps, fs, n);
    }
    snprintf(label, sizeof label, "peak RSS, %ux%u render", ri->render_side,
             ri->render_side);
    row(out, label, c_rss, ps, fs, n);
    row(out, "  rays rendered for it", c_rss_rays, ps, fs, n);
    if (any_march) {
        row(out, "training step: encoding", c_enc, ps, fs, n);
        row(out, "  MLP", c_mlp, ps, fs, n);
        row(out, "  compositing (march, fwd, bwd)", c_comp, ps, fs, n);
        row(out, "  opacity cut (density pass)", c_cut, ps, fs, n);
        row(out, "  optimiser (zero grads, Adam)", c_opt, ps, fs, n);
        snprintf(label, sizeof label, "  grid refresh (1/%u per step)",
                 NERF__GRID_EVERY);
        row(out, label, c_gridup, ps, fs, n);
        row(out, "  sum of the parts", c_bd_sum, ps, fs, n);
        row(out, "  timed on samples", c_bd_samples, ps, fs, n);
        row(out, "step floor: fp32 FMA peak", c_peak, ps, fs, n);
        row(out, "  hash read/add, level 0 .. last", c_access, ps, fs, n);
        row(out, "  distinct corners; cached read/add", c_cached, ps, fs,
            n);
        row(out, "  encoding (hash fwd + bwd)", c_fl_enc, ps, fs, n);
        row(out, "  MLP at peak", c_fl_mlp, ps, fs, n);
        row(out, "  optimiser", c_fl_opt, ps, fs, n);
        row(out, "  parameters touched", c_fl_touched, ps, fs, n);
        row(out, "  table lines touched, update", c_fl_lines, ps, fs, n);
        row(out, "  table arrays: their lines / streamed", c_fl_table, ps,
            fs, n);
        row(out, "  grid refresh", c_fl_grid, ps, fs, n);
        row(out, "  floor / fast_floor_share", c_fl_sum, ps, fs, n);
        row(out, "  furthest above their floors", c_fl_furthest, ps, fs,
            n);
    }

    if (ri->data) {
        fprintf(out, "\nTraining: %u-ray steps on the training split of "
                "%s (%u views of %ux%u)", BATCH_RAYS, ri->data,
                ri->train_views, ri->train_side, ri->train_height);
    } else {
        fprintf(out, "\nTraining: %u-ray steps on the built-in scene (%u "
                "views of %ux%u)", BATCH_RAYS, ri->train_views,
                ri->train_side, ri->train_side);
    }
    /* With --data the views are its first training camera's. */
    const char *view = ri->data ? "the data's first camera, 800 pixels wide"
                                : "an 800x800 view";
    const char *fast_view = ri->data ? "the data's first camera" :
                                       "the 800x800 view's camera";
    fprintf(out,
            ", after the warm-up steps.  Rendering: "
            "nerf_renderer_render_rays on %u rays of %s per "
            "call, after a warm-up call.\n",
            render_rays(), view);
    fprintf(out, "sgemm: the products of one training step (per layer "
                 "Y = X W^T, dW = dY^T X, dX = dY W; coarse net on %u x "
                 "n_coarse samples, fine net on %u x (n_coarse + n_fine)), "
                 "timed call by call before training and again after "
                 "rendering, the better rate kept; the render bound uses the "
                 "forward products' rate.\n",
            BATCH_RAYS, BATCH_RAYS);
    if (any_march) {
        fprintf(out,
                "fast: training timed in whole cycles of %u steps (one "
                "occupancy-grid refresh each) after the warm-up steps "
                "(grid fully refreshed every %u steps before step %u, "
                "occupied cells and a sixteenth of the others after).  "
                "Samples: network evaluations (stats.samples_per_ray in "
                "training; rendering: counted by replaying the timed call "
                "in the renderer's blocks of %u rays).  Rendering: "
                "nerf_renderer_render_rays on every pixel of %s "
                "at %u pixels wide, model as trained, after a "
                "warm-up call.\n",
                NERF__GRID_EVERY, NERF__GRID_EVERY_WARMUP, NERF__GRID_WARMUP,
                NERF__RENDER_BLOCK, fast_view, FAST_RENDER_SIDE);
        fprintf(out,
                "fast, training step: the library's building blocks timed "
                "one by one in the bench (no timers in the library) on the "
                "packed samples of the last timed step, each called as the "
                "step calls it; percentages of their sum, which is set "
                "beside the mean step.  encoding = hash grid forward + "
                "backward + SH; MLP = the network's forward + backward "
                "less the encoding; compositing = march + points, "
                "composite forward + backward; opacity cut = the "
                "density pass, in rounds of a few samples a ray, that "
                "finds where each ray turns opaque (the other parts run on "
                "the samples up to there; density: the samples it "
                "evaluated), less the hash forward of those, whose "
                "encodings the forward reuses; optimiser = Adam (which "
                "zeroes the gradients as it reads them); grid refresh = "
                "one refresh / %u.  The "
                "rest of the step (ray drawing, loss, direction copies) is "
                "the gap to 100%%.\n",
                NERF__GRID_EVERY);
        fprintf(out,
                "fast, step floor: what the same step must cost at least "
                "here (nerf-bench-floor.c, docs/performance.md): %s.  In "
                "brackets: floor / measured part (100%%: at the floor); "
                "fast_floor_share = floor sum / mean step.\n",
                floor_method);
    }
    for (int i = 0; i < n; i++) {
        if (fs[i].ran && !fs[i].rss_skipped && fs[i].rss.ok) {
            char buf[512];
            fprintf(out, "peak RSS, %s: %s.\n", ps[i].name,
                    rss_method(&fs[i].rss, buf, sizeof buf));
        }
    }
}
