/*
 * query.c - point queries (rl_irradiance, rl_irradiance_cluster): the
 * irradiance at given points, as Radiance's rtrace -I.
 *
 * Each point becomes a receiver of zero area facing its normal (rl__map_point),
 * and one more pass of the engine's pass runner (engine.c) gathers onto the
 * points from the scene's emitters and, with bounces, from the radiance maps
 * solved first, each re-emitting the irradiance summed over its passes.
 * Invariants: a point's answer depends only on the scene and the point (its
 * index keys its samples), never on threads, ranks or the other points.
 */
#include <math.h>
#include <stdlib.h>

#include "engine_internal.h"

/* Checks the points and builds one zero-area receiver per point. @return RL_OK or an error. */
static rl_status point_maps(const double *points, size_t count, rl_map **out)
{
    rl_map *maps = calloc(count ? count : 1, sizeof *maps);
    if (!maps)
        return rl__fail(RL_ERR_NOMEM, "out of memory for %zu points", count);
    for (size_t k = 0; k < count; k++) {
        v3 p = v3_load(points + 6 * k), n = v3_load(points + 6 * k + 3);
        double len = v3_len(n);
        if (!isfinite(v3_maxabs(p)) || !isfinite(len) || !(len > 0)) {
            rl__maps_free(maps, k);
            return rl__fail(RL_ERR_ARG, "point %zu: position and normal must be finite, normal nonzero", k + 1);
        }
        if (rl__map_point(p, v3_scale(n, 1.0 / len), &maps[k]) != RL_OK) {
            rl__maps_free(maps, k + 1);
            return rl__fail(RL_ERR_NOMEM, "out of memory for %zu points", count);
        }
    }
    *out = maps;
    return RL_OK;
}

rl_status rl_irradiance(const rl_scene *scene, const rl_job *job, const double *points, size_t count, double *out,
                        rl_pass_stats *stats)
{
    return rl_irradiance_cluster(scene, NULL, job, points, count, out, stats);
}

rl_status rl_irradiance_cluster(const rl_scene *scene, const rl_cluster *cluster, const rl_job *job,
                                const double *points, size_t count, double *out, rl_pass_stats *stats)
{
    if (!scene || (count > 0 && (!points || !out)))
        return rl__fail(RL_ERR_ARG, "rl_irradiance: NULL argument");
    rl_map *pts = NULL;
    rl_solution *sol = NULL;
    rl__run run;
    rl_status st = rl__job_resolve(scene, job, &run);
    const rl_cluster *cl = st == RL_OK ? rl__check_cluster(cluster, &st) : NULL;
    if (st != RL_OK)
        return st;
    st = point_maps(points, count, &pts);
    if (st != RL_OK)
        return st;
    /* Light reflected by the scene: solve `bounces` passes and let every lit
     * map re-emit the irradiance summed over them. */
    uint32_t bounces = run.sampling.bounces;
    /* the solve's share of the progress, by its expected work against the points' pass (engine.c) */
    double solve = rl__solve_work(scene, &run, bounces, NULL), receivers = 0.0, primary = 0.0;
    for (size_t k = 0; k < scene->npolygons; k++) {
        const rl_material *mat = &scene->materials[scene->polygons[k].material];
        receivers += mat->albedo[0] > 0 || mat->albedo[1] > 0 || mat->albedo[2] > 0;
        primary += mat->emission[0] > 0 || mat->emission[1] > 0 || mat->emission[2] > 0;
    }
    primary += (double)scene->nlightfields;
    double points_work = rl__pass_work(&run.sampling, 0, (double)count, primary + (bounces > 0 ? receivers : 0.0));
    double share = solve + points_work > 0 ? solve / (solve + points_work) : 0.0;
    run.maps_ready = NULL; /* these maps are the query's own */
    st = rl__solve(scene, cl, &run, bounces, share, &sol);
    size_t ne = 0;
    rl_emitter *e = st == RL_OK ? rl__primary_emitters(scene, sol->slab_tables, bounces > 0 ? sol->nmaps : 0, &ne) : NULL;
    if (st == RL_OK && !e)
        st = rl__fail(RL_ERR_NOMEM, "out of memory for emitters");
    /* the solved maps re-emit their total: rl__solve() settled them, e_prev naming e_total */
    if (st == RL_OK && bounces > 0)
        ne = rl__append_bounce_emitters(scene, sol->maps, sol->nmaps, e, ne);
    rl_pass_stats local;
    double *measured = NULL;
    /* the points' pass comes after the solve's passes, and gathers at partition_n */
    rl__pass in = {.scene = scene, .tracer = st == RL_OK ? sol->tracer : NULL, .cl = cl, .run = &run,
                   .pass = bounces, .gather_level_pass = 0, .maps = pts, .nmaps = count, .e = e, .ne = ne,
                   .base = share, .span = 1.0 - share};
    if (st == RL_OK)
        st = rl__run_pass(&in, &measured, stats ? stats : &local);
    free(measured);
    for (size_t k = 0; st == RL_OK && k < count; k++)
        for (int c = 0; c < 3; c++)
            out[3 * k + c] = pts[k].e_pass[0][c];
    if (st == RL_OK && run.progress)
        run.progress(run.user, 1.0);
    free(e);
    rl_solution_destroy(sol);
    rl__maps_free(pts, count);
    return st;
}
