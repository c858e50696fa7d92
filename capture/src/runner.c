/*
 * runner.c - fills a slab position by position on worker threads
 * (cap__run_positions in internal.h). Used by the capture and by
 * reprojection, which differ only in how one position is computed.
 *
 * The worker threads are the project's one pool (ilf/pool.h: ilf_parallel,
 * one cap and one meaning of 0 = every core).
 *
 * Invariants: a worker owns one position buffer of 4n^2 RGB floats and
 * computes into it without locks; the slab is written only under the
 * mutex, one position at a time, because lfio writes need exclusive access;
 * positions are claimed in increasing order, so when one fails every lower
 * position has been claimed, and reporting the lowest failure makes the
 * result independent of scheduling. Memory: threads x one buffer, plus what
 * the position function allocates.
 */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ilf/pool.h"
#include "internal.h"

typedef struct run_state {
    lfio_slab *slab;
    cap__position_fn fn;
    void *ctx;
    cap_progress_fn progress;
    void *user;
    uint32_t nu;
    uint64_t total, next, done;
    size_t buffer_floats;
    pthread_mutex_t lock;
    /* the lowest failed position (total if none), its status and message */
    uint64_t failed_at;
    cap_status failure;
    char message[1024];
} run_state;

/* Records a failure at position k if it is the lowest so far; called with the lock held. */
static void record_failure(run_state *r, uint64_t k, cap_status st, const char *message)
{
    if (k >= r->failed_at)
        return;
    r->failed_at = k;
    r->failure = st;
    snprintf(r->message, sizeof r->message, "%s", message);
}

/* Claims the next position. @return 1 and *k, or 0 when none is left or a failure stops the run. */
static int claim(run_state *r, uint64_t *k)
{
    pthread_mutex_lock(&r->lock);
    int ok = r->next < r->total && r->failed_at == r->total;
    if (ok)
        *k = r->next++;
    pthread_mutex_unlock(&r->lock);
    return ok;
}

/* Writes position k's buffer into the slab and reports progress; called without the lock. */
static void store(run_state *r, uint64_t k, const float *rgb)
{
    pthread_mutex_lock(&r->lock);
    uint32_t i = (uint32_t)(k % r->nu), j = (uint32_t)(k / r->nu);
    lfio_status ls = lfio_slab_write_position(r->slab, i, j, rgb);
    if (ls != LFIO_OK) {
        char text[1024];
        snprintf(text, sizeof text, "position (%u, %u): %s", i, j, lfio_errmsg());
        record_failure(r, k, CAP_ERR_INPUT, text);
    } else {
        r->done++;
        if (r->progress != NULL)
            r->progress(r->user, r->done, r->total);
    }
    pthread_mutex_unlock(&r->lock);
}

static void worker(void *arg, unsigned index)
{
    (void)index;
    run_state *r = arg;
    float *rgb = malloc(r->buffer_floats * sizeof *rgb);
    uint64_t k;
    while (claim(r, &k)) {
        cap_status st = rgb != NULL ? r->fn(r->ctx, (uint32_t)(k % r->nu), (uint32_t)(k / r->nu), rgb)
                                    : cap__fail(CAP_ERR_NOMEM, "out of memory for a position buffer");
        if (st == CAP_OK) {
            store(r, k, rgb);
            continue;
        }
        pthread_mutex_lock(&r->lock);
        record_failure(r, k, st, cap_error_message());
        pthread_mutex_unlock(&r->lock);
    }
    free(rgb);
}

cap_status cap__run_positions(lfio_slab *slab, unsigned threads, cap__position_fn fn, void *ctx,
                              cap_progress_fn progress, void *user)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(slab);
    run_state r;
    memset(&r, 0, sizeof r);
    r.slab = slab;
    r.fn = fn;
    r.ctx = ctx;
    r.progress = progress;
    r.user = user;
    r.nu = d->nu;
    r.total = (uint64_t)d->nu * d->nv;
    r.failed_at = r.total;
    r.buffer_floats = (size_t)lfio_slab_dir_count(slab) * 3;
    if (pthread_mutex_init(&r.lock, NULL) != 0)
        return cap__fail(CAP_ERR_NOMEM, "cannot create a mutex");
    unsigned count = ilf_thread_count(threads);
    ilf_parallel((uint64_t)count > r.total ? (unsigned)r.total : count, worker, &r);
    pthread_mutex_destroy(&r.lock);
    if (r.failed_at < r.total)
        return cap__fail_text(r.failure, r.message);
    return CAP_OK;
}
