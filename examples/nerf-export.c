/* nerf-export: take a trained model elsewhere, one subcommand a format. */
#include <stdio.h>
#include <string.h>

#include "common/cli.h"
#include "common/options.h"
#include "export.h"

typedef struct subcommand {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *what;
} subcommand;

static const subcommand subcommands[] = {
    {"depth", export_depth,
     "distance, z depth and opacity of views as float32 .npy"},
    {"points", export_points,
     "a point cloud (PLY) from the expected depth of views"},
};

#define N_SUBCOMMANDS (sizeof subcommands / sizeof subcommands[0])

static void usage(FILE *f)
{
    fputs("usage: nerf-export SUBCOMMAND [OPTIONS]\n"
          "Export a trained model's geometry and depth.  Subcommands:\n", f);
    for (size_t i = 0; i < N_SUBCOMMANDS; i++) {
        fprintf(f, "  %-8s %s\n", subcommands[i].name, subcommands[i].what);
    }
    fputs("nerf-export SUBCOMMAND --help describes its options.\n", f);
}

int main(int argc, char **argv)
{
    cli_blas_single_thread();
    if (argc < 2) {
        fputs("nerf-export: a subcommand is required; nerf-export --help "
              "lists them\n", stderr);
        return 2;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        usage(stdout);
        return 0;
    }
    const char *names[N_SUBCOMMANDS + 1];
    for (size_t i = 0; i < N_SUBCOMMANDS; i++) {
        if (strcmp(argv[1], subcommands[i].name) == 0) {
            return subcommands[i].run(argc - 1, argv + 1);
        }
        names[i] = subcommands[i].name;
    }
    names[N_SUBCOMMANDS] = NULL;
    const char *near = cli_suggest(argv[1], names);
    if (near) {
        fprintf(stderr, "nerf-export: unknown subcommand '%s' (did you mean "
                "%s?); nerf-export --help lists them\n", argv[1], near);
    } else {
        fprintf(stderr, "nerf-export: unknown subcommand '%s'; nerf-export "
                "--help lists them\n", argv[1]);
    }
    return 2;
}
