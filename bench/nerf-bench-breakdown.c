/*
 * Where a training step of a marching preset (fast) goes: encoding, MLP,
 * compositing, optimiser and occupancy-grid refresh.  The library has no
 * timers in its loops, which would cost every user time in every step;
 * instead its building blocks are timed here one at a time, each called
 * as the step calls it, on the packed samples of the trainer's last step
 * (nerf-bench.h says more).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nerf-bench.h"

/*
 * Time the blocks of the trainer's last step in rounds until `budget`
 * seconds (at least three), then two grid refreshes.  Everything here
 * writes the model (gradients, Adam, the grid): it runs after every other
 * measurement of the preset.
 */
int time_breakdown(nerf_trainer *t, double budget, step_breakdown *bd)
{
    nerf_model *m = t->model;
    nerf__batch *b = &t->batch;
    /* What the step's marching engine left: its packed samples. */
    nerf__march_state *mb = &b->marching;
    const nerf__march_samples *bs = &mb->samples;
    const nerf__network *net = &m->nets[0];
    nerf__occupancy *g = m->grid;
    memset(bd, 0, sizeof *bd);
    if (!b->marched || !b->kept || bs->total == 0 || g == NULL ||
        net->pos_enc.kind != NERF_ENCODING_HASHGRID || !net->use_viewdirs ||
        net->dir_enc.kind != NERF_ENCODING_SPHERICAL_HARMONICS) {
        /* Said here: the library set no error for the caller to print. */
        fprintf(stderr, "nerf-bench: the last step left no marched "
                "samples of a hash-grid model with spherical harmonics to "
                "time (%zu samples)\n", b->marched ? bs->total : 0);
        return -1;
    }
    const size_t n = bs->total, B = b->n_rays;
    const uint64_t step = m->step; /* the Adam rounds below advance it */
    bd->rays = B;
    bd->samples = n;

    /* The step's march: the settings and rays the marching path makes of
     * the trainer's setup, which still numbers the step's rays. */
    nerf__march_options mo;
    nerf__render_march_options(&t->setup, g, &mo);
    nerf__march_rays rays =
        nerf__render_march_rays(&t->setup, B, t->origins, t->directions);
    /* In NDC the step marches the warped rays, as nerf__render_march()
     * makes them. */
    float *ndc_o = NULL, *ndc_d = NULL;
    if (t->setup.sampler->opts.ndc) {
        ndc_o = malloc(3 * B * sizeof(float));
        ndc_d = malloc(3 * B * sizeof(float));
        if (ndc_o == NULL || ndc_d == NULL) {
            free(ndc_o);
            free(ndc_d);
            return -1;
        }
        nerf__render_ndc_rays(&t->setup, B, t->origins, t->directions,
                              ndc_o, ndc_d);
        rays.origins = ndc_o;
        rays.dirs = ndc_d;
    }
    nerf__march_samples ms;
    nerf__march_samples_init(&ms, &m->env);
    int rc = nerf__march_run(g, &mo, &rays, &ms);
    const size_t n_march = ms.total > n ? ms.total : n;
    float *points = malloc(3 * n_march * sizeof(float));
    float *enc = malloc(n * net->pos_width * sizeof(float));
    float *d_enc = malloc(n * net->pos_width * sizeof(float));
    float *sh = malloc(n * net->dir_width * sizeof(float));
    float *rgb = malloc(3 * B * sizeof(float));
    /* The density pass's encodings go to the marched samples' rows. */
    float *cut_enc = malloc(n_march * net->pos_width * sizeof(float));
    uint32_t *count = malloc(B * sizeof(uint32_t));
    nerf__opacity_cut cut;
    nerf__opacity_cut_init(&cut, &m->env);
    if (rc != NERF_OK || !points || !enc || !d_enc || !sh || !rgb ||
        !cut_enc || !count) {
        rc = -1;
        goto done;
    }
    /* The step kept a prefix of each ray's samples, so the march matches
     * it in its total and in each ray's first sample. */
    bool same = ms.total == b->n_evaluated && ms.n_rays == B;
    for (size_t k = 0; same && k < B; k++) {
        same = bs->offsets[k + 1] == bs->offsets[k] ||
               ms.t[ms.offsets[k]] == bs->t[bs->offsets[k]];
    }
    for (size_t i = 0; i < n * net->pos_width; i++) {
        d_enc[i] = 1e-3f * (float)(i % 7);
    }
    nerf__packed_out po = {.rgb = rgb};
    size_t touched = 0, touched_lines = 0;
    size_t level_entries[NERF__HASHGRID_MAX_LEVELS] = {0};

    /* The pass that finds where each ray turns opaque, first: the rounds
     * below train the model on this one batch again and again, which
     * turns its rays opaque sooner and would shorten the pass.  Here the
     * weights are the step's own but for its Adam update.  Round 0 is
     * untimed: it faults in the bench's own buffers, which the step has
     * long had. */
    nerf__march_points(&mo, &rays, ms.offsets, ms.t, points);
    double cut_seconds = 0.0;
    for (int round = 0, timed = 0; timed < 3 || cut_seconds < budget / 4;
         round++) {
        double a = now();
        rc = nerf__opacity_cut_run(&cut, m, &ms, points, NULL,
                                   NERF__COMPOSITE_EPS_DEFAULT, count,
                                   cut_enc);
        if (rc != NERF_OK) {
            goto done;
        }
        if (round > 0) {
            cut_seconds += now() - a;
            timed++;
            bd->opacity_cut = cut_seconds / timed;
        }
    }
    const double cut_mean = bd->opacity_cut;

    double t0 = now();
    for (int round = 0;; round++) {
        if (round == 1) {
            memset(bd, 0, sizeof *bd);
            bd->rays = B;
            bd->samples = n;
            bd->marched = ms.total;
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
        nerf__march_points(&mo, &rays, ms.offsets, ms.t, points);
        double c = now();
        bd->march += c - a;
        a = c;
        /* The encodings as the network runs them, on their own. */
        nerf__encoding_forward(&net->pos_enc, m->params + net->pos_params, n,
                               mb->points, enc, net->pos_width);
        c = now();
        bd->hash_fw += c - a;
        a = c;
        nerf__encoding_backward(&net->pos_enc, n, mb->points, d_enc,
                                net->pos_width, m->grads + net->pos_params);
        c = now();
        bd->hash_bw += c - a;
        a = c;
        nerf__encoding_forward(&net->dir_enc, NULL, n, mb->dirs, sh,
                               net->dir_width);
        c = now();
        bd->sh_fw += c - a;
        /* The step itself, block by block.  In the untimed first round
         * the gradient starts from zero, without the standalone encoding
         * backward's adds, so that what it touches is the step's own. */
        if (round == 0) {
            nerf__model_zero_grad(m);
        }
        a = now();
        /* As the step: a no-op after an Adam step, which zeroes them. */
        nerf__model_clear_grad(m);
        c = now();
        bd->zero_grad += c - a;
        a = c;
        rc = nerf__model_forward(m, 0, &b->ws[0], n, mb->points,
                                 mb->dirs, mb->rgb, mb->sigma);
        if (rc != NERF_OK) {
            goto done;
        }
        c = now();
        bd->net_fw += c - a;
        a = c;
        nerf__composite_packed(&mb->packed, &po);
        c = now();
        bd->composite_fw += c - a;
        a = c;
        nerf__composite_packed_backward(&mb->packed, t->d_rgb[0], NULL, NULL,
                                        mb->d_rgb, mb->d_sigma);
        c = now();
        bd->composite_bw += c - a;
        a = c;
        nerf__model_backward(m, 0, &b->ws[0], mb->d_rgb, mb->d_sigma);
        c = now();
        bd->net_bw += c - a;
        if (round == 0) {
            touched = touched_params(m, &touched_lines, level_entries);
        }
        a = now();
        nerf__model_adam_step(m);
        c = now();
        bd->adam += c - a;
        bd->rounds += round > 0;
    }

    /* The refresh rule of the timed steps' regime. */
    const size_t n_random = nerf__grid_random_cells(step, g->cells);
    for (int i = 0; i < 2 && rc == NERF_OK; i++) {
        double a = now();
        rc = nerf__occupancy_update(g, nerf__trainer_grid_density, t,
                                    n_random);
        bd->grid_update += now() - a;
        bd->grid_updates++;
        bd->grid_cells_evaluated += g->evaluated;
    }
    if (rc != NERF_OK) {
        goto done;
    }
    const double r = bd->rounds;
    bd->march /= r;
    bd->opacity_cut = cut_mean;
    bd->cut_evaluated = cut.evaluated;
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
    bd->touched = touched;
    bd->touched_lines = touched_lines;
    memcpy(bd->level_entries, level_entries, sizeof level_entries);
    bd->ok = true;
done:
    nerf__march_samples_release(&ms);
    free(ndc_o);
    free(ndc_d);
    free(points);
    free(enc);
    free(d_enc);
    free(sh);
    free(rgb);
    free(cut_enc);
    free(count);
    nerf__opacity_cut_release(&cut);
    return rc == NERF_OK ? 0 : -1;
}

step_shares shares_of(const step_breakdown *b)
{
    step_shares s;
    s.encoding = b->hash_fw + b->hash_bw + b->sh_fw;
    /* The network's own calls encode first: what remains is the products
     * and the element-wise passes between them. */
    s.mlp = fmax(0.0, b->net_fw + b->net_bw - s.encoding);
    s.compositing = b->march + b->composite_fw + b->composite_bw;
    /* The forward takes the kept samples' position encodings from the
     * density pass, and the encoding part counts them already. */
    s.cut = fmax(0.0, b->opacity_cut - b->hash_fw);
    s.optimiser = b->zero_grad + b->adam;
    s.grid = b->grid_update / NERF__GRID_EVERY;
    s.sum = s.encoding + s.mlp + s.compositing + s.cut + s.optimiser +
            s.grid;
    return s;
}
