/* nerf-export: geometry and data out of a trained model, by subcommand. */
#include <stdio.h>
#include <string.h>

#include "common/cli.h"
#include "common/options.h"
#include "export.h"

typedef struct subcommand {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} subcommand;

static const subcommand subcommands[] = {
    {"mesh", export_mesh, "a triangle mesh of the density (PLY or OBJ)"},
    {"grid", export_grid, "the density sampled on a grid (float32 .npy)"},
    {"depth", export_depth,
     "distance, z depth and opacity of views as float32 .npy"},
    {"points", export_points,
     "a point cloud (PLY) from the expected depth of views"},
};

#define N_SUBCOMMANDS (sizeof subcommands / sizeof subcommands[0])

static void usage(FILE *out)
{
    fputs("usage: nerf-export SUBCOMMAND --model MODEL --out OUT [options]\n"
          "Write what a trained model holds in forms other tools read.\n"
          "Subcommands:\n", out);
    for (size_t i = 0; i < N_SUBCOMMANDS; i++) {
        fprintf(out, "  %-8s %s\n", subcommands[i].name,
                subcommands[i].summary);
    }
    fputs("  nerf-export SUBCOMMAND --help   the subcommand's options\n"
          "Examples:\n"
          "  nerf-export mesh --model lego.nerf --out lego.ply\n"
          "  nerf-export grid --model lego.nerf --out lego.npy \\\n"
          "      --resolution 128\n"
          "  nerf-export depth --model lego.nerf --data lego --out depth\n"
          "  nerf-export points --model lego.nerf --data lego \\\n"
          "      --out lego-points.ply\n",
          out);
}

int main(int argc, char **argv)
{
    cli_blas_single_thread();
    if (argc < 2) {
        cli_usage_error("nerf-export", "a subcommand is required");
        return 2;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        usage(stdout);
        return 0;
    }
    const char *names[N_SUBCOMMANDS + 3];
    for (size_t i = 0; i < N_SUBCOMMANDS; i++) {
        if (strcmp(argv[1], subcommands[i].name) == 0) {
            return subcommands[i].run(argc - 1, argv + 1);
        }
        names[i] = subcommands[i].name;
    }
    names[N_SUBCOMMANDS] = "--help";
    names[N_SUBCOMMANDS + 1] = NULL;
    const char *near = cli_suggest(argv[1], names);
    if (near && near[0] != '-') {
        cli_usage_error("nerf-export", "unknown subcommand '%s' (did you mean "
                        "%s?)", argv[1], near);
    } else {
        char list[256] = "";
        for (size_t i = 0; i < N_SUBCOMMANDS; i++) {
            strncat(list, i ? ", " : "", sizeof list - strlen(list) - 1);
            strncat(list, subcommands[i].name, sizeof list - strlen(list) - 1);
        }
        cli_usage_error("nerf-export", "unknown subcommand '%s' (one of %s)",
                        argv[1], list);
    }
    return 2;
}
