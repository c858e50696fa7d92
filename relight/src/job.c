/*
 * job.c - the job (relight/job.h's rl_job): what to compute (sampling
 * settings, cell size) and how (run options), apart from the scene. A scene
 * file suggests a job (its "sampling" and "radiance_maps" sections and
 * sampling.time_budget); rl_job_default() hands that suggestion out and the
 * engine reads only the job it is given, never the scene's suggestion.
 *
 * The run options alone, and a job whole, are resolved here for the engine
 * (job_internal.h's rl__run).
 *
 * Invariants: rl_job_check() accepts exactly the jobs the engine runs, with
 * the bounds of settings.c's table (not its text bounds), so a checked job
 * never reaches the engine out of range.
 */
#include <math.h>
#include <string.h>

#include "ilf/pool.h"
#include "job_internal.h"
#include "scene_model.h"

void rl_run_options_default(rl_run_options *o)
{
    if (o)
        *o = (rl_run_options){0, NULL, NULL, 0.0, NULL, NULL};
}

rl_status rl__run_resolve(const char *call, const rl_run_options *options, rl__run *run)
{
    rl_run_options o;
    rl_run_options_default(&o);
    if (options)
        o = *options;
    if (o.threads > RL_MAX_THREADS)
        return rl__fail(RL_ERR_ARG, "%s: threads must be an integer in 0..%u, got %u", call, RL_MAX_THREADS,
                        o.threads);
    if (!(o.time_budget >= 0) || !isfinite(o.time_budget))
        return rl__fail(RL_ERR_ARG, "%s: time_budget must be finite and >= 0, got %g", call, o.time_budget);
    memset(run, 0, sizeof *run);
    run->threads = ilf_thread_count(o.threads);
    run->progress = o.progress, run->user = o.progress_user;
    run->time_budget = o.time_budget;
    run->maps_ready = o.maps_ready, run->maps_ready_user = o.maps_ready_user;
    return RL_OK;
}

rl_status rl__job_resolve(const rl_scene *scene, const rl_job *job, rl__run *run)
{
    rl_job own;
    if (!job) {
        rl_job_default(scene, &own);
        job = &own;
    }
    rl_status st = rl_job_check(job);
    if (st == RL_OK)
        st = rl__run_resolve("rl_job: run", &job->run, run);
    if (st == RL_OK) {
        run->sampling = job->sampling;
        run->cell_size = job->cell_size;
    }
    return st;
}

void rl_job_default(const rl_scene *scene, rl_job *job)
{
    if (!job)
        return;
    memset(job, 0, sizeof *job);
    job->size = sizeof *job;
    rl_run_options_default(&job->run);
    if (scene) {
        job->sampling = scene->sampling;
        job->cell_size = scene->cell_size;
        job->run.time_budget = scene->time_budget;
    } else {
        rl_sampling_default(&job->sampling);
        job->cell_size = RL_DEFAULT_CELL_SIZE;
    }
}

/* Checks the sampling settings against the table's bounds. @return RL_OK or RL_ERR_ARG naming the field. */
static rl_status check_sampling(const rl_sampling *s)
{
    for (size_t k = 0; k < rl_sampling_setting_count(); k++) {
        const rl_setting_info *set = rl_sampling_setting(k);
        double value = 0;
        char rule[128];
        rl_sampling_get(s, k, &value);
        if (rl_sampling_setting_allows(k, value, 0))
            continue;
        if (set->type == RL_SETTING_METHOD)
            return rl__fail(RL_ERR_ARG, "rl_job: sampling.method %d is not a method", (int)s->method);
        if (set->type == RL_SETTING_REAL)
            return rl__fail(RL_ERR_ARG, "rl_job: sampling.%s must be %s, got %g", set->key,
                            rl_sampling_setting_rule(k, rule, sizeof rule), value);
        return rl__fail(RL_ERR_ARG, "rl_job: sampling.%s must be %s, got %.0f", set->key,
                        rl_sampling_setting_rule(k, rule, sizeof rule), value);
    }
    return RL_OK;
}

rl_status rl_job_check(const rl_job *job)
{
    if (!job)
        return rl__fail(RL_ERR_ARG, "rl_job: NULL job");
    if (job->size != sizeof *job)
        return rl__fail(RL_ERR_ARG, "rl_job: size must be sizeof(rl_job) = %zu (set by rl_job_default()), got %zu",
                        sizeof *job, job->size);
    if (!(job->cell_size > 0) || !isfinite(job->cell_size))
        return rl__fail(RL_ERR_ARG, "rl_job: cell_size must be finite and > 0 metres, got %g", job->cell_size);
    rl__run run;
    rl_status st = check_sampling(&job->sampling);
    return st == RL_OK ? rl__run_resolve("rl_job: run", &job->run, &run) : st;
}
