/*
 * bench_rays.c - rl_bench_rays(): the ray tracer alone, the ceiling that the
 * engine's ray rate is measured against (`ilf bench --rays`, bench/src, reports it).
 *
 * Each worker draws a chunk of random shadow rays (uniform points on the
 * scene's polygons by area, cosine-distributed directions), then traces it
 * in packets exactly as the methods do (pair.c), and only the tracing is timed.
 * Invariants: worker k's rays come from a sequence keyed by k alone, so a
 * run's rays depend only on the thread count; the tracer is built with the
 * same thread count, and nothing else of the engine is involved.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "engine_internal.h"
#include "ilf/clock.h"
#include "ilf/pool.h"
#include "sampling.h"

/* Rays drawn before each timed stretch of tracing. */
#define RAY_CHUNK 4096

typedef struct ray_job {
    const rl_scene *scene;
    const rl_tracer *tracer;
    const double *cdf; /* cumulative polygon areas, npolygons entries */
    uint64_t per_thread;
    atomic_uint_fast64_t occluded;
    _Atomic double trace_cpu, trace_wall; /* summed over threads; the longest thread */
} ray_job;

/* @return a uniform double in [0, 1) from state. */
static double next_unit(uint64_t *state)
{
    *state = ilf_hash_mix(*state, 0x632be59bd9b4e019ull);
    return (*state >> 11) * (1.0 / 9007199254740992.0);
}

/* Gives a random shadow ray: from a point uniform on the scene's polygons
 * (by area) in a cosine-distributed direction about the polygon's normal. */
static void random_ray(const ray_job *job, uint64_t *state, v3 *org, v3 *dir)
{
    const rl_scene *sc = job->scene;
    double pick_a = next_unit(state) * job->cdf[sc->npolygons - 1];
    size_t lo = 0, hi = sc->npolygons - 1;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (job->cdf[mid] <= pick_a)
            lo = mid + 1;
        else
            hi = mid;
    }
    const rl_polygon *pg = &sc->polygons[lo];
    const double(*v)[3] = sc->vertices + pg->first;
    /* a point on one fan triangle, a cosine-distributed direction about the normal */
    uint32_t t = 1 + (uint32_t)(next_unit(state) * (pg->count - 2));
    double su = sqrt(next_unit(state)), b = next_unit(state);
    v3 a0 = v3_load(v[0]), a1 = v3_load(v[t]), a2 = v3_load(v[t + 1]);
    *org = v3_add(v3_add(v3_scale(a0, 1 - su), v3_scale(a1, su * (1 - b))), v3_scale(a2, su * b));
    v3 n = v3_load(pg->normal), e1 = v3_norm(v3_sub(a1, a0)), e2 = v3_cross(n, e1);
    double r1 = next_unit(state), phi = 2 * ILF_PI * next_unit(state), sr = sqrt(r1);
    *dir = v3_add(v3_scale(n, sqrt(1 - r1)), v3_add(v3_scale(e1, sr * cos(phi)), v3_scale(e2, sr * sin(phi))));
}

/* Worker `index`: traces its share of random shadow rays, chunk by chunk, timing only the tracing. */
static void ray_worker(void *p, unsigned index)
{
    ray_job *job = p;
    uint64_t state = ilf_hash_mix(0x5eed, index), hits = 0;
    double reach = 4.0 * rl__tracer_extent(job->tracer), cpu = 0.0, wall = 0.0;
    v3 *org = malloc(RAY_CHUNK * sizeof *org), *dir = malloc(RAY_CHUNK * sizeof *dir);
    double *tn = malloc(RAY_CHUNK * sizeof *tn), *tf = malloc(RAY_CHUNK * sizeof *tf);
    rl__tracer_thread_init();
    for (uint64_t done = 0; org && dir && tn && tf && done < job->per_thread; done += RAY_CHUNK) {
        size_t n = job->per_thread - done < RAY_CHUNK ? (size_t)(job->per_thread - done) : RAY_CHUNK;
        for (size_t i = 0; i < n; i++) {
            random_ray(job, &state, &org[i], &dir[i]);
            tn[i] = 1e-6 * reach;
            tf[i] = reach;
        }
        double c0 = ilf_clock_thread_cpu(), w0 = ilf_clock_wall();
        for (size_t i = 0; i < n; i += RL_RAY_PACKET) {
            int occ[RL_RAY_PACKET];
            size_t m = n - i < RL_RAY_PACKET ? n - i : RL_RAY_PACKET;
            rl__tracer_occluded_n(job->tracer, m, org + i, dir + i, tn + i, tf + i, occ);
            for (size_t k = 0; k < m; k++)
                hits += occ[k] != 0;
        }
        cpu += ilf_clock_thread_cpu() - c0;
        wall += ilf_clock_wall() - w0;
    }
    free(org);
    free(dir);
    free(tn);
    free(tf);
    atomic_fetch_add(&job->occluded, hits);
    double c = atomic_load(&job->trace_cpu);
    while (!atomic_compare_exchange_weak(&job->trace_cpu, &c, c + cpu))
        ;
    double w = atomic_load(&job->trace_wall);
    while (w < wall && !atomic_compare_exchange_weak(&job->trace_wall, &w, wall))
        ;
}

rl_status rl_bench_rays(const rl_scene *scene, const rl_run_options *options, uint64_t rays, rl_ray_bench *out)
{
    if (!scene || !out)
        return rl__fail(RL_ERR_ARG, "rl_bench_rays: NULL argument");
    memset(out, 0, sizeof *out);
    rl__run run;
    rl_status st = rl__run_resolve("rl_bench_rays", options, &run);
    if (st != RL_OK)
        return st;
    if (scene->npolygons == 0)
        return rl__fail(RL_ERR_ARG, "%s: the scene has no polygons to trace against", scene->path);
    rl_tracer *tracer = NULL;
    st = rl__tracer_new(scene, run.threads, &tracer);
    if (st != RL_OK)
        return st;
    double *cdf = malloc(scene->npolygons * sizeof *cdf);
    if (!cdf) {
        rl__tracer_destroy(tracer);
        return rl__fail(RL_ERR_NOMEM, "out of memory");
    }
    double acc = 0;
    for (size_t k = 0; k < scene->npolygons; k++)
        cdf[k] = acc += scene->polygons[k].area;
    ray_job job = {scene, tracer, cdf, rays / run.threads + 1, 0, 0.0, 0.0};
    ilf_parallel(run.threads, ray_worker, &job);
    out->wall_seconds = atomic_load(&job.trace_wall);
    out->cpu_seconds = atomic_load(&job.trace_cpu);
    out->rays = job.per_thread * run.threads;
    out->occluded = atomic_load(&job.occluded);
    free(cdf);
    rl__tracer_destroy(tracer);
    return RL_OK;
}
