/*
 * cmd_verify.c - `ilf verify FILE...`: checks each file completely with
 * lfio_verify() and prints one line per file, "FILE: ok" or
 * "FILE: <first problem> (N problems)". stderr gets a settings line (how many
 * files, how many bytes) and a progress bar weighted by the files' sizes (the
 * work of a verification is reading every byte), neither with --quiet.
 *
 * Invariants: every file is checked even after a failure, so one run reports
 * on all of them; the exit code is 0 only when every file is valid, and 2
 * (bad input) otherwise. Results go to stdout, usage errors to stderr.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "lfio/lightfield.h"
#include "radmap_cli.h"

static const cli_option verify_options[] = {
    {"quiet", 'q', NULL, "print only the files that fail; no settings line or progress bar"},
};

static const cli_usage verify_usage = {
    "verify",
    "[--quiet] FILE...",
    "Checks each light field file completely: format, attributes and shapes, every\n"
    "checksum (by reading all data), the stored directions, solid angles and mask.\n"
    "A radiance-map file (radiance.h5 of 'ilf relight') is checked as lfio reads it:\n"
    "format, shapes, every checksum and value.\n"
    "Prints \"FILE: ok\" or \"FILE: <first problem> (N problems)\" for each file and\n"
    "exits 0 when all are valid, 2 when one is not, 1 when one could not be checked\n"
    "for want of memory.",
    "ilf verify data/beams_lightfield.h5 out/beams/radiance.h5",
};

/* Checks a file lfio_verify() refused as no light field as a radiance map, read whole (every checksum and value).
 * A file that is neither keeps the light field's report. @return LFIO_OK if it is a valid radiance map, else the
 * status, with *report's first problem the one to print. */
static lfio_status verify_radmap(const char *path, lfio_verify_report *report)
{
    char lf_msg[sizeof report->first];
    snprintf(lf_msg, sizeof lf_msg, "%s", report->first[0] != '\0' ? report->first : lfio_errmsg());
    lfio_radmap *map = NULL;
    lfio_status st = ilf_radmap_try(path, lf_msg, &map, report->first, sizeof report->first);
    lfio_radmap_destroy(map);
    if (st != LFIO_OK && st != LFIO_ERR_FORMAT)
        report->problems = 1;
    return st;
}

/* Verifies one file and prints its line, clearing bar's line first. @return LFIO_OK if the file is valid, else
 * lfio's status. */
static lfio_status verify_one(const char *path, int quiet, cli_progress *bar)
{
    lfio_verify_report report = {0};
    lfio_status status = lfio_verify(path, &report);
    if (status == LFIO_ERR_FORMAT)
        status = verify_radmap(path, &report);
    cli_progress_clear(bar);
    if (status == LFIO_OK) {
        if (!quiet)
            printf("%s: ok\n", path);
        return LFIO_OK;
    }
    char line[1024];
    /* A file that cannot be opened at all may leave the report empty. HDF5's
     * messages can span lines; the output keeps one line per file. */
    const char *problem = cli_one_line(report.first[0] != '\0' ? report.first : lfio_errmsg(), line, sizeof line);
    if (problem[0] == '\0')
        problem = lfio_status_name(status);
    /* The line starts with the path already; do not repeat it when lfio's message does. */
    size_t len = strlen(path);
    if (strncmp(problem, path, len) == 0 && strncmp(problem + len, ": ", 2) == 0)
        problem += len + 2;
    unsigned problems = report.problems > 0 ? (unsigned)report.problems : 1u;
    printf("%s: %s (%u problem%s)\n", path, problem, problems, problems == 1 ? "" : "s");
    return status;
}

int ilf_cmd_verify(int argc, char **argv)
{
    cli_parser parser;
    cli_parser_init(&parser, &verify_usage, verify_options, sizeof verify_options / sizeof verify_options[0],
                    argc, argv);
    /* Options may follow file names, so gather the names first. */
    const char **files = calloc((size_t)argc, sizeof *files);
    if (files == NULL) {
        cli_error("verify", "out of memory");
        return ILF_EXIT_FAILED;
    }
    size_t file_count = 0;
    int quiet = 0, code = -1;
    const char *value;
    for (int opt; code < 0 && (opt = cli_next(&parser, &value)) != CLI_DONE;) {
        if (opt == CLI_POSITIONAL)
            files[file_count++] = value;
        else if (opt == CLI_HELP)
            code = ILF_EXIT_OK;
        else if (opt == CLI_BAD)
            code = ILF_EXIT_USAGE;
        else
            quiet = 1;
    }
    if (code < 0 && file_count == 0) {
        cli_error("verify", "no file given (see 'ilf verify --help')");
        code = ILF_EXIT_USAGE;
    }
    if (code < 0) {
        /* Running out of memory says nothing about the file: that run failed (exit 1). */
        int all_valid = 1, unchecked = 0;
        uint64_t bytes = 0;
        for (size_t k = 0; k < file_count; k++)
            bytes += cli_file_size(files[k]) > 0 ? (uint64_t)cli_file_size(files[k]) : 0u;
        char size[32];
        cli_set_quiet(quiet);
        cli_settings("verify", "%zu file%s, %s, every byte read and checked", file_count, file_count == 1 ? "" : "s",
                     cli_format_bytes((long long)bytes, size, sizeof size));
        cli_progress bar;
        cli_progress_start(&bar, "verify", bytes);
        for (size_t k = 0; k < file_count; k++) {
            long long done = cli_file_size(files[k]);
            lfio_status st = verify_one(files[k], quiet, &bar);
            fflush(stdout);
            cli_progress_add(&bar, done > 0 ? (uint64_t)done : 0u);
            all_valid &= st == LFIO_OK;
            unchecked |= st == LFIO_ERR_NOMEM;
        }
        cli_progress_finish(&bar);
        code = unchecked ? ILF_EXIT_FAILED : all_valid ? ILF_EXIT_OK : ILF_EXIT_USAGE;
    }
    free(files);
    return code;
}
