/*
 * ilf_mpi.c - entry point of `ilf-mpi`, the MPI build of the two commands
 * whose work divides over processes (docs/cluster.md):
 *
 *   mpirun -n K ilf-mpi relight SCENE -o DIR
 *   mpirun -n K ilf-mpi irradiance SCENE --points FILE
 *
 * Each rank runs the same command code as `ilf` (cmd_relight.c,
 * cmd_irradiance.c) against job_mpi.c. Every rank returns the job's agreed
 * exit code, so mpirun's status is the command's.
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "job.h"
#include "job_mpi.h"
#include "lfio/lfio.h"

static void print_help(FILE *out)
{
    fprintf(out,
            "Usage: mpirun -n K ilf-mpi relight SCENE -o DIR [OPTIONS]\n"
            "       mpirun -n K ilf-mpi irradiance SCENE --points FILE [OPTIONS]\n"
            "       ilf-mpi --help | --version\n\n"
            "The relight and irradiance commands of ilf (see 'ilf relight --help' and\n"
            "'ilf irradiance --help'), with their work divided over the K ranks of an MPI\n"
            "job and over threads within each rank. Every rank reads the scene; rank 0\n"
            "reads the points and prints the results; radiance.h5 is written by all ranks\n"
            "with parallel HDF5. The results are bit for bit those of one process.\n"
            "Without --threads, each rank uses its share of the cores of its machine.\n\n"
            "Exit status as ilf's: 0 success, 1 failure while running, 2 bad usage or input;\n"
            "when one rank fails, the job ends with its status and message.\n");
}

/* @return the command's exit code, the same on every rank. */
static int run(int argc, char **argv)
{
    if (argc < 2) {
        if (job_rank() == 0)
            print_help(stderr);
        return ILF_EXIT_USAGE;
    }
    const char *first = argv[1];
    if (strcmp(first, "--help") == 0 || strcmp(first, "-h") == 0 || strcmp(first, "help") == 0) {
        if (job_rank() == 0)
            print_help(stdout);
        return ILF_EXIT_OK;
    }
    if (strcmp(first, "--version") == 0 || strcmp(first, "-V") == 0) {
        if (job_rank() == 0)
            printf("ilf-mpi (ilfkit) %s, lfio %s\n", ILFKIT_VERSION, lfio_version());
        return ILF_EXIT_OK;
    }
    if (strcmp(first, "relight") == 0)
        return ilf_cmd_relight(argc - 1, argv + 1);
    if (strcmp(first, "irradiance") == 0)
        return ilf_cmd_irradiance(argc - 1, argv + 1);
    if (job_rank() == 0)
        fprintf(stderr, "ilf-mpi: unknown %s '%s': ilf-mpi runs relight and irradiance (see 'ilf-mpi --help')\n",
                first[0] == '-' ? "option" : "command", first);
    return ILF_EXIT_USAGE;
}

int main(int argc, char **argv)
{
    if (!job_mpi_start(&argc, &argv)) {
        fprintf(stderr, "ilf-mpi: MPI could not start\n");
        return ILF_EXIT_FAILED;
    }
    return job_mpi_finish(run(argc, argv));
}
