/*
 * job.h - the processes that run one command together. A plain `ilf` is a
 * job of one (job_single.c); `ilf-mpi`, built with the CMake option
 * ILFKIT_MPI, is one rank of an MPI job (job_mpi.c, docs/cluster.md). The
 * relight and irradiance commands are written against this header alone, so
 * one piece of code serves both programs.
 *
 * Every function marked collective must be called by every rank, in the
 * same order. Rank 0 does what happens once: it reads standard input,
 * prints results and the summary, and creates and places output files.
 */
#ifndef ILF_JOB_H
#define ILF_JOB_H

#include <stddef.h>

#include "lfio/radmap.h"
#include "relight/engine.h"

/** @return this process's rank, 0 in a job of one. */
int job_rank(void);

/** @return the number of processes in the job, 1 in a job of one. */
int job_ranks(void);

/** @return the engine's view of the job (relight/engine.h), or NULL in a job of one. */
const rl_cluster *job_cluster(void);

/**
 * Collective: combines every rank's exit code after a step that can fail on
 * some ranks only. Errors reported by ranks other than 0 reach stderr only
 * when rank 0 succeeded (the same bad input is reported once, by rank 0).
 * @return the largest code: 0 when every rank succeeded.
 */
int job_agree(int code);

/** Collective: copies rank 0's size bytes at buf to every rank. @return 1, or 0 after reporting (sub names the command). */
int job_share(const char *sub, void *buf, size_t size);

/**
 * Ends the whole job from a step the other ranks cannot leave on their own
 * (they wait in an exchange): flushes this rank's errors and aborts every
 * rank with code, so that the job's exit status is code. In a job of one,
 * @return code.
 */
int job_fail(int code);

/** Collective: writes a radiance-map file as lfio_radmap_write_with() does, stored as opt says; in a job of
 * several ranks through lfio_radmap_write_rows_mpi() (lfio/radmap_mpi.h), every rank holding every patch's
 * cells: in format 2 each rank asks rows for the cells of its own chunks of the file, slices of at most
 * LFIO_RADMAP_ROWS_MAX; in format 1 for whole patches (count unbounded).
 * @return as lfio_radmap_write_with(), the same on every rank. */
lfio_status job_radmap_write(const char *path, const char *creator, const char *scene, size_t count,
                             lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                             const lfio_radmap_write_options *opt);

/** @return 1 if radiance.h5 may be written on a thread of its own while the engine runs (one process: no
 * MPI call leaves the main thread), else 0. */
int job_write_beside(void);

/** @return the worker threads a rank uses when neither the scene nor --threads sets them: every core,
 * shared evenly by the ranks on this machine. */
unsigned job_threads_per_rank(void);

/** One exchange of pass results between the ranks. */
typedef struct job_exchange {
    double wait_seconds; /**< the longest any rank waited for the slowest to finish the pass */
    double move_seconds; /**< moving the data, on this rank */
    unsigned long long bytes; /**< gathered onto each rank */
    unsigned long long tiles_claimed; /**< tiles this rank claimed in the pass (0: tiles dealt up front) */
} job_exchange;

/** @return the exchanges so far (at most 64 are kept), in order, in *log; 0 in a job of one. */
size_t job_exchange_log(const job_exchange **log);

#endif /* ILF_JOB_H */
