/*
 * job_internal.h - a call's job and run options once checked and resolved (rl__run),
 * as every file of the engine that runs work reads them: the passes
 * (engine.c), point queries (query.c), the camera view (view.c) and the ray
 * benchmark (bench_rays.c). job.c implements them with the public
 * rl_run_options_default(), rl_job_default() and rl_job_check().
 *
 * Invariants: an rl__run comes only from rl__run_resolve() or
 * rl__job_resolve(), so its fields are in range; it is copied by value and
 * never outlives the call that resolved it.
 */
#ifndef RELIGHT_JOB_INTERNAL_H
#define RELIGHT_JOB_INTERNAL_H

#include "relight/job.h"

/* A call's run options, checked, with the thread count resolved; for the calls that solve, also the
 * job's sampling and cell size (rl__job_resolve()). */
typedef struct rl__run {
    rl_sampling sampling;    /* what to compute (rl__job_resolve(); zero for calls that only render or trace) */
    double cell_size;        /* the radiance maps' cell size, metres (likewise) */
    unsigned threads;        /* >= 1: ilf_thread_count(options->threads) */
    rl_progress_fn progress; /* or NULL */
    void *user;
    double time_budget;      /* seconds, 0 = none */
    rl_maps_ready_fn maps_ready; /* or NULL */
    void *maps_ready_user;
    const rl_solution *reporting; /* set by rl__solve() for a run whose maps are final once finish() has run on
                                     them (told to maps_ready as they are) */
    /* with reporting: called with each map index once its tiles have finished, from the worker that
     * finished the last one (a map with nothing to gather has an empty tile; only a pass without emitters
     * calls it from the calling thread), before the map is told of; it completes the map (NULL: nothing to
     * complete) */
    void (*finish)(void *user, size_t map);
    void *finish_user;
} rl__run;

/* Checks options (NULL: the defaults) and resolves them into *run; `call` names the caller in messages.
 * @return RL_OK, or RL_ERR_ARG naming the field out of range. */
rl_status rl__run_resolve(const char *call, const rl_run_options *options, rl__run *run);

/* Checks job (NULL: rl_job_default(scene)) with rl_job_check() and resolves it into *run: its sampling, cell
 * size and run options. @return RL_OK, or RL_ERR_ARG naming the field. */
rl_status rl__job_resolve(const rl_scene *scene, const rl_job *job, rl__run *run);

#endif /* RELIGHT_JOB_INTERNAL_H */
