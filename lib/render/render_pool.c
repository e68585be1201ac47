/*
 * The chunk driver.  Chunks go to worker threads through a shared counter;
 * each worker owns its scratch, so workers share nothing but the counter,
 * the read-only model and disjoint parts of the output.  The calling thread
 * does no rendering itself while workers run: it sleeps on a condition
 * variable and wakes after each chunk to report progress, which keeps every
 * callback on the caller's thread as the threading contract requires.
 */
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "parallel.h"
#include "progress.h"
#include "renderer.h"

#define MSG_MAX 512

typedef struct pool {
    nerf_renderer *r;
    bool cover_cores; /* the workers occupy every core between them */
    nerf__chunk_fn fn;
    void *job;
    size_t n, n_chunks;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    size_t next;      /* next chunk to hand out */
    size_t done;      /* items finished */
    uint32_t running; /* workers not yet finished */
    bool stop;
    int rc;           /* failure of the lowest failing chunk */
    size_t rc_chunk;
    char msg[MSG_MAX];
} pool;

typedef struct worker_arg {
    pool *p;
    nerf__worker *w;
} worker_arg;

static int report(nerf_renderer *r, size_t done, size_t total, double t0)
{
    return nerf__progress_report(r->progress, r->progress_user,
                                 NERF_PROGRESS_RENDER, done, total, t0);
}

int nerf__renderer_ensure_workers(nerf_renderer *r, uint32_t count)
{
    if (count <= r->n_workers) {
        return NERF_OK;
    }
    nerf__worker **list = nerf__calloc(&r->env, count, sizeof *list);
    if (list == NULL) {
        return NERF_ENOMEM;
    }
    if (r->n_workers) {
        memcpy(list, r->workers, r->n_workers * sizeof *list);
    }
    nerf__free(&r->env, r->workers);
    r->workers = list;
    while (r->n_workers < count) {
        nerf__worker *w = nerf__calloc(&r->env, 1, sizeof *w);
        if (w == NULL) {
            return NERF_ENOMEM;
        }
        nerf__batch_init(&w->batch, &r->env);
        r->workers[r->n_workers++] = w;
    }
    return NERF_OK;
}

static void *worker_main(void *arg)
{
    worker_arg *a = arg;
    pool *p = a->p;
    nerf__parallel_set_inline(p->cover_cores);
    pthread_mutex_lock(&p->mu);
    for (;;) {
        if (p->stop || p->next >= p->n_chunks) {
            break;
        }
        if (atomic_load(&p->r->cancel)) {
            p->stop = true;
            break;
        }
        size_t c = p->next++;
        pthread_mutex_unlock(&p->mu);
        size_t first = c * p->r->chunk;
        size_t count = p->n - first < p->r->chunk ? p->n - first : p->r->chunk;
        int rc = p->fn(p->job, a->w, first, count);
        pthread_mutex_lock(&p->mu);
        if (rc != NERF_OK) {
            /* Keep the failure of the lowest chunk, so the message does
             * not depend on thread timing. */
            if (p->rc == NERF_OK || c < p->rc_chunk) {
                p->rc = rc;
                p->rc_chunk = c;
                snprintf(p->msg, sizeof p->msg, "%s", nerf_last_error());
            }
            p->stop = true;
        } else {
            p->done += count;
        }
        pthread_cond_signal(&p->cv);
    }
    p->running--;
    pthread_cond_signal(&p->cv);
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

static int run_inline(nerf_renderer *r, size_t n, nerf__chunk_fn fn,
                      void *job, double t0)
{
    for (size_t first = 0; first < n; first += r->chunk) {
        if (atomic_load(&r->cancel)) {
            return nerf__error(NERF_ECANCELLED, "render cancelled");
        }
        size_t count = n - first < r->chunk ? n - first : r->chunk;
        int rc = fn(job, r->workers[0], first, count);
        if (rc != NERF_OK) {
            return rc;
        }
        if (report(r, first + count, n, t0) != 0) {
            return nerf__error(NERF_ECANCELLED, "render cancelled by the "
                               "progress callback");
        }
    }
    return NERF_OK;
}

static int run_threads(nerf_renderer *r, uint32_t threads, size_t n,
                       nerf__chunk_fn fn, void *job, double t0)
{
    pool p;
    memset(&p, 0, sizeof p);
    p.r = r;
    p.fn = fn;
    p.job = job;
    p.n = n;
    p.n_chunks = (n + r->chunk - 1) / r->chunk;
    p.cover_cores = threads >= nerf__parallel_threads();
    if (pthread_mutex_init(&p.mu, NULL) != 0) {
        return nerf__error(NERF_ERROR, "render: cannot create a mutex");
    }
    if (pthread_cond_init(&p.cv, NULL) != 0) {
        pthread_mutex_destroy(&p.mu);
        return nerf__error(NERF_ERROR, "render: cannot create a condition "
                           "variable");
    }
    pthread_t tids[NERF__MAX_THREADS];
    worker_arg args[NERF__MAX_THREADS];
    uint32_t started = 0;
    pthread_mutex_lock(&p.mu);
    for (uint32_t i = 0; i < threads; i++) {
        args[i] = (worker_arg){&p, r->workers[i]};
        if (pthread_create(&tids[i], NULL, worker_main, &args[i]) != 0) {
            break; /* go on with the workers we have */
        }
        started++;
        p.running++;
    }
    bool by_callback = false;
    size_t reported = 0;
    while (p.running > 0) {
        pthread_cond_wait(&p.cv, &p.mu);
        if (p.done != reported && !p.stop) {
            reported = p.done;
            pthread_mutex_unlock(&p.mu);
            int stop = report(r, reported, n, t0);
            pthread_mutex_lock(&p.mu);
            if (stop) {
                /* Through the flag, workers also drop the chunk they are
                 * in at its next block. */
                atomic_store(&r->cancel, 1);
                p.stop = true;
                by_callback = true;
            }
        }
    }
    pthread_mutex_unlock(&p.mu);
    for (uint32_t i = 0; i < started; i++) {
        pthread_join(tids[i], NULL);
    }
    pthread_cond_destroy(&p.cv);
    pthread_mutex_destroy(&p.mu);
    if (started == 0) {
        return run_inline(r, n, fn, job, t0);
    }
    if (p.rc != NERF_OK && p.rc != NERF_ECANCELLED) {
        /* The message was set on the worker's thread: raise it here. */
        return nerf__error(p.rc, "%s", p.msg);
    }
    if (by_callback) {
        return nerf__error(NERF_ECANCELLED, "render cancelled by the "
                           "progress callback");
    }
    if (p.rc == NERF_ECANCELLED || p.done < n) {
        return nerf__error(NERF_ECANCELLED, "render cancelled");
    }
    if (reported != n) {
        /* The last chunk finished while the callback was running. */
        if (report(r, n, n, t0) != 0) {
            return nerf__error(NERF_ECANCELLED, "render cancelled by the "
                               "progress callback");
        }
    }
    return NERF_OK;
}

int nerf__renderer_run(nerf_renderer *r, size_t n, nerf__chunk_fn fn,
                       void *job)
{
    /* A cancel applies to the call running when it arrives. */
    atomic_store(&r->cancel, 0);
    if (n == 0) {
        return NERF_OK;
    }
    double t0 = nerf__seconds();
    size_t n_chunks = (n + r->chunk - 1) / r->chunk;
    uint32_t threads = r->threads;
    if (threads > n_chunks) {
        threads = (uint32_t)n_chunks;
    }
    if (threads > NERF__MAX_THREADS) {
        threads = NERF__MAX_THREADS;
    }
    int rc = nerf__renderer_ensure_workers(r, threads);
    if (rc != NERF_OK) {
        return rc;
    }
    if (threads <= 1) {
        return run_inline(r, n, fn, job, t0);
    }
    return run_threads(r, threads, n, fn, job, t0);
}
