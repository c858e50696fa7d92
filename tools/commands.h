/*
 * commands.h - the subcommands of `ilf`. Each lives in its own cmd_*.c file
 * and has the shape of main: it receives argv with argv[0] = its own name
 * and returns an exit code from enum ilf_exit (cli.h). None of them exits.
 */
#ifndef ILF_COMMANDS_H
#define ILF_COMMANDS_H

#include <stdint.h>

int ilf_cmd_synth(int argc, char **argv);
int ilf_cmd_info(int argc, char **argv);
int ilf_cmd_verify(int argc, char **argv);
int ilf_cmd_slice(int argc, char **argv);
int ilf_cmd_relight(int argc, char **argv);
int ilf_cmd_irradiance(int argc, char **argv);
int ilf_cmd_capture(int argc, char **argv);
int ilf_cmd_render_probes(int argc, char **argv);
int ilf_cmd_reproject(int argc, char **argv);
int ilf_cmd_export(int argc, char **argv);
int ilf_cmd_view(int argc, char **argv);

/* Shared by the capture commands (capture, render-probes, reproject); defined in cmd_capture.c. */

/** Reports the capture library's last message for a failed call with status
 * (a cap_status) and maps it to an exit code: bad input or argument 2, else 1. */
int ilf_capture_failure(const char *sub, int status);

/** A cap_progress_fn whose user is a started cli_progress: advances it to done. */
void ilf_capture_progress(void *bar, uint64_t done, uint64_t total);

#endif /* ILF_COMMANDS_H */
