/*
 * bench_ref.c - the reference solution `ilf bench` measures errors against
 * (see bench.h): two converged `solidangle` runs with different seeds,
 * averaged; half the RMSE of their difference estimates the RMSE of the
 * average (each run's error has variance s^2, the difference 2 s^2, the
 * average s^2 / 2). The average is cached as a radiance-map file
 * (lfio/radmap.h), CACHE/ref-<key>.h5, with a sidecar CACHE/ref-<key>.json
 * holding the error estimate and the settings.
 *
 * The cache's key is bench_reference_key() (bench_refkey.c) over a line of
 * the reference settings: the cell size, method, samples, seeds, bounces,
 * bounce level, cell factor and rays, partition level and descent.
 *
 * Invariants: a cached reference is used only when both files read back
 * whole and the sidecar carries the same key; the computation runs in a
 * child (bench_run.c), so the parent only ever reads the cache; the maps of
 * a reference are in the engine's order, as every run's are.
 */
#include <cjson/cJSON.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench.h"
#include "ilf/message.h"
#include "cli.h"
#include "jsonout.h"
#include "lfio/radmap.h"

/* The two reference seeds: far from the small seeds scenes use, so no run shares its noise. */
static const uint64_t REFERENCE_SEEDS[2] = {0x5eed0001u, 0x5eed0002u};

/* @return the first-hit rays a cell the reference's bounce passes take: as many as its samples (a bounce
 * gather as converged as its direct pass), or 0 where the scene gathers bounces by its method. */
static uint32_t reference_bounce_rays(const bench_config *cfg, const rl_sampling *s)
{
    return s->bounce_rays > 0 ? cfg->reference_samples : 0;
}

/* Computes the cache key of the scene's solidangle reference with the given settings. @return 1, or 0 after reporting. */
static int reference_key(const bench_config *cfg, uint64_t *key)
{
    const rl_sampling *s = &cfg->job.sampling;
    char settings[512];
    snprintf(settings, sizeof settings,
             "cell_size=%.17g method=solidangle samples=%" PRIu32 " seeds=%" PRIu64 ",%" PRIu64
             " bounces=%" PRIu32 " bounce_partition_n=%" PRIu32 " bounce_cell_factor=%" PRIu32 " bounce_rays=%" PRIu32
             " partition_n=%" PRIu32
             " descend=%" PRIu32,
             cfg->job.cell_size, cfg->reference_samples, REFERENCE_SEEDS[0], REFERENCE_SEEDS[1], s->bounces,
             s->bounce_partition_n, s->bounce_cell_factor, reference_bounce_rays(cfg, s), s->partition_n,
             s->descend);
    return bench_reference_key(cfg, settings, key);
}

/* ------------------------------------------------------------ computing (in a child) */

/* What the reference child needs. */
typedef struct reference_job {
    rl_scene *scene;
    const bench_config *cfg;
    const char *h5, *json, *key;
} reference_job;

/* Every cell of both runs, flat, and the patches that borrow from it. */
typedef struct reference_arrays {
    size_t maps, cells;
    lfio_radmap_patch *patches;
    uint32_t *ij;
    double *area, *centre;
    float *irr, *rad, *irr_b, *rad_b;
} reference_arrays;

/* Releases the arrays of a. */
static void arrays_free(reference_arrays *a)
{
    free(a->patches);
    free(a->ij);
    free(a->area);
    free(a->centre);
    free(a->irr);
    free(a->rad);
    free(a->irr_b);
    free(a->rad_b);
}

/* Allocates a for the maps and cells of solution sol. @return 1, or 0 when memory runs out. */
static int arrays_alloc(reference_arrays *a, const rl_solution *sol)
{
    memset(a, 0, sizeof *a);
    a->maps = rl_solution_map_count(sol);
    for (size_t m = 0; m < a->maps; m++) {
        rl_map_info info;
        if (rl_solution_map_info(sol, m, &info) == RL_OK)
            a->cells += info.ncells;
    }
    size_t n = a->cells ? a->cells : 1;
    a->patches = calloc(a->maps ? a->maps : 1, sizeof *a->patches);
    a->ij = malloc(2 * n * sizeof *a->ij);
    a->area = malloc(n * sizeof *a->area);
    a->centre = malloc(3 * n * sizeof *a->centre);
    a->irr = malloc(3 * n * sizeof *a->irr);
    a->rad = malloc(3 * n * sizeof *a->rad);
    a->irr_b = malloc(3 * n * sizeof *a->irr_b);
    a->rad_b = malloc(3 * n * sizeof *a->rad_b);
    return a->patches && a->ij && a->area && a->centre && a->irr && a->rad && a->irr_b && a->rad_b;
}

/* Copies a map's frame, grid and material into patch p (its cell arrays are set by the caller). */
static void patch_frame(const rl_map_info *m, lfio_radmap_patch *p)
{
    p->label = m->label;
    p->polygon = m->polygon;
    p->nverts = m->nvertices;
    p->vertices = m->vertices;
    memcpy(p->origin, m->origin, sizeof p->origin);
    memcpy(p->e1, m->e1, sizeof p->e1);
    memcpy(p->e2, m->e2, sizeof p->e2);
    memcpy(p->normal, m->normal, sizeof p->normal);
    p->cell_size = m->cell_size;
    p->u0 = m->u0;
    p->v0 = m->v0;
    p->nu = m->nu;
    p->nv = m->nv;
    p->ncells = m->ncells;
    memcpy(p->albedo, m->albedo, sizeof p->albedo);
    memcpy(p->emission, m->emission, sizeof p->emission);
}

/* Fills a from runs sa and sb (the same maps). @return 1, or 0 with the reason in r. */
static int arrays_fill(reference_arrays *a, const rl_solution *sa, const rl_solution *sb, bench_result *r)
{
    size_t at = 0;
    for (size_t m = 0; m < a->maps; m++) {
        rl_map_info info, info_b;
        int ok = rl_solution_map_info(sa, m, &info) == RL_OK && rl_solution_map_info(sb, m, &info_b) == RL_OK &&
                 info.ncells == info_b.ncells &&
                 rl_solution_map_cells(sa, m, a->ij + 2 * at, a->area + at, a->centre + 3 * at, a->irr + 3 * at,
                                       a->rad + 3 * at) == RL_OK &&
                 rl_solution_map_cells(sb, m, NULL, NULL, NULL, a->irr_b + 3 * at, a->rad_b + 3 * at) == RL_OK;
        if (!ok) {
            snprintf(r->message, sizeof r->message, "the two reference runs differ in map %zu", m);
            return 0;
        }
        lfio_radmap_patch *p = &a->patches[m];
        patch_frame(&info, p);
        p->cell_ij = a->ij + 2 * at;
        p->cell_area = a->area + at;
        p->cell_centre = a->centre + 3 * at;
        p->irradiance = a->irr + 3 * at;
        p->radiosity = a->rad + 3 * at;
        at += info.ncells;
    }
    return 1;
}

/* Replaces run a's values by the mean of both runs and sets r's error estimate, mean and peak. */
static void average_runs(reference_arrays *a, bench_result *r)
{
    double sum_d2 = 0.0, sum_y = 0.0, peak = 0.0;
    for (size_t c = 0; c < a->cells; c++) {
        double d = bench_luminance(a->irr + 3 * c) - bench_luminance(a->irr_b + 3 * c);
        sum_d2 += d * d;
        for (int k = 0; k < 3; k++) {
            a->irr[3 * c + k] = 0.5f * (a->irr[3 * c + k] + a->irr_b[3 * c + k]);
            a->rad[3 * c + k] = 0.5f * (a->rad[3 * c + k] + a->rad_b[3 * c + k]);
        }
        double y = bench_luminance(a->irr + 3 * c);
        sum_y += y;
        peak = y > peak ? y : peak;
    }
    double n = a->cells > 0 ? (double)a->cells : 1.0;
    r->ref_error = 0.5 * sqrt(sum_d2 / n);
    r->ref_mean = sum_y / n;
    r->ref_peak = peak;
    r->cells = a->cells;
    r->maps = a->maps;
}

/* Writes the sidecar: key, settings, error estimate and time. @return 1, or 0 with the reason in r. */
static int write_sidecar(const reference_job *job, bench_result *r)
{
    cJSON *root = cJSON_CreateObject();
    double seeds[2] = {(double)REFERENCE_SEEDS[0], (double)REFERENCE_SEEDS[1]};
    char err[BENCH_PATH_MAX + 256] = "out of memory";
    int ok = root != NULL && cJSON_AddStringToObject(root, "key", job->key) &&
             cJSON_AddStringToObject(root, "creator", BENCH_CREATOR) &&
             cJSON_AddStringToObject(root, "scene", job->cfg->scene) &&
             cJSON_AddStringToObject(root, "method", "solidangle") &&
             cJSON_AddNumberToObject(root, "samples_per_cell", job->cfg->reference_samples) &&
             json_add_doubles(root, "seeds", seeds, 2) &&
             cJSON_AddNumberToObject(root, "bounces", job->cfg->job.sampling.bounces) &&
             cJSON_AddNumberToObject(root, "maps", (double)r->maps) &&
             cJSON_AddNumberToObject(root, "cells", (double)r->cells) &&
             cJSON_AddNumberToObject(root, "error_estimate_rmse", r->ref_error) &&
             cJSON_AddNumberToObject(root, "mean", r->ref_mean) && cJSON_AddNumberToObject(root, "peak", r->ref_peak) &&
             cJSON_AddNumberToObject(root, "wall_seconds", r->wall_seconds) &&
             cJSON_AddNumberToObject(root, "cpu_seconds", r->cpu_seconds);
    ok = ok && json_write_file(job->json, root, err, sizeof err);
    if (!ok)
        ilf_format_cut(r->message, sizeof r->message, "%s", err);
    cJSON_Delete(root);
    return ok;
}

/* Runs the reference once with seed, adding its time to r. @return the solution, or NULL (r says why). */
static rl_solution *reference_run(const reference_job *job, uint64_t seed, const char *label, bench_result *r)
{
    rl_job rj = job->cfg->job;
    rj.sampling.seed = seed;
    rj.sampling.bounce_rays = reference_bounce_rays(job->cfg, &rj.sampling);
    bench_result run;
    memset(&run, 0, sizeof run);
    bench_setting setting = {.method = RL_METHOD_SOLIDANGLE, .samples = job->cfg->reference_samples};
    rl_solution *sol = bench_relight_timed(job->scene, &rj, &setting, job->cfg->quiet ? NULL : label, &run);
    r->wall_seconds += run.wall_seconds;
    r->cpu_seconds += run.cpu_seconds;
    r->rays_cast += run.rays_cast;
    if (sol == NULL)
        memcpy(r->message, run.message, sizeof r->message);
    return sol;
}

/* bench_job_fn: computes the reference and writes both cache files. */
static void reference_child(void *arg, bench_result *out)
{
    const reference_job *job = arg;
    rl_solution *a = reference_run(job, REFERENCE_SEEDS[0], "reference 1/2", out);
    rl_solution *b = a != NULL ? reference_run(job, REFERENCE_SEEDS[1], "reference 2/2", out) : NULL;
    reference_arrays arr;
    memset(&arr, 0, sizeof arr);
    int ok = b != NULL;
    if (ok && !arrays_alloc(&arr, a)) {
        snprintf(out->message, sizeof out->message, "out of memory for the reference's cells");
        ok = 0;
    }
    ok = ok && arrays_fill(&arr, a, b, out);
    rl_solution_destroy(b);
    if (ok) {
        average_runs(&arr, out);
        lfio_status st = lfio_radmap_write(job->h5, BENCH_CREATOR, job->cfg->scene, arr.patches, arr.maps);
        if (st != LFIO_OK) {
            char line[sizeof out->message];
            snprintf(out->message, sizeof out->message, "%s", cli_one_line(lfio_errmsg(), line, sizeof line));
            ok = 0;
        }
    }
    ok = ok && write_sidecar(job, out);
    arrays_free(&arr);
    rl_solution_destroy(a);
    out->ok = ok;
}

/* ------------------------------------------------------------ loading */

/* Reads the sidecar into r if its key matches. @return 1 when it does. */
static int read_sidecar(const char *path, const char *key, bench_reference *r)
{
    char *text = bench_read_text(path);
    cJSON *root = text != NULL ? cJSON_Parse(text) : NULL;
    free(text);
    const cJSON *k = cJSON_GetObjectItemCaseSensitive(root, "key");
    const cJSON *e = cJSON_GetObjectItemCaseSensitive(root, "error_estimate_rmse");
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(root, "wall_seconds");
    int ok = cJSON_IsString(k) && strcmp(k->valuestring, key) == 0 && cJSON_IsNumber(e) && cJSON_IsNumber(t);
    if (ok) {
        r->error = e->valuedouble;
        r->wall_seconds = t->valuedouble;
    }
    cJSON_Delete(root);
    return ok;
}

/* Fills r's cells from radiance-map file path. @return 1, or 0 (quietly: a bad cache is recomputed). */
static int read_maps(const char *path, bench_reference *r)
{
    lfio_radmap *map = NULL;
    if (lfio_radmap_read(path, &map) != LFIO_OK)
        return 0;
    r->maps = lfio_radmap_count(map);
    r->cells = 0;
    lfio_radmap_patch p;
    for (size_t m = 0; m < r->maps; m++)
        if (lfio_radmap_get(map, m, &p) == LFIO_OK)
            r->cells += p.ncells;
    r->polygon = malloc((r->maps ? r->maps : 1) * sizeof *r->polygon);
    r->offset = malloc((r->maps + 1) * sizeof *r->offset);
    r->y = malloc((r->cells ? r->cells : 1) * sizeof *r->y);
    int ok = r->polygon && r->offset && r->y;
    double sum = 0.0;
    r->peak = 0.0;
    if (ok)
        r->offset[0] = 0;
    for (size_t m = 0; ok && m < r->maps; m++) {
        ok = lfio_radmap_get(map, m, &p) == LFIO_OK;
        r->polygon[m] = p.polygon;
        r->offset[m + 1] = r->offset[m] + p.ncells;
        for (uint32_t c = 0; ok && c < p.ncells; c++) {
            double y = bench_luminance(p.irradiance + 3 * c);
            r->y[r->offset[m] + c] = y;
            sum += y;
            r->peak = y > r->peak ? y : r->peak;
        }
    }
    r->mean = r->cells > 0 ? sum / (double)r->cells : 0.0;
    r->valued = r->cells;
    lfio_radmap_destroy(map);
    if (!ok)
        bench_reference_free(r);
    return ok;
}

/* Loads the cached reference into r. @return 1, or 0 when it is missing, stale or unreadable. */
static int load_cached(const char *h5, const char *json, const char *key, bench_reference *r)
{
    return read_sidecar(json, key, r) && read_maps(h5, r);
}

/* Computes the reference in a child and writes it to the cache. @return an exit code. */
static int compute(const bench_config *cfg, rl_scene *scene, const char *h5, const char *json, const char *key)
{
    if (!cfg->quiet)
        printf("reference: computing: solidangle, %" PRIu32 " samples per cell, seeds %" PRIu64 " and %" PRIu64
               " (not in the cache)\n",
               cfg->reference_samples, REFERENCE_SEEDS[0], REFERENCE_SEEDS[1]);
    reference_job job = {scene, cfg, h5, json, key};
    bench_result r;
    if (!bench_fork(reference_child, &job, &r) || !r.ok) {
        cli_error(BENCH_SUB, "reference: %s", r.message);
        return ILF_EXIT_FAILED;
    }
    if (!cfg->quiet)
        printf("reference: computed in %.2f s wall, %.2f s cpu, peak %.1f MiB\n", r.wall_seconds, r.cpu_seconds,
               r.peak_mib);
    return ILF_EXIT_OK;
}

int bench_reference_obtain(const bench_config *cfg, rl_scene *scene, bench_reference *r)
{
    if (cfg->reference_pathtrace)
        return bench_reference_pathtrace(cfg, scene, r);
    memset(r, 0, sizeof *r);
    r->method = "solidangle";
    uint64_t key;
    if (!reference_key(cfg, &key) || !bench_make_folder(cfg->cache))
        return ILF_EXIT_USAGE;
    char hex[17], name[64], json[BENCH_PATH_MAX];
    snprintf(hex, sizeof hex, "%016" PRIx64, key);
    snprintf(name, sizeof name, "ref-%s.h5", hex);
    if (!bench_path(r->path, cfg->cache, name))
        return ILF_EXIT_USAGE;
    snprintf(name, sizeof name, "ref-%s.json", hex);
    if (!bench_path(json, cfg->cache, name))
        return ILF_EXIT_USAGE;
    r->samples = cfg->reference_samples;
    memcpy(r->seeds, REFERENCE_SEEDS, sizeof r->seeds);
    r->cached = load_cached(r->path, json, hex, r);
    if (!r->cached) {
        int code = compute(cfg, scene, r->path, json, hex);
        if (code != ILF_EXIT_OK)
            return code;
        if (!load_cached(r->path, json, hex, r)) {
            cli_error(BENCH_SUB, "reference: cannot read back %s", r->path);
            return ILF_EXIT_FAILED;
        }
    }
    if (!cfg->quiet)
        printf("reference: %s %s: %zu maps, %zu cells, mean Y %.6g, peak %.6g, error estimate %.4g W m^-2\n",
               r->cached ? "cached" : "stored", r->path, r->maps, r->cells, r->mean, r->peak, r->error);
    return ILF_EXIT_OK;
}
