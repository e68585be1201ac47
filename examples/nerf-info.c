/*
 * nerf-info: print the library's version and how it was built, or what a
 * model file holds; write a model's weights-only export.
 */
#include <nerf.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "common/cli.h"
#include "common/model_info.h"
#include "common/options.h"
#include "common/opt_table.h"
#include "common/shared_opts.h"
#include "common/out_file.h"

/* Fixed, not argv[0]: an installed program's path says nothing. */
#define PROGRAM "nerf-info"

static const char about[] =
    "Without arguments, print libnerf's version and build information.\n"
    "With MODEL (a file nerf-train wrote), describe it: its preset, encodings\n"
    "and networks, parameter count, whether its weights are finite, training\n"
    "step, scene space and bound,\n"
    "matmul mode, what the file holds (a training checkpoint with the\n"
    "optimiser's moments, or a weights-only export) and the settings it is\n"
    "rendered with (recorded by training; guessed for older files).  Status 1\n"
    "when the weights are not finite (the run that trained MODEL diverged):\n"
    "it is described, but no program renders, evaluates or trains it.\n";

static const char after[] =
    "Status 1 if the library found at run time is not the version the\n"
    "program was built against.\n"
    "Examples:\n"
    "  nerf-info\n"
    "  nerf-info lego.nerf\n"
    "  nerf-info lego.nerf --export lego-weights.nerf\n";

typedef struct args {
    const char *model, *export_to;
    int json, overwrite;
} args;

/* 0: parsed; 2: a usage error, reported. */
static int parse(int argc, char **argv, args *a)
{
    memset(a, 0, sizeof *a);
    const opt opts[] = {
        {.name = "--json", OPT_FLAG_SETS(&a->json, 1),
         .help = "print the description as one JSON object (default: text)"},
        {.name = "--export", OPT_TEXT_TO(&a->export_to), .value = "FILE",
         .help = "write MODEL without its optimiser state to FILE "
                 "(under half\n"
                 "a checkpoint's size), for sharing, rendering\n"
                 "and evaluating; nerf-train cannot resume from it.  The\n"
                 "description is then FILE's.  FILE is never MODEL\n"
                 "itself (by any path or link)"},
        {OPT_OVERWRITE(&a->overwrite),
         .help = "replace FILE if it exists (default off: an existing\n"
                 "FILE is refused)"},
        {.name = NULL},
    };
    const opt_program p = {.name = PROGRAM, .opts = opts, .column = 17,
                           .about = about, .after = after,
                           .operand = "MODEL", .operand_to = &a->model};
    if (opt_parse(&p, argc, argv) != 0) {
        return 2;
    }
    if (a->model == NULL && (a->json || a->export_to)) {
        fprintf(stderr, PROGRAM ": --json and --export describe a MODEL; see "
                PROGRAM " --help\n");
        return 2;
    }
    if (a->overwrite && a->export_to == NULL) {
        cli_usage_error(PROGRAM, "--overwrite goes with --export");
        return 2;
    }
    const out_input model = {"MODEL", a->model};
    if (a->export_to != NULL &&
        out_file_check(PROGRAM, a->export_to, a->overwrite, NULL, &model, 1) !=
            0) {
        return 2;
    }
    return 0;
}

static int build_info(void)
{
    printf("%s\n", nerf_build_info());
    if (nerf_version_number() != NERF_VERSION_NUMBER) {
        fprintf(stderr, "warning: built against libnerf %s but running %s\n",
                NERF_VERSION_STRING, nerf_version_string());
        return 1;
    }
    return 0;
}

static int describe(const args *a)
{
    /* The library's warnings (a diverged run's weights, products loaded
     * as others) say what the description can only name. */
    nerf_hooks hooks;
    NERF_HOOKS_INIT(&hooks);
    hooks.log_cb = cli_log;
    hooks.log_user = PROGRAM;
    hooks.log_level = NERF_LOG_WARN;
    nerf_model *model = NULL;
    int rc = nerf_model_load(&model, a->model, &hooks);
    if (rc != NERF_OK) {
        cli_report(PROGRAM, rc);
        return 1;
    }
    const char *shown = a->model;
    if (a->export_to) {
        rc = nerf_model_export(model, a->export_to);
        nerf_model_destroy(model);
        model = NULL;
        if (rc == NERF_OK) {
            /* Describe what was written, read back as a user would. */
            rc = nerf_model_load(&model, a->export_to, &hooks);
        }
        if (rc != NERF_OK) {
            cli_report(PROGRAM, rc);
            return 1;
        }
        shown = a->export_to;
    }
    struct stat st;
    long long bytes = stat(shown, &st) == 0 ? (long long)st.st_size : -1;
    cJSON *info = model_info(model, shown, bytes);
    /* Described, but of no use: a script asking nerf-info learns it. */
    const int diverged = (nerf_model_contents(model) &
                          NERF_MODEL_HAS_NONFINITE_WEIGHTS) != 0;
    nerf_model_destroy(model);
    if (info == NULL) {
        fprintf(stderr, PROGRAM ": out of memory\n");
        return 1;
    }
    if (a->json) {
        char *text = cJSON_Print(info);
        if (text) {
            printf("%s\n", text);
        }
        cJSON_free(text);
    } else {
        model_info_print_text(info, stdout);
    }
    cJSON_Delete(info);
    if (diverged) {
        fprintf(stderr, PROGRAM ": %s: the weights are not finite: the run "
                "that trained it diverged\n", shown);
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    args a;
    if (parse(argc, argv, &a) != 0) {
        return 2;
    }
    return a.model ? describe(&a) : build_info();
}
