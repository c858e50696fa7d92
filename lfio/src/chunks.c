/*
 * chunks.c - HDF5's shuffle, deflate and Fletcher-32 filters over whole
 * chunks, on threads (chunks.h).
 *
 * Writing a large radiance-map file is mostly zlib, and HDF5 runs its filters
 * on the one thread that calls it. Filtering here lets the chunks of a patch
 * be compressed side by side, and beside HDF5's own work on the patch's
 * objects. Invariants: a chunk's stored bytes are exactly what HDF5's pipeline
 * (shuffle, deflate at the same level through compress2(), Fletcher-32 last,
 * little-endian) makes of the same values, the part of the chunk past the
 * dataset's end holding zeros; the result does not depend on the number of
 * threads; a failure frees everything.
 */
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "chunks.h"
#include "ilf/pool.h"

uint32_t lfio__fletcher32(const unsigned char *p, size_t n)
{
    uint32_t a = 0, b = 0;
    size_t words = n / 2;
    while (words > 0) {
        /* fold before the sums can overflow: 360 words keep b below 2^32 */
        size_t run = words < 360 ? words : 360;
        words -= run;
        for (size_t k = 0; k < run; k++, p += 2) {
            a += ((uint32_t)p[0] << 8) | p[1];
            b += a;
        }
        a = (a & 0xffffu) + (a >> 16);
        b = (b & 0xffffu) + (b >> 16);
    }
    if (n % 2) {
        a += (uint32_t)p[0] << 8;
        b += a;
        a = (a & 0xffffu) + (a >> 16);
        b = (b & 0xffffu) + (b >> 16);
    }
    a = (a & 0xffffu) + (a >> 16);
    b = (b & 0xffffu) + (b >> 16);
    return (b << 16) | a;
}

/* Shuffles present values of elem bytes from raw into elem byte planes of count bytes each: byte k of
 * value i to plane k, place i. Called with elem a constant, the compiler unrolls the inner loop for it
 * (with elem a variable, the shuffle was an eighth of a 1.3 M-cell write's instructions). */
static inline void shuffle(const unsigned char *restrict raw, size_t present, size_t count, size_t elem,
                           unsigned char *restrict planes)
{
    for (size_t i = 0; i < present; i++)
        for (size_t k = 0; k < elem; k++)
            planes[k * count + i] = raw[i * elem + k];
}

/* Filters one chunk into c->out, with scratch for the shuffled values (c->chunk_bytes). @return 0 or -1. */
static int filter_one(lfio__chunk *c, unsigned char *scratch)
{
    /* shuffle: byte k of every value together, the values in order (the zeros past the end likewise) */
    size_t count = c->chunk_bytes / c->elem, present = c->raw_bytes / c->elem;
    for (size_t k = 0; present < count && k < c->elem; k++) /* the zeros past the end, in each byte plane */
        memset(scratch + k * count + present, 0, count - present);
    if (c->elem == 4)
        shuffle(c->raw, present, count, 4, scratch);
    else if (c->elem == 8)
        shuffle(c->raw, present, count, 8, scratch);
    else
        shuffle(c->raw, present, count, c->elem, scratch);
    size_t most = lfio__chunks_stored_most(c->chunk_bytes); /* zlib's bound and the checksum */
    uLongf packed = (uLongf)(most - 4);
    c->out = malloc(most);
    if (c->out == NULL)
        return -1;
    if (compress2(c->out, &packed, scratch, (uLong)c->chunk_bytes, c->level) != Z_OK) {
        free(c->out);
        c->out = NULL;
        return -1;
    }
    uint32_t sum = lfio__fletcher32(c->out, packed);
    for (int k = 0; k < 4; k++)
        c->out[packed + k] = (unsigned char)(sum >> (8 * k));
    c->out_bytes = packed + 4;
    /* the bound is the raw size: give back what compression saved while the chunk waits to be stored */
    unsigned char *fit = realloc(c->out, c->out_bytes);
    if (fit != NULL)
        c->out = fit;
    return 0;
}

/* What the threads share: the chunks, the next one to take, and each worker's scratch. */
typedef struct filter_work {
    lfio__chunk *c;
    size_t n;
    unsigned char *scratch; /* most bytes per worker, made before they start: the allocations made do not
                               depend on how the chunks fall to the workers */
    size_t most;            /* the largest chunk_bytes */
    atomic_size_t next;
    atomic_int failed;
} filter_work;

/* Worker `index` (0, the calling thread, first): takes chunks until none is left. */
static void filter_worker(filter_work *w, unsigned index)
{
    unsigned char *scratch = w->scratch + (size_t)index * w->most;
    for (size_t k; (k = atomic_fetch_add(&w->next, 1)) < w->n;)
        if (filter_one(&w->c[k], scratch) != 0)
            atomic_store(&w->failed, 1);
}

/* A helper thread of lfio__chunks_filter(): worker index + 1. */
static void filter_helper(void *arg, unsigned index)
{
    filter_worker(arg, index + 1);
}

int lfio__chunks_filter(lfio__chunk *c, size_t n, unsigned threads, void (*call_between)(void *), void *user)
{
    for (size_t k = 0; k < n; k++)
        c[k].out = NULL, c[k].out_bytes = 0;
    /* helpers only when there is more than one chunk to share */
    unsigned helpers = threads > 1 && n > 1 ? (threads - 1 < n - 1 ? threads - 1 : (unsigned)(n - 1)) : 0;
    size_t most = 1;
    for (size_t k = 0; k < n; k++)
        most = c[k].chunk_bytes > most ? c[k].chunk_bytes : most;
    unsigned char *scratch = most <= SIZE_MAX / (helpers + 1u) ? malloc((size_t)(helpers + 1u) * most) : NULL;
    filter_work w = {c, n, scratch, most, 0, 0};
    atomic_init(&w.next, 0);
    atomic_init(&w.failed, 0);
    ilf_team *team = NULL;
    /* a scratch or a team that cannot be allocated is out of memory, reported as such (nothing has run yet) */
    if (scratch == NULL || (helpers > 0 && ilf_team_start(helpers, filter_helper, &w, &team) != 0)) {
        free(scratch);
        return -1;
    }
    if (call_between)
        call_between(user);
    filter_worker(&w, 0);
    ilf_team_join(team);
    free(scratch);
    if (atomic_load(&w.failed)) {
        lfio__chunks_free(c, n);
        return -1;
    }
    return 0;
}

size_t lfio__chunks_stored_most(size_t chunk_bytes)
{
    return (size_t)compressBound((uLong)chunk_bytes) + 4;
}

/* What the threads of lfio__chunks_unfilter() share. */
typedef struct unfilter_work {
    const lfio__stored *c;
    size_t n;
    void (*place)(void *user, size_t k, const unsigned char *values);
    void *user;
    unsigned char *scratch; /* 2 * most bytes per worker, made before they start: the allocations made do not
                               depend on how the chunks fall to the workers */
    size_t most;            /* the largest chunk_bytes */
    atomic_size_t next;
    int *status; /* [n] */
    atomic_int failed;
} unfilter_work;

int lfio__chunks_check(const lfio__stored *c, int fletcher32, int deflate, unsigned char *out)
{
    size_t packed = c->in_bytes;
    if (fletcher32) {
        if (packed < 4)
            return LFIO__STORED_BROKEN;
        packed -= 4;
        uint32_t sum = 0;
        for (int k = 0; k < 4; k++)
            sum |= (uint32_t)c->in[packed + k] << (8 * k);
        if (lfio__fletcher32(c->in, packed) != sum)
            return LFIO__STORED_CHECKSUM;
    }
    if (!deflate)
        return packed == c->chunk_bytes ? LFIO__STORED_OK : LFIO__STORED_BROKEN;
    /* uncompress() stops at the buffer's end: a stream that would go on is an error, never more memory */
    uLongf got = (uLongf)c->chunk_bytes;
    if (uncompress(out, &got, c->in, (uLong)packed) != Z_OK || got != c->chunk_bytes)
        return LFIO__STORED_BROKEN;
    return LFIO__STORED_OK;
}

/* Undoes one chunk's pipeline into values, with scratch for the shuffled bytes (both chunk_bytes).
 * @return an LFIO__STORED_ value. */
static int unfilter_one(const lfio__stored *c, unsigned char *scratch, unsigned char *values)
{
    int rc = lfio__chunks_check(c, 1, 1, scratch);
    if (rc != LFIO__STORED_OK)
        return rc;
    size_t count = c->chunk_bytes / c->elem;
    for (size_t i = 0; i < count; i++)
        for (size_t k = 0; k < c->elem; k++)
            values[i * c->elem + k] = scratch[k * count + i];
    return LFIO__STORED_OK;
}

/* Worker `index` of lfio__chunks_unfilter(): takes chunks until none is left or one has failed. */
static void unfilter_worker(void *arg, unsigned index)
{
    unfilter_work *w = arg;
    unsigned char *scratch = w->scratch + (size_t)index * 2 * w->most, *values = scratch + w->most;
    for (size_t k; !atomic_load(&w->failed) && (k = atomic_fetch_add(&w->next, 1)) < w->n;) {
        w->status[k] = unfilter_one(&w->c[k], scratch, values);
        if (w->status[k] == LFIO__STORED_OK)
            w->place(w->user, k, values);
        else
            atomic_store(&w->failed, 1);
    }
}

int lfio__chunks_unfilter(const lfio__stored *c, size_t n, unsigned threads,
                          void (*place)(void *user, size_t k, const unsigned char *values), void *user, size_t *bad)
{
    unsigned workers = n < threads ? (unsigned)(n ? n : 1) : (threads ? threads : 1);
    size_t most = 1;
    for (size_t k = 0; k < n; k++)
        most = c[k].chunk_bytes > most ? c[k].chunk_bytes : most;
    int *status = calloc(n ? n : 1, sizeof *status);
    unsigned char *scratch = most <= SIZE_MAX / 2 / workers ? malloc((size_t)workers * 2 * most) : NULL;
    *bad = 0;
    if (status == NULL || scratch == NULL) {
        free(status);
        free(scratch);
        return LFIO__STORED_NOMEM;
    }
    unfilter_work w = {c, n, place, user, scratch, most, 0, status, 0};
    atomic_init(&w.next, 0);
    atomic_init(&w.failed, 0);
    ilf_parallel(workers, unfilter_worker, &w);
    int rc = LFIO__STORED_OK;
    for (size_t k = 0; k < n && rc == LFIO__STORED_OK; k++)
        if (status[k] != LFIO__STORED_OK)
            rc = status[k], *bad = k;
    free(status);
    free(scratch);
    return rc;
}

void lfio__chunks_free(lfio__chunk *c, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        free(c[k].out);
        c[k].out = NULL;
    }
}
