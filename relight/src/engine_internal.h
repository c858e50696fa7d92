/*
 * engine_internal.h - what the engine's files share: the solution object
 * and the pass runner that solutions (engine.c) and point queries (query.c)
 * are both made by; a call's job and run options, resolved, are job_internal.h's.
 *
 * Invariants: a solution's maps, tracer, light field tables and polygon_map
 * are built together by rl__solve(), for its job, from a scene it only
 * reads, and never change after it returns, except the `flat` shading
 * switch; everything here is internal to librelight (rl__ prefix).
 */
#ifndef RELIGHT_ENGINE_INTERNAL_H
#define RELIGHT_ENGINE_INTERNAL_H

#include "relight/engine.h"
#include "bounce.h"
#include "job_internal.h"
#include "transfer.h"

struct rl_solution {
    const rl_scene *scene;
    rl_map *maps;
    size_t nmaps;
    int32_t *polygon_map; /* scene polygon -> map index, or -1 */
    rl_tracer *tracer;
    rl_slab_tables *slab_tables; /* [scene->nlightfields]: where each light field's slab is lit */
    rl_pass_stats *passes;
    uint32_t npasses;
    int flat; /* shade each cell's own value instead of interpolating between cells */
    uint64_t accumulator_bytes; /* the maps' irradiance arrays at their most (before rl__map_settle()) */
};

/* @return the cluster to run with, NULL for one process; checks it, RL_ERR_ARG in *st. */
const rl_cluster *rl__check_cluster(const rl_cluster *cl, rl_status *st);

/* Solves the scene's maps as run's job says with `passes` passes (may be 0), reporting progress over
 * [0, span) of the run.
 * @return RL_OK and *out (rl_solution_destroy), or an error. */
rl_status rl__solve(const rl_scene *scene, const rl_cluster *cl, const rl__run *run, uint32_t passes, double span,
                    rl_solution **out);

/* @return the expected work of pass `pass` of a job with sampling s (rays; the sampling that pass uses)
 * gathering on `cells` cells from `emitters` emitters: the weight of its share of a run's progress. */
double rl__pass_work(const rl_sampling *s, uint32_t pass, double cells, double emitters);

/* @return the expected work of rl__solve() of run's job with `passes` passes, each pass's in
 * per_pass[0 .. passes) unless per_pass is NULL. */
double rl__solve_work(const rl_scene *scene, const rl__run *run, uint32_t passes, double *per_pass);

/* Casts the camera's rays through the centres of an nx x ny grid over its image (the scene has a camera):
 * *hits of them meet a surface, *back of those its back face. */
void rl__view_faces(const rl_solution *s, uint32_t nx, uint32_t ny, uint64_t *hits, uint64_t *back);

/* Builds the emitters of the scene itself (pass 0), its light fields reading `tables` (a solution's), with
 * room for `extra` more. @return the array (count in *n) or NULL when out of memory. */
rl_emitter *rl__primary_emitters(const rl_scene *scene, const rl_slab_tables *tables, size_t extra, size_t *n);

/* Appends to e (room assumed) one emitter per map that re-emits light (e_prev nonzero). @return the new count. */
size_t rl__append_bounce_emitters(const rl_scene *scene, const rl_map *maps, size_t nmaps, rl_emitter *e, size_t n);

/* What one pass gathers, from what, and where it stands in its run (rl__run_pass()). */
typedef struct rl__pass {
    const rl_scene *scene;
    const rl_tracer *tracer;
    const rl_cluster *cl;       /* the ranks sharing the pass, NULL for one process */
    const rl__run *run;         /* its job and run options */
    uint32_t pass;              /* its index in the run: keys its samples */
    uint32_t gather_level_pass; /* the partition level: 0 partition_n, else the bounce level; > 0 with
                                   sampling.bounce_rays > 0, the first-hit gather from the maps the emitters
                                   re-emit (bounce.c) for every polygon's map */
    rl_map *maps;               /* the receivers: nmaps maps (or points) */
    size_t nmaps;
    rl_map *with;               /* NULL, or nmaps more maps gathered in the same job (one process only, cl
                                   NULL), map m's tiles of both lying together, so that a reporting run
                                   finishes map m once both have */
    const rl_emitter *e;        /* the ne emitters */
    size_t ne;
    double base, span;          /* its place within the run's progress */
} rl__pass;

/* Runs one pass. With several ranks, *measured holds the previous pass's per-tile CPU times (NULL: none)
 * and receives this pass's; st receives its statistics. @return RL_OK or an error. */
rl_status rl__run_pass(const rl__pass *in, double **measured, rl_pass_stats *st);

#endif /* RELIGHT_ENGINE_INTERNAL_H */
