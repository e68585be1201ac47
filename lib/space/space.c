#include "space.h"

#include <string.h>

void nerf__space_world(nerf__space *s)
{
    memset(s, 0, sizeof *s);
    s->kind = NERF__SPACE_WORLD;
}

void nerf__space_cube(nerf__space *s, float half)
{
    memset(s, 0, sizeof *s);
    s->kind = NERF__SPACE_BOX;
    for (int a = 0; a < 3; a++) {
        s->lo[a] = -half;
        s->hi[a] = half;
    }
}
