/*
 * ilf.c - entry point of the `ilf` command: handles --help and --version and
 * hands the remaining arguments to a subcommand from the table below.
 *
 * Invariants: the table is the single list of subcommands (help prints from
 * it, so a subcommand appears in --help exactly when it exists); main is the
 * only place the process exits, by returning the subcommand's exit code.
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "lfio/lfio.h"

#ifdef __SANITIZE_ADDRESS__
#include <sanitizer/lsan_interface.h>
#endif

typedef struct ilf_command {
    const char *name;
    const char *summary;
    int (*run)(int argc, char **argv);
} ilf_command;

static const ilf_command commands[] = {
    {"synth", "write a synthetic light field (constant, radial or spot emitters)", ilf_cmd_synth},
    {"info", "describe a light field or radiance-map file: headers; --stats for the data", ilf_cmd_info},
    {"verify", "check light field and radiance-map files completely: format, checksums, values", ilf_cmd_verify},
    {"slice", "write one position (or its environment map) or one direction of a slab as an image", ilf_cmd_slice},
    {"relight", "relight a scene: radiance maps, statistics and the camera's view", ilf_cmd_relight},
    {"export", "export a radiance map's relit surfaces to glTF (.glb), PLY or CSV", ilf_cmd_export},
    {"view", "render a camera's view of a radiance map without relighting", ilf_cmd_view},
    {"irradiance", "print the irradiance of a scene at given points (like rtrace -I)", ilf_cmd_irradiance},
    {"capture", "turn light probe images (a manifest) into a light field file", ilf_cmd_capture},
    {"render-probes", "render the light probes a scene gives on a grid of a plane, and their manifest",
     ilf_cmd_render_probes},
    {"reproject", "depth correction: move a captured light field onto proxy rectangles", ilf_cmd_reproject},
    {"bench", "measure speed against accuracy: sweeps, references, plots, ray ceiling", ilf_cmd_bench},
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
    cli_interrupts_install(); /* an interrupted command says so, and what it kept (cli.h) */
    /* results on stdout are outputs too: one that cannot be written (a full disk, /dev/full) fails the run */
    int code = cli_stdout_finish(first, command->run(argc - 1, argv + 1));
#ifdef __SANITIZE_ADDRESS__
    /* Sanitizer builds look for leaks here, while the libraries' thread pools
     * are idle: at exit their static destructors stop those threads while
     * LeakSanitizer walks them, which crashed its tracer in CI. */
    __lsan_do_leak_check();
#endif
    return code;
}
