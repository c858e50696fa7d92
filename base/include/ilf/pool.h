/*
 * ilf/pool.h - the project's one way to run work on threads.
 *
 * A team is n workers started together and joined together; each is called
 * as fn(arg, k) with its own index k in [0, n). Workers share work through
 * the caller's own counters (an atomic "next item"), so the result never
 * depends on how many of them actually started: where a thread cannot be
 * created, its index runs on the joining thread instead. The only way to
 * fail is a team record that cannot be allocated (ilf_team_start); ilf_parallel
 * keeps its record on the stack and cannot fail. Thread counts follow one rule everywhere:
 * ilf_thread_count(0) is every online core, and no team is larger than
 * ILF_MAX_THREADS (ilf/limits.h).
 */
#ifndef ILF_POOL_H
#define ILF_POOL_H

#include <stddef.h>

/* @return the number of workers for a requested count: 0 means every online core; capped at ILF_MAX_THREADS. */
unsigned ilf_thread_count(unsigned requested);

typedef void (*ilf_worker_fn)(void *arg, unsigned index);
typedef struct ilf_team ilf_team;

/* Starts fn(arg, k) for k = 0..n-1 (n >= 1, capped at ILF_MAX_THREADS) on threads of their own.
 * @return 0 and *out, the team to join; -1 and *out = NULL if its record could not be allocated,
 * in which case nothing has run (the caller reports it: out of memory is never absorbed). */
int ilf_team_start(unsigned n, ilf_worker_fn fn, void *arg, ilf_team **out);

/* Waits for every worker, runs any index whose thread could not be created, and frees team. NULL is a no-op. */
void ilf_team_join(ilf_team *team);

/* @return how many workers of team run on threads of their own (0 for NULL). */
unsigned ilf_team_threads(const ilf_team *team);

/* Runs fn(arg, k) for k = 0..n-1: k = 0 on the calling thread, the rest on new threads; returns when all are done. */
void ilf_parallel(unsigned n, ilf_worker_fn fn, void *arg);

typedef void (*ilf_index_fn)(void *arg, size_t k);

/* Runs fn(arg, k) for every k in [0, n), each once, the indices shared in order between up to
 * ilf_thread_count(threads) workers (0 = every online core, as for every thread count; 1 = the calling
 * thread alone; ilf_parallel(), so it cannot fail); fn must write nothing another call reads or writes. */
void ilf_parallel_for(unsigned threads, size_t n, ilf_index_fn fn, void *arg);

#endif /* ILF_POOL_H */
