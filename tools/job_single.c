/*
 * job_single.c - the job of one process that a plain `ilf` is (job.h):
 * every collective step is the identity, and nothing aborts.
 */
#include <unistd.h>

#include "job.h"

int job_rank(void)
{
    return 0;
}

int job_ranks(void)
{
    return 1;
}

const rl_cluster *job_cluster(void)
{
    return NULL;
}

int job_agree(int code)
{
    return code;
}

int job_share(const char *sub, void *buf, size_t size)
{
    (void)sub, (void)buf, (void)size;
    return 1;
}

int job_fail(int code)
{
    return code;
}

lfio_status job_radmap_write(const char *path, const char *creator, const char *scene, size_t count,
                             lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                             const lfio_radmap_write_options *opt)
{
    return lfio_radmap_write_with(path, creator, scene, count, describe, rows, user, opt);
}

int job_write_beside(void)
{
    return 1;
}

unsigned job_threads_per_rank(void)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    return cores > 0 ? (unsigned)cores : 1u;
}

size_t job_exchange_log(const job_exchange **log)
{
    *log = NULL;
    return 0;
}
