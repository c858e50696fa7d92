/*
 * ilf_bench.c - entry point of ilf-bench, the program behind `ilf bench`
 * (docs/bench.md): ilf runs it from its own folder with the command's
 * arguments, so that ilf itself does not link the benchmark; it can also be
 * run by its own name.
 *
 * Invariants: it runs the one command as ilf runs its own
 * (cli_program_run()), with argv[0] "bench", so that what the command
 * records and prints is the same by either name ("ilf bench: ..." in
 * messages, `ilf bench ARGS` as the command in bench.json).
 */
#include "bench.h"
#include "cli.h"

int main(int argc, char **argv)
{
    static char name[] = "bench";
    argv[0] = name;
    return cli_program_run(name, ilf_cmd_bench, argc, argv);
}
