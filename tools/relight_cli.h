/*
 * relight_cli.h - what `ilf relight` and `ilf irradiance` share: the
 * sampling options that override a scene's settings, loading a scene with
 * them, turning relight library failures into messages and exit codes, and
 * describing a pass's statistics.
 *
 * Invariants: an option given on the command line replaces exactly that
 * field of the scene's sampling settings and nothing else; every value is
 * range-checked when parsed, and rl_scene_set_sampling() checks the whole
 * again, so a bad value is always bad usage (exit 2), never a crash.
 */
#ifndef ILF_RELIGHT_CLI_H
#define ILF_RELIGHT_CLI_H

#include <stdio.h>

#include "cli.h"
#include "relight/engine.h"

/* The sampling options, in the order of enum sampling_option_id. Commands
 * put them first in their option tables, so an option's index is its id. */
#define RELIGHT_SAMPLING_OPTIONS                                                                  \
    {"method", 0, "M", "culled, naive, area, solidangle or adaptive (default: the scene's)"},       \
    {"threads", 0, "N", "worker threads, 0 = every processor (default 0)"},                        \
    {"seed", 0, "S", "random seed, 0 .. 2^53 (default: the scene's)"},                             \
    {"partition-n", 0, "N", "partition level, a power of two up to 4096 (default: the scene's)"},  \
    {"rays", 0, "K", "rays per (cell, solid angle), 1 .. 65536 (default: the scene's)"},           \
    {"samples", 0, "N", "shadow rays per (cell, emitter), area and solidangle (default: scene's)"}, \
    {"bounces", 0, "B", "diffuse passes after the direct one, 0 .. 64 (default: the scene's)"},    \
    {"bounce-partition-n", 0, "N", "partition level of bounce passes, 0 = partition-n / 4 (default: scene's)"}, \
    {"bounce-cell-factor", 0, "F", "bounces gather on cells F times larger, interpolated; 1 = every cell, 0 = 2 (default: scene's)"}, \
    {"descend", 0, "0|1", "1: exact views of small emitters, Lambert ratio for diffuse ones (default: scene's)"}, \
    {"zero-culling", 0, "0|1", "1: cull light field directions and cells by zero radiance (default: scene's)"}, \
    {"target-error", 0, "E", "adaptive: refine while a cell's error exceeds E of it, (0, 1] (default: scene's)"}, \
    {"time-budget", 0, "S", "adaptive: stop refining after S seconds, 0 = never (default: the scene's)"}

enum sampling_option_id {
    SAMPLING_OPT_METHOD,
    SAMPLING_OPT_THREADS,
    SAMPLING_OPT_SEED,
    SAMPLING_OPT_PARTITION_N,
    SAMPLING_OPT_RAYS,
    SAMPLING_OPT_SAMPLES,
    SAMPLING_OPT_BOUNCES,
    SAMPLING_OPT_BOUNCE_PARTITION_N,
    SAMPLING_OPT_BOUNCE_CELL_FACTOR,
    SAMPLING_OPT_DESCEND,
    SAMPLING_OPT_ZERO_CULLING,
    SAMPLING_OPT_TARGET_ERROR,
    SAMPLING_OPT_TIME_BUDGET,
    SAMPLING_OPT_COUNT
};

/** Sampling settings and run options given on the command line. */
typedef struct sampling_overrides {
    unsigned given;      /**< bit k set when option k (enum sampling_option_id) was given */
    rl_sampling values;  /**< the given values; other fields unused */
    uint32_t threads;    /**< --threads, when given */
    double time_budget;  /**< --time-budget, when given */
} sampling_overrides;

/**
 * Parses the value of sampling option opt (< SAMPLING_OPT_COUNT) into o.
 * @return 1, or 0 after reporting the bad value.
 */
int sampling_option_apply(const cli_parser *p, sampling_overrides *o, int opt, const char *value);

/**
 * Loads scene path and applies the overrides to its sampling settings.
 * @return ILF_EXIT_OK and *out (the caller destroys it); an exit code after
 * reporting, with *out = NULL.
 */
int relight_scene_open(const char *sub, const char *path, const sampling_overrides *o, rl_scene **out);

/**
 * Fills *out with the run options of a call on scene: --threads when given,
 * else 0 (every core), or this rank's share of the cores in a job of several
 * ranks; --time-budget when given, else the scene's suggestion
 * (rl_scene_time_budget()); no progress callback. o may be NULL (nothing given).
 */
void relight_run_options(const sampling_overrides *o, const rl_scene *scene, rl_run_options *out);

/** @return the worker threads a call with options ro uses: 0 means every core, as in the engine. */
unsigned relight_threads_used(const rl_run_options *ro);

/**
 * Reports a failed relight call with rl_errmsg() and maps st to an exit
 * code: invalid or unreadable input is bad input (2); memory and internal
 * failures are failures while running (1).
 */
int relight_failure(const char *sub, rl_status st);

/** Prints one line per pass statistic group for pass k ("pass 0 (direct): ..."). */
void relight_print_pass(FILE *out, uint32_t k, const rl_pass_stats *s);

#endif /* ILF_RELIGHT_CLI_H */
