/*
 * job.h - what the relighting engine is to compute and how, apart from the
 * scene it computes it on (relight/scene.h): a job (rl_job) holds the
 * sampling settings and the radiance maps' cell size (what) and the run
 * options (rl_run_options: threads, progress, time budget, maps told ready:
 * how). A scene file suggests a job (rl_job_default()); a caller edits a
 * copy and passes it to rl_relight() or rl_irradiance() (relight/engine.h),
 * and the calls that only read a solution or trace rays take the run
 * options alone. Conventions as in relight/relight.h.
 *
 * This header is valid C99 and C++.
 */
#ifndef RELIGHT_JOB_H
#define RELIGHT_JOB_H

#include "relight/scene.h"
#include "ilf/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Progress callback: done in [0, 1] over the whole run, never decreasing. Called from the calling thread only. */
typedef void (*rl_progress_fn)(void *user, double done);

/** Most worker threads a run may ask for (the cap of ilfkit's one thread pool). */
#define RL_MAX_THREADS ILF_MAX_THREADS

/** A solved scene: radiance maps of every receiving polygon. Opaque. */
typedef struct rl_solution rl_solution;

/**
 * Told that maps [0, ready) of the solution being computed hold their final
 * values: from then on they may be read with rl_solution_map_cells() and
 * rl_solution_map_rows(), and every map (ready or not) described with
 * rl_solution_map_info(), which does not change during the run, from any
 * thread, while the run goes on (no other
 * call on solution is allowed before rl_relight() returns it). Called from
 * one of the engine's threads, with ready increasing, the last time with
 * the map count, and only if the run succeeds that far. A run on one
 * process reports maps as its last pass finishes them (in order: its work
 * goes map by map; a map with bounces is finished once the last of its
 * cells gathered in that pass are); a run across processes reports them
 * all at its end. It must return
 * quickly and call nothing of the engine's but those accessors. If the
 * run then fails, it is called once more with solution NULL and ready 0
 * before the solution is freed: that call must return only once nothing
 * reads the solution any more.
 */
typedef void (*rl_maps_ready_fn)(void *user, const rl_solution *solution, size_t ready);

/**
 * How to run one call, apart from what to compute: the job's sampling
 * settings and cell size decide the result; these decide only how it is
 * reached. Part of an rl_job for the calls that solve; passed alone, by
 * pointer, to the calls that only render or trace (NULL means
 * rl_run_options_default()). The call copies what it needs and keeps no
 * pointer to the options.
 */
typedef struct rl_run_options {
    uint32_t threads;        /**< worker threads, 0 (default) = every core; at most RL_MAX_THREADS.
                                  The ray tracer's own threads (building its hierarchy) follow the same
                                  count. Results do not depend on it. */
    rl_progress_fn progress; /**< called with the fraction done; NULL (default): none */
    void *progress_user;     /**< passed to progress */
    double time_budget;      /**< adaptive method: seconds after which no solid angle is refined further
                                  (the result then depends on timing); 0 (default) = none; finite, >= 0.
                                  A scene file may suggest one (its sampling.time_budget): rl_job_default() */
    rl_maps_ready_fn maps_ready; /**< rl_relight() only: told as maps are finished; NULL (default): not */
    void *maps_ready_user;       /**< passed to maps_ready */
} rl_run_options;

/** Fills *o with the defaults: every core, no progress, no time budget. NULL is a no-op. */
void rl_run_options_default(rl_run_options *o);

/**
 * One job for the engine: what to compute (sampling settings, cell size) and
 * how (run options), apart from the scene, which it only reads. Start from
 * rl_job_default() and change fields; the solving calls take it by pointer,
 * copy what they need and keep no pointer to it, so one scene may be solved
 * with several jobs at once, from several threads.
 */
typedef struct rl_job {
    size_t size;          /**< sizeof(rl_job), set by rl_job_default(): lets the struct grow in later versions */
    rl_sampling sampling; /**< what to compute: method, partition, rays, bounces, seed, ... (relight.h) */
    double cell_size;     /**< side of the radiance maps' square cells, metres; finite, > 0 */
    rl_run_options run;   /**< how: threads, progress, time budget, maps_ready */
} rl_job;

/**
 * Fills *job with what the scene file suggests: its "sampling" settings,
 * its "radiance_maps.cell_size" and its "sampling.time_budget" as
 * job->run.time_budget; the other run options as rl_run_options_default().
 * A NULL scene gives rl_sampling_default(), RL_DEFAULT_CELL_SIZE and no time
 * budget. NULL job is a no-op. Thread-safe (the scene is only read).
 */
void rl_job_default(const rl_scene *scene, rl_job *job);

/**
 * Checks a job as the solving calls do: size equal to sizeof(rl_job), cell_size, every sampling setting
 * within its bounds (rl_sampling_setting_allows(), without text bounds), and the run options (threads at
 * most RL_MAX_THREADS, time_budget finite and >= 0). Reads only *job; thread-safe.
 * @return RL_OK, or RL_ERR_ARG (NULL job, or a field out of range) with a message naming the field
 * ("rl_job: sampling.partition_n must be a power of two in 1..4096, got 3").
 */
rl_status rl_job_check(const rl_job *job);

#ifdef __cplusplus
}
#endif

#endif /* RELIGHT_JOB_H */
