#include "grid_box.h"

#include <math.h>

#include "error.h"

int nerf__grid_box_init(nerf__grid_box *g, const float lo[3],
                        const float hi[3], uint32_t resolution,
                        const char *who)
{
    if (resolution < 1 || resolution > 16384) {
        return nerf__error(NERF_EINVAL, "%s: resolution %u is out of range "
                           "(1..16384 cells along the box's longest side)",
                           who, (unsigned)resolution);
    }
    float longest = 0.0f;
    for (int a = 0; a < 3; a++) {
        const float side = hi[a] - lo[a];
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || !isfinite(side) ||
            !(side > 0.0f)) {
            return nerf__error(NERF_EINVAL, "%s: the box [%g %g %g] - "
                               "[%g %g %g] has no volume or is not finite "
                               "(each max must exceed its min)", who,
                               (double)lo[0], (double)lo[1], (double)lo[2],
                               (double)hi[0], (double)hi[1], (double)hi[2]);
        }
        longest = side > longest ? side : longest;
    }
    for (int a = 0; a < 3; a++) {
        const float side = hi[a] - lo[a];
        double cells = floor((double)resolution * side / longest + 0.5);
        g->cells[a] = cells < 1.0 ? 1u : (uint32_t)cells;
        g->lo[a] = lo[a];
        g->hi[a] = hi[a];
        g->step[a] = side / (float)g->cells[a];
    }
    return NERF_OK;
}
