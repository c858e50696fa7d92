/*
 * clock.c - ilf/clock.h over POSIX clock_gettime and nanosleep. Each clock is
 * read whole (seconds and nanoseconds together), so readings never step back
 * on the monotonic clock.
 */
#include "ilf/clock.h"

#include <time.h>

static double read_clock(clockid_t id)
{
    struct timespec ts;
    if (clock_gettime(id, &ts) != 0)
        return 0.0;
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

double ilf_clock_wall(void) { return read_clock(CLOCK_MONOTONIC); }
double ilf_clock_thread_cpu(void) { return read_clock(CLOCK_THREAD_CPUTIME_ID); }
double ilf_clock_process_cpu(void) { return read_clock(CLOCK_PROCESS_CPUTIME_ID); }

void ilf_clock_sleep(double seconds)
{
    if (!(seconds > 0))
        return;
    struct timespec ts;
    ts.tv_sec = (time_t)seconds;
    ts.tv_nsec = (long)((seconds - (double)ts.tv_sec) * 1e9);
    while (nanosleep(&ts, &ts) != 0)
        ;
}
