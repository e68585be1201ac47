/*
 * Weights that are not finite: what a run that diverged leaves.  A model
 * holding them still loads, so that it can be inspected, but nothing is
 * made of it: renderers, trainers, meshes and saves refuse it, saying
 * what it is, rather than drawing black, blaming the images or writing a
 * checkpoint over a good one.
 */
#include <stdio.h>
#include <string.h>

#include "model.h"

enum { FINITE_UNKNOWN = 0, FINITE_YES = 1, FINITE_NO = 2 };

static bool is_finite_bits(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    return (u & 0x7f800000u) != 0x7f800000u;
}

/* One pass over the weights; an integer test, so that it vectorises. */
static bool all_finite(const float *p, size_t n)
{
    uint32_t bad = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t u;
        memcpy(&u, p + i, sizeof u);
        bad |= (uint32_t)((u & 0x7f800000u) == 0x7f800000u);
    }
    return bad == 0;
}

bool nerf__model_finite(const nerf_model *m)
{
    int state = atomic_load_explicit(&m->finite, memory_order_relaxed);
    if (state == FINITE_UNKNOWN) {
        state = all_finite(m->params, m->n_params) ? FINITE_YES : FINITE_NO;
        /* The model's memory is the caller's, never const storage: the
         * answer is kept until the weights change.  Concurrent readers
         * store the same answer. */
        atomic_store_explicit(&((nerf_model *)m)->finite, state,
                              memory_order_relaxed);
    }
    return state == FINITE_YES;
}

void nerf__model_finite_unknown(nerf_model *m)
{
    atomic_store_explicit(&m->finite, FINITE_UNKNOWN, memory_order_relaxed);
}

/* Where parameter i lies within one layer: its weights or its bias. */
static bool in_linear(const nerf__linear *l, const char *name, size_t i,
                      char *buf, size_t size)
{
    const size_t w = (size_t)l->in * l->out;
    if (l->out == 0 || i < l->w || i >= l->b + l->out) {
        return false;
    }
    if (i < l->w + w) {
        snprintf(buf, size, "%s weights [row %zu, column %zu]", name,
                 (i - l->w) / l->in, (i - l->w) % l->in);
    } else {
        snprintf(buf, size, "%s bias [%zu]", name, i - l->b);
    }
    return true;
}

static void describe_in_network(const nerf__network *net, size_t i,
                                char *buf, size_t size)
{
    const size_t table = nerf__encoding_params(&net->pos_enc);
    if (table > 0 && i >= net->pos_params && i < net->pos_params + table) {
        const size_t k = i - net->pos_params;
        uint32_t level = 0;
        if (net->pos_enc.kind == NERF_ENCODING_HASHGRID) {
            const nerf__hashgrid *hg = &net->pos_enc.u.hash;
            while (level + 1 < hg->levels && k >= hg->offset[level + 1]) {
                level++;
            }
        }
        snprintf(buf, size, "hash table, level %u [entry %zu of the table]",
                 (unsigned)level, k);
        return;
    }
    char name[32];
    for (uint32_t t = 0; t < net->depth; t++) {
        snprintf(name, sizeof name, "trunk layer %u", (unsigned)t);
        if (in_linear(&net->trunk[t], name, i, buf, size)) {
            return;
        }
    }
    if (in_linear(&net->head, "density head", i, buf, size)) {
        return;
    }
    for (uint32_t v = 0; v < net->view_depth; v++) {
        snprintf(name, sizeof name, "colour layer %u", (unsigned)v);
        if (in_linear(&net->view[v], name, i, buf, size)) {
            return;
        }
    }
    if (!in_linear(&net->rgb, "rgb layer", i, buf, size)) {
        snprintf(buf, size, "parameter %zu", i - net->offset);
    }
}

void nerf__model_nonfinite_text(const nerf_model *m, char *buf, size_t size)
{
    size_t count = 0, first = 0;
    for (size_t i = 0; i < m->n_params; i++) {
        if (!is_finite_bits(m->params[i])) {
            first = count == 0 ? i : first;
            count++;
        }
    }
    char where[192] = "";
    for (uint32_t k = 0; k < m->n_nets; k++) {
        const nerf__network *net = &m->nets[k];
        if (first >= net->offset && first < net->offset + net->count) {
            char part[112];
            describe_in_network(net, first, part, sizeof part);
            snprintf(where, sizeof where, "the %s network's %s",
                     k == NERF_NETWORK_COARSE ? "coarse" : "fine", part);
        }
    }
    snprintf(buf, size, "%zu of %zu weights are NaN or infinite, the first "
             "in %s", count, m->n_params, where);
}

int nerf__model_check_finite(const nerf_model *m, const char *fn)
{
    if (nerf__model_finite(m)) {
        return NERF_OK;
    }
    char text[320];
    nerf__model_nonfinite_text(m, text, sizeof text);
    if (m->source != NULL) {
        return nerf__error(NERF_EINVAL, "%s: the weights of %s are not "
                           "finite (%s): the run that trained it diverged",
                           fn, m->source, text);
    }
    return nerf__error(NERF_EINVAL, "%s: the model's weights are not finite "
                       "(%s): its training diverged", fn, text);
}

void nerf__model_warn_nonfinite(const nerf_model *m, const char *path)
{
    if (nerf__model_finite(m)) {
        return;
    }
    char text[320];
    nerf__model_nonfinite_text(m, text, sizeof text);
    nerf__log(&m->env, NERF_LOG_WARN, "%s: %s: the run that trained it "
              "diverged; the model loads for inspection (nerf_model_query), "
              "but renderers, trainers, meshes and saves refuse it", path,
              text);
}
