/* The public model API: options versioning, presets, query, parameters,
 * hooks and allocation failures. */
#include <stddef.h>
#include <string.h>

#include "../fail_alloc.h"
#include "../harness.h"
#include "layer_bounds.h"
#include "model.h"
#include "nerf.h"

TEST(defaults_are_the_reference)
{
    nerf_model_options o;
    CHECK_OK(NERF_MODEL_OPTIONS_INIT(&o));
    CHECK_EQ_INT(o.struct_size, sizeof o);
    CHECK_EQ_INT(o.depth, 8);
    CHECK_EQ_INT(o.width, 256);
    CHECK_EQ_INT(o.skip_layer, 5);
    CHECK_EQ_INT(o.pos_frequencies, 10);
    CHECK_EQ_INT(o.dir_frequencies, 4);
    CHECK_EQ_INT(o.view_width, 128);
    CHECK_EQ_INT(o.encoding_flags, NERF_ENCODING_INCLUDE_INPUT);
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    /* Per network: 63*256+256 + 6*(256*256+256) + (319*256+256)
     * + 256*257+257 + 283*128+128 + 128*3+3 = 595844, as the reference. */
    CHECK_EQ_INT(nerf_model_param_count(m), 2 * 595844);
    nerf_model_destroy(m);
    CHECK_EQ_INT(nerf_model_param_count(NULL), 0);
    nerf_model_destroy(NULL);
}

TEST(presets)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.seed = 99;
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_TINY));
    CHECK_EQ_INT(o.width, 64);
    CHECK_EQ_INT(o.seed, 99); /* kept */
    CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_REFERENCE));
    CHECK_EQ_INT(o.width, 256);
    CHECK_EQ_INT(nerf_model_options_preset(&o, 12345), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "preset") != NULL);
}

TEST(smaller_struct_from_an_older_header)
{
    /* An old caller knew only the fields up to and including use_fine. */
    nerf_model_options o;
    memset(&o, 0xab, sizeof o);
    CHECK_OK(nerf_model_options_init(&o, offsetof(nerf_model_options, reserved0)));
    CHECK_EQ_INT(o.struct_size, offsetof(nerf_model_options, reserved0));
    CHECK_EQ_INT(o.depth, 8);
    /* Bytes beyond the old struct are not the library's to write. */
    unsigned char tail;
    memcpy(&tail, (char *)&o + offsetof(nerf_model_options, seed), 1);
    CHECK_EQ_INT(tail, 0xab);
    o.width = 32;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    nerf_model_options got;
    NERF_MODEL_OPTIONS_INIT(&got);
    CHECK_OK(nerf_model_get_options(m, &got));
    CHECK_EQ_INT(got.width, 32);
    CHECK_EQ_INT(got.seed, 0); /* default, not the 0xab garbage */
    CHECK(got.hooks == NULL);
    nerf_model_destroy(m);
}

TEST(larger_struct_from_a_newer_header)
{
    struct {
        nerf_model_options o;
        uint64_t future_field;
    } big;
    memset(&big, 0, sizeof big);
    CHECK_OK(nerf_model_options_init(&big.o, sizeof big));
    CHECK_EQ_INT(big.o.struct_size, sizeof big);
    big.o.depth = 2;
    big.o.skip_layer = 1;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &big.o)); /* unknown tail is zero */
    nerf_model_destroy(m);
    m = NULL;
    big.future_field = 1;
    CHECK_EQ_INT(nerf_model_create(&m, &big.o), NERF_EVERSION);
    CHECK(m == NULL);
    CHECK(strstr(nerf_last_error(), "newer") != NULL);
}

TEST(invalid_options)
{
    nerf_model *m = NULL;
    nerf_model_options o;
    CHECK_EQ_INT(nerf_model_create(&m, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_create(NULL, NULL), NERF_EINVAL);
    NERF_MODEL_OPTIONS_INIT(&o);
    o.skip_layer = 8;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "skip_layer") != NULL);
    NERF_MODEL_OPTIONS_INIT(&o);
    o.width = 0;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    NERF_MODEL_OPTIONS_INIT(&o);
    o.encoding_flags = 0;
    o.pos_frequencies = 0;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    NERF_MODEL_OPTIONS_INIT(&o);
    o.struct_size = 0;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "struct_size") != NULL);
    CHECK(m == NULL);
}

static void query_some(const nerf_model *m, int net, float *rgb, float *sigma)
{
    float pos[5 * 3], dir[5 * 3];
    for (int i = 0; i < 15; i++) {
        pos[i] = 0.1f * (float)i - 0.7f;
        dir[i] = i % 3 == 2 ? 1.0f : 0.0f;
    }
    CHECK_OK(nerf_model_query(m, net, 5, pos, dir, rgb, sigma));
}

TEST(query_is_deterministic_per_seed)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    nerf_model *a = NULL, *b = NULL, *c = NULL;
    o.seed = 5;
    CHECK_OK(nerf_model_create(&a, &o));
    CHECK_OK(nerf_model_create(&b, &o));
    o.seed = 6;
    CHECK_OK(nerf_model_create(&c, &o));
    float ra[15], sa[5], rb[15], sb[5], rc[15], sc[5];
    query_some(a, NERF_NETWORK_FINE, ra, sa);
    query_some(b, NERF_NETWORK_FINE, rb, sb);
    query_some(c, NERF_NETWORK_FINE, rc, sc);
    CHECK(memcmp(ra, rb, sizeof ra) == 0 && memcmp(sa, sb, sizeof sa) == 0);
    CHECK(memcmp(ra, rc, sizeof ra) != 0);
    for (int i = 0; i < 15; i++) {
        CHECK(ra[i] > 0.0f && ra[i] < 1.0f);
    }
    /* Coarse and fine are initialised from different streams. */
    float rf[15], sf[5];
    query_some(a, NERF_NETWORK_COARSE, rf, sf);
    CHECK(memcmp(ra, rf, sizeof ra) != 0);
    nerf_model_destroy(a);
    nerf_model_destroy(b);
    nerf_model_destroy(c);
}

TEST(query_arguments)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    o.use_fine = 0;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    float p[3] = {0}, d[3] = {0, 0, 1}, rgb[3], s[1];
    CHECK_EQ_INT(nerf_model_query(m, NERF_NETWORK_FINE, 1, p, d, rgb, s),
                 NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "network") != NULL);
    CHECK_EQ_INT(nerf_model_query(m, NERF_NETWORK_COARSE, 1, p, NULL, rgb, s),
                 NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_query(NULL, 0, 1, p, d, rgb, s), NERF_EINVAL);
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_COARSE, 0, p, d, rgb, s));
    CHECK_OK(nerf_model_query(m, NERF_NETWORK_COARSE, 1, p, d, NULL, s));
    nerf_model_destroy(m);
}

/*
 * A query's outputs for n samples (rgb, sigma) as a forward that keeps its
 * activations gives them (the same products), each of its layers against
 * the network in double from its own float input (layer_bounds.h).
 */
static void check_query_layers(nerf_model *m, int network, size_t n,
                               const float *pos, const float *dir,
                               const float *rgb, const float *sigma)
{
    nerf__workspace ws;
    memset(&ws, 0, sizeof ws);
    float *r = malloc(3 * n * sizeof(float)), *s = malloc(n * sizeof(float));
    CHECK_OK(nerf__model_forward(m, network, &ws, n, pos, dir, r, s));
    CHECK(memcmp(r, rgb, 3 * n * sizeof(float)) == 0);
    CHECK(memcmp(s, sigma, n * sizeof(float)) == 0);
    lb_net b;
    lb_open(&b, &m->nets[network], m->params);
    lb_check_forward(&b, &ws, pos, s, lb_eps(&m->nets[network]), "query");
    lb_close(&b);
    nerf__workspace_release(nerf__model_env(m), &ws);
    free(r);
    free(s);
}

/*
 * A query of more samples than a block gives what queries of its blocks
 * give, bit for bit: the same calls.  Single-sample queries give the same
 * bits where each sample's outputs are computed from it alone
 * (nerf__model_rows_alone(): the fused path, oneDNN's brgemm kernels).
 * Through the CBLAS a product's size may change a row's rounding: there
 * both, the blocks and the single samples, are checked layer by layer.
 */
TEST(query_in_blocks_matches_one_by_one)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    enum { n = NERF__QUERY_BLOCK + 904 }; /* more than one block */
    float *pos = malloc(n * 3 * sizeof(float)), *dir = malloc(n * 3 * sizeof(float));
    float *rgb = malloc(n * 3 * sizeof(float)), *sig = malloc(n * sizeof(float));
    float *rgb2 = malloc(n * 3 * sizeof(float));
    float *sig2 = malloc(n * sizeof(float));
    for (int i = 0; i < n * 3; i++) {
        pos[i] = (float)((i * 37) % 101) / 50.0f - 1.0f;
        dir[i] = i % 3 == 1 ? 1.0f : 0.0f;
    }
    CHECK_OK(nerf_model_query(m, 1, n, pos, dir, rgb, sig));
    const size_t b = NERF__QUERY_BLOCK;
    CHECK_OK(nerf_model_query(m, 1, b, pos, dir, rgb2, sig2));
    CHECK_OK(nerf_model_query(m, 1, n - b, pos + 3 * b, dir + 3 * b,
                              rgb2 + 3 * b, sig2 + b));
    CHECK(memcmp(rgb, rgb2, n * 3 * sizeof(float)) == 0);
    CHECK(memcmp(sig, sig2, n * sizeof(float)) == 0);
    const bool alone = nerf__model_rows_alone(m);
    if (!alone) {
        check_query_layers(m, 1, b, pos, dir, rgb, sig);
        check_query_layers(m, 1, n - b, pos + 3 * b, dir + 3 * b,
                           rgb + 3 * b, sig + b);
    }
    for (int i = 0; i < n; i += 997) {
        float r1[3], s1;
        CHECK_OK(nerf_model_query(m, 1, 1, pos + 3 * i, dir + 3 * i, r1, &s1));
        if (alone) {
            CHECK(memcmp(r1, rgb + 3 * i, sizeof r1) == 0);
            CHECK(memcmp(&s1, sig + i, sizeof s1) == 0);
        } else {
            check_query_layers(m, 1, 1, pos + 3 * i, dir + 3 * i, r1, &s1);
        }
    }
    free(pos);
    free(dir);
    free(rgb);
    free(sig);
    free(rgb2);
    free(sig2);
    nerf_model_destroy(m);
}

TEST(training_parameters)
{
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    double v = 0.0, lo, hi;
    CHECK_OK(nerf_model_get_param(m, NERF_PARAM_ADAM_EPS, &v));
    CHECK_NEAR(v, 1e-7, 0.0);
    CHECK_OK(nerf_model_get_param(m, NERF_PARAM_LEARNING_RATE, &v));
    CHECK_NEAR(v, 5e-3, 0.0); /* the tiny preset's */
    CHECK_OK(nerf_model_set_param(m, NERF_PARAM_ADAM_EPS, 1e-8));
    CHECK_OK(nerf_model_get_param(m, NERF_PARAM_ADAM_EPS, &v));
    CHECK_NEAR(v, 1e-8, 0.0);
    CHECK_OK(nerf_param_bounds(NERF_PARAM_ADAM_BETA1, &lo, &hi));
    CHECK(lo == 0.0 && hi < 1.0);
    CHECK_EQ_INT(nerf_model_set_param(m, NERF_PARAM_ADAM_BETA1, 1.0), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "outside") != NULL);
    CHECK_EQ_INT(nerf_model_set_param(m, NERF_PARAM_ADAM_BETA1, NAN), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_set_param(m, 7, 1.0), NERF_EINVAL);
    CHECK_EQ_INT(nerf_param_bounds(7, &lo, &hi), NERF_EINVAL);
    nerf_model_destroy(m);
}

TEST(allocation_failures)
{
    nerf_hooks hooks;
    fail_alloc f;
    fail_alloc_hooks(&hooks, &f);
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    o.hooks = &hooks;
    int succeeded_at = 0;
    for (int k = 1; k < 20 && !succeeded_at; k++) {
        f = (fail_alloc){0, k, 0};
        nerf_model *m = NULL;
        int rc = nerf_model_create(&m, &o);
        if (rc == NERF_OK) {
            succeeded_at = k;
            CHECK(f.live > 0);
            nerf_model_destroy(m);
        } else {
            CHECK_EQ_INT(rc, NERF_ENOMEM);
            CHECK(m == NULL);
        }
        CHECK_EQ_INT(f.live, 0);
    }
    CHECK(succeeded_at > 1);
    hooks.free = NULL;
    nerf_model *m = NULL;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "alloc and free") != NULL);
}

static int log_count;

static void count_log(int level, const char *msg, void *user)
{
    (void)level;
    (void)msg;
    *(int *)user += 1;
}

TEST(per_handle_log)
{
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = count_log;
    hooks.log_user = &log_count;
    hooks.log_level = NERF_LOG_DEBUG;
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    nerf_model_options_preset(&o, NERF_PRESET_TINY);
    o.hooks = &hooks;
    nerf_model *m = NULL;
    CHECK_OK(nerf_model_create(&m, &o));
    CHECK(log_count > 0);
    nerf_model_destroy(m);
}

int main(void)
{
    RUN(defaults_are_the_reference);
    RUN(presets);
    RUN(smaller_struct_from_an_older_header);
    RUN(larger_struct_from_a_newer_header);
    RUN(invalid_options);
    RUN(query_is_deterministic_per_seed);
    RUN(query_arguments);
    RUN(query_in_blocks_matches_one_by_one);
    RUN(training_parameters);
    RUN(allocation_failures);
    RUN(per_handle_log);
    HARNESS_EXIT();
}
