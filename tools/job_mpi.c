/*
 * job_mpi.c - one rank of an MPI job (job.h), for `ilf-mpi`: the engine's
 * exchanges as MPI collectives over MPI_COMM_WORLD, its tiles claimed from a
 * count that rank 0 holds in an MPI window (one-sided MPI_Fetch_and_op, so a
 * rank takes the next tile as soon as it is free), the radiance-map file
 * through lfio's parallel HDF5 writer, and failures that end the whole job.
 * The only file of tools/ that includes mpi.h.
 *
 * The count of claims: two slots on rank 0, pass after pass in turn. A rank
 * starting a pass's claims has been through the exchange that ended the
 * previous pass, which every rank entered only once done claiming; so when
 * rank 0 starts a pass and resets the other slot, no one is using it, and no
 * one uses it again before the exchange that ends this pass, which rank 0
 * enters after the reset.
 *
 * Invariants: ranks other than 0 hold what they write to stderr until a
 * collective step says whether rank 0 failed too (then rank 0's message
 * stands for all, since every rank read the same input) or not (then theirs
 * is printed); whatever they still hold is printed before the job is
 * aborted or the rank ends. Each exchange records its bytes and its time,
 * split into waiting for the slowest rank and moving the data.
 */
#define _GNU_SOURCE /* open_memstream is POSIX 2008, but glibc lets stderr be assigned */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <mpi.h>

#include "cli.h"
#include "job.h"
#include "job_mpi.h"
#include "lfio/radmap_mpi.h"

/* one exchange a pass, two for a bounce pass that gathers cells on their own: 64 bounces at most */
#define MAX_EXCHANGES (2 * 64 + 1)

static MPI_Comm job_comm = MPI_COMM_NULL;
static int this_rank = 0, rank_count = 1, ranks_on_node = 1;
static FILE *real_stderr = NULL; /* ranks > 0: stderr while held */
static char *held = NULL;        /* what a rank > 0 wrote to stderr and has not printed yet */
static size_t held_size = 0;
static rl_cluster cluster;
static job_exchange exchanges[MAX_EXCHANGES];
static size_t exchange_count = 0;
static MPI_Win claims = MPI_WIN_NULL; /* two uint64_t slots on rank 0: the count of claims, pass by pass */
static uint64_t claim_round = 0;      /* passes whose tiles this rank has claimed */
static int claiming = 0;              /* this rank claimed tiles since the last exchange */
static double claim_wait = 0.0;       /* waited for the others after claiming, not yet logged */
static uint64_t claimed = 0;          /* tiles this rank claimed since the last exchange logged */

/* @return monotonic time in seconds. */
static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* ------------------------------------------------------------- stderr */

/* Starts holding stderr (ranks > 0). */
static void hold_stderr(void)
{
    FILE *f = open_memstream(&held, &held_size);
    if (f != NULL) {
        real_stderr = stderr;
        stderr = f;
    }
}

/* Ends holding: prints what was held (print) or drops it, then holds again. */
static void release_stderr(int print)
{
    if (real_stderr == NULL)
        return;
    fclose(stderr);
    stderr = real_stderr;
    real_stderr = NULL;
    if (print && held_size > 0)
        fwrite(held, 1, held_size, stderr), fflush(stderr);
    free(held);
    held = NULL;
    held_size = 0;
}

/* --------------------------------------------------------- the engine's calls */

/* Waits at a barrier for every rank to reach it. @return 0 and the seconds waited in *waited, or -1. */
static int timed_barrier(double *waited)
{
    double t0 = seconds();
    int ok = MPI_Barrier(job_comm) == MPI_SUCCESS;
    *waited = seconds() - t0;
    return ok ? 0 : -1;
}

/* rl_cluster.allgather over the job: MPI_Allgatherv in place, timed. */
static int allgather(void *user, double *values, const uint64_t *counts, const uint64_t *offsets)
{
    (void)user;
    int *n = malloc(rank_count * sizeof *n), *at = malloc(rank_count * sizeof *at);
    int ok = n && at;
    uint64_t bytes = 0;
    for (int r = 0; ok && r < rank_count; r++) {
        /* MPI counts are ints: 2^31 doubles (16 GiB) per rank and in all */
        ok = counts[r] <= INT32_MAX && offsets[r] <= INT32_MAX - counts[r];
        if (ok)
            n[r] = (int)counts[r], at[r] = (int)offsets[r], bytes += counts[r] * sizeof *values;
    }
    /* The barrier separates waiting for the slowest rank (load imbalance) from moving the data;
     * the longest wait of any rank is what the imbalance cost. */
    double waited = 0.0;
    ok = ok && timed_barrier(&waited) == 0;
    waited += claim_wait;
    claim_wait = 0.0;
    double t1 = seconds(), longest = waited;
    ok = ok && MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, values, n, at, MPI_DOUBLE, job_comm) == MPI_SUCCESS;
    double moved = seconds() - t1;
    ok = ok && MPI_Allreduce(&waited, &longest, 1, MPI_DOUBLE, MPI_MAX, job_comm) == MPI_SUCCESS;
    if (ok && exchange_count < MAX_EXCHANGES)
        exchanges[exchange_count++] = (job_exchange){longest, moved, (unsigned long long)bytes, claimed};
    claimed = 0;
    free(n);
    free(at);
    return ok ? 0 : -1;
}

/* rl_cluster.sum over the job. The first exchange after a pass's claims is where a rank waits for the
 * slowest: timed, and logged with the next allgather. */
static int sum(void *user, double *values, size_t n)
{
    (void)user;
    double waited = 0.0;
    if (claiming && timed_barrier(&waited) != 0)
        return -1;
    claiming = 0;
    claim_wait += waited;
    return n <= INT32_MAX && MPI_Allreduce(MPI_IN_PLACE, values, (int)n, MPI_DOUBLE, MPI_SUM, job_comm) == MPI_SUCCESS
               ? 0
               : -1;
}

/* rl_cluster.next: the next place of the pass's count on rank 0 (the engine's workers call it one at a
 * time). A failed MPI call claims nothing more: the pass then misses tiles, which the exchange of
 * owners catches. @return the place, or n when none is left. */
static uint64_t next(void *user, uint64_t n)
{
    (void)user;
    uint64_t one = 1, zero = 0, got = n, old = 0;
    if (!claiming) { /* this rank's first claim of a pass */
        claiming = 1;
        claim_round++;
        if (this_rank == 0 &&
            (MPI_Fetch_and_op(&zero, &old, MPI_UINT64_T, 0, (claim_round + 1) % 2, MPI_REPLACE, claims) !=
                 MPI_SUCCESS ||
             MPI_Win_flush(0, claims) != MPI_SUCCESS))
            return n;
    }
    if (MPI_Fetch_and_op(&one, &got, MPI_UINT64_T, 0, claim_round % 2, MPI_SUM, claims) != MPI_SUCCESS ||
        MPI_Win_flush(0, claims) != MPI_SUCCESS)
        return n;
    claimed += got < n;
    return got < n ? got : n;
}

/* Opens the count of claims (collective). @return 1, or 0 when it cannot be had (tiles are then dealt
 * up front). */
static int claims_open(void)
{
    uint64_t *slots = NULL;
    MPI_Aint size = this_rank == 0 ? 2 * sizeof *slots : 0;
    if (MPI_Win_allocate(size, sizeof *slots, MPI_INFO_NULL, job_comm, &slots, &claims) != MPI_SUCCESS)
        return 0;
    if (this_rank == 0)
        slots[0] = slots[1] = 0;
    /* the slots are set before any rank claims, and each rank holds the window open from now on */
    if (MPI_Barrier(job_comm) != MPI_SUCCESS || MPI_Win_lock_all(MPI_MODE_NOCHECK, claims) != MPI_SUCCESS) {
        MPI_Win_free(&claims);
        return 0;
    }
    return 1;
}

/* ------------------------------------------------------------------ job.h */

int job_rank(void)
{
    return this_rank;
}

int job_ranks(void)
{
    return rank_count;
}

const rl_cluster *job_cluster(void)
{
    return rank_count > 1 ? &cluster : NULL;
}

int job_agree(int code)
{
    int codes[2] = {code, this_rank == 0 ? code : 0}, all[2] = {code, code};
    if (MPI_Allreduce(codes, all, 2, MPI_INT, MPI_MAX, job_comm) != MPI_SUCCESS)
        return job_fail(ILF_EXIT_FAILED);
    /* all[1] is rank 0's code: when it failed, its message stands for the same failure here */
    release_stderr(all[1] == 0);
    if (this_rank > 0)
        hold_stderr();
    return all[0];
}

int job_share(const char *sub, void *buf, size_t size)
{
    if (size > INT32_MAX || MPI_Bcast(buf, (int)size, MPI_BYTE, 0, job_comm) != MPI_SUCCESS) {
        cli_error(sub, "cannot share %zu bytes between the ranks", size);
        return 0;
    }
    return 1;
}

int job_fail(int code)
{
    release_stderr(1);
    fflush(stdout);
    MPI_Abort(job_comm, code);
    return code; /* not reached */
}

/* Every rank holds the whole solution once the engine returns (relight/engine.h), so each takes the cells of
 * its own chunks of the file from it, with no trade between the ranks. */
lfio_status job_radmap_write(const char *path, const char *creator, const char *scene, size_t count,
                             lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                             const lfio_radmap_write_options *opt)
{
    return lfio_radmap_write_rows_mpi(path, creator, scene, count, describe, rows, user, opt, job_comm);
}

/* --------------------------------------------------------------- job_mpi.h */

int job_mpi_start(int *argc, char ***argv)
{
    int provided = 0;
    /* The engine's workers claim tiles (one at a time); every other MPI call is the calling thread's. */
    if (MPI_Init_thread(argc, argv, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS)
        return 0;
    job_comm = MPI_COMM_WORLD;
    MPI_Comm_rank(job_comm, &this_rank);
    MPI_Comm_size(job_comm, &rank_count);
    MPI_Comm node;
    if (MPI_Comm_split_type(job_comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) == MPI_SUCCESS) {
        MPI_Comm_size(node, &ranks_on_node);
        MPI_Comm_free(&node);
    }
    /* without serialised threads (or a window), the tiles are dealt up front */
    int claim = rank_count > 1 && provided >= MPI_THREAD_SERIALIZED;
    int agreed = 0;
    MPI_Allreduce(&claim, &agreed, 1, MPI_INT, MPI_MIN, job_comm);
    claim = agreed && claims_open();
    cluster = (rl_cluster){(uint32_t)this_rank, (uint32_t)rank_count, allgather, sum, claim ? next : NULL, NULL};
    static char suffix[64];
    snprintf(suffix, sizeof suffix, " (rank %d of %d)", this_rank, rank_count);
    cli_set_identity("ilf-mpi", rank_count > 1 ? suffix : "");
    /* Rank 0 prints what the job prints (help, results, the summary). */
    if (this_rank > 0 && freopen("/dev/null", "w", stdout) == NULL)
        fclose(stdout);
    if (this_rank > 0)
        hold_stderr();
    return 1;
}

int job_mpi_finish(int code)
{
    /* A usage error every rank met is reported once, by rank 0. */
    code = job_agree(code);
    release_stderr(1);
    if (claims != MPI_WIN_NULL) {
        MPI_Win_unlock_all(claims);
        MPI_Win_free(&claims);
    }
    MPI_Finalize();
    return code;
}

/* The engine's workers claim tiles over MPI while it runs and the collective write makes MPI calls:
 * a writer beside the engine would make them from two threads at once. */
int job_write_beside(void)
{
    return 0;
}

unsigned job_threads_per_rank(void)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    long each = (cores > 0 ? cores : 1) / (ranks_on_node > 0 ? ranks_on_node : 1);
    return each > 0 ? (unsigned)each : 1u;
}

size_t job_exchange_log(const job_exchange **log)
{
    *log = exchanges;
    return exchange_count;
}
