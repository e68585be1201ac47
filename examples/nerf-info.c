/* nerf-info: print the library's version and how it was built. */
#include <nerf.h>

#include <stdio.h>
#include <string.h>

#include "common/options.h"

static const char usage[] =
    "usage: nerf-info\n"
    "Print libnerf's version and how it was built (compiler, BLAS, SIMD,\n"
    "optional libraries); status 1 if the library found at run time is\n"
    "not the version the program was built against.\n"
    "  --help   print this help and exit\n"
    "Examples:\n"
    "  nerf-info\n";

int main(int argc, char **argv)
{
    static const char *const options[] = {"--help", "-h", NULL};
    if (argc > 1) {
        if (cli_check_option("nerf-info", argv[1], options) != 0) {
            return 2;
        }
        fputs(usage, stdout);
        return 0;
    }
    printf("%s\n", nerf_build_info());
    if (nerf_version_number() != NERF_VERSION_NUMBER) {
        fprintf(stderr, "warning: built against libnerf %s but running %s\n",
                NERF_VERSION_STRING, nerf_version_string());
        return 1;
    }
    return 0;
}
