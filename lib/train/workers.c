/*
 * Data-parallel training: which rays of a step's batch this worker trains
 * on, the gradient exchange through the caller's hook, and the check that
 * the workers' weights are still the same.  The transport (MPI or other)
 * is the caller's: the library only calls the hooks.
 */
#include <string.h>
#include <zlib.h>

#include "encoding.h"
#include "march.h"
#include "occupancy.h"
#include "trainer.h"

void nerf__trainer_exchange_init(nerf_trainer *t)
{
    nerf_exchange *x = &t->exchange;
    memset(x, 0, sizeof *x);
    x->struct_size = sizeof *x;
    x->worker_rank = t->opts.worker_rank;
    x->worker_count = t->workers;
    const nerf_model *m = t->model;
    for (uint32_t i = 0; i < m->n_nets; i++) {
        const nerf__network *net = &m->nets[i];
        const size_t enc = nerf__encoding_params(&net->pos_enc);
        if (enc && x->n_sparse < NERF_EXCHANGE_MAX_SPARSE) {
            x->sparse_begin[x->n_sparse] = net->pos_params;
            x->sparse_end[x->n_sparse] = net->pos_params + enc;
            x->n_sparse++;
        }
    }
}

/*
 * Rays the whole step takes of the batch_rays drawn: all of them, or with
 * batch_samples the fewest first rays whose samples reach the budget (at
 * least one), as nerf__render_batch() cuts a batch for a trainer alone.
 * A marching sampler's counts come from a march of every ray without the
 * network, exactly the march the render would make (same grid, options
 * and ray numbering).
 */
static size_t step_rays(nerf_trainer *t)
{
    const size_t B = t->opts.batch_rays;
    const size_t budget = t->opts.batch_samples;
    if (budget == 0) {
        return B;
    }
    if (!t->march) {
        const nerf_sampler_options *so = &t->sampler->opts;
        const size_t per_ray =
            so->n_coarse + (so->n_fine > 0 ? (size_t)so->n_coarse + so->n_fine : 0);
        const size_t fit = (budget + per_ray - 1) / per_ray;
        return fit < B ? fit : B;
    }
    const nerf__occupancy *g = nerf__model_grid(t->model);
    nerf__march_options mo;
    nerf__render_march_options(&t->setup, g, &mo);
    nerf__march_rays rays = nerf__render_march_rays(&t->setup, B, t->origins,
                                                    t->directions);
    const size_t *off = t->march_offsets;
    nerf__march_count(g, &mo, &rays, t->march_offsets);
    size_t n = 1;
    while (n < B && off[n] < budget) {
        n++;
    }
    return n;
}

void nerf__trainer_share(nerf_trainer *t, uint64_t step, nerf__share *s)
{
    const size_t B = t->opts.batch_rays;
    t->setup.first_ray = step * B;
    s->all = step_rays(t);
    /* Contiguous and as even as can be: the workers' shares tile [0, all)
     * in rank order, so the batch is the lone trainer's in its order. */
    const uint64_t W = t->workers, r = t->opts.worker_rank;
    s->lo = (size_t)((uint64_t)s->all * r / W);
    s->hi = (size_t)((uint64_t)s->all * (r + 1) / W);
}

static int hook_failed(nerf_trainer *t, const char *what, int ret,
                       uint64_t step)
{
    const char *msg = t->exchange.message;
    if (msg[0]) {
        return nerf__error(NERF_ERROR, "nerf_trainer_step: the %s hook of "
                           "worker %u of %u failed at step %llu: %s", what,
                           (unsigned)t->opts.worker_rank,
                           (unsigned)t->workers, (unsigned long long)step,
                           msg);
    }
    return nerf__error(NERF_ERROR, "nerf_trainer_step: the %s hook of worker "
                       "%u of %u failed at step %llu (it returned %d and "
                       "gave no reason)", what, (unsigned)t->opts.worker_rank,
                       (unsigned)t->workers, (unsigned long long)step, ret);
}

int nerf__trainer_exchange(nerf_trainer *t, uint64_t step, size_t rays,
                           size_t all)
{
    if (t->opts.grad_hook == NULL) {
        return NERF_OK;
    }
    nerf_model *m = t->model;
    nerf_exchange *x = &t->exchange;
    x->step = step;
    x->rays = rays;
    x->batch_rays = all;
    x->message[0] = '\0';
    /* The hook writes every element; the next step must clear them. */
    m->grads_dirty = true;
    int ret = t->opts.grad_hook(t->opts.hook_user, m->grads, m->n_params, x);
    x->message[sizeof x->message - 1] = '\0';
    return ret == 0 ? NERF_OK : hook_failed(t, "gradient", ret, step);
}

/* CRC-32 of the parameters' bytes: cheap next to a step (one pass over
 * the weights), and any difference in any bit shows. */
static uint32_t weights_crc(const nerf_model *m)
{
    return (uint32_t)crc32_z(0L, (const unsigned char *)m->params,
                             m->n_params * sizeof(float));
}

int nerf__trainer_check_workers(nerf_trainer *t, bool first)
{
    const uint32_t every = t->opts.checksum_every;
    nerf_model *m = t->model;
    if (every == 0 || (!first && m->step % every != 0)) {
        return NERF_OK;
    }
    nerf_exchange *x = &t->exchange;
    const uint32_t own = weights_crc(m);
    uint32_t range[2] = {own, own};
    x->step = m->step;
    x->rays = x->batch_rays = 0;
    x->message[0] = '\0';
    int ret = t->opts.checksum_hook(t->opts.hook_user, range, x);
    x->message[sizeof x->message - 1] = '\0';
    if (ret != 0) {
        return hook_failed(t, "checksum", ret, m->step);
    }
    if (range[0] != range[1]) {
        return nerf__error(NERF_ERROR, "nerf_trainer_step: the workers' "
                           "weights differ at step %llu (CRC-32 from %08x to "
                           "%08x across the %u workers; worker %u has %08x): "
                           "they %s", (unsigned long long)m->step,
                           (unsigned)range[0], (unsigned)range[1],
                           (unsigned)t->workers,
                           (unsigned)t->opts.worker_rank, (unsigned)own,
                           first ? "did not start from the same model (same "
                                   "seed and options, or the same checkpoint)"
                                 : "diverged: a gradient hook that does not "
                                   "give every worker the same sum, or "
                                   "workers with different data or options");
    }
    nerf__log(&t->env, NERF_LOG_DEBUG, "trainer: step %llu, the %u workers' "
              "weights agree (CRC-32 %08x)", (unsigned long long)m->step,
              (unsigned)t->workers, (unsigned)own);
    return NERF_OK;
}
