/* One process: nothing to agree with. */
#include "dist.h"

#include <string.h>

int dist_init(dist *d, int *argc, char ***argv, const char *name)
{
    (void)argc;
    (void)argv;
    memset(d, 0, sizeof *d);
    d->size = 1;
    d->name = name;
    return 0;
}

void dist_finish(dist *d)
{
    (void)d;
}

void dist_fail(dist *d, int status)
{
    (void)d;
    (void)status;
}

void dist_trainer_options(dist *d, nerf_trainer_options *o)
{
    (void)d;
    (void)o;
}

void dist_step_agree(dist *d, int *sig, int *out_of_time, double *loss,
                     double *psnr)
{
    (void)d;
    (void)sig;
    (void)out_of_time;
    (void)loss;
    (void)psnr;
}

void dist_barrier(dist *d)
{
    (void)d;
}

void dist_report(const dist *d)
{
    (void)d;
}
