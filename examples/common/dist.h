/*
 * What a program needs to run as one of several processes (MPI ranks):
 * nerf-train and nerf-render link either dist_none.c (one process, the
 * plain programs) or dist_mpi.c (nerf-train-mpi, nerf-render-mpi, built
 * when meson finds Open MPI).  The library knows nothing of MPI: the
 * trainer's hooks (nerf_trainer_options.grad_hook) are set here.
 */
#ifndef NERF_EXAMPLES_DIST_H
#define NERF_EXAMPLES_DIST_H

#include <nerf.h>

typedef struct dist {
    int rank, size;   /* 0 and 1 alone */
    const char *name; /* the program's name, for messages */
    /* Seconds spent in the gradient exchange, and the exchanges made
     * (dense or sparse), for the report at the end. */
    double exchange_seconds;
    unsigned long long dense, sparse;
    double sparse_bytes, dense_bytes;
} dist;

/* Start (MPI_Init); nonzero on failure, said on stderr. */
int dist_init(dist *d, int *argc, char ***argv, const char *name);
/* End (MPI_Finalize). */
void dist_finish(dist *d);

/*
 * A process that cannot go on while the others wait for it: ends the
 * whole job (MPI_Abort with `status`) when there are others; returns
 * otherwise, so that a lone process cleans up and exits as before.
 */
void dist_fail(dist *d, int status);

/* Make the trainer options one worker's: its rank and the hooks that sum
 * the gradients and compare checksums across the processes. */
void dist_trainer_options(dist *d, nerf_trainer_options *o);

/*
 * Collective, after every step, so that all processes stop at the same
 * step: *sig becomes the largest signal number any process caught (0:
 * none), *out_of_time whether any ran out of time; the loss and PSNR
 * become the means over the processes' shares.  Alone: unchanged.
 */
void dist_step_agree(dist *d, int *sig, int *out_of_time, double *loss,
                     double *psnr);

/* Wait for every process (after rank 0 has saved, before the others
 * read what it wrote). */
void dist_barrier(dist *d);

/* A line on stderr with the exchange's figures (several processes). */
void dist_report(const dist *d);

#endif
