/* nerf-info: print the library's version and how it was built. */
#include <nerf.h>

#include <stdio.h>
#include <string.h>

int main(int argc, char **argv)
{
    if (argc > 1) {
        FILE *out = strcmp(argv[1], "--help") == 0 ? stdout : stderr;
        fprintf(out, "usage: %s\nPrint libnerf's version and build information.\n",
                argv[0]);
        return out == stdout ? 0 : 2;
    }
    printf("%s\n", nerf_build_info());
    if (nerf_version_number() != NERF_VERSION_NUMBER) {
        fprintf(stderr, "warning: built against libnerf %s but running %s\n",
                NERF_VERSION_STRING, nerf_version_string());
        return 1;
    }
    return 0;
}
