/*
 * ilf.c - entry point of the `ilf` command: handles --help and --version and
 * hands the remaining arguments to a subcommand from the table below.
 *
 * Invariants: the table is the single list of subcommands (help prints from
 * it, so a subcommand appears in --help exactly when it exists); main is the
 * only place the process exits, by returning the subcommand's exit code;
 * `ilf bench` is the program ilf-bench, found in the folder ilf itself runs
 * from (built and installed side by side), which replaces this process with
 * the same arguments: ilf does not link the benchmark.
 */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "lfio/lfio.h"

typedef struct ilf_command {
    const char *name;
    const char *summary;
    int (*run)(int argc, char **argv); /* the command in this program, or NULL: */
    const char *program;                /* the program beside ilf that is the command (run_beside()) */
} ilf_command;

/* Longest path of ilf's own executable that run_beside() handles. */
#define SELF_PATH_BYTES 4096

/* Replaces this process with program, found in the folder of ilf's own executable (/proc/self/exe), as
 * `program ARGS` for argv = {command, ARGS...}. @return ILF_EXIT_FAILED after reporting, when it cannot. */
static int run_beside(const char *command, const char *program, char **argv)
{
    char path[SELF_PATH_BYTES];
    ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
    if (n > 0)
        path[n] = '\0';
    char *slash = n > 0 ? strrchr(path, '/') : NULL;
    size_t folder = slash ? (size_t)(slash - path) + 1 : 0;
    if (slash == NULL || folder + strlen(program) >= sizeof path) {
        cli_error(command, "cannot find the folder of ilf's own executable%s%s",
                  n < 0 ? ": " : "", n < 0 ? strerror(errno) : "");
        return ILF_EXIT_FAILED;
    }
    strcpy(path + folder, program);
    argv[0] = path;
    fflush(NULL);
    execv(path, argv);
    cli_error(command, "cannot run %s: %s (the %s program is installed beside ilf)", path,
              strerror(errno), program);
    return ILF_EXIT_FAILED;
}

static const ilf_command commands[] = {
    {"synth", "write a synthetic light field (constant, radial or spot emitters)", ilf_cmd_synth, NULL},
    {"info", "describe a light field or radiance-map file: headers; --stats for the data", ilf_cmd_info, NULL},
    {"verify", "check light field and radiance-map files completely: format, checksums, values", ilf_cmd_verify, NULL},
    {"slice", "write one position (or its environment map) or one direction of a slab as an image", ilf_cmd_slice, NULL},
    {"relight", "relight a scene: radiance maps, statistics and the camera's view", ilf_cmd_relight, NULL},
    {"export", "export a radiance map's relit surfaces to glTF (.glb), PLY or CSV", ilf_cmd_export, NULL},
    {"view", "render a camera's view of a radiance map without relighting", ilf_cmd_view, NULL},
    {"irradiance", "print the irradiance of a scene at given points (like rtrace -I)", ilf_cmd_irradiance, NULL},
    {"capture", "turn light probe images (a manifest) into a light field file", ilf_cmd_capture, NULL},
    {"render-probes", "render the light probes a scene gives on a grid of a plane, and their manifest",
     ilf_cmd_render_probes, NULL},
    {"reproject", "depth correction: move a captured light field onto proxy rectangles", ilf_cmd_reproject, NULL},
    {"bench", "measure speed against accuracy: sweeps, references, plots, ray ceiling", NULL, "ilf-bench"},
};

static const size_t command_count = sizeof commands / sizeof commands[0];

static void print_help(FILE *out)
{
    fprintf(out,
            "Usage: ilf COMMAND [OPTIONS] [ARGS]\n"
            "       ilf --help | --version\n\n"
            "Tools for incident light fields stored as sphere-plane slabs in HDF5 files.\n\n"
            "Commands:\n");
    /* The column is as wide as the longest name, so no name runs into its summary. */
    int width = 0;
    for (size_t k = 0; k < command_count; k++)
        if ((int)strlen(commands[k].name) > width)
            width = (int)strlen(commands[k].name);
    for (size_t k = 0; k < command_count; k++)
        fprintf(out, "  %-*s  %s\n", width, commands[k].name, commands[k].summary);
    fprintf(out,
            "\nRun 'ilf COMMAND --help' for a command's options and examples.\n\n"
            "Exit status: 0 success; 1 failure while running (e.g. an output cannot be\n"
            "written); 2 bad usage or bad input (unknown option, invalid value,\n"
            "missing or corrupt input file).\n\n"
            "Example:\n"
            "  ilf synth --kind radial -o radial.h5 && ilf info radial.h5\n");
}

static const ilf_command *find_command(const char *name)
{
    for (size_t k = 0; k < command_count; k++)
        if (strcmp(commands[k].name, name) == 0)
            return &commands[k];
    return NULL;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        print_help(stderr);
        return ILF_EXIT_USAGE;
    }
    const char *first = argv[1];
    if (strcmp(first, "--help") == 0 || strcmp(first, "-h") == 0 || strcmp(first, "help") == 0) {
        print_help(stdout);
        return ILF_EXIT_OK;
    }
    if (strcmp(first, "--version") == 0 || strcmp(first, "-V") == 0) {
        printf("ilf (ilfkit) %s, lfio %s\n", ILFKIT_VERSION, lfio_version());
        return ILF_EXIT_OK;
    }
    const ilf_command *command = find_command(first);
    if (command == NULL) {
        fprintf(stderr, "ilf: unknown %s '%s' (see 'ilf --help')\n", first[0] == '-' ? "option" : "command",
                first);
        return ILF_EXIT_USAGE;
    }
    if (command->program != NULL) /* before any handler or thread of ours: the program installs its own */
        return run_beside(first, command->program, argv + 1);
    return cli_program_run(first, command->run, argc - 1, argv + 1);
}
