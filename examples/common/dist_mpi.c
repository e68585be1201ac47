/*
 * Several processes over MPI (Open MPI): every rank trains its share of
 * each step's rays, and the gradient hook sums the ranks' gradients with
 * MPI_Allreduce so that every rank takes the same Adam step.
 *
 * The hash tables' gradients are mostly zeros (a step touches a few
 * entries of each level), so their ranges travel as (index, value) pairs
 * through MPI_Allgatherv when that is smaller than summing them densely,
 * the choice made by every rank alike from the counts of all ranks.  The
 * pairs are added in rank order onto zeros, so every rank computes the
 * same bits; the dense ranges go through one MPI_Allreduce, whose result
 * Open MPI gives alike to every rank.  docs/distributed.md has the sizes.
 */
#include "dist.h"

#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Sums go out in pieces no larger than this, MPI counts being ints. */
#define PIECE (1 << 28)

typedef struct exchange_buf {
    float *dense;        /* the dense ranges, packed */
    uint32_t *pairs;     /* own (index, value bits) pairs */
    uint32_t *all_pairs; /* every rank's, in rank order */
    size_t cap_dense, cap_pairs, cap_all;
    int *counts, *displs;
    uint64_t *nonzero;   /* per rank */
} exchange_buf;

static exchange_buf buf;

static int grow(void **p, size_t *cap, size_t n, size_t size)
{
    if (n <= *cap) {
        return 0;
    }
    void *q = realloc(*p, n * size);
    if (q == NULL) {
        return -1;
    }
    *p = q;
    *cap = n;
    return 0;
}

static int mpi_failed(nerf_exchange *x, const char *what, int err)
{
    char s[MPI_MAX_ERROR_STRING];
    int len = 0;
    MPI_Error_string(err, s, &len);
    snprintf(x->message, sizeof x->message, "%s failed (another rank may "
             "have died): %.160s", what, s);
    return 1;
}

static int allreduce_floats(float *v, size_t n, nerf_exchange *x)
{
    for (size_t at = 0; at < n; at += PIECE) {
        size_t k = n - at < PIECE ? n - at : PIECE;
        int err = MPI_Allreduce(MPI_IN_PLACE, v + at, (int)k, MPI_FLOAT,
                                MPI_SUM, MPI_COMM_WORLD);
        if (err != MPI_SUCCESS) {
            return mpi_failed(x, "MPI_Allreduce", err);
        }
    }
    return 0;
}

/*
 * Copy the elements outside the sparse ranges (which nerf_exchange gives
 * in increasing order) between g and the packed dense, in either
 * direction.
 */
static void copy_dense(const nerf_exchange *x, float *g, size_t n,
                       float *dense, int pack)
{
    size_t from = 0, k = 0;
    for (uint32_t r = 0; r <= x->n_sparse; r++) {
        size_t to = r < x->n_sparse ? (size_t)x->sparse_begin[r] : n;
        if (to > from) {
            if (pack) {
                memcpy(dense + k, g + from, (to - from) * sizeof(float));
            } else {
                memcpy(g + from, dense + k, (to - from) * sizeof(float));
            }
            k += to - from;
        }
        from = r < x->n_sparse ? (size_t)x->sparse_end[r] : n;
    }
}

/* NERF_MPI_EXCHANGE=dense or sparse forces the choice below (to measure
 * one against the other); unset or auto: by size. */
static int forced_exchange(void)
{
    const char *v = getenv("NERF_MPI_EXCHANGE");
    return v == NULL ? 0 : strcmp(v, "dense") == 0 ? 1
                         : strcmp(v, "sparse") == 0 ? 2 : 0;
}

/* The sparse ranges as pairs: each rank's nonzeros, gathered by all and
 * added onto zeros in rank order. */
static int exchange_pairs(dist *d, float *g, const nerf_exchange *xr,
                          uint64_t own, uint64_t total, nerf_exchange *x)
{
    if (grow((void **)&buf.pairs, &buf.cap_pairs, 2 * own + 2,
             sizeof(uint32_t)) ||
        grow((void **)&buf.all_pairs, &buf.cap_all, 2 * total + 2,
             sizeof(uint32_t))) {
        snprintf(x->message, sizeof x->message, "out of memory");
        return 1;
    }
    size_t k = 0;
    for (uint32_t r = 0; r < xr->n_sparse; r++) {
        for (uint64_t i = xr->sparse_begin[r]; i < xr->sparse_end[r]; i++) {
            if (g[i] != 0.0f) {
                buf.pairs[2 * k] = (uint32_t)i;
                memcpy(&buf.pairs[2 * k + 1], &g[i], sizeof(float));
                k++;
            }
        }
        memset(g + xr->sparse_begin[r], 0,
               (xr->sparse_end[r] - xr->sparse_begin[r]) * sizeof(float));
    }
    int at = 0;
    for (int r = 0; r < d->size; r++) {
        buf.counts[r] = (int)(2 * buf.nonzero[r]);
        buf.displs[r] = at;
        at += buf.counts[r];
    }
    int err = MPI_Allgatherv(buf.pairs, (int)(2 * own), MPI_UINT32_T,
                             buf.all_pairs, buf.counts, buf.displs,
                             MPI_UINT32_T, MPI_COMM_WORLD);
    if (err != MPI_SUCCESS) {
        return mpi_failed(x, "MPI_Allgatherv", err);
    }
    for (uint64_t p = 0; p < total; p++) {
        float v;
        memcpy(&v, &buf.all_pairs[2 * p + 1], sizeof v);
        g[buf.all_pairs[2 * p]] += v;
    }
    return 0;
}

static int grad_hook(void *user, float *g, size_t n, nerf_exchange *x)
{
    dist *d = user;
    const double t0 = MPI_Wtime();
    /* Nonzeros of the sparse ranges, every rank's. */
    uint64_t own = 0, span = 0;
    for (uint32_t r = 0; r < x->n_sparse; r++) {
        span += x->sparse_end[r] - x->sparse_begin[r];
        for (uint64_t i = x->sparse_begin[r]; i < x->sparse_end[r]; i++) {
            own += g[i] != 0.0f;
        }
    }
    uint64_t total = 0;
    int sparse = 0;
    if (span > 0 && n < UINT32_MAX) {
        int err = MPI_Allgather(&own, 1, MPI_UINT64_T, buf.nonzero, 1,
                                MPI_UINT64_T, MPI_COMM_WORLD);
        if (err != MPI_SUCCESS) {
            return mpi_failed(x, "MPI_Allgather", err);
        }
        for (int r = 0; r < d->size; r++) {
            total += buf.nonzero[r];
        }
        /* A ring all-reduce moves about 2 (p-1)/p of the range's 4 bytes
         * an element through each rank; the gather moves (p-1)/p of the
         * pairs' 8 bytes each.  Sparse when that is under a quarter, the
         * rest left for the scans, packing and adds the pairs cost. */
        const int force = forced_exchange();
        sparse = force == 2 ||
                 (force == 0 && 4.0 * 8.0 * (double)total < 2.0 * 4.0 * (double)span);
        sparse = sparse && 2 * total < (uint64_t)INT32_MAX;
    }
    /* The dense part: everything outside the ranges sent as pairs. */
    size_t nd = sparse ? n - span : n;
    float *dense = g;
    if (sparse) {
        if (grow((void **)&buf.dense, &buf.cap_dense, nd + 1, sizeof(float))) {
            snprintf(x->message, sizeof x->message, "out of memory");
            return 1;
        }
        dense = buf.dense;
        copy_dense(x, g, n, dense, 1);
    }
    int ret = allreduce_floats(dense, nd, x);
    if (ret == 0 && sparse) {
        copy_dense(x, g, n, dense, 0);
        ret = exchange_pairs(d, g, x, own, total, x);
    }
    if (sparse) {
        d->sparse++;
        d->sparse_bytes += 4.0 * (double)nd + 8.0 * (double)total;
    } else {
        d->dense++;
        d->dense_bytes += 4.0 * (double)n;
    }
    d->exchange_seconds += MPI_Wtime() - t0;
    return ret;
}

static int checksum_hook(void *user, uint32_t range[2], nerf_exchange *x)
{
    (void)user;
    /* The largest of ~c is ~(the smallest c): one MAX gives both ends. */
    uint32_t v[2] = {~range[0], range[1]};
    int err = MPI_Allreduce(MPI_IN_PLACE, v, 2, MPI_UINT32_T, MPI_MAX,
                            MPI_COMM_WORLD);
    if (err != MPI_SUCCESS) {
        return mpi_failed(x, "MPI_Allreduce", err);
    }
    range[0] = ~v[0];
    range[1] = v[1];
    return 0;
}

/* A program that exits on its own (--help) must still finalize, or
 * mpirun reports the exit as a failure. */
static void finalize_at_exit(void)
{
    int done = 0;
    MPI_Finalized(&done);
    if (!done) {
        MPI_Finalize();
    }
}

int dist_init(dist *d, int *argc, char ***argv, const char *name)
{
    memset(d, 0, sizeof *d);
    d->name = name;
    if (MPI_Init(argc, argv) != MPI_SUCCESS) {
        fprintf(stderr, "%s: MPI_Init failed (run it with mpirun)\n", name);
        return -1;
    }
    /* Errors come back as codes, so a failed exchange ends the step with
     * a message rather than killing the rank without one. */
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    atexit(finalize_at_exit);
    MPI_Comm_rank(MPI_COMM_WORLD, &d->rank);
    MPI_Comm_size(MPI_COMM_WORLD, &d->size);
    buf.counts = calloc((size_t)d->size, sizeof *buf.counts);
    buf.displs = calloc((size_t)d->size, sizeof *buf.displs);
    buf.nonzero = calloc((size_t)d->size, sizeof *buf.nonzero);
    if (!buf.counts || !buf.displs || !buf.nonzero) {
        fprintf(stderr, "%s: out of memory\n", name);
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    return 0;
}

void dist_finish(dist *d)
{
    (void)d;
    free(buf.dense);
    free(buf.pairs);
    free(buf.all_pairs);
    free(buf.counts);
    free(buf.displs);
    free(buf.nonzero);
    memset(&buf, 0, sizeof buf);
    finalize_at_exit();
}

void dist_fail(dist *d, int status)
{
    if (d->size > 1) {
        fprintf(stderr, "%s: rank %d of %d failed: ending the job\n", d->name,
                d->rank, d->size);
        MPI_Abort(MPI_COMM_WORLD, status);
    }
}

/* Checksums every this many steps: a CRC-32 over the weights costs about
 * as much as a pass of Adam over them. */
#define CHECK_EVERY 100

void dist_trainer_options(dist *d, nerf_trainer_options *o)
{
    if (d->size <= 1) {
        return;
    }
    o->worker_rank = (uint32_t)d->rank;
    o->worker_count = (uint32_t)d->size;
    o->grad_hook = grad_hook;
    o->checksum_hook = checksum_hook;
    o->hook_user = d;
    o->checksum_every = CHECK_EVERY;
    if (d->rank != 0) {
        /* One writer: rank 0 saves what every rank holds. */
        o->checkpoint_path = NULL;
        o->checkpoint_every = 0;
        o->checkpoint_seconds = 0.0;
    }
}

void dist_step_agree(dist *d, int *sig, int *out_of_time, double *loss,
                     double *psnr)
{
    if (d->size <= 1) {
        return;
    }
    double sum[2] = {*loss, *psnr};
    int any[2] = {*sig, *out_of_time};
    int err = MPI_Allreduce(MPI_IN_PLACE, sum, 2, MPI_DOUBLE, MPI_SUM,
                            MPI_COMM_WORLD);
    if (err == MPI_SUCCESS) {
        err = MPI_Allreduce(MPI_IN_PLACE, any, 2, MPI_INT, MPI_MAX,
                            MPI_COMM_WORLD);
    }
    if (err != MPI_SUCCESS) {
        fprintf(stderr, "%s: rank %d: MPI_Allreduce failed (another rank may "
                "have died)\n", d->name, d->rank);
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    *loss = sum[0] / d->size;
    *psnr = sum[1] / d->size;
    *sig = any[0];
    *out_of_time = any[1];
}

void dist_barrier(dist *d)
{
    if (d->size > 1) {
        MPI_Barrier(MPI_COMM_WORLD);
    }
}

void dist_report(const dist *d)
{
    const unsigned long long n = d->dense + d->sparse;
    if (d->size <= 1 || n == 0) {
        return;
    }
    fprintf(stderr, "%s: %d ranks; rank %d spent %.2f s in %llu gradient "
            "exchanges (%.2f ms each; %llu dense, %llu sparse, %.0f kB a "
            "step on average)\n", d->name, d->size, d->rank,
            d->exchange_seconds, n, 1e3 * d->exchange_seconds / (double)n,
            d->dense, d->sparse,
            (d->dense_bytes + d->sparse_bytes) / (double)n / 1e3);
}
