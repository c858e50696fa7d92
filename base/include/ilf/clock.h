/*
 * ilf/clock.h - time in seconds, as doubles: the monotonic wall clock and the
 * CPU time of the process and of the calling thread.
 */
#ifndef ILF_CLOCK_H
#define ILF_CLOCK_H

/* @return seconds on the monotonic clock since an arbitrary start. */
double ilf_clock_wall(void);
/* @return CPU seconds used by the calling thread. */
double ilf_clock_thread_cpu(void);
/* @return CPU seconds used by the whole process. */
double ilf_clock_process_cpu(void);
/* Sleeps for about seconds (>= 0). */
void ilf_clock_sleep(double seconds);

#endif /* ILF_CLOCK_H */
