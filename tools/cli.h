/*
 * cli.h - what every `ilf` subcommand shares: exit codes, error reporting,
 * a table-driven option parser that also prints --help, strict parsers for
 * numbers and number lists, slab selection, and a progress bar.
 *
 * Invariants:
 *   - Errors go to stderr as "ilf SUB: <what was wrong>"; results go to stdout.
 *   - Every parser either accepts the whole text or reports why it did not;
 *     it never accepts a prefix ("3x" is not 3) or a non-finite number.
 *   - The progress bar draws only when stderr is a terminal, so scripts and
 *     tests see exactly the same stderr with or without it.
 */
#ifndef ILF_CLI_H
#define ILF_CLI_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "ilf/vec.h"
#include "lfio/lightfield.h"

/* Set by the build (CMake's PROJECT_VERSION); the fallback keeps other builds compiling. */
#ifndef ILFKIT_VERSION
#define ILFKIT_VERSION "unknown"
#endif

/** Exit codes of `ilf`, shared by every subcommand. */
enum ilf_exit {
    ILF_EXIT_OK = 0,     /**< success */
    ILF_EXIT_FAILED = 1, /**< a failure while running, such as an output that cannot be written */
    ILF_EXIT_USAGE = 2   /**< bad usage or bad input: unknown option, invalid value, unreadable file */
};

/** Names the messages' sender from now on: "PROGRAM SUB SUFFIX: ..." (default "ilf", no suffix;
 * ilf-mpi gives its rank). program must outlive every message; suffix is copied (up to 63 bytes). */
void cli_set_identity(const char *program, const char *suffix);

/** Prints "ilf SUB: <message>" (cli_set_identity()) and a newline to stderr. */
void cli_error(const char *sub, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* ------------------------------------------------------------- warnings */

/** Silences (quiet nonzero) or restores the settings line (cli_settings()), warnings (cli_warn()) and the
 * progress bar; warnings are still kept for stats.json. Call from the main thread before any work. */
void cli_set_quiet(int quiet);

/**
 * Prints "ilf: warning: <message>" to stderr unless quiet, and keeps the
 * message (up to 32 of them, 639 bytes each) for cli_warning(). Main thread only.
 */
void cli_warn(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

/** @return the number of warnings kept so far. */
size_t cli_warning_count(void);

/** @return warning k (< cli_warning_count()), without the "ilf: warning: " prefix. */
const char *cli_warning(size_t k);

/**
 * Prints what a long command is about to do, "ilf SUB: <settings>", to stderr
 * unless quiet: method, samples, bounces, threads, so that no setting taken
 * silently from a file decides how long a run takes.
 */
void cli_settings(const char *sub, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** Copies text into buf (size bytes) as one line, newlines turned to spaces. @return buf. */
const char *cli_one_line(const char *text, char *buf, size_t size);

/** Whether a file the failing call worked on was an input or an output. */
typedef enum cli_role { CLI_INPUT, CLI_OUTPUT } cli_role;

/**
 * Reports a failed lfio call on path with lfio_errmsg() and maps its status
 * to an exit code: every problem with an input is bad input (2); a failure to
 * produce an output, or running out of memory, is a failure while running (1).
 */
int cli_lfio_failure(const char *sub, lfio_status status, cli_role role, const char *path);

/** As cli_lfio_failure(), with message msg: lfio_errmsg() as another thread saw it. */
int cli_lfio_failure_msg(const char *sub, lfio_status status, cli_role role, const char *path, const char *msg);

/* ------------------------------------------------------------- options */

/** One accepted option; a table of these drives parsing and --help. */
typedef struct cli_option {
    const char *name;       /**< long name without "--", e.g. "grid" */
    char short_name;        /**< single-letter alias, or 0 */
    const char *value_name; /**< placeholder for the value ("NUxNV"); NULL for a flag */
    const char *help;       /**< one line of description, including the default */
} cli_option;

/** A subcommand's help text around its option table. */
typedef struct cli_usage {
    const char *sub;      /**< subcommand name */
    const char *synopsis; /**< the part after "ilf SUB " on the usage line */
    const char *summary;  /**< one paragraph on what it does */
    const char *example;  /**< one or more example command lines, newline separated */
} cli_usage;

/** Walks a subcommand's arguments; see cli_next(). */
typedef struct cli_parser {
    const cli_usage *usage;
    const cli_option *options;
    size_t option_count;
    int argc;
    char **argv;
    int next;             /* index of the next argument to look at */
    int options_ended;    /* set after "--": everything left is positional */
    const char *current;  /* long name of the option last returned, for messages */
} cli_parser;

/** Results of cli_next() besides an option index. */
enum {
    CLI_POSITIONAL = -1, /**< *value is a positional argument */
    CLI_DONE = -2,       /**< no arguments left */
    CLI_HELP = -3,       /**< --help or -h was given; help has been printed to stdout */
    CLI_BAD = -4         /**< an unknown option or a missing value; already reported */
};

/** Starts parsing argv[1..argc-1] (argv[0] is the subcommand's name). */
void cli_parser_init(cli_parser *p, const cli_usage *usage, const cli_option *options,
                     size_t option_count, int argc, char **argv);

/**
 * Returns the index in the option table of the next option, with its value
 * in *value (from "--name VALUE", "--name=VALUE" or "-x VALUE"), or one of
 * the CLI_ codes above.
 */
int cli_next(cli_parser *p, const char **value);

/**
 * Applies option opt (an index in the option table, or CLI_POSITIONAL when
 * the subcommand takes no FILE) with its value to ctx.
 * @return 1, or 0 after reporting.
 */
typedef int (*cli_apply_fn)(const cli_parser *p, int opt, const char *value, void *ctx);

/**
 * Parses a subcommand's arguments: a positional one is its single FILE,
 * kept in *path (with path NULL, positional arguments go to apply as
 * CLI_POSITIONAL), and every option goes to apply with ctx.
 * @return -1 when every argument was taken; ILF_EXIT_OK after --help
 * (printed); ILF_EXIT_USAGE after a reported error.
 */
int cli_parse(const cli_usage *usage, const cli_option *options, size_t option_count, int argc, char **argv,
              const char **path, cli_apply_fn apply, void *ctx);

/** Prints the usage line, summary, option table and examples. */
void cli_print_help(FILE *out, const cli_usage *usage, const cli_option *options, size_t option_count);

/**
 * Stores the single FILE argument of a subcommand in *path.
 * @return 1; 0 after reporting when a file was already given.
 */
int cli_single_path(const char *sub, const char **path, const char *value);

/** Reports "ilf SUB: --OPT 'VALUE': <why>" for the option last returned. @return ILF_EXIT_USAGE. */
int cli_bad_value(const cli_parser *p, const char *value, const char *why);

/* ------------------------------------------------------------- numbers */

/*
 * Low-level parsers: 1 on success; 0 with a reason in why (why_size bytes)
 * on failure, outputs untouched.
 */

/** A finite decimal or scientific number, the whole text. */
int cli_parse_double(const char *text, double *out, char *why, size_t why_size);

/** Exactly count finite numbers separated by commas ("x,y,z"). */
int cli_parse_doubles(const char *text, double *out, size_t count, char *why, size_t why_size);

/** An unsigned decimal integer in [lo, hi], digits only. */
int cli_parse_u32(const char *text, uint32_t lo, uint32_t hi, uint32_t *out, char *why, size_t why_size);

/** Two unsigned integers in [lo, hi] separated by sep ("32x32", "3,4"). */
int cli_parse_u32_pair(const char *text, char sep, uint32_t lo, uint32_t hi, uint32_t out[2],
                       char *why, size_t why_size);

/*
 * Option-value parsers: the same, but they report a failure themselves
 * (through cli_bad_value) and return 0.
 */
int cli_value_double(const cli_parser *p, const char *text, double *out);
int cli_value_doubles(const cli_parser *p, const char *text, double *out, size_t count);
int cli_value_u32(const cli_parser *p, const char *text, uint32_t lo, uint32_t hi, uint32_t *out);
/* The one parser of every command's --threads: 0 (every processor) .. ILF_MAX_THREADS, the rule of
 * ilf_thread_count(), which resolves it. */
int cli_value_threads(const cli_parser *p, const char *text, uint32_t *out);
int cli_value_u32_pair(const cli_parser *p, const char *text, char sep, uint32_t lo, uint32_t hi,
                       uint32_t out[2]);

struct tone_fixed; /* tonemap.h */

/** Parses a display option's value into *f: --exposure EV (exposure nonzero), -100 .. 100, or --scale W, a
 * finite W > 0. Reports giving both. @return 1, or 0 after reporting. */
int cli_value_tone(const cli_parser *p, const char *text, int exposure, struct tone_fixed *f);

/* --------------------------------------------------------------- slabs */

/**
 * Resolves --slab NAME|INDEX against an open file: a string of digits is an
 * index, anything else a name. NULL selects slab 0.
 * @return 1 and *index; 0 after reporting that no such slab exists.
 */
int cli_select_slab(const char *sub, const char *path, const lfio_reader *r, const char *which,
                    size_t *index);

/**
 * Checks, before any work, that file output path may be written (ilf/file_kind.h): it names a regular file or
 * nothing (not a folder, a FIFO or a device node), in an existing folder this process may write. Reports the
 * problem when not. @return ILF_EXIT_OK; ILF_EXIT_USAGE when path names what must not be replaced;
 * ILF_EXIT_FAILED when its folder is missing or cannot be written (the system's reason).
 */
int cli_output_check(const char *sub, const char *path);

/**
 * As cli_output_check() for a folder of outputs: dir is a folder this process may write, or can be created
 * (its nearest existing ancestor is one), and each of the count names in it that exists is a regular file.
 */
int cli_output_folder_check(const char *sub, const char *dir, const char *const *names, size_t count);

/**
 * Flushes standard output, where results are printed: a failed write (a full disk, /dev/full) is a failed
 * output, reported with the system's reason. @return code, or ILF_EXIT_FAILED when code was ILF_EXIT_OK and
 * the flush failed.
 */
int cli_stdout_finish(const char *sub, int code);

/**
 * Runs command run(argc, argv) as a program's main does (ilf's for its commands, ilf-bench's for the
 * benchmark): with the interruption handlers installed (cli_interrupts_install()), standard output flushed
 * after (cli_stdout_finish()), and, in sanitizer builds, the leak check done while the thread pools are idle.
 * @return its exit code.
 */
int cli_program_run(const char *sub, int (*run)(int argc, char **argv), int argc, char **argv);

/** Size of a file in bytes, or -1 if it cannot be examined. */
long long cli_file_size(const char *path);

/** Formats a byte count for people ("12.6 MiB") into buf. @return buf. */
const char *cli_format_bytes(long long bytes, char *buf, size_t size);

/** Number of processors to use by default (at least 1). */
unsigned cli_default_threads(void);

/* -------------------------------------------------------- interruption */

/**
 * Registers path as an output this command is about to write. The first call
 * installs handlers for SIGINT, SIGTERM and SIGHUP: on any of them the
 * temporaries the atomic writers keep beside every registered output
 * ("<name>.tmp-XXXXXX", ".<name>.tmp-XXXXXX.<ext>") are removed, with every
 * staging folder and every folder the command created (cli_folder_make()),
 * one line on stderr says which registered outputs had already been placed
 * ("ilf: interrupted; kept (complete) PATH" or "ilf: interrupted; nothing
 * written"), then the process ends by that signal (exit status 128 + its
 * number: 130 for SIGINT). Outputs under their final names are always
 * complete, so an interrupted command leaves either the old file, the new
 * one, or nothing. At most 16 registrations, with paths under 4096 bytes;
 * others are not watched. It allocates nothing.
 */
void cli_output_watch(const char *path);

/*
 * Creates a staging folder from template (mkdtemp's XXXXXX, replaced in place;
 * outputs are written into it, then renamed into place together) and registers
 * it in the same step, so that SIGINT, SIGTERM or SIGHUP at any moment removes
 * it with every file in it. Same limits as cli_output_watch().
 * @return template, or NULL with errno set.
 */
char *cli_staging_make(char *template);

/* Unregisters staging folder path, once it is gone or emptied into place. */
void cli_staging_forget(const char *path);

/*
 * Creates folder path and any missing parents (mkdir -p) and registers what it created in the same step, so
 * that an interruption at any moment removes them again when they are empty. *created_from receives the length
 * of the first prefix of path it created (0: none). @return 1, or 0 after reporting.
 */
int cli_folder_make(const char *sub, const char *path, size_t *created_from);

/* Removes folder path and its parents down to the prefix of created_from bytes (cli_folder_make()), deepest
 * first, each only if it is empty. */
void cli_folder_unmake(const char *path, size_t created_from);

/* Installs the handlers and the watcher of cli_output_watch() now, so that a command interrupted before it
 * registers anything still says so in one line ("ilf: interrupted"). */
void cli_interrupts_install(void);

/*
 * Holds interruptions off (they wait, then clean up as above) while the calling thread places a set of outputs,
 * so that a set is never left half placed; registrations from the same thread go on meanwhile. Pair each call
 * with cli_interrupts_release().
 */
void cli_interrupts_hold(void);
void cli_interrupts_release(void);

/* ------------------------------------------------------------ progress */

/**
 * A one-line progress bar on stderr: the share done, the time taken and, once
 * a little of the work is done, the time left, estimated as if the rest went
 * at the pace so far (so the steps must be proportional to the work: callers
 * count work units, such as the engine's work-weighted fraction, not calls).
 * cli_progress_add() may be called from any thread; it redraws at most about
 * ten times a second. Nothing is drawn when stderr is not a terminal or the
 * command is quiet (cli_set_quiet()).
 */
typedef struct cli_progress {
    const char *label;
    uint64_t total;
    atomic_uint_fast64_t done;
    atomic_flag drawing;       /* held by the thread that is redrawing */
    atomic_int_fast64_t last_draw_ms;
    int64_t start_ms;          /* when the bar started */
    int enabled;               /* stderr is a terminal and the command is not quiet */
} cli_progress;

/** Formats a time left or taken for people ("4.2 s", "3 min 05 s", "1 h 02 min") into buf. @return buf. */
const char *cli_format_duration(double seconds, char *buf, size_t size);

/** @return the time of clock clock_id (CLOCK_MONOTONIC, CLOCK_PROCESS_CPUTIME_ID, ...) in seconds. */
double cli_clock_seconds(int clock_id);

/** Steps of a bar that shows a fraction of a run (cli_progress_fraction()). */
#define CLI_PROGRESS_STEPS 1000u

void cli_progress_start(cli_progress *p, const char *label, uint64_t total);
void cli_progress_add(cli_progress *p, uint64_t count);
/** Advances p to done steps; a count at or below what is drawn changes nothing. One caller thread at a time. */
void cli_progress_reach(cli_progress *p, uint64_t done);
/** An rl_progress_fn: moves bar (a cli_progress started with CLI_PROGRESS_STEPS) to fraction done of [0, 1]. */
void cli_progress_fraction(void *bar, double done);
/** Erases the bar's line so that a result line can be printed; the next redraw brings it back. Call from the
 * thread that prints, with no other thread adding. */
void cli_progress_clear(cli_progress *p);
/** Draws the final state and ends the line (or does nothing when disabled). */
void cli_progress_finish(cli_progress *p);

#endif /* ILF_CLI_H */
