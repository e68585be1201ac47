// Built as C++ with -Werror: the public header must serve C++ users too.
#include <nerf.h>

#include <cstdio>

int main()
{
    nerf_hooks opts;
    if (NERF_HOOKS_INIT(&opts) != NERF_OK) {
        return 1;
    }
    std::printf("%s\n", nerf_version_string());
    return nerf_version_number() == NERF_VERSION_NUMBER ? 0 : 1;
}
