/*
 * commands.h - the subcommands of `ilf`. Each lives in its own cmd_*.c file
 * and has the shape of main: it receives argv with argv[0] = its own name
 * and returns an exit code from enum ilf_exit (cli.h). None of them exits.
 */
#ifndef ILF_COMMANDS_H
#define ILF_COMMANDS_H

int ilf_cmd_synth(int argc, char **argv);
int ilf_cmd_info(int argc, char **argv);
int ilf_cmd_verify(int argc, char **argv);
int ilf_cmd_slice(int argc, char **argv);
int ilf_cmd_relight(int argc, char **argv);
int ilf_cmd_irradiance(int argc, char **argv);

#endif /* ILF_COMMANDS_H */
