/*
 * pool.c - ilf/pool.h over POSIX threads.
 *
 * Invariant: every index k < n runs exactly once, either on the thread made
 * for it or, if pthread_create failed, on the thread that joins the team, after
 * the other workers have finished (they share the caller's work queue, so the
 * late index usually finds nothing left). Nothing here allocates per item.
 */
#include "ilf/pool.h"

#include <pthread.h>
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

/* @return a team running fn(arg, first + k) for k = 0..n-1 on threads of their own, or NULL without memory. */
static ilf_team *start_members(unsigned n, unsigned first, ilf_worker_fn fn, void *arg)
{
    ilf_team *t = malloc(sizeof *t + (n ? n : 1) * sizeof t->members[0]);
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

ilf_team *ilf_team_start(unsigned n, ilf_worker_fn fn, void *arg)
{
    n = n < 1 ? 1 : n > ILF_MAX_THREADS ? ILF_MAX_THREADS : n;
    ilf_team *t = start_members(n, 0, fn, arg);
    if (t == NULL)
        for (unsigned k = 0; k < n; k++)
            fn(arg, k);
    return t;
}

unsigned ilf_team_threads(const ilf_team *team) { return team != NULL ? team->threads : 0u; }

void ilf_team_join(ilf_team *team)
{
    if (team == NULL)
        return;
    for (unsigned k = 0; k < team->n; k++)
        if (team->members[k].started)
            pthread_join(team->members[k].thread, NULL);
    for (unsigned k = 0; k < team->n; k++)
        if (!team->members[k].started)
            team->fn(team->arg, team->members[k].index);
    free(team);
}

void ilf_parallel(unsigned n, ilf_worker_fn fn, void *arg)
{
    n = n < 1 ? 1 : n > ILF_MAX_THREADS ? ILF_MAX_THREADS : n;
    /* Workers 1..n-1 on threads of their own, worker 0 here. */
    ilf_team *t = n > 1 ? start_members(n - 1, 1, fn, arg) : NULL;
    fn(arg, 0);
    if (t != NULL)
        ilf_team_join(t);
    else
        for (unsigned k = 1; k < n; k++)
            fn(arg, k);
}
