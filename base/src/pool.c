/*
 * pool.c - ilf/pool.h over POSIX threads.
 *
 * Invariant: every index k < n runs exactly once, either on the thread made
 * for it or, if pthread_create failed, on the thread that joins the team, after
 * the other workers have finished (they share the caller's work queue, so the
 * late index usually finds nothing left). Nothing here allocates per item,
 * and ilf_parallel allocates nothing at all (its team is on the caller's stack).
 */
#include "ilf/pool.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdlib.h>
#include <unistd.h>

#include "ilf/limits.h"

typedef struct member {
    ilf_team *team;
    unsigned index;
    int started;
    pthread_t thread;
} member;

struct ilf_team {
    ilf_worker_fn fn;
    void *arg;
    unsigned n, threads;
    member members[];
};

unsigned ilf_thread_count(unsigned requested)
{
    if (requested == 0) {
        long online = sysconf(_SC_NPROCESSORS_ONLN);
        requested = online > 0 ? (unsigned)online : 1u;
    }
    return requested > ILF_MAX_THREADS ? ILF_MAX_THREADS : requested;
}

static void *run_member(void *p)
{
    member *m = p;
    m->team->fn(m->team->arg, m->index);
    return NULL;
}

/* @return the bytes of a team of n members. */
static size_t team_bytes(unsigned n) { return sizeof(ilf_team) + (n ? n : 1) * sizeof(member); }

/* Starts fn(arg, first + k) for k = 0..n-1 on threads of their own, in t (team_bytes(n) bytes). @return t. */
static ilf_team *start_members(ilf_team *t, unsigned n, unsigned first, ilf_worker_fn fn, void *arg)
{
    if (t == NULL)
        return NULL;
    t->fn = fn;
    t->arg = arg;
    t->n = n;
    t->threads = 0;
    for (unsigned k = 0; k < n; k++) {
        member *m = &t->members[k];
        *m = (member){t, first + k, 0, 0};
        m->started = pthread_create(&m->thread, NULL, run_member, m) == 0;
        t->threads += m->started ? 1u : 0u;
    }
    return t;
}

int ilf_team_start(unsigned n, ilf_worker_fn fn, void *arg, ilf_team **out)
{
    n = n < 1 ? 1 : n > ILF_MAX_THREADS ? ILF_MAX_THREADS : n;
    *out = start_members(malloc(team_bytes(n)), n, 0, fn, arg);
    return *out != NULL ? 0 : -1;
}

unsigned ilf_team_threads(const ilf_team *team) { return team != NULL ? team->threads : 0u; }

/* Joins team's workers and runs the indices whose threads could not start. */
static void join_members(ilf_team *team)
{
    for (unsigned k = 0; k < team->n; k++)
        if (team->members[k].started)
            pthread_join(team->members[k].thread, NULL);
    for (unsigned k = 0; k < team->n; k++)
        if (!team->members[k].started)
            team->fn(team->arg, team->members[k].index);
}

void ilf_team_join(ilf_team *team)
{
    if (team == NULL)
        return;
    join_members(team);
    free(team);
}

void ilf_parallel(unsigned n, ilf_worker_fn fn, void *arg)
{
    n = n < 1 ? 1 : n > ILF_MAX_THREADS ? ILF_MAX_THREADS : n;
    /* Workers 1..n-1 on threads of their own, worker 0 here. The team lives on this stack (at most
     * ILF_MAX_THREADS members of a few words), so running in parallel never needs memory. */
    max_align_t space[(team_bytes(n - 1) + sizeof(max_align_t) - 1) / sizeof(max_align_t)];
    ilf_team *t = n > 1 ? start_members((ilf_team *)space, n - 1, 1, fn, arg) : NULL;
    fn(arg, 0);
    if (t != NULL)
        join_members(t);
}

/* What the workers of ilf_parallel_for() share: the body and the next index to take. */
typedef struct loop {
    ilf_index_fn fn;
    void *arg;
    size_t n;
    atomic_size_t next;
} loop;

/* A worker of ilf_parallel_for(): takes indices until none is left. */
static void loop_worker(void *p, unsigned index)
{
    (void)index;
    loop *l = p;
    for (size_t k; (k = atomic_fetch_add(&l->next, 1)) < l->n;)
        l->fn(l->arg, k);
}

void ilf_parallel_for(unsigned threads, size_t n, ilf_index_fn fn, void *arg)
{
    threads = ilf_thread_count(threads); /* 0 = every online core, as everywhere */
    loop l = {fn, arg, n, 0};
    atomic_init(&l.next, 0);
    ilf_parallel(n < threads ? (unsigned)(n ? n : 1) : threads, loop_worker, &l);
}
