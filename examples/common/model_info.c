#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model_info.h"
#include "matmul_name.h"
#include "scene_setup.h"
#include "shared_opts.h"

static const char *preset_name(int preset)
{
    const char *name = opt_choice_name(preset_choices, preset);
    return name != NULL ? name : "custom";
}

static const char *encoding_name(uint32_t e)
{
    switch (e) {
    case NERF_ENCODING_FREQUENCY: return "frequency";
    case NERF_ENCODING_HASHGRID: return "hashgrid";
    case NERF_ENCODING_SPHERICAL_HARMONICS: return "spherical_harmonics";
    default: return "unknown";
    }
}

static const char *space_name(uint32_t s)
{
    return s == NERF_SPACE_NDC ? "ndc"
           : s == NERF_SPACE_UNBOUNDED ? "unbounded" : "box";
}

static cJSON *encoding_object(const nerf_model_options *mo)
{
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "positions", encoding_name(mo->encoding));
    if (mo->encoding == NERF_ENCODING_HASHGRID) {
        cJSON_AddNumberToObject(e, "levels", mo->hash_levels);
        cJSON_AddNumberToObject(e, "features", mo->hash_features);
        cJSON_AddNumberToObject(e, "log2_size", mo->hash_log2_size);
        cJSON_AddNumberToObject(e, "min_resolution", mo->hash_min_resolution);
        cJSON_AddNumberToObject(e, "max_resolution", mo->hash_max_resolution);
    } else {
        cJSON_AddNumberToObject(e, "frequencies", mo->pos_frequencies);
    }
    if (mo->use_viewdirs) {
        const uint32_t d = mo->dir_encoding ? mo->dir_encoding
                                            : NERF_ENCODING_FREQUENCY;
        cJSON_AddStringToObject(e, "directions", encoding_name(d));
        cJSON_AddNumberToObject(e, d == NERF_ENCODING_SPHERICAL_HARMONICS
                                       ? "sh_degree" : "dir_frequencies",
                                d == NERF_ENCODING_SPHERICAL_HARMONICS
                                    ? mo->sh_degree : mo->dir_frequencies);
    } else {
        cJSON_AddStringToObject(e, "directions", "none");
    }
    return e;
}

static cJSON *network_object(const nerf_model_options *mo)
{
    cJSON *n = cJSON_CreateObject();
    cJSON_AddNumberToObject(n, "depth", mo->depth);
    cJSON_AddNumberToObject(n, "width", mo->width);
    cJSON_AddNumberToObject(n, "view_depth", mo->view_depth);
    cJSON_AddNumberToObject(n, "view_width", mo->view_width);
    cJSON_AddNumberToObject(n, "geo_features", mo->geo_features);
    cJSON_AddBoolToObject(n, "fine_network", mo->use_fine != 0);
    return n;
}

static cJSON *render_object(const nerf_model *model)
{
    nerf_sampler_options so;
    nerf_renderer_options ro;
    NERF_SAMPLER_OPTIONS_INIT(&so);
    NERF_RENDERER_OPTIONS_INIT(&ro);
    cJSON *r = cJSON_CreateObject();
    const int recorded = (nerf_model_contents(model) &
                          NERF_MODEL_HAS_RENDER_SETTINGS) != 0;
    /* Without a recording these are the library's guess: say which. */
    cJSON_AddStringToObject(r, "source", recorded ? "recorded in training"
                                                  : "guessed from the shape");
    if (nerf_model_render_settings(model, &so, &ro) != NERF_OK) {
        cJSON_AddStringToObject(r, "error", nerf_last_error());
        return r;
    }
    if (so.march_steps > 0) {
        cJSON_AddNumberToObject(r, "march_steps", so.march_steps);
        cJSON_AddNumberToObject(r, "max_samples", so.max_samples);
    } else {
        cJSON_AddNumberToObject(r, "n_coarse", so.n_coarse);
        cJSON_AddNumberToObject(r, "n_fine", so.n_fine);
    }
    cJSON_AddNumberToObject(r, "near", so.t_near);
    cJSON_AddNumberToObject(r, "far", so.t_far);
    cJSON_AddBoolToObject(r, "ndc", so.ndc != 0);
    if (so.ndc && so.ndc_focal > 0.0f) {
        cJSON_AddNumberToObject(r, "ndc_focal", so.ndc_focal);
        cJSON_AddNumberToObject(r, "ndc_width", so.ndc_width);
        cJSON_AddNumberToObject(r, "ndc_height", so.ndc_height);
    }
    cJSON_AddStringToObject(r, "background",
                            ro.white_background ? "white" : "black");
    return r;
}

/* The learning-rate schedule: its rates, and how its length was set. */
static cJSON *schedule_object(const nerf_model *model)
{
    nerf_schedule sc;
    memset(&sc, 0, sizeof sc);
    sc.struct_size = sizeof sc;
    nerf_model_schedule(model, &sc);
    double lr0 = 0.0, lr1 = 0.0, start = 0.0, average = 0.0;
    nerf_model_get_param(model, NERF_PARAM_LEARNING_RATE, &lr0);
    nerf_model_get_param(model, NERF_PARAM_LEARNING_RATE_FINAL, &lr1);
    nerf_model_get_param(model, NERF_PARAM_DECAY_START, &start);
    nerf_model_get_param(model, NERF_PARAM_AVERAGE_STEPS, &average);
    cJSON *o = cJSON_CreateObject();
    static const char *const kinds[] = {"steps", "measuring", "fitted"};
    cJSON_AddStringToObject(o, "kind", sc.state < 3 ? kinds[sc.state] : "?");
    cJSON_AddNumberToObject(o, "lr", lr0);
    cJSON_AddNumberToObject(o, "lr_final", lr1);
    if (sc.state != NERF_SCHEDULE_MEASURING) {
        cJSON_AddNumberToObject(o, "decay_start", start);
        cJSON_AddNumberToObject(o, "steps", (double)sc.total_steps);
    }
    if (average > 0.0) {
        cJSON_AddNumberToObject(o, "average_steps", average);
    }
    if (sc.state != NERF_SCHEDULE_STEPS) {
        cJSON_AddNumberToObject(o, "budget_seconds", sc.budget_seconds);
    }
    if (sc.state == NERF_SCHEDULE_FITTED) {
        cJSON_AddNumberToObject(o, "steps_per_second",
                                round(sc.steps_per_second * 10.0) / 10.0);
    }
    return o;
}

/* Whether anything can be made of the model (a diverged run's cannot). */
static const char *weights_state(const nerf_model *model)
{
    return nerf_model_contents(model) & NERF_MODEL_HAS_NONFINITE_WEIGHTS
               ? "not finite: the run that trained it diverged"
               : "finite";
}

cJSON *model_info(const nerf_model *model, const char *path, long long bytes)
{
    nerf_model_options mo;
    NERF_MODEL_OPTIONS_INIT(&mo);
    nerf_model_get_options(model, &mo);
    const uint32_t c = nerf_model_contents(model);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "file", path);
    cJSON_AddNumberToObject(o, "bytes", (double)bytes);
    cJSON_AddStringToObject(o, "kind", c & NERF_MODEL_HAS_OPTIMIZER
                                           ? "checkpoint" : "weights-only");
    cJSON_AddStringToObject(o, "preset",
                            preset_name(setup_model_preset(model)));
    cJSON_AddItemToObject(o, "encoding", encoding_object(&mo));
    cJSON_AddItemToObject(o, "network", network_object(&mo));
    cJSON_AddNumberToObject(o, "parameters",
                            (double)nerf_model_param_count(model));
    cJSON_AddStringToObject(o, "weights", weights_state(model));
    cJSON_AddNumberToObject(o, "step", (double)nerf_model_step(model));
    cJSON_AddItemToObject(o, "schedule", schedule_object(model));
    cJSON_AddStringToObject(o, "space", space_name(mo.space));
    if (mo.encoding == NERF_ENCODING_HASHGRID) {
        cJSON_AddNumberToObject(o, "bound", mo.bound);
    }
    cJSON_AddStringToObject(o, "matmul", matmul_name(mo.matmul));
    cJSON *holds = cJSON_AddArrayToObject(o, "holds");
    cJSON_AddItemToArray(holds, cJSON_CreateString("weights"));
    if (c & NERF_MODEL_HAS_OPTIMIZER) {
        cJSON_AddItemToArray(holds, cJSON_CreateString("optimiser moments"));
    }
    if (c & NERF_MODEL_HAS_ADAM_CORRECTIONS) {
        cJSON_AddItemToArray(holds, cJSON_CreateString("Adam corrections"));
    }
    if (c & NERF_MODEL_HAS_OCCUPANCY) {
        cJSON_AddItemToArray(holds, cJSON_CreateString("occupancy grid"));
    }
    if (c & NERF_MODEL_HAS_RENDER_SETTINGS) {
        cJSON_AddItemToArray(holds, cJSON_CreateString("render settings"));
    }
    if (c & NERF_MODEL_HAS_DATA_RECORD) {
        char data[256];
        cJSON_AddItemToArray(holds, cJSON_CreateString("data record"));
        if (nerf_model_training_data(model, data, sizeof data) == NERF_OK) {
            cJSON_AddStringToObject(o, "data", data);
        }
    }
    if (c & NERF_MODEL_HAS_BATCH_RECORD) {
        uint32_t rays = 0, samples = 0;
        nerf_model_training_batch(model, &rays, &samples);
        cJSON_AddItemToArray(holds, cJSON_CreateString("batch record"));
        cJSON *b = cJSON_AddObjectToObject(o, "batch");
        cJSON_AddNumberToObject(b, "rays", rays);
        cJSON_AddNumberToObject(b, "samples", samples);
    }
    if (c & NERF_MODEL_HAS_APPEARANCE) {
        uint32_t n = 0;
        float code[NERF_APPEARANCE_CODE_FLOATS];
        nerf_model_appearance_count(model, &n);
        nerf_model_appearance_code(model, NERF_APPEARANCE_NEUTRAL, code);
        cJSON_AddItemToArray(holds, cJSON_CreateString("appearance codes"));
        cJSON *a = cJSON_AddObjectToObject(o, "appearance");
        cJSON_AddNumberToObject(a, "images", n);
        cJSON *gains = cJSON_AddArrayToObject(a, "neutral_gains");
        for (uint32_t k = 0; k < NERF_APPEARANCE_CODE_FLOATS; k++) {
            /* Rounded: the line is for reading, not for reuse. */
            double g = exp((double)code[k]);
            cJSON_AddItemToArray(gains,
                                 cJSON_CreateNumber(round(g * 1e4) / 1e4));
        }
    }
    cJSON_AddItemToObject(o, "render", render_object(model));
    return o;
}

static void print_value(const cJSON *v, FILE *out)
{
    if (cJSON_IsString(v)) {
        fputs(v->valuestring, out);
    } else if (cJSON_IsBool(v)) {
        fputs(cJSON_IsTrue(v) ? "yes" : "no", out);
    } else if (cJSON_IsNumber(v)) {
        fprintf(out, "%.10g", v->valuedouble);
    } else {
        const char *sep = "";
        for (const cJSON *x = v->child; x; x = x->next) {
            fputs(sep, out);
            if (cJSON_IsObject(v)) {
                fprintf(out, "%s ", x->string);
            }
            print_value(x, out);
            sep = ", ";
        }
    }
}

void model_info_print_text(const cJSON *info, FILE *out)
{
    for (const cJSON *x = info->child; x; x = x->next) {
        fprintf(out, "%-11s ", x->string);
        print_value(x, out);
        if (strcmp(x->string, "bytes") == 0 && x->valuedouble >= 1e6) {
            fprintf(out, " (%.1f MB)", x->valuedouble / 1e6);
        }
        if (strcmp(x->string, "kind") == 0) {
            fputs(strcmp(x->valuestring, "checkpoint") == 0
                      ? " (training can resume from it)"
                      : " (no optimiser state: renders and evaluates; "
                        "training cannot resume from it)", out);
        }
        fputc('\n', out);
    }
}
