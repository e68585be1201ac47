#include "model.h"

#include <math.h>
#include <string.h>

#include "average.h"
#include "dispatch.h"
#include "gemm_onednn.h"
#include "network_fused.h"
#include "occupancy.h"
#include "options.h"

/* The defaults are the reference preset: the paper's network. */
static void model_defaults(nerf_model_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->encoding = NERF_ENCODING_FREQUENCY;
    o->pos_frequencies = 10;
    o->dir_frequencies = 4;
    o->encoding_flags = NERF_ENCODING_INCLUDE_INPUT;
    o->depth = 8;
    o->width = 256;
    o->skip_layer = 5;
    o->view_width = 128;
    o->use_viewdirs = 1;
    o->use_fine = 1;
    o->dir_encoding = NERF_ENCODING_FREQUENCY;
    o->sh_degree = 4;
    o->hash_levels = 16;
    o->hash_features = 2;
    o->hash_log2_size = 19;
    o->hash_min_resolution = 16;
    o->hash_max_resolution = 2048;
    o->bound = 1.5f;
    o->view_depth = 1;
    o->density_activation = NERF_DENSITY_RELU;
}

/* Mueller et al.'s NeRF configuration: hash grid, a 64-wide one-layer
 * density network with 16 outputs, a two-layer 64-wide colour network on
 * spherical harmonics. */
static void fast_options(nerf_model_options *o)
{
    model_defaults(o);
    o->encoding = NERF_ENCODING_HASHGRID;
    o->dir_encoding = NERF_ENCODING_SPHERICAL_HARMONICS;
    o->depth = 1;
    o->width = 64;
    o->skip_layer = 0;
    o->geo_features = 16;
    o->view_width = 64;
    o->view_depth = 2;
    o->density_activation = NERF_DENSITY_EXP;
    o->use_fine = 0;
    /* Mueller et al. spread the levels to 2048 cells; in the tens of
     * thousands of steps a CPU trains, 1024 scored higher on lego (ten
     * and thirty minutes) and on fern (docs/perf-log/
     * 2026-11-29-0.10.5-to-0.10.8.md, "0.10.5"). */
    o->hash_max_resolution = 1024;
    /* Eight levels of four features where Mueller et al. take sixteen of
     * two: the same 32 inputs to the network and about as many table
     * parameters, but half the corners a sample reads and writes (an
     * entry's four features share a cache line), which is what a CPU
     * step waits on.  A step learns a little less, and a timed run
     * takes more of them: on lego, ten minutes scored higher on all
     * three seeds (docs/perf-log/2026-11-29-0.10.5-to-0.10.8.md,
     * "0.10.8"). */
    o->hash_levels = 8;
    o->hash_features = 4;
}

NERF_API int nerf_model_options_init(nerf_model_options *opts,
                                     size_t struct_size)
{
    nerf_model_options d;
    model_defaults(&d);
    return nerf__options_init(opts, struct_size, &d, sizeof d,
                              "nerf_model_options");
}

NERF_API int nerf_model_options_preset(nerf_model_options *opts, int preset)
{
    nerf_model_options o;
    model_defaults(&o);
    int rc = nerf__options_read(&o, sizeof o, opts, "nerf_model_options");
    if (rc != NERF_OK) {
        return rc;
    }
    uint64_t seed = o.seed;
    const nerf_hooks *hooks = o.hooks;
    const uint32_t matmul = o.matmul;
    switch (preset) {
    case NERF_PRESET_REFERENCE:
        model_defaults(&o);
        o.learning_rate = 5e-4;
        break;
    case NERF_PRESET_TINY:
        model_defaults(&o);
        o.depth = 4;
        o.width = 64;
        o.skip_layer = 2;
        o.view_width = 32;
        /* The small network learns at ten times the paper's rate: at
         * 5e-4 it takes several times the steps to the same PSNR. */
        o.learning_rate = 5e-3;
        break;
    case NERF_PRESET_FAST:
        fast_options(&o);
        o.learning_rate = 1e-2;
        break;
    default:
        return nerf__error(NERF_EINVAL, "nerf_model_options_preset: unknown "
                           "preset %d", preset);
    }
    o.seed = seed;
    o.hooks = hooks;
    o.matmul = matmul;
    nerf__options_write(opts, &o, sizeof o);
    return NERF_OK;
}

/*
 * The space a model's networks work in: a hash-grid model's grids cover
 * its domain (the cube of half-side `bound`, its NDC counterpart, or the
 * contracted cube of an unbounded scene), and nothing outside it has
 * density; the frequency encoding reads world coordinates anywhere.
 */
void nerf__model_options_space(const nerf_model_options *o, nerf__space *space)
{
    if (o->encoding != NERF_ENCODING_HASHGRID) {
        nerf__space_world(space);
    } else if (o->space == NERF_SPACE_NDC) {
        nerf__space_ndc(space, o->bound);
    } else if (o->space == NERF_SPACE_UNBOUNDED) {
        nerf__space_contract(space, o->bound);
    } else {
        nerf__space_cube(space, o->bound);
    }
}

/* A hash grid laid over the space's box. */
static void hash_setup(nerf__hashgrid *hg, const nerf_model_options *o,
                       const nerf__space *space)
{
    memset(hg, 0, sizeof *hg);
    hg->levels = o->hash_levels;
    hg->features = o->hash_features;
    hg->log2_table = o->hash_log2_size;
    hg->min_resolution = o->hash_min_resolution;
    hg->max_resolution = o->hash_max_resolution;
    for (int c = 0; c < 3; c++) {
        hg->bound_min[c] = space->lo[c];
        hg->bound_max[c] = space->hi[c];
    }
}

static const char *check_hash(const nerf_model_options *o)
{
    if (o->hash_levels < 1 || o->hash_levels > NERF__HASHGRID_MAX_LEVELS) {
        return "hash_levels must be 1..32";
    }
    if (o->hash_features < 1 || o->hash_features > NERF__HASHGRID_MAX_FEATURES) {
        return "hash_features must be 1..8";
    }
    if (o->hash_log2_size < 10 || o->hash_log2_size > 24) {
        return "hash_log2_size must be 10..24";
    }
    if (o->hash_min_resolution < 1 ||
        o->hash_max_resolution < o->hash_min_resolution ||
        o->hash_max_resolution > NERF__HASHGRID_MAX_RESOLUTION) {
        return "hash resolutions must satisfy 1 <= min <= max <= 2^20";
    }
    if (!(o->bound > 0.0f) || !(o->bound < 1e6f)) {
        return "bound must be a positive finite number below 1e6";
    }
    return NULL;
}

/* The fields added in 0.2. */
static const char *check_fast_fields(const nerf_model_options *o)
{
    const uint32_t dir = o->dir_encoding ? o->dir_encoding
                                         : NERF_ENCODING_FREQUENCY;
    if (dir != NERF_ENCODING_FREQUENCY &&
        dir != NERF_ENCODING_SPHERICAL_HARMONICS) {
        return "dir_encoding must be FREQUENCY or SPHERICAL_HARMONICS";
    }
    if (dir == NERF_ENCODING_SPHERICAL_HARMONICS &&
        (o->sh_degree < 1 || o->sh_degree > 4)) {
        return "sh_degree must be 1..4";
    }
    if (o->encoding == NERF_ENCODING_HASHGRID) {
        const char *what = check_hash(o);
        if (what) {
            return what;
        }
    }
    if (o->view_depth < 1 || o->view_depth > NERF__MAX_VIEW_DEPTH) {
        return "view_depth must be 1..8";
    }
    if (o->geo_features > 4096) {
        return "geo_features must be 0..4096";
    }
    if (o->density_activation > NERF_DENSITY_EXP) {
        return "density_activation is not a known nerf_density_activation";
    }
    if (o->matmul > NERF_MATMUL_FP32_FASTEST) {
        return "matmul is not a known nerf_matmul";
    }
    if (o->space > NERF_SPACE_UNBOUNDED) {
        return "space is not a known nerf_space";
    }
    if (o->space != NERF_SPACE_BOX && o->encoding != NERF_ENCODING_HASHGRID) {
        return "space NDC or UNBOUNDED needs the hash-grid encoding (the "
               "frequency encoding reads coordinates anywhere)";
    }
    return NULL;
}

int nerf__model_check_options(const nerf_model_options *o)
{
    const char *what = check_fast_fields(o);
    if (what) {
        /* reported below */
    } else if (o->encoding != NERF_ENCODING_FREQUENCY &&
               o->encoding != NERF_ENCODING_HASHGRID) {
        what = "encoding must be FREQUENCY or HASHGRID";
    } else if (o->encoding_flags & ~(NERF_ENCODING_INCLUDE_INPUT |
                                     NERF_ENCODING_SCALE_PI)) {
        what = "encoding_flags has unknown bits";
    } else if (o->pos_frequencies > 20 || o->dir_frequencies > 20) {
        what = "frequencies must be at most 20";
    } else if (!(o->encoding_flags & NERF_ENCODING_INCLUDE_INPUT) &&
               (o->pos_frequencies == 0 ||
                (o->use_viewdirs && o->dir_frequencies == 0))) {
        what = "0 frequencies without INCLUDE_INPUT leaves nothing to encode";
    } else if (o->depth < 1 || o->depth > NERF__MAX_DEPTH) {
        what = "depth must be 1..32";
    } else if (o->width < 1 || o->width > 4096) {
        what = "width must be 1..4096";
    } else if (o->skip_layer >= o->depth) {
        what = "skip_layer must be below depth (0 = no skip)";
    } else if (o->use_viewdirs > 1 || o->use_fine > 1) {
        what = "use_viewdirs and use_fine must be 0 or 1";
    } else if (o->use_viewdirs && (o->view_width < 1 || o->view_width > 4096)) {
        what = "view_width must be 1..4096";
    } else if (o->reserved0 != 0 || o->reserved2 != 0) {
        what = o->reserved0 ? "reserved0 must be 0" : "reserved2 must be 0";
    } else if (!(o->learning_rate == 0.0 ||
                 (o->learning_rate > 0.0 && o->learning_rate <= 1.0))) {
        what = "learning_rate must be 0 (the model kind's) or in (0, 1]";
    }
    if (what) {
        return nerf__error(NERF_EINVAL, "nerf_model_options: %s", what);
    }
    const char *why;
    if (o->matmul != NERF_MATMUL_FP32 && o->matmul != NERF_MATMUL_FP32_FASTEST &&
        !nerf__onednn_supported(o->matmul, &why)) {
        return nerf__error(NERF_EINVAL, "nerf_model_options: matmul = %s, "
                           "but those products are not available: %s",
                           o->matmul == NERF_MATMUL_BF16
                               ? "NERF_MATMUL_BF16"
                               : "NERF_MATMUL_FP32_ONEDNN",
                           why);
    }
    return NERF_OK;
}

NERF_API int nerf_matmul_supported(int kind)
{
    if (kind == NERF_MATMUL_FP32) {
        return 1;
    }
    return kind > 0 && nerf__onednn_supported((uint32_t)kind, NULL);
}

static void setup_network(nerf__network *net, const nerf_model_options *o,
                          size_t offset)
{
    memset(net, 0, sizeof *net);
    bool raw = (o->encoding_flags & NERF_ENCODING_INCLUDE_INPUT) != 0;
    bool pi = (o->encoding_flags & NERF_ENCODING_SCALE_PI) != 0;
    const uint32_t dir = o->dir_encoding ? o->dir_encoding
                                         : NERF_ENCODING_FREQUENCY;
    nerf__model_options_space(o, &net->space);
    if (o->encoding == NERF_ENCODING_HASHGRID) {
        nerf__hashgrid hg;
        hash_setup(&hg, o, &net->space);
        /* Checked by nerf__model_check_options(), so it cannot fail. */
        (void)nerf__hashgrid_layout(&hg);
        nerf__encoding_hashgrid(&net->pos_enc, &hg);
    } else {
        nerf__encoding_frequency(&net->pos_enc, o->pos_frequencies, raw, pi);
    }
    if (dir == NERF_ENCODING_SPHERICAL_HARMONICS) {
        nerf__encoding_sh(&net->dir_enc, o->sh_degree);
    } else {
        nerf__encoding_frequency(&net->dir_enc, o->dir_frequencies, raw, pi);
    }
    net->depth = o->depth;
    net->width = o->width;
    net->skip = o->skip_layer;
    net->view_width = o->use_viewdirs ? o->view_width : 0;
    net->view_depth = o->view_depth;
    net->geo_features = o->use_viewdirs ? o->geo_features : 0;
    net->use_viewdirs = o->use_viewdirs != 0;
    net->exp_density = o->density_activation == NERF_DENSITY_EXP;
    nerf__network_layout(net, offset);
}

size_t nerf__model_options_param_count(const nerf_model_options *o)
{
    nerf__network net;
    setup_network(&net, o, 0);
    return net.count * (o->use_fine ? 2u : 1u);
}

/* The oneDNN backend of kind `matmul` over the networks' layers.  Each
 * network's layers follow its hash table (if any), which products never
 * read, so the table is not rounded. */
static int onednn_setup(nerf_model *m, uint32_t matmul)
{
    nerf__onednn_region regions[NERF__ONEDNN_MAX_REGIONS];
    for (uint32_t i = 0; i < m->n_nets; i++) {
        const nerf__network *net = &m->nets[i];
        regions[i].offset = net->trunk[0].w;
        regions[i].count = net->offset + net->count - net->trunk[0].w;
    }
    int rc = nerf__onednn_create(&m->env, matmul, m->params, regions,
                                 (int)m->n_nets, &m->onednn);
    if (rc != NERF_OK) {
        return rc;
    }
    for (uint32_t i = 0; i < m->n_nets; i++) {
        m->nets[i].onednn = m->onednn;
    }
    return NERF_OK;
}

/*
 * What computes the products of a model of kind `matmul`: the kind itself,
 * except that NERF_FP32_PRODUCTS=onednn moves fp32 models to oneDNN's fp32
 * products where this build and processor have them (common/dispatch.h),
 * so that the test suites can run through them.  The model's options keep
 * NERF_MATMUL_FP32: the choice is the process's, not the model's.
 */
static uint32_t products_of(uint32_t matmul, const nerf__env *env)
{
    if (matmul != NERF_MATMUL_FP32 || !nerf__fp32_onednn_override()) {
        return matmul;
    }
    const char *why = NULL;
    if (nerf__onednn_supported(NERF_MATMUL_FP32_ONEDNN, &why)) {
        return NERF_MATMUL_FP32_ONEDNN;
    }
    nerf__log(env, NERF_LOG_WARN, "NERF_FP32_PRODUCTS=onednn: %s; the "
              "products go through the CBLAS", why);
    return NERF_MATMUL_FP32;
}

/* NERF_MATMUL_FP32_FASTEST made concrete: oneDNN's fp32 trains the
 * frequency-encoded networks faster than cblas where it has its AVX-512
 * kernels (docs/performance.md, "The reference and tiny presets"); the
 * hash-grid networks' narrow layers run fastest on the fused kernels,
 * which only FP32 uses. */
static uint32_t fastest_fp32(const nerf_model_options *o)
{
    const char *why = NULL;
    return o->encoding != NERF_ENCODING_HASHGRID &&
                   nerf__onednn_supported(NERF_MATMUL_FP32_ONEDNN, &why)
               ? NERF_MATMUL_FP32_ONEDNN
               : NERF_MATMUL_FP32;
}

void nerf__model_weights_changed(nerf_model *m)
{
    nerf__onednn_weights_changed(m->onednn);
    nerf__model_finite_unknown(m);
}

int nerf__model_alloc(nerf_model **out, const nerf_model_options *opts,
                      const nerf__env *env)
{
    nerf_model *m = nerf__calloc(env, 1, sizeof *m);
    if (m == NULL) {
        return NERF_ENOMEM;
    }
    m->env = *env;
    m->opts = *opts;
    m->opts.hooks = NULL;
    if (m->opts.matmul == NERF_MATMUL_FP32_FASTEST) {
        m->opts.matmul = fastest_fp32(opts);
    }
    atomic_init(&m->finite, 0); /* not known yet */
    m->n_nets = opts->use_fine ? 2 : 1;
    size_t offset = 0;
    for (uint32_t i = 0; i < m->n_nets; i++) {
        setup_network(&m->nets[i], opts, offset);
        offset += m->nets[i].count;
    }
    m->n_params = offset;
    if (opts->encoding == NERF_ENCODING_HASHGRID) {
        /* Mueller et al.'s Adam: beta2 0.99 and a tiny eps, which the
         * rarely touched hash entries need to move at all. */
        m->adam = (nerf__adam){1e-2, 1e-3, 20000.0, 0.9, 0.99, 1e-15, 1e-6,
                               0.0, NERF__AVERAGE_STEPS_FAST};
    } else {
        m->adam = (nerf__adam){5e-4, 5e-5, 250000.0, 0.9, 0.999, 1e-7, 0.0,
                               0.0, 0.0};
    }
    if (opts->learning_rate > 0.0) {
        m->adam.lr = opts->learning_rate;
        m->adam.lr_final = opts->learning_rate / 10;
    }
    /* A rate asked for at creation is the schedule's from then on, a
     * parameter like any other: the options do not keep it. */
    m->opts.learning_rate = 0.0;
    float **arrays[4] = {&m->params, &m->grads, &m->adam_m, &m->adam_v};
    for (int i = 0; i < 4; i++) {
        *arrays[i] = nerf__calloc(env, m->n_params, sizeof(float));
        if (*arrays[i] == NULL) {
            nerf_model_destroy(m);
            return NERF_ENOMEM;
        }
    }
    for (uint32_t i = 0; i < m->n_nets; i++) {
        m->n_table += nerf__encoding_params(&m->nets[i].pos_enc);
    }
    if (m->n_table > 0) {
        m->adam_r = nerf__alloc(env, 2 * m->n_table * sizeof(float));
        if (m->adam_r == NULL) {
            nerf_model_destroy(m);
            return NERF_ENOMEM;
        }
        for (size_t i = 0; i < 2 * m->n_table; i++) {
            m->adam_r[i] = 1.0f; /* beta^0: no update yet */
        }
        m->corrected = true;
    }
    const uint32_t matmul = products_of(m->opts.matmul, env);
    if (matmul != NERF_MATMUL_FP32) {
        int rc = onednn_setup(m, matmul);
        if (rc != NERF_OK) {
            nerf_model_destroy(m);
            return rc;
        }
    }
    if (opts->encoding == NERF_ENCODING_HASHGRID) {
        /* The grid covers the space's box: outside it the model has no
         * density, so there is nothing to march. */
        const nerf__space *space = &m->nets[0].space;
        nerf__occupancy_options go;
        nerf__occupancy_defaults(&go, space->lo, space->hi);
        go.resolution = NERF__MODEL_GRID_RESOLUTION;
        go.seed = opts->seed;
        int rc = nerf__occupancy_create(env, &go, &m->grid);
        if (rc != NERF_OK) {
            nerf_model_destroy(m);
            return rc;
        }
    }
    *out = m;
    return NERF_OK;
}

/* Read a caller's options struct over the defaults and validate it. */
static int read_options(nerf_model_options *o, const nerf_model_options *in)
{
    model_defaults(o);
    int rc = nerf__options_read(o, sizeof *o, in, "nerf_model_options");
    if (rc == NERF_OK) {
        rc = nerf__model_check_options(o);
    }
    return rc;
}

NERF_API int nerf_model_create(nerf_model **out,
                               const nerf_model_options *opts)
{
    if (out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_create: out is NULL");
    }
    *out = NULL;
    nerf_model_options o;
    int rc = read_options(&o, opts);
    nerf__env env;
    if (rc == NERF_OK) {
        rc = nerf__env_from_hooks(&env, o.hooks);
    }
    nerf_model *m = NULL;
    if (rc == NERF_OK) {
        rc = nerf__model_alloc(&m, &o, &env);
    }
    if (rc != NERF_OK) {
        return rc;
    }
    for (uint32_t i = 0; i < m->n_nets; i++) {
        nerf__network_init(&m->nets[i], m->params, o.seed, 1000u * (i + 1));
    }
    nerf__model_weights_changed(m);
    nerf__log(&m->env, NERF_LOG_DEBUG,
              "model: %u network(s), %zu parameters, depth %u, width %u",
              m->n_nets, m->n_params, o.depth, o.width);
    *out = m;
    return NERF_OK;
}

NERF_API void nerf_model_destroy(nerf_model *model)
{
    if (model == NULL) {
        return; /* support free on NULL */
    }
    nerf__env env = model->env;
    nerf__free(&env, model->params);
    nerf__free(&env, model->grads);
    nerf__free(&env, model->adam_m);
    nerf__free(&env, model->adam_v);
    nerf__free(&env, model->adam_r);
    nerf__average_free(model);
    nerf__appearance_free(&model->env, &model->appearance);
    nerf__onednn_destroy(model->onednn);
    nerf__occupancy_destroy(model->grid);
    nerf__free(&env, model->source);
    nerf__free(&env, model);
}

NERF_API int nerf_model_get_options(const nerf_model *model,
                                    nerf_model_options *out)
{
    if (model == NULL || out == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_get_options: NULL argument");
    }
    if (out->struct_size < sizeof(uint32_t) || out->struct_size > 65536) {
        return nerf__error(NERF_EINVAL, "nerf_model_get_options: struct_size "
                           "%u is invalid", (unsigned)out->struct_size);
    }
    size_t n = out->struct_size < sizeof model->opts ? out->struct_size
                                                     : sizeof model->opts;
    memcpy((char *)out + sizeof(uint32_t),
           (const char *)&model->opts + sizeof(uint32_t), n - sizeof(uint32_t));
    return NERF_OK;
}

NERF_API size_t nerf_model_param_count(const nerf_model *model)
{
    return model ? model->n_params : 0;
}

NERF_API uint64_t nerf_model_step(const nerf_model *model)
{
    return model ? model->step : 0;
}

NERF_API uint32_t nerf_model_contents(const nerf_model *model)
{
    if (model == NULL) {
        return 0;
    }
    uint32_t c = model->weights_only ? 0 : NERF_MODEL_HAS_OPTIMIZER;
    if (model->grid != NULL && model->grid->updates > 0) {
        c |= NERF_MODEL_HAS_OCCUPANCY;
    }
    if (model->has_render) {
        c |= NERF_MODEL_HAS_RENDER_SETTINGS;
    }
    if (model->data.known) {
        c |= NERF_MODEL_HAS_DATA_RECORD;
    }
    if (model->batch_rays > 0) {
        c |= NERF_MODEL_HAS_BATCH_RECORD;
    }
    if (model->corrected && !model->weights_only) {
        c |= NERF_MODEL_HAS_ADAM_CORRECTIONS;
    }
    if (!nerf__model_finite(model)) {
        c |= NERF_MODEL_HAS_NONFINITE_WEIGHTS;
    }
    if (model->appearance.n > 0) {
        c |= NERF_MODEL_HAS_APPEARANCE;
    }
    return c;
}

NERF_API int nerf_model_training_batch(const nerf_model *model,
                                       uint32_t *rays, uint32_t *samples)
{
    if (model == NULL || rays == NULL || samples == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_training_batch: NULL "
                           "argument");
    }
    *rays = model->batch_rays;
    *samples = model->batch_samples;
    return NERF_OK;
}

NERF_API int nerf_model_training_data(const nerf_model *model, char *buf,
                                      size_t size)
{
    if (model == NULL || buf == NULL || size == 0) {
        return nerf__error(NERF_EINVAL, "nerf_model_training_data: NULL "
                           "model or buffer, or size 0");
    }
    buf[0] = '\0';
    if (model->data.known) {
        nerf__fingerprint_describe(&model->data, 1, buf, size);
    }
    return NERF_OK;
}

int nerf__model_network(const nerf_model *m, int network)
{
    if (network == NERF_NETWORK_COARSE) {
        return 0;
    }
    if (network == NERF_NETWORK_FINE && m->n_nets == 2) {
        return 1;
    }
    return -1;
}

NERF_API int nerf_model_query(const nerf_model *model, int network, size_t n,
                              const float *positions, const float *directions,
                              float *rgb_out, float *sigma_out)
{
    if (model == NULL || positions == NULL || (rgb_out == NULL && sigma_out == NULL)) {
        return nerf__error(NERF_EINVAL, "nerf_model_query: NULL model, "
                           "positions or outputs");
    }
    int net_index = nerf__model_network(model, network);
    if (net_index < 0) {
        return nerf__error(NERF_EINVAL, "nerf_model_query: network %d is not "
                           "in this model", network);
    }
    const nerf__network *net = &model->nets[net_index];
    if (net->use_viewdirs && directions == NULL) {
        return nerf__error(NERF_EINVAL, "nerf_model_query: the model uses "
                           "view directions but directions is NULL");
    }
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    size_t block = n < NERF__QUERY_BLOCK ? n : NERF__QUERY_BLOCK;
    int rc = nerf__workspace_reserve(&model->env, &ws, net, block, false);
    if (rc != NERF_OK) {
        return rc;
    }
    /* World positions reach an unbounded model's networks contracted. */
    float *mapped = NULL;
    if (rc == NERF_OK && net->space.kind == NERF__SPACE_CONTRACT) {
        mapped = nerf__alloc(&model->env, 3 * block * sizeof(float) + 1);
        rc = mapped ? NERF_OK : NERF_ENOMEM;
    }
    for (size_t at = 0; at < n && rc == NERF_OK; at += block) {
        size_t k = n - at < block ? n - at : block;
        const float *pos = positions + 3 * at;
        if (mapped) {
            for (size_t i = 0; i < k; i++) {
                nerf__space_to_domain(&net->space, pos + 3 * i, mapped + 3 * i);
            }
            pos = mapped;
        }
        rc = nerf__network_forward(net, model->params, &ws, k, pos,
                                   directions ? directions + 3 * at : NULL,
                                   rgb_out ? rgb_out + 3 * at : NULL,
                                   sigma_out ? sigma_out + at : NULL);
    }
    nerf__free(&model->env, mapped);
    nerf__workspace_release(&model->env, &ws);
    return rc;
}

int nerf__model_forward(const nerf_model *m, int network, nerf__workspace *ws,
                        size_t n, const float *positions,
                        const float *directions, float *rgb_out,
                        float *sigma_out)
{
    const nerf__network *net = &m->nets[network];
    int rc = nerf__workspace_reserve(&m->env, ws, net, n, true);
    if (rc != NERF_OK) {
        return rc;
    }
    return nerf__network_forward(net, m->params, ws, n, positions, directions,
                                 rgb_out, sigma_out);
}

int nerf__model_evaluate(const nerf_model *m, int network,
                         nerf__workspace *ws, size_t n,
                         const float *positions, const float *directions,
                         float *rgb_out, float *sigma_out)
{
    const nerf__network *net = &m->nets[network];
    int rc = nerf__workspace_reserve(&m->env, ws, net, n, false);
    if (rc != NERF_OK) {
        return rc;
    }
    return nerf__network_forward(net, m->params, ws, n, positions, directions,
                                 rgb_out, sigma_out);
}

int nerf__model_head(const nerf_model *m, int network, nerf__workspace *ws,
                     size_t n, const float *positions, float *sigma_out)
{
    const nerf__network *net = &m->nets[network];
    int rc = nerf__workspace_reserve(&m->env, ws, net, n, false);
    if (rc != NERF_OK) {
        return rc;
    }
    return nerf__network_head(net, m->params, ws, n, positions, sigma_out);
}

int nerf__model_colour(const nerf_model *m, int network, nerf__workspace *ws,
                       size_t n_colour, const float *directions,
                       float *rgb_out)
{
    return nerf__network_colour(&m->nets[network], m->params, ws, n_colour,
                                directions, rgb_out);
}

int nerf__model_reserve(const nerf_model *m, int network, nerf__workspace *ws,
                        size_t n, bool keep)
{
    return nerf__workspace_reserve(&m->env, ws, &m->nets[network], n, keep);
}

const nerf__env *nerf__model_env(const nerf_model *m)
{
    return &m->env;
}

bool nerf__model_uses_viewdirs(const nerf_model *m)
{
    return m->nets[0].use_viewdirs;
}

bool nerf__model_uses_blas(const nerf_model *m)
{
    for (uint32_t i = 0; i < m->n_nets; i++) {
        if (!nerf__fused_active(&m->nets[i])) {
            return true;
        }
    }
    return false;
}

bool nerf__model_rows_alone(nerf_model *m)
{
    if (m->onednn) {
        return nerf__onednn_rows_alone(m->onednn);
    }
    return !nerf__model_uses_blas(m);
}

const nerf__space *nerf__model_space(const nerf_model *m)
{
    return &m->nets[0].space;
}

const nerf__occupancy *nerf__model_grid(const nerf_model *m)
{
    return m->grid;
}

int nerf__model_density(const nerf_model *m, int network, nerf__workspace *ws,
                        size_t n, const float *positions, float *sigma_out)
{
    const nerf__network *net = &m->nets[network];
    int rc = nerf__workspace_reserve_density(&m->env, ws, net, n);
    if (rc != NERF_OK) {
        return rc;
    }
    return nerf__network_density(net, m->params, ws, n, positions,
                                 sigma_out);
}

int nerf__model_backward(nerf_model *m, int network, nerf__workspace *ws,
                         const float *d_rgb, const float *d_sigma)
{
    m->grads_dirty = true;
    return nerf__network_backward(&m->nets[network], m->params, m->grads, ws,
                                  d_rgb, d_sigma);
}

void nerf__model_zero_grad(nerf_model *m)
{
    memset(m->grads, 0, m->n_params * sizeof(float));
    m->grads_dirty = false;
}

void nerf__model_clear_grad(nerf_model *m)
{
    if (m->grads_dirty) {
        nerf__model_zero_grad(m);
    }
}

static void adam_range(nerf_model *m, double lr, size_t begin, size_t end,
                       unsigned flags)
{
    nerf__adam_update(&m->adam, m->step, lr, end - begin, m->params + begin,
                      m->grads + begin, m->adam_m + begin, m->adam_v + begin,
                      flags);
}

/* The sparse update of a table of n parameters from params[begin] on,
 * whose corrections are the at-th of adam_r's. */
static void adam_table(nerf_model *m, double lr, size_t begin, size_t n,
                       size_t at)
{
    if (!m->corrected) {
        adam_range(m, lr, begin, begin + n, NERF__ADAM_SPARSE);
        return;
    }
    float *r1 = m->adam_r + at, *r2 = m->adam_r + m->n_table + at;
    nerf__adam_update_corrected(&m->adam, lr, n, m->params + begin,
                                m->grads + begin, m->adam_m + begin,
                                m->adam_v + begin, r1, r2);
}

int nerf__model_adam_step(nerf_model *m)
{
    int rc = nerf__average_reserve(m);
    if (rc != NERF_OK) {
        return rc;
    }
    double lr = nerf__adam_rate(&m->adam, m->step);
    m->step++;
    size_t at = 0;
    for (uint32_t i = 0; i < m->n_nets; i++) {
        const nerf__network *net = &m->nets[i];
        size_t layers = net->offset;
        const size_t enc = nerf__encoding_params(&net->pos_enc);
        if (enc) {
            /* The encoding's parameters (a hash table) come first in a
             * network's slice; a step touches few of their entries. */
            layers = net->pos_params + enc;
            adam_table(m, lr, net->pos_params, enc, at);
            at += enc;
        }
        adam_range(m, lr, layers, net->offset + net->count, NERF__ADAM_DECAY);
    }
    nerf__appearance_step(m, m->step);
    m->grads_dirty = false;
    nerf__average_step(m);
    nerf__model_weights_changed(m);
    return NERF_OK;
}
