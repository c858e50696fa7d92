/*
 * bench.h - the parts of `ilf bench`, the program ilf-bench (ilf_bench.c, its
 * entry point; cmd_bench.c, the command), and what they share:
 *
 *   bench_util.c     text buffers, paths, one-level folders, atomic text files
 *   bench_run.c      one measured job in a forked child: a relighting with
 *                    its error against the reference, or the ray ceiling
 *   bench_ref.c      the reference solution: cache key, computing, loading
 *   bench_ptref.c    the path-traced reference (--reference pathtrace) on
 *                    sampled cells, with bench_pathtrace.c's estimator
 *   bench_report.c   Pareto fronts, ratios at equal error and equal time,
 *                    bench.csv, bench.json and summary.md
 *   bench_plot.c     gnuplot scripts and running gnuplot
 *   bench_scaling.c  `ilf bench --scaling`
 *
 * Invariants: the process that forks never runs the relighting engine or
 * the ray tracer itself (children do), so no library thread pool exists when
 * it forks; every file the bench writes is replaced atomically (a temporary
 * beside it renamed over it); errors are reported once, where they happen,
 * as "ilf bench: ...", and travel up as exit codes or 0/1 returns.
 */
#ifndef ILF_BENCH_H
#define ILF_BENCH_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "relight/engine.h"
#include "relight_cli.h"

/** `ilf bench`, as ilf's commands have the shape of main: argv[0] is "bench". @return an exit code (cli.h). */
int ilf_cmd_bench(int argc, char **argv);

#define BENCH_SUB "bench"
#define BENCH_CREATOR "ilf bench (ilfkit " ILFKIT_VERSION ")"
#define BENCH_PATH_MAX 4096
/* Most methods --methods may list. */
#define BENCH_MAX_METHODS 8

/* ------------------------------------------------------------ configuration */

/** What the command line asked for (cmd_bench.c fills it). */
typedef struct bench_config {
    const char *scene;              /**< scene file */
    const char *output;             /**< DIR; NULL only for --rays without -o */
    char cache[BENCH_PATH_MAX];     /**< folder of cached references */
    sampling_overrides sampling;    /**< threads and bounces (bounces given as 0 unless --bounces) */
    rl_job job;                     /**< the scene's job with those overrides (relight_job()), once it is open;
                                         bench_scaling() does not use it */
    rl_method methods[BENCH_MAX_METHODS];
    size_t nmethods;
    uint32_t reference_samples;     /**< per (cell, emitter) of each reference run; pathtrace: paths per cell */
    int reference_pathtrace;        /**< --reference pathtrace: bench_ptref.c's reference instead of solidangle's */
    uint32_t reference_cells;       /**< pathtrace: cells sampled, evenly spaced in the engine's order */
    int scene_settings;             /**< --scene-settings: one run at the scene's own sampling settings */
    uint64_t rays_count;            /**< --rays: rays to trace */
    double time_limit;              /**< seconds: skip a setting predicted to take longer */
    int quick, quiet;
    char command[1024];             /**< the command line, for the reports */
} bench_config;

/* ------------------------------------------------------------ bench_util.c */

/** A growing text; once an allocation fails it stays failed and ignores appends. */
typedef struct bench_text {
    char *data;
    size_t len, cap;
    int failed;
} bench_text;

/** Appends formatted text. */
void bench_printf(bench_text *t, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** Releases t's memory and empties it. */
void bench_text_free(bench_text *t);

/** @return the whole file as a NUL-terminated string (free() it); NULL if unreadable or it holds a NUL byte. */
char *bench_read_text(const char *path);

/** Writes into out (BENCH_PATH_MAX bytes) file name as seen from the folder of file scene (absolute names as they are). @return 1, or 0 if too long. */
int bench_resolve_beside(char *out, const char *scene, const char *name);

/** Writes dir/name into out (BENCH_PATH_MAX bytes). @return 1, or 0 after reporting a too long path. */
int bench_path(char *out, const char *dir, const char *name);

/** Creates folder path if it does not exist (its parent must). @return 1, or 0 after reporting. */
int bench_make_folder(const char *path);

/** Writes t to path atomically; unless quiet prints "wrote PATH: what". @return 1, or 0 after reporting. */
int bench_write_text(const char *path, const bench_text *t, const char *what, int quiet);


/** @return the luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of a linear Rec.709 colour. */
double bench_luminance(const float rgb[3]);

/* ------------------------------------------------------------ bench_run.c */

/** One point of a sweep: a method and its knobs (a knob the method does not use is 0). */
typedef struct bench_setting {
    rl_method method;
    uint32_t partition_n;  /**< culled, naive */
    uint32_t rays;         /**< rays per solid angle: culled, naive */
    uint32_t samples;      /**< samples per (cell, emitter): area, solidangle */
    double target_error;   /**< adaptive: refine while a cell's error exceeds this fraction of it */
    double cost;           /**< nominal relative cost, for predicting times within one method */
} bench_setting;

/** Writes a short name of s ("culled n=16 k=4", "area s=64") into buf. @return buf. */
const char *bench_setting_label(const bench_setting *s, char *buf, size_t size);

/** What a child reports: a fixed-size record sent through a pipe. */
typedef struct bench_result {
    int32_t ok;                      /**< 1 when the job succeeded */
    char message[240];               /**< why it did not */
    double wall_seconds, cpu_seconds;/**< of the relighting (or the ray tracing) alone */
    uint64_t samples, rays_cast, rays_kept;
    uint64_t solid_angles_considered, solid_angles_culled;
    uint64_t maps, cells;
    double rmse, rel_rmse, snr_db;   /**< of Y against the reference; NaN without one */
    double mottling;                 /**< median over lit cells of |Y - mean of its two neighbours| / Y, along
                                          rows and columns of each map: the cell-to-cell noise a view shows,
                                          which a shadow's few edge cells hardly move; NaN without cells */
    double ref_error;                /**< reference job: RMSE(a - b) / 2 */
    double ref_mean, ref_peak;       /**< reference job: mean and largest Y of the mean */
    double peak_mib;                 /**< the child's peak resident memory (parent fills it in) */
} bench_result;

/** The reference: Y of every cell, maps in the engine's order. */
typedef struct bench_reference {
    size_t maps, cells;
    uint32_t *polygon;   /**< [maps] scene polygon of each map */
    size_t *offset;      /**< [maps + 1] first cell of each map in y */
    double *y;           /**< [cells] luminance of irradiance, W m^-2; NaN where the reference has no value
                          *   (pathtrace samples some cells): errors are over the finite cells alone */
    double mean, peak;   /**< over cells with a value */
    double error;        /**< its own RMSE estimate: RMSE(a - b) / 2, or pathtrace's RMS standard error */
    uint32_t samples;    /**< per (cell, emitter) of each run; pathtrace: paths per cell */
    size_t valued;       /**< cells with a value (all but pathtrace's unsampled) */
    const char *method;  /**< "solidangle" or "pathtrace" */
    uint64_t seeds[2];
    int cached;          /**< 1 when read from the cache rather than computed now */
    double wall_seconds; /**< wall time its computation took (now, or when it was cached) */
    char path[BENCH_PATH_MAX]; /**< the cached radiance-map file */
} bench_reference;

/** Releases the arrays of r. */
void bench_reference_free(bench_reference *r);

/** A job run in a child; it fills *out (already zeroed, metrics NaN). */
typedef void (*bench_job_fn)(void *arg, bench_result *out);

/**
 * Runs job in a forked child and collects its record and peak memory.
 * @return 1 with *out filled (out->ok says whether the job succeeded); 0 when
 * no child could be started (out->message says why).
 */
int bench_fork(bench_job_fn job, void *arg, bench_result *out);

/** A relighting job: the settings, what to compare with and what to write. */
typedef struct bench_relight_job {
    rl_scene *scene;                 /**< the inherited scene, or NULL to load scene_path in the child */
    const char *scene_path;
    const sampling_overrides *overrides; /**< applied to the scene's job, with its run options (relight_job());
                                          NULL: none given */
    double cell_size;                /**< > 0: the job's cell size instead of the scene file's (metres) */
    bench_setting setting;
    const bench_reference *ref;      /**< NULL: no error metrics */
    const char *image_path;          /**< camera view of |error| / peak, float32 [height][width]; NULL: none */
    const char *label;               /**< progress bar label; NULL: no bar */
} bench_relight_job;

/**
 * In a child: relights scene with job, setting s applied to its sampling (its
 * progress replaced by a bar labelled label; NULL: none), timing it and
 * summing every pass's counters into r. @return the solution, or NULL with r->message.
 */
rl_solution *bench_relight_timed(const rl_scene *scene, const rl_job *job, const bench_setting *s, const char *label,
                                 bench_result *r);

/** bench_job_fn of a bench_relight_job. */
void bench_relight_child(void *arg, bench_result *out);

/** A ray-ceiling job: rl_bench_rays on the inherited scene. */
typedef struct bench_rays_job {
    const rl_scene *scene;
    uint64_t rays;
    rl_run_options run; /**< threads of the measurement */
} bench_rays_job;

/** bench_job_fn of a bench_rays_job: rays_cast = rays traced, rays_kept = those not blocked. */
void bench_rays_child(void *arg, bench_result *out);

/** bench_job_fn that does nothing: its peak memory is what every child inherits (libraries, scene, reference). */
void bench_idle_child(void *arg, bench_result *out);

/* ------------------------------------------------------------ bench_ref.c */

/**
 * Makes r the reference of the loaded scene: read from the cache when its
 * key matches, else computed in a child (solidangle, cfg->reference_samples,
 * two seeds) and cached. Prints which unless quiet.
 * @return an exit code.
 */
int bench_reference_obtain(const bench_config *cfg, rl_scene *scene, bench_reference *r);

/* ------------------------------------------------------------ bench_ref.c, bench_ptref.c */

/** Computes the cache key of the scene's reference: the scene's and its files' bytes and the given
 * settings line. @return 1, or 0 after reporting. */
int bench_reference_key(const bench_config *cfg, const char *settings, uint64_t *key);

/**
 * Makes r the path-traced reference of the loaded scene (bench_ptref.c): read from the cache when its
 * key matches, else computed in a child and cached. Prints which unless quiet. @return an exit code.
 */
int bench_reference_pathtrace(const bench_config *cfg, rl_scene *scene, bench_reference *r);

/* ------------------------------------------------------------ bench_report.c */

/** One setting of the sweep: run, skipped or failed. */
typedef struct bench_entry {
    bench_setting setting;
    bench_result result;
    int ran;           /**< 1 when a child ran it (result.ok says if it succeeded) */
    double predicted;  /**< predicted wall seconds when skipped */
    int on_front;      /**< 1 when on its method's Pareto front */
} bench_entry;

/** The sweep's results, for the reports. */
typedef struct bench_sweep {
    const bench_config *cfg;
    const bench_reference *ref;
    bench_entry *entries;
    size_t count;
    unsigned threads;            /**< worker threads used */
    uint32_t bounces;
    bench_result ceiling;        /**< ray ceiling run (ceiling.ok 0 if none) */
    bench_result baseline;       /**< an idle child: the memory every run starts from */
    uint32_t camera_width, camera_height; /**< 0 without a camera */
    int best[BENCH_MAX_METHODS]; /**< entry of each method's most accurate run, -1 if none */
} bench_sweep;

/** Marks each method's Pareto front (wall time against RMSE) in s->entries, among runs whose RMSE is at least 10x the reference's error estimate. */
void bench_mark_fronts(bench_sweep *s);

/** Writes bench.csv, bench.json and summary.md into the output folder. @return an exit code. */
int bench_write_reports(const bench_sweep *s);

/** Writes the least-squares fit log y = a + b log x over n points into *a, *b. @return 1, or 0 with fewer than 2 distinct x. */
int bench_fit_power(const double *x, const double *y, size_t n, double *a, double *b);

/* ------------------------------------------------------------ bench_plot.c */

/**
 * Writes DIR/name.gp and, when gnuplot is installed, runs it in DIR to make
 * DIR/name.png (the script writes to the file named by its variable
 * `outfile`, 'name.png' when unset). Warns instead when gnuplot is missing.
 * @return 1, or 0 after reporting a failure.
 */
int bench_plot(const char *dir, const char *name, const bench_text *script, int quiet);

/** Plots error against wall time, log-log, with each method's Pareto front: error_vs_time; and the mottling
 * (bench_result.mottling) of the same runs: mottling_vs_time. @return 1 or 0. */
int bench_plot_error_vs_time(const bench_sweep *s);

/**
 * Plots the error image of each method's most accurate run (DIR/error_<method>.bin)
 * as error_<method>, all on one colour scale. @return 1 or 0.
 */
int bench_plot_error_images(const bench_sweep *s);

/** One series of a scaling plot: x, wall time and peak memory of n runs, and the fitted exponents. */
typedef struct bench_scaling_series {
    const char *name;     /**< file name without extension: scaling_cells, scaling_n */
    const char *xlabel;
    const double *x, *time, *mib;
    size_t n;
    double time_a, time_b, mib_a, mib_b; /**< fits: log y = a + b log x */
    int fitted;
} bench_scaling_series;

/** Plots time and peak memory against x, log-log, with the fitted lines. @return 1 or 0. */
int bench_plot_scaling(const char *dir, const bench_scaling_series *s, int quiet);

/* ------------------------------------------------------------ bench_scaling.c */

/** `ilf bench --scaling`: time and memory against cells and against partition_n. @return an exit code. */
int bench_scaling(const bench_config *cfg);

#endif /* ILF_BENCH_H */
