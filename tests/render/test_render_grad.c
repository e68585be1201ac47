/*
 * The backward pass of the whole path (compositing and both networks)
 * along random directions in parameter space and along each bias, for
 * the parameters after the networks' ReLUs: against the exact derivative
 * of the forward from the kept activations on, taken in forward mode in
 * a double mirror, within bounds derived from both sides' arithmetic
 * (tail_derivative()).  Samples are constants of the backward, as in the
 * reference, so each check perturbs only parameters that do not move the
 * samples of the output it differentiates.  Over all parameters the
 * central difference is printed, not asserted.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../float_bounds.h"
#include "../harness.h"
#include "network_fused.h"
#include "occupancy.h"
#include "render_batch.h"
#include "rng.h"
#include "smm.h"

enum { RAYS = 12 };

typedef struct fixture {
    nerf_model *m;
    nerf_sampler *s;
    nerf__render_setup setup;
    nerf__batch b;
    float o[3 * RAYS], d[3 * RAYS];
    /* Loss weights per pass: L = sum g_rgb.rgb + g_d depth + g_o opacity */
    float g_rgb[2][3 * RAYS], g_d[2][RAYS], g_o[2][RAYS];
    int use_pass[2];
    float *noise[2];
    double mean_opacity; /* of the last pass, at the last loss() */
} fixture;

/* A fresh tiny model's raw densities straddle 0 with a small spread; lift
 * them so that the rays cross partly transparent matter, where every term
 * of the compositing gradient is alive. */
static void bias_density(nerf_model *m)
{
    for (uint32_t k = 0; k < m->n_nets; k++) {
        const nerf__network *nw = &m->nets[k];
        m->params[nw->head.b + nw->width] += 0.3f;
    }
}

static void setup(fixture *f, uint32_t n_f, bool training)
{
    memset(f, 0, sizeof *f);
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    mo.seed = 9;
    CHECK_OK(nerf_model_create(&f->m, &mo));
    bias_density(f->m);
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    so.n_coarse = 24;
    so.n_fine = n_f;
    so.seed = 4;
    CHECK_OK(nerf_sampler_create(&f->s, &so));
    f->setup.model = f->m;
    f->setup.sampler = f->s;
    f->setup.training = training;
    f->setup.noise_std = training ? 1.0f : 0.0f;
    f->setup.white_background = true;
    f->setup.first_ray = 100;
    f->setup.keep = true;
    nerf__env env;
    nerf__env_default(&env);
    nerf__batch_init(&f->b, &env);
    nerf__rng g = nerf__rng_make(5, 0);
    for (int k = 0; k < RAYS; k++) {
        /* Rays from a sphere of radius 4 towards the origin's area. */
        float a = 6.2831853f * nerf__rng_uniform(&g);
        float o[3] = {4.0f * cosf(a), 4.0f * sinf(a), 0.5f};
        for (int c = 0; c < 3; c++) {
            f->o[3 * k + c] = o[c];
            f->d[3 * k + c] = -o[c] * (0.25f + 0.05f * nerf__rng_uniform(&g)) +
                              0.1f * (nerf__rng_uniform(&g) - 0.5f);
        }
    }
    for (int p = 0; p < 2; p++) {
        for (int k = 0; k < RAYS; k++) {
            for (int c = 0; c < 3; c++) {
                f->g_rgb[p][3 * k + c] = 2.0f * nerf__rng_uniform(&g) - 1.0f;
            }
            f->g_d[p][k] = 0.2f * (nerf__rng_uniform(&g) - 0.5f);
            f->g_o[p][k] = nerf__rng_uniform(&g) - 0.5f;
        }
    }
}

/*
 * Density noise supplied by the caller, chosen to keep every raw density
 * at least 0.1 away from the ReLU's kink at 0.  The last sample of a ray
 * has delta = 1e10, so its alpha is a step at 0: a finite difference that
 * straddles it measures the step, not the derivative.
 */
static void avoid_kinks(fixture *f)
{
    nerf__pass_out out[2];
    memset(out, 0, sizeof out);
    for (int p = 0; p < 2; p++) {
        size_t n = (size_t)RAYS * (f->s->opts.n_coarse + f->s->opts.n_fine);
        f->noise[p] = calloc(n, sizeof(float));
        f->setup.noise[p] = f->noise[p];
    }
    /* Pass 0's noise moves the fine samples, so fix it first. */
    for (int p = 0; p < (int)(f->s->opts.n_fine ? 2 : 1); p++) {
        CHECK_OK(nerf__render_batch(&f->b, &f->setup, RAYS, f->o, f->d, out));
        const uint32_t m = f->b.n_samples[p];
        for (size_t i = 0; i < (size_t)RAYS * m; i++) {
            float raw = f->b.stratified.sigma[p][i] - f->noise[p][i];
            if (i % m == m - 1 && (i / m) % 3 != 0) {
                /* Empty beyond the last interval: opacity < 1, so the
                 * background and opacity terms carry gradient. */
                f->noise[p][i] = -0.5f - raw;
            } else if (fabsf(raw) < 0.2f) {
                f->noise[p][i] = raw >= 0.0f ? 0.3f : -0.3f;
            }
        }
    }
}

static void teardown(fixture *f)
{
    free(f->noise[0]);
    free(f->noise[1]);
    nerf__batch_release(&f->b);
    nerf_sampler_destroy(f->s);
    nerf_model_destroy(f->m);
}

static double loss(fixture *f)
{
    float rgb[2][3 * RAYS], depth[2][RAYS], opac[2][RAYS];
    nerf__pass_out out[2];
    for (int p = 0; p < 2; p++) {
        out[p] = (nerf__pass_out){rgb[p], depth[p], NULL, opac[p]};
    }
    int rc = nerf__render_batch(&f->b, &f->setup, RAYS, f->o, f->d, out);
    CHECK_OK(rc);
    double l = 0.0;
    f->mean_opacity = 0.0;
    for (int k = 0; k < RAYS; k++) {
        f->mean_opacity += opac[f->b.n_pass - 1][k] / RAYS;
    }
    for (uint32_t p = 0; p < f->b.n_pass; p++) {
        if (!f->use_pass[p]) {
            continue;
        }
        for (int k = 0; k < RAYS; k++) {
            for (int c = 0; c < 3; c++) {
                l += (double)f->g_rgb[p][3 * k + c] * rgb[p][3 * k + c];
            }
            l += (double)f->g_d[p][k] * depth[p][k];
            l += (double)f->g_o[p][k] * opac[p][k];
        }
    }
    return l;
}

/* Whether parameter i (relative to the network) feeds the outputs without
 * a ReLU in between: the rgb layer and the sigma row of the head (not
 * with geo_features, where the density column feeds the colour branch
 * too). */
static bool after_relus(const nerf__network *nw, size_t i)
{
    size_t at = nw->offset + i;
    size_t sigma_row = nw->head.w + (size_t)nw->width * nw->width;
    if (at >= nw->rgb.w && at < nw->rgb.b + 3) {
        return true;
    }
    if (nw->geo_features > 0) {
        return false;
    }
    return (at >= sigma_row && at < sigma_row + nw->width) ||
           at == nw->head.b + nw->width;
}

/* (L(theta + h v) - L(theta - h v)) / 2h over network net, theta = saved. */
static double central(fixture *f, int net, const float *saved,
                      const float *v, float h)
{
    nerf_model *m = f->m;
    const nerf__network *nw = &m->nets[net];
    for (size_t i = 0; i < nw->count; i++) {
        m->params[nw->offset + i] = saved[i] + h * v[i];
    }
    double lp = loss(f);
    for (size_t i = 0; i < nw->count; i++) {
        m->params[nw->offset + i] = saved[i] - h * v[i];
    }
    double lm = loss(f);
    memcpy(m->params + nw->offset, saved, sizeof(float) * nw->count);
    return (lp - lm) / (2.0 * (double)h);
}

/*
 * The head check: v on the parameters after the network's ReLUs alone
 * (after_relus()).  Then the layers before them compute the same bits in
 * every evaluation, and the loss is a smooth function of v's parameters
 * given those layers' outputs, which the workspace keeps: the rgb layer's
 * input (the colour branch's last activations) and, without
 * geo_features, the sigma row's (the trunk's last).  That function is
 * mirrored here in double (float_bounds.h) from those inputs on: the rgb
 * layer and the sigmoid, the sigma row and the density noise, and the
 * compositing of the pass the network serves (composite.c, or
 * composite_packed.c on the samples a marching batch kept); its
 * derivative along v taken in forward mode, with a bound on its
 * rounding.  The library's gradient along v lies within a bound of the
 * exact one too: its compositing backward within the running bound of
 * its operations on the float colours and densities (themselves within
 * the bound of their dot products, any order: gamma(k + 1) of the terms'
 * magnitudes); the sigmoid's backward likewise; each weight's gradient a
 * sum over the N samples of the pass, in any order, blocked or not: within
 * gamma(N) of its terms' magnitudes plus the terms' own errors; and the
 * dot product with v in double.
 */

/* Rows of k inputs x through one output of a linear layer, as the
 * product and its bias compute it in float (any order: gamma(k + 1)),
 * with the derivative along the direction vw, vb of its parameters. */
static fbd tail_dot(const float *w, const float *vw, float b, float vb,
                    const float *x, uint32_t k)
{
    double v = b, mag = fabs(b), dv = vb, dmag = fabs(vb);
    for (uint32_t i = 0; i < k; i++) {
        v += (double)w[i] * x[i];
        mag += fabs((double)w[i] * x[i]);
        if (vw) {
            dv += (double)vw[i] * x[i];
            dmag += fabs((double)vw[i] * x[i]);
        }
    }
    const double g = float_gamma(k + 1), gd = DOUBLE_U * (k + 1) * 1.01;
    return (fbd){{v, g * mag, gd * mag}, {dv, 0.0, gd * dmag}};
}

/* The library's sigmoid, 1 / (1 + expf(-z)). */
static fbd tail_sigmoid(fbd z)
{
    return fbd_div(fbd_in(1.0),
                   fbd_add(fbd_in(1.0), fbd_expf(fbd_neg(z))));
}

/* The background ray k was finished on (NULL: black). */
static const float *ray_bg_of(const fixture *f, size_t k)
{
    static const float white[3] = {1.0f, 1.0f, 1.0f};
    const nerf__batch *b = &f->b;
    if (b->marched) {
        const nerf__packed_batch *pb = &b->marching.packed;
        return pb->bg ? pb->bg + k * pb->bg_stride : NULL;
    }
    return f->setup.background ? f->setup.background + 3 * k
           : f->setup.white_background ? white
                                       : NULL;
}

/* The exact derivative of the loss along v (its bound in *err) and a
 * bound on the library's gradient's distance from it, for v on the
 * parameters after the ReLUs of network `net`. */
static double tail_derivative(fixture *f, int net, const float *v,
                              double *err, double *grad_err)
{
    nerf_model *m = f->m;
    nerf__batch *b = &f->b;
    const nerf__network *nw = &m->nets[net];
    int p = -1, passes = 0;
    for (int q = 0; q < (int)b->n_pass; q++) {
        if (f->use_pass[q] && b->net[q] == net) {
            p = q;
            passes++;
        }
    }
    /* One pass reaches the network: the others' outputs are constants. */
    CHECK_EQ_INT(passes, 1);
    CHECK(nw->use_viewdirs && nw->view_depth >= 1);
    if (passes != 1) {
        *err = *grad_err = INFINITY;
        return 0.0;
    }
    nerf__workspace *ws = &b->ws[b->marched ? 0 : p];
    const nerf__stratified_state *sb = &b->stratified;
    const nerf__march_state *mb = &b->marching;
    const nerf__march_samples *ms = &mb->samples;
    const size_t N = ws->n;
    const uint32_t V = nw->view_width;
    const bool sig_row = nw->geo_features == 0;
    const float *x_rgb = nerf__view_buffer(nw, ws, nw->view_depth - 1);
    const float *x_head = nerf__trunk_buffer(nw, ws, nw->depth - 1);
    const float *P = m->params;
    const float *vr = v + (nw->rgb.w - nw->offset);
    const float *vrb = v + (nw->rgb.b - nw->offset);
    const uint32_t sc = nerf__network_sigma_col(nw);
    const size_t srow = nw->head.w + (size_t)sc * nw->head.in;
    const float *lib_rgb = b->marched ? mb->rgb : sb->rgb[p];
    const float *lib_sigma = b->marched ? mb->sigma : sb->sigma[p];
    const float *noise = f->setup.noise[p];
    CHECK(b->marched || noise || !f->setup.training ||
          f->setup.noise_std == 0.0f);
    fbd *rgb = malloc(sizeof(fbd) * 3 * N), *sig = malloc(sizeof(fbd) * N);
    fb *rgb_x = malloc(sizeof(fb) * 3 * N), *sig_x = malloc(sizeof(fb) * N);
    fb *d_rgb = malloc(sizeof(fb) * 3 * N), *d_sig = malloc(sizeof(fb) * N);
    int off = 0;
    for (size_t r = 0; r < N; r++) {
        for (int c = 0; c < 3; c++) {
            const fbd z = tail_dot(P + nw->rgb.w + (size_t)c * V,
                                   vr + (size_t)c * V, P[nw->rgb.b + c],
                                   vrb[c], x_rgb + r * V, V);
            rgb[3 * r + c] = tail_sigmoid(z);
            rgb_x[3 * r + c] = rgb[3 * r + c].x;
            off += !fb_holds(lib_rgb[3 * r + c], rgb_x[3 * r + c]);
        }
        /* The density: the sigma row (moving with v where it is after the
         * ReLUs) and the noise; a marching model's exponential of its
         * head's column (fixed: v leaves a geo_features head alone). */
        const fbd raw = tail_dot(P + srow, sig_row ? v + (srow - nw->offset)
                                                   : NULL,
                                 P[nw->head.b + sc],
                                 sig_row ? v[nw->head.b + sc - nw->offset]
                                         : 0.0f,
                                 x_head + r * nw->head.in, nw->head.in);
        if (nw->exp_density) {
            CHECK(fb_sign_known(fb_sub(raw.x, fb_in(NERF__EXP_DENSITY_MAX))) &&
                  raw.x.v < NERF__EXP_DENSITY_MAX);
            sig[r] = fbd_expf(raw);
        } else {
            sig[r] = fbd_add(raw, fbd_in(noise ? noise[r] : 0.0f));
        }
        sig_x[r] = sig[r].x;
        off += !fb_holds(lib_sigma[r], sig_x[r]);
    }
    /* The mirror computes what the library did. */
    CHECK_EQ_INT(off, 0);
    fbd L = fbd_in(0.0);
    for (size_t k = 0; k < b->n_rays; k++) {
        const float *bg = ray_bg_of(f, k);
        const double dc[3] = {f->g_rgb[p][3 * k], f->g_rgb[p][3 * k + 1],
                              f->g_rgb[p][3 * k + 2]};
        const double dd = f->g_d[p][k], dop = f->g_o[p][k];
        fbd out[5];
        size_t at;
        if (b->marched) {
            at = ms->offsets[k];
            const uint32_t n = (uint32_t)(ms->offsets[k + 1] - at);
            /* Training kept the samples its composite uses: all. */
            float T = 1.0f;
            CHECK_EQ_INT(nerf__composite_packed_ray_used(
                             n, ms->dt + at, lib_sigma + at,
                             mb->packed.eps, &T),
                         n);
            CHECK(n <= FB_RAY_MAX);
            fb_ray ray;
            fb_ray_init(&ray);
            for (uint32_t i = 0; i < n; i++) {
                fb_packed_step(&ray, ms->t[at + i],
                               ms->dt[at + i], rgb + 3 * (at + i),
                               sig[at + i], NULL);
            }
            fb_packed_rgb(&ray, bg, out);
            out[3] = ray.depth;
            out[4] = ray.opacity;
            fb_packed_backward(n, ms->t + at, ms->dt + at,
                               rgb_x + 3 * at, sig_x + at, bg, dc, dd, dop,
                               d_rgb + 3 * at, d_sig + at);
        } else {
            const uint32_t n = b->n_samples[p];
            at = k * n;
            const float *t = sb->t[p] + at;
            fb_composite_forward(n, t, b->dir_norm[k], rgb + 3 * at,
                                 sig + at, bg, out, &out[3], &out[4], NULL);
            fb_composite_backward(n, t, b->dir_norm[k], rgb_x + 3 * at,
                                  sig_x + at, bg, dc, dd, dop, d_rgb + 3 * at,
                                  d_sig + at);
        }
        for (int c = 0; c < 3; c++) {
            L = fbd_add(L, fbd_mul(fbd_in(dc[c]), out[c]));
        }
        L = fbd_add(L, fbd_mul(fbd_in(dd), out[3]));
        L = fbd_add(L, fbd_mul(fbd_in(dop), out[4]));
    }
    /* What the batch's backward gave the network (the last pass it ran,
     * which is p): the compositing backward of the library's own float
     * colours and densities, within the running bound of its operations
     * on them. */
    bool last_pass = true;
    for (int q = p + 1; q < (int)b->n_pass; q++) {
        last_pass = last_pass && !f->use_pass[q];
    }
    CHECK(last_pass);
    const float *lib_d_rgb = b->marched ? mb->d_rgb : sb->d_rgb;
    const float *lib_d_sigma = b->marched ? mb->d_sigma : sb->d_sigma;
    int wired = 0;
    for (size_t r = 0; r < N; r++) {
        rgb_x[3 * r] = fb_in(lib_rgb[3 * r]);
        rgb_x[3 * r + 1] = fb_in(lib_rgb[3 * r + 1]);
        rgb_x[3 * r + 2] = fb_in(lib_rgb[3 * r + 2]);
        sig_x[r] = fb_in(lib_sigma[r]);
    }
    fb *lib_in_d_rgb = malloc(sizeof(fb) * 3 * N);
    fb *lib_in_d_sig = malloc(sizeof(fb) * N);
    for (size_t k = 0; k < b->n_rays; k++) {
        const float *bg = ray_bg_of(f, k);
        const double dc[3] = {f->g_rgb[p][3 * k], f->g_rgb[p][3 * k + 1],
                              f->g_rgb[p][3 * k + 2]};
        const double dd = f->g_d[p][k], dop = f->g_o[p][k];
        size_t at, n;
        if (b->marched) {
            at = ms->offsets[k];
            n = ms->offsets[k + 1] - at;
            fb_packed_backward((uint32_t)n, ms->t + at,
                               ms->dt + at, rgb_x + 3 * at, sig_x + at,
                               bg, dc, dd, dop, lib_in_d_rgb + 3 * at,
                               lib_in_d_sig + at);
        } else {
            n = b->n_samples[p];
            at = k * n;
            fb_composite_backward((uint32_t)n, sb->t[p] + at, b->dir_norm[k],
                                  rgb_x + 3 * at, sig_x + at, bg, dc, dd,
                                  dop, lib_in_d_rgb + 3 * at,
                                  lib_in_d_sig + at);
        }
        for (size_t i = at; i < at + n; i++) {
            wired += !fb_holds(lib_d_sigma[i], lib_in_d_sig[i]);
            for (int c = 0; c < 3; c++) {
                wired += !fb_holds(lib_d_rgb[3 * i + c],
                                   lib_in_d_rgb[3 * i + c]);
            }
        }
    }
    CHECK_EQ_INT(wired, 0);
    free(lib_in_d_rgb);
    free(lib_in_d_sig);
    for (size_t r = 0; r < N; r++) {
        for (int c = 0; c < 3; c++) {
            rgb_x[3 * r + c] = rgb[3 * r + c].x;
        }
        sig_x[r] = sig[r].x;
    }
    /* The library's gradient of each parameter after the ReLUs: sums over
     * the N samples of dz x (the sigmoid's backward g y (1 - y) for the
     * colours, the density's gradient itself for the raw sigma). */
    double bound = 0.0, dot = 0.0;
    const double gN = float_gamma((double)N);
    for (int c = 0; c < 3; c++) {
        double gb_mag = 0.0, gb_err = 0.0;
        double *gw_mag = calloc(V, sizeof(double));
        double *gw_err = calloc(V, sizeof(double));
        for (size_t r = 0; r < N; r++) {
            const fb y = rgb_x[3 * r + c];
            const fb dz = fb_mul(fb_mul(d_rgb[3 * r + c], y),
                                 fb_sub(fb_in(1.0), y));
            gb_mag += fb_mag(dz);
            gb_err += dz.e;
            for (uint32_t i = 0; i < V; i++) {
                const double x = fabs(x_rgb[r * V + i]);
                gw_mag[i] += fb_mag(dz) * x;
                gw_err[i] += dz.e * x;
            }
        }
        for (uint32_t i = 0; i < V; i++) {
            bound += fabs(vr[c * V + i]) * (gN * gw_mag[i] + gw_err[i]);
        }
        bound += fabs(vrb[c]) * (gN * gb_mag + gb_err);
        free(gw_mag);
        free(gw_err);
    }
    if (sig_row) {
        const uint32_t K = nw->head.in;
        double gb_mag = 0.0, gb_err = 0.0;
        double *gw_mag = calloc(K, sizeof(double));
        double *gw_err = calloc(K, sizeof(double));
        for (size_t r = 0; r < N; r++) {
            gb_mag += fb_mag(d_sig[r]);
            gb_err += d_sig[r].e;
            for (uint32_t i = 0; i < K; i++) {
                const double x = fabs(x_head[r * K + i]);
                gw_mag[i] += fb_mag(d_sig[r]) * x;
                gw_err[i] += d_sig[r].e * x;
            }
        }
        const float *vs = v + (srow - nw->offset);
        for (uint32_t i = 0; i < K; i++) {
            bound += fabs(vs[i]) * (gN * gw_mag[i] + gw_err[i]);
        }
        bound += fabs(v[nw->head.b + sc - nw->offset]) * (gN * gb_mag + gb_err);
        free(gw_mag);
        free(gw_err);
    }
    /* The dot product with v, in double. */
    for (size_t i = 0; i < nw->count; i++) {
        dot += fabs((double)v[i] * m->grads[nw->offset + i]);
    }
    bound += DOUBLE_U * (double)nw->count * 1.01 * dot;
    free(rgb);
    free(sig);
    free(rgb_x);
    free(sig_x);
    free(d_rgb);
    free(d_sig);
    *err = L.dx.ed;
    *grad_err = bound;
    return L.dx.v;
}

/*
 * dL/dtheta . v for a random v over network `net`'s parameters.  `last`
 * restricts v to the parameters after the network's ReLUs, and the
 * library's value is checked against the exact derivative within the
 * bound of both sides' arithmetic (tail_derivative()).  Over all
 * parameters hidden units may switch within any step and the float
 * forward's rounding enters a difference quotient at 1/h, and no bound
 * is derived for either: the central difference is printed, not
 * asserted (test_network checks the networks' own backward against a
 * double reference of every parameter).
 */
static void check_direction(fixture *f, int net, uint64_t seed, bool last)
{
    nerf_model *m = f->m;
    nerf__model_zero_grad(m);
    loss(f);
    const float *gr[2], *gd[2], *go[2];
    for (int p = 0; p < 2; p++) {
        gr[p] = f->use_pass[p] ? f->g_rgb[p] : NULL;
        gd[p] = f->use_pass[p] ? f->g_d[p] : NULL;
        go[p] = f->use_pass[p] ? f->g_o[p] : NULL;
    }
    CHECK_OK(nerf__render_batch_backward(&f->b, m, gr, gd, go));
    const nerf__network *nw = &m->nets[net];
    float *v = malloc(sizeof(float) * nw->count);
    float *saved = malloc(sizeof(float) * nw->count);
    memcpy(saved, m->params + nw->offset, sizeof(float) * nw->count);
    nerf__rng g = nerf__rng_make(seed, 77);
    double analytic = 0.0;
    for (size_t i = 0; i < nw->count; i++) {
        v[i] = 2.0f * nerf__rng_uniform(&g) - 1.0f;
        if (last && !after_relus(nw, i)) {
            v[i] = 0.0f;
        }
        analytic += (double)v[i] * m->grads[nw->offset + i];
    }
    /* Partly transparent rays: every term of the gradient is in play. */
    CHECK(f->mean_opacity > 0.2 && f->mean_opacity < 0.97);
    CHECK(fabs(analytic) > 1e-3);
    if (last) {
        double exact_err, grad_err;
        const double exact = tail_derivative(f, net, v, &exact_err,
                                             &grad_err);
        const double tol = (exact_err + grad_err) * (1.0 + 0x1p-30);
        printf("  network %d (head): analytic %.9g, exact %.9g (differ by "
               "%.2g of the tolerance %.2g; mean opacity %.3f)\n", net,
               analytic, exact, fabs(analytic - exact) / tol, tol,
               f->mean_opacity);
        CHECK(fabs(analytic - exact) <= tol);
        /* The biases one by one too: their gradients are sums over the
         * samples alone, whose bounds do not add up over every weight of
         * the layer as a random direction's do. */
        const size_t one[4] = {nw->rgb.b, nw->rgb.b + 1, nw->rgb.b + 2,
                               nw->head.b + nerf__network_sigma_col(nw)};
        for (int k = 0; k < (nw->geo_features ? 3 : 4); k++) {
            memset(v, 0, sizeof(float) * nw->count);
            v[one[k] - nw->offset] = 1.0f;
            const double a = m->grads[one[k]];
            const double e = tail_derivative(f, net, v, &exact_err,
                                             &grad_err);
            const double t = (exact_err + grad_err) * (1.0 + 0x1p-30);
            if (!(fabs(a - e) <= t)) {
                FAILF("network %d, bias %zu: analytic %.9g, exact %.9g "
                      "(tolerance %.2g)", net, one[k] - nw->offset, a, e, t);
            }
        }
    } else {
        const double fd = central(f, net, saved, v, 5e-4f);
        printf("  network %d: analytic %.6g, finite difference %.6g (rel "
               "%.1e, not asserted; mean opacity %.3f)\n", net, analytic, fd,
               fabs(fd - analytic) / fmax(fabs(fd), 5e-2), f->mean_opacity);
    }
    free(v);
    free(saved);
}

TEST(coarse_only_with_noise)
{
    /* Training draws (jittered samples, density noise) are fixed by the
     * seed, so the forward is a deterministic function of the weights. */
    fixture f;
    setup(&f, 0, true);
    f.use_pass[0] = 1;
    /* The generator's noise reaches the densities. */
    loss(&f);
    float noisy = f.b.stratified.sigma[0][5];
    f.setup.noise_std = 0.0f;
    loss(&f);
    CHECK(f.b.stratified.sigma[0][5] != noisy);
    avoid_kinks(&f);
    for (uint64_t seed = 1; seed <= 3; seed++) {
        check_direction(&f, 0, seed, true);
        check_direction(&f, 0, seed, false);
    }
    teardown(&f);
}

TEST(hierarchical_both_networks)
{
    fixture f;
    setup(&f, 32, false);
    avoid_kinks(&f);
    /* Coarse outputs against coarse weights (the fine pass is ignored). */
    f.use_pass[0] = 1;
    check_direction(&f, 0, 11, true);
    check_direction(&f, 0, 11, false);
    /* Fine outputs against fine weights: the coarse pass, hence the fine
     * samples, stay put. */
    f.use_pass[0] = 0;
    f.use_pass[1] = 1;
    check_direction(&f, 1, 12, true);
    check_direction(&f, 1, 12, false);
    /* Both losses: the coarse loss does not reach the fine network. */
    f.use_pass[0] = 1;
    check_direction(&f, 1, 13, true);
    teardown(&f);
}

TEST(no_fine_network)
{
    /* A model without a fine network evaluates the fine samples with the
     * coarse one; its gradient then collects both passes. */
    fixture f;
    setup(&f, 16, false);
    nerf_model_destroy(f.m);
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    mo.use_fine = 0;
    CHECK_OK(nerf_model_create(&f.m, &mo));
    f.setup.model = f.m;
    f.use_pass[1] = 1;
    /* Only the fine loss: moving the weights moves the fine samples too,
     * so check just that both passes ran on network 0 and backward ran. */
    loss(&f);
    CHECK(f.b.n_pass == 2 && f.b.net[0] == 0 && f.b.net[1] == 0);
    const float *gr[2] = {NULL, f.g_rgb[1]};
    nerf__model_zero_grad(f.m);
    CHECK_OK(nerf__render_batch_backward(&f.b, f.m, gr, NULL, NULL));
    double norm = 0.0;
    for (size_t i = 0; i < f.m->n_params; i++) {
        norm += fabs(f.m->grads[i]);
    }
    CHECK(norm > 0.0);
    /* Backward without a kept forward is refused. */
    f.setup.keep = false;
    loss(&f);
    CHECK_EQ_INT(nerf__render_batch_backward(&f.b, f.m, gr, NULL, NULL),
                 NERF_EINVAL);
    teardown(&f);
}

TEST(batch_split_reproducible)
{
    /* Training draws are keyed by ray: one batch of 12 and two of 6 give
     * the same samples and noise.  What passes through the network is the
     * same where every sample is computed alone, whatever else shares its
     * products: the fused path, forced here from before the batch's first
     * forward (a workspace reserved off it stays off it) on a tiny model
     * one narrower, so that its head (width + 1 outputs) fits the fused
     * kernels; oneDNN models, which it does not apply to, only where
     * nerf__model_rows_alone() says so. */
    const int was = nerf__smm_variant();
    CHECK_OK(nerf__smm_use(nerf__smm_best()));
    fixture f;
    setup(&f, 16, true);
    nerf_model_destroy(f.m);
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_TINY);
    mo.width = NERF__FUSED_MAX_WIDTH - 1;
    mo.seed = 9;
    CHECK_OK(nerf_model_create(&f.m, &mo));
    bias_density(f.m);
    f.setup.model = f.m;
    CHECK(f.m->onednn != NULL || !nerf__model_uses_blas(f.m));
    f.use_pass[0] = f.use_pass[1] = 1;
    loss(&f);
    const uint32_t n0 = f.b.n_samples[0], n1 = f.b.n_samples[1];
    float *t0_all = malloc(sizeof(float) * RAYS * n0);
    float *t_all = malloc(sizeof(float) * RAYS * n1);
    float *s_all = malloc(sizeof(float) * RAYS * n1);
    memcpy(t0_all, f.b.stratified.t[0], sizeof(float) * RAYS * n0);
    memcpy(t_all, f.b.stratified.t[1], sizeof(float) * RAYS * n1);
    memcpy(s_all, f.b.stratified.sigma[0], sizeof(float) * RAYS * n0);
    nerf__pass_out out[2];
    memset(out, 0, sizeof out);
    int differ = 0;
    for (int half = 0; half < 2; half++) {
        nerf__render_setup s = f.setup;
        s.first_ray += 6 * half;
        CHECK_OK(nerf__render_batch(&f.b, &s, 6, f.o + 18 * half,
                                    f.d + 18 * half, out));
        /* The jittered coarse samples do not depend on the network. */
        CHECK(memcmp(f.b.stratified.t[0], t0_all + 6 * half * n0,
                     sizeof(float) * 6 * n0) == 0);
        /* Densities with their noise, and the fine samples they place. */
        differ += memcmp(f.b.stratified.sigma[0], s_all + 6 * half * n0,
                         sizeof(float) * 6 * n0) != 0;
        differ += memcmp(f.b.stratified.t[1], t_all + 6 * half * n1,
                         sizeof(float) * 6 * n1) != 0;
    }
    if (nerf__model_rows_alone(f.m)) {
        CHECK_EQ_INT(differ, 0);
    } else {
        /* A oneDNN model that made a primitive other than brgemm; the
         * fine samples move by where the densities put the weights, for
         * which no bound is derived here. */
        printf("  densities and fine samples not compared (%d differ): "
               "this oneDNN model does not compute samples alone\n", differ);
    }
    free(t0_all);
    free(t_all);
    free(s_all);
    teardown(&f);
    CHECK_OK(nerf__smm_use(was));
}

static int ball(void *ctx, size_t n, const float *xyz, float *sigma)
{
    (void)ctx;
    for (size_t i = 0; i < n; i++) {
        const float *p = xyz + 3 * i;
        sigma[i] = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] < 0.64f ? 100.0f
                                                                  : 0.0f;
    }
    return 0;
}

/*
 * The marching path: a small fast model, its grid keeping a ball of
 * radius 0.8, jittered training samples.  The grid does not change during
 * the check, so neither do the samples, and the densities stay far from
 * early termination: the loss is a smooth function of the rgb layer.
 */
/* Swap the fixture's model and sampler for a small fast model whose grid
 * keeps a ball of radius 0.8, and its marching sampler. */
static bool use_fast(fixture *f)
{
    nerf_model_destroy(f->m);
    nerf_sampler_destroy(f->s);
    f->m = NULL;
    f->s = NULL;
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_options_preset(&mo, NERF_PRESET_FAST);
    mo.hash_levels = 4;
    mo.hash_log2_size = 12;
    mo.hash_max_resolution = 64;
    mo.seed = 9;
    CHECK_OK(nerf_model_create(&f->m, &mo));
    nerf_sampler_options so;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    nerf_sampler_options_preset(&so, NERF_PRESET_FAST);
    so.seed = 4;
    CHECK_OK(nerf_sampler_create(&f->s, &so));
    if (f->m == NULL || f->s == NULL) {
        return false;
    }
    /* exp(logit - 1): about 0.4 per unit, so the rays are partly
     * transparent. */
    f->m->params[f->m->nets[0].head.b] -= 1.0f;
    CHECK_OK(nerf__occupancy_update(f->m->grid, ball, NULL,
                                    f->m->grid->cells));
    f->setup.model = f->m;
    f->setup.sampler = f->s;
    f->setup.noise_std = 0.0f;
    return true;
}

/*
 * Each pass's colours of the rays on per-ray backgrounds against the same
 * rays on black: the difference must be (1 - opacity) bg, ray by ray.
 */
static void check_backgrounds(fixture *f, const float *bg)
{
    float black[2][3 * RAYS], rgb[2][3 * RAYS], opac[2][RAYS];
    nerf__pass_out out[2];
    for (int p = 0; p < 2; p++) {
        out[p] = (nerf__pass_out){black[p], NULL, NULL, opac[p]};
    }
    nerf__render_setup s = f->setup;
    s.white_background = false;
    s.background = NULL;
    CHECK_OK(nerf__render_batch(&f->b, &s, RAYS, f->o, f->d, out));
    for (int p = 0; p < 2; p++) {
        out[p].rgb = rgb[p];
    }
    /* The per-ray colours override white_background. */
    s.white_background = true;
    s.background = bg;
    CHECK_OK(nerf__render_batch(&f->b, &s, RAYS, f->o, f->d, out));
    int bad = 0;
    double clear = 0.0;
    for (uint32_t p = 0; p < f->b.n_pass; p++) {
        for (int k = 0; k < RAYS; k++) {
            clear += 1.0 - opac[p][k];
            for (int c = 0; c < 3; c++) {
                float want = black[p][3 * k + c] +
                             (1.0f - opac[p][k]) * bg[3 * k + c];
                bad += fabsf(rgb[p][3 * k + c] - want) > 1e-5f;
            }
        }
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(clear > 0.5); /* the backgrounds showed */
}

/*
 * random_background training: every ray finished on its own colour, in
 * the forward and in the backward, on both paths.  A backward that
 * finished on white (or black) instead fails the head comparisons.
 */
TEST(per_ray_background)
{
    float bg[3 * RAYS];
    nerf__rng g = nerf__rng_make(31, 0);
    for (int i = 0; i < 3 * RAYS; i++) {
        bg[i] = nerf__rng_uniform(&g);
    }
    fixture f;
    setup(&f, 16, true);
    avoid_kinks(&f);
    check_backgrounds(&f, bg);
    f.setup.background = bg;
    f.use_pass[0] = 1;
    check_direction(&f, 0, 31, true);
    check_direction(&f, 0, 32, false);
    f.use_pass[0] = 0;
    f.use_pass[1] = 1;
    check_direction(&f, 1, 33, true);
    teardown(&f);

    setup(&f, 0, true);
    if (use_fast(&f)) {
        check_backgrounds(&f, bg);
        f.setup.background = bg;
        f.use_pass[0] = 1;
        loss(&f);
        CHECK(f.b.marched);
        check_direction(&f, 0, 34, true);
        check_direction(&f, 0, 35, false);
    }
    teardown(&f);
}

TEST(marching_fast_model)
{
    fixture f;
    setup(&f, 0, true);
    if (!use_fast(&f)) {
        teardown(&f);
        return;
    }
    f.use_pass[0] = 1;
    loss(&f);
    /* The batch's packed samples, of each call below in turn. */
    const nerf__march_samples *ms = &f.b.marching.samples;
    CHECK(f.b.marched && f.b.n_pass == 1);
    CHECK(ms->total > RAYS && ms->total < RAYS * 400);
    check_direction(&f, 0, 21, true);
    check_direction(&f, 0, 22, false);
    /* Jittered samples are keyed by ray: one batch or two, the same.
     * Training cuts each ray where the densities turn it opaque, which
     * would make the samples' t depend on the network's rounding too; these
     * densities cut nothing (the premise, asserted), so what is compared
     * is the march alone. */
    CHECK_EQ_INT(f.b.n_evaluated, ms->total);
    const size_t total = ms->total;
    float *t_all = malloc(sizeof(float) * total);
    memcpy(t_all, ms->t, sizeof(float) * total);
    size_t at = 0;
    nerf__pass_out out[2];
    memset(out, 0, sizeof out);
    for (int half = 0; half < 2; half++) {
        nerf__render_setup s = f.setup;
        s.first_ray += 6 * half;
        CHECK_OK(nerf__render_batch(&f.b, &s, 6, f.o + 18 * half,
                                    f.d + 18 * half, out));
        CHECK_EQ_INT(f.b.n_evaluated, ms->total);
        CHECK(at + ms->total <= total);
        if (at + ms->total <= total) {
            CHECK(memcmp(ms->t, t_all + at,
                         sizeof(float) * ms->total) == 0);
        }
        at += ms->total;
    }
    CHECK_EQ_INT(at, total);
    free(t_all);
    teardown(&f);
}

int main(void)
{
    RUN(coarse_only_with_noise);
    RUN(hierarchical_both_networks);
    RUN(no_fine_network);
    RUN(batch_split_reproducible);
    RUN(marching_fast_model);
    RUN(per_ray_background);
    HARNESS_EXIT();
}
