/*
 * relight_cli.h - what `ilf relight` and `ilf irradiance` share: the
 * sampling options that override the job a scene file suggests, loading a
 * scene and making its job with them, turning relight library failures into
 * messages and exit codes, and describing a pass's statistics.
 *
 * Invariants: an option given on the command line replaces exactly that
 * field of the job's sampling settings (or that run option) and nothing
 * else; the scene itself is never changed. Every value is range-checked when
 * parsed, against the same table of settings the scene loader reads, and
 * rl_job_check() checks the whole job again, so a bad value is always bad
 * usage (exit 2), never a crash.
 */
#ifndef ILF_RELIGHT_CLI_H
#define ILF_RELIGHT_CLI_H

#include <stdio.h>

#include "cli.h"
#include "relight/engine.h"

/* The sampling options: first one per row of relight's table of sampling
 * settings (rl_sampling_setting(k) is option k: its name, placeholder,
 * bounds and help all come from there), then the run options --threads and
 * --time-budget. Commands reserve the first SAMPLING_OPT_COUNT entries of
 * their option tables and fill them with relight_options_fill(), so an
 * option's index is its id. */
enum sampling_option_id {
    SAMPLING_OPT_SETTINGS = 13, /* rows of the settings table: relight_options_fill() checks the count */
    SAMPLING_OPT_THREADS = SAMPLING_OPT_SETTINGS,
    SAMPLING_OPT_TIME_BUDGET,
    SAMPLING_OPT_COUNT
};

/**
 * Fills table[0 .. SAMPLING_OPT_COUNT) with the sampling options (strings
 * static, built once; call from the main thread).
 * @return 1, or 0 after reporting when relight's table no longer has SAMPLING_OPT_SETTINGS rows.
 */
int relight_options_fill(const char *sub, cli_option *table);

/** Sampling settings and run options given on the command line. */
typedef struct sampling_overrides {
    unsigned given;      /**< bit k set when option k (enum sampling_option_id) was given */
    rl_sampling values;  /**< the given values; other fields unused */
    uint32_t threads;    /**< --threads, when given */
    double time_budget;  /**< --time-budget, when given */
} sampling_overrides;

/**
 * Parses the value of sampling option opt (< SAMPLING_OPT_COUNT) into o, checked against the
 * setting's bounds in relight's table.
 * @return 1, or 0 after reporting the bad value.
 */
int sampling_option_apply(const cli_parser *p, sampling_overrides *o, int opt, const char *value);

/**
 * Loads scene path and, unless job is NULL (a caller that needs the scene
 * alone), makes its job with the overrides (relight_job()), checked by
 * rl_job_check().
 * @return ILF_EXIT_OK, *out (the caller destroys it) and *job; an exit code
 * after reporting, with *out = NULL.
 */
int relight_scene_open(const char *sub, const char *path, const sampling_overrides *o, rl_scene **out, rl_job *job);

/**
 * Fills *job with the job that scene's file suggests (rl_job_default()), each
 * sampling setting given in o replacing the file's, and the run options:
 * --threads when given, else 0 (every core), or this rank's share of the
 * cores in a job of several ranks; --time-budget when given, else the file's
 * suggestion; no progress callback. o may be NULL (nothing given).
 */
void relight_job(const sampling_overrides *o, const rl_scene *scene, rl_job *job);

/** @return the worker threads a call with options ro uses: 0 means every core, as in the engine. */
unsigned relight_threads_used(const rl_run_options *ro);

/**
 * Reports a failed relight call with rl_errmsg() and maps st to an exit
 * code: invalid or unreadable input is bad input (2); memory and internal
 * failures are failures while running (1).
 */
int relight_failure(const char *sub, rl_status st);

/** @return the calling thread's engine message (rl_errmsg()) on one line in buf, or a generic one if empty. */
const char *relight_failure_text(char *buf, size_t size);

/**
 * Describes sampling settings s for people into buf: the method and what it
 * samples (the partition and rays per solid angle, or the samples per cell
 * and emitter for area and solidangle), then the bounces and how they gather.
 * @return buf.
 */
const char *relight_describe(const rl_sampling *s, char *buf, size_t size);

/** Prints the settings line of a run of job (cli_settings()): what it does and on how many threads, before
 * it starts. */
void relight_print_settings(const char *sub, const rl_job *job);

/** Warns (cli_warn()) of every finding of rl_scene_diagnose(scene), leaving out the missing camera unless
 * want_view. */
void relight_warn_scene(const rl_scene *scene, int want_view);

/** Warns (cli_warn()) of every finding of rl_solution_diagnose(solution), leaving out what the camera sees
 * unless want_view. */
void relight_warn_solution(const rl_solution *solution, int want_view);

/** Prints one line per pass statistic group for pass k ("pass 0 (direct): ..."). */
void relight_print_pass(FILE *out, uint32_t k, const rl_pass_stats *s);

#endif /* ILF_RELIGHT_CLI_H */
