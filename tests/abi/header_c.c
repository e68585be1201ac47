/* Built as C99 -pedantic -Werror: the public header must compile alone. */
#include <nerf.h>

#include <stdio.h>

int main(void)
{
    if (nerf_version_number() != NERF_VERSION_NUMBER) {
        printf("header says %d, library says %u\n", NERF_VERSION_NUMBER,
               nerf_version_number());
        return 1;
    }
    printf("%s\n", nerf_version_string());
    return 0;
}
