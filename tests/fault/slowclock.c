/*
 * slowclock.c - makes a process slow at every tile of the relighting engine,
 * for tests/mpi_test.sh (loaded with LD_PRELOAD on one rank): its thread CPU
 * clock, which the engine reads before and after each tile of a job of
 * ranks, sleeps first. So one rank of a job is slower than the others by a
 * known time per tile, whatever the machine's load.
 *
 * Environment: ILFKIT_SLOW_CLOCK=SECONDS, the sleep per reading of a thread's
 * CPU clock (unset or 0: none). Every call is forwarded to the next
 * definition of clock_gettime (glibc's).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdlib.h>
#include <time.h>

typedef int (*clock_fn)(clockid_t, struct timespec *);

int clock_gettime(clockid_t id, struct timespec *ts)
{
    static clock_fn next = NULL;
    if (next == NULL)
        next = (clock_fn)dlsym(RTLD_NEXT, "clock_gettime");
    const char *env = getenv("ILFKIT_SLOW_CLOCK");
    double slow = env ? atof(env) : 0.0;
    if (id == CLOCK_THREAD_CPUTIME_ID && slow > 0) {
        struct timespec nap = {(time_t)slow, (long)((slow - (double)(time_t)slow) * 1e9)};
        while (nanosleep(&nap, &nap) != 0)
            ;
    }
    return next ? next(id, ts) : -1;
}
