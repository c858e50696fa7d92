/*
 * job_mpi.h - starting and ending the MPI rank that `ilf-mpi` is (job_mpi.c);
 * between the two, job.h describes the job.
 */
#ifndef ILF_JOB_MPI_H
#define ILF_JOB_MPI_H

/** Initialises MPI (serialised threads: the engine's workers claim tiles) over MPI_COMM_WORLD, and the count of
 * claims of a job of several ranks. @return 1, or 0 if MPI could not start. */
int job_mpi_start(int *argc, char ***argv);

/** Collective: agrees on the job's exit code (the largest), prints what this rank still holds and
 * finalises MPI. @return the job's exit code. */
int job_mpi_finish(int code);

#endif /* ILF_JOB_MPI_H */
