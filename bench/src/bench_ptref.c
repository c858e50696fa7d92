/*
 * bench_ptref.c - `ilf bench --reference pathtrace`: the independent
 * reference (bench_pathtrace.c) on a sample of the scene's cells, in place
 * of the converged solidangle runs of bench_ref.c.
 *
 * The cells are --reference-cells of them, evenly spaced over every cell in
 * the engine's order (cell g_s = floor((s + 1/2) C / S) of C), so every map
 * is sampled in proportion to its cells; each gets --reference-samples
 * paths of the run's bounces, seeded by its index. The engine itself is
 * run once, at one sample per cell and no bounce, only for the layout of
 * its maps (which cells exist, where, and on which polygon): no value of it
 * is read. A run's errors are then over the sampled cells alone (the other
 * cells' reference values are NaN), and the reference's error estimate is
 * the RMS of its cells' standard errors.
 *
 * The result is cached as one text file, CACHE/ref-<key>.pt, whose key (the
 * scene's bytes and files, as bench_ref.c's, and the settings) is its
 * second line; a file that does not parse whole, or carries another key, is
 * recomputed.
 *
 * Invariants: the path tracing runs in a child (bench_run.c's bench_fork),
 * so the parent never holds a ray tracer or a thread pool; the file is
 * written atomically.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench.h"
#include "ilf/message.h"
#include "bench_pathtrace.h"
#include "cli.h"
#include "ilf/pool.h"

#define PT_MAGIC "ilfkit pathtrace reference 1"
/* The seed every cell's stream starts from, mixed with its index. */
#define PT_SEED 0x9a7470ace0000001ull

/* One sampled cell: where it is, and its estimate. */
typedef struct pt_cell {
    size_t global;       /* index over every cell, in the engine's order */
    rl_map_info info;    /* its map (borrowing the layout solution) */
    uint32_t i, j;
    double centre[3];
    bench_pt_estimate e;
} pt_cell;

/* What the child needs, and what its workers share. */
typedef struct pt_job {
    rl_scene *scene;
    const bench_config *cfg;
    const char *path, *key;
    const bench_pt *pt;
    pt_cell *cells;
    uint32_t bounces;
} pt_job;

/* ilf_index_fn: path-traces sampled cell k. */
static void trace_cell(void *arg, size_t k)
{
    pt_job *job = arg;
    pt_cell *c = &job->cells[k];
    bench_pt_cell(job->pt, &c->info, c->i, c->j, c->centre, job->bounces, job->cfg->reference_samples,
                  PT_SEED ^ (c->global * 0x9e3779b97f4a7c15ull), &c->e);
}

/* Runs the engine cheaply for the layout of the maps. @return the solution, or NULL with the reason in r. */
static rl_solution *layout(const rl_scene *scene, const rl_job *given, bench_result *r)
{
    rl_job job = *given;
    job.sampling.method = RL_METHOD_AREA;
    job.sampling.samples_per_cell = 1;
    job.sampling.bounces = 0;
    rl_solution *sol = NULL;
    if (rl_relight(scene, &job, &sol) != RL_OK) {
        char line[sizeof r->message];
        snprintf(r->message, sizeof r->message, "layout of the maps: %s", cli_one_line(rl_errmsg(), line, sizeof line));
        return NULL;
    }
    return sol;
}

/* Fills the sampled cells' places from solution sol (count of total cells). @return 1, or 0 with the reason in r. */
static int place_cells(const rl_solution *sol, size_t total, pt_cell *cells, size_t count, bench_result *r)
{
    size_t s = 0, first = 0;
    for (size_t m = 0; s < count && m < rl_solution_map_count(sol); m++) {
        rl_map_info info;
        if (rl_solution_map_info(sol, m, &info) != RL_OK)
            return snprintf(r->message, sizeof r->message, "map %zu: no description", m), 0;
        size_t n = info.ncells;
        uint32_t *ij = malloc(2 * (n ? n : 1) * sizeof *ij);
        double *centre = malloc(3 * (n ? n : 1) * sizeof *centre);
        int ok = ij && centre && rl_solution_map_cells(sol, m, ij, NULL, centre, NULL, NULL) == RL_OK;
        for (; ok && s < count; s++) {
            size_t g = (size_t)(((double)s + 0.5) * (double)total / (double)count);
            if (g >= first + n)
                break;
            pt_cell *c = &cells[s];
            c->global = g;
            c->info = info;
            c->i = ij[2 * (g - first)];
            c->j = ij[2 * (g - first) + 1];
            memcpy(c->centre, centre + 3 * (g - first), sizeof c->centre);
        }
        free(ij);
        free(centre);
        if (!ok)
            return snprintf(r->message, sizeof r->message, "out of memory for map %zu's cells", m), 0;
        first += n;
    }
    return 1;
}

/* Writes the cache file: header, maps, then the sampled cells. @return 1, or 0 after reporting. */
static int write_cache(const pt_job *job, const rl_solution *sol, const pt_cell *cells, size_t count, size_t total,
                       const bench_result *r)
{
    bench_text t = {0};
    size_t maps = rl_solution_map_count(sol);
    bench_printf(&t, "%s\nkey %s\nbounces %" PRIu32 " paths %" PRIu32 " maps %zu cells %zu sampled %zu wall %.9g\n",
                 PT_MAGIC, job->key, job->bounces, job->cfg->reference_samples, maps, total, count, r->wall_seconds);
    for (size_t m = 0; m < maps; m++) {
        rl_map_info info;
        rl_solution_map_info(sol, m, &info);
        bench_printf(&t, "map %" PRIu32 " %" PRIu32 "\n", info.polygon, info.ncells);
    }
    for (size_t s = 0; s < count; s++)
        bench_printf(&t, "cell %zu %.9g %.9g\n", cells[s].global, cells[s].e.y, cells[s].e.y_se);
    int ok = bench_write_text(job->path, &t, "path-traced reference", 1);
    bench_text_free(&t);
    return ok;
}

/* bench_job_fn: the layout, the sampled cells path-traced, the cache file. */
static void pathtrace_child(void *arg, bench_result *out)
{
    pt_job *job = arg;
    job->bounces = job->cfg->job.sampling.bounces;
    rl_solution *sol = layout(job->scene, &job->cfg->job, out);
    if (sol == NULL)
        return;
    size_t total = 0;
    for (size_t m = 0; m < rl_solution_map_count(sol); m++) {
        rl_map_info info;
        if (rl_solution_map_info(sol, m, &info) == RL_OK)
            total += info.ncells;
    }
    size_t count = job->cfg->reference_cells < total ? job->cfg->reference_cells : total;
    char why[256] = "out of memory";
    job->cells = calloc(count ? count : 1, sizeof *job->cells);
    bench_pt *pt = job->cells != NULL ? bench_pt_new(job->scene, why, sizeof why) : NULL;
    int ok = pt != NULL;
    if (!ok)
        ilf_format_cut(out->message, sizeof out->message, "path tracer: %s", why);
    ok = ok && place_cells(sol, total, job->cells, count, out);
    if (ok) {
        job->pt = pt;
        double wall0 = cli_clock_seconds(CLOCK_MONOTONIC), cpu0 = cli_clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
        ilf_parallel_for(relight_threads_used(&job->cfg->job.run), count, trace_cell, job);
        out->wall_seconds = cli_clock_seconds(CLOCK_MONOTONIC) - wall0;
        out->cpu_seconds = cli_clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
        ok = write_cache(job, sol, job->cells, count, total, out);
        if (!ok)
            snprintf(out->message, sizeof out->message, "cannot write %s", job->path);
    }
    bench_pt_destroy(pt);
    free(job->cells);
    rl_solution_destroy(sol);
    out->ok = ok;
}

/* Reads the cache file at path into r if it parses whole and carries key. @return 1 when it does. */
static int read_cache(const char *path, const char *key, bench_reference *r)
{
    char *text = bench_read_text(path);
    if (text == NULL)
        return 0;
    char magic[64] = "", got[32] = "";
    uint32_t bounces = 0, paths = 0;
    size_t sampled = 0;
    int at = 0;
    int ok = sscanf(text, "%63[^\n]\nkey %31s\nbounces %" SCNu32 " paths %" SCNu32 " maps %zu cells %zu sampled %zu "
                          "wall %lf\n%n",
                    magic, got, &bounces, &paths, &r->maps, &r->cells, &sampled, &r->wall_seconds, &at) == 8 &&
             strcmp(magic, PT_MAGIC) == 0 && strcmp(got, key) == 0 && r->maps <= r->cells + 1 && sampled <= r->cells;
    const char *p = text + at;
    if (ok) {
        r->polygon = malloc((r->maps ? r->maps : 1) * sizeof *r->polygon);
        r->offset = malloc((r->maps + 1) * sizeof *r->offset);
        r->y = malloc((r->cells ? r->cells : 1) * sizeof *r->y);
        ok = r->polygon && r->offset && r->y;
    }
    if (ok) {
        r->offset[0] = 0;
        for (size_t c = 0; c < r->cells; c++)
            r->y[c] = NAN;
    }
    for (size_t m = 0; ok && m < r->maps; m++) {
        size_t n = 0;
        int used = 0;
        ok = sscanf(p, "map %" SCNu32 " %zu\n%n", &r->polygon[m], &n, &used) == 2 && used > 0;
        r->offset[m + 1] = r->offset[m] + n;
        ok = ok && r->offset[m + 1] <= r->cells;
        p += used;
    }
    ok = ok && r->offset[r->maps] == r->cells;
    double sum = 0.0, sum_se2 = 0.0;
    r->peak = 0.0;
    for (size_t s = 0; ok && s < sampled; s++) {
        size_t g = 0;
        double y = 0.0, se = 0.0;
        int used = 0;
        ok = sscanf(p, "cell %zu %lf %lf\n%n", &g, &y, &se, &used) == 3 && used > 0 && g < r->cells && isfinite(y) &&
             isfinite(se);
        if (ok) {
            r->y[g] = y;
            sum += y;
            sum_se2 += se * se;
            r->peak = y > r->peak ? y : r->peak;
        }
        p += used;
    }
    free(text);
    if (!ok) {
        bench_reference_free(r);
        return 0;
    }
    r->valued = sampled;
    r->mean = sampled > 0 ? sum / (double)sampled : 0.0;
    r->error = sampled > 0 ? sqrt(sum_se2 / (double)sampled) : 0.0;
    return 1;
}

int bench_reference_pathtrace(const bench_config *cfg, rl_scene *scene, bench_reference *r)
{
    memset(r, 0, sizeof *r);
    r->method = "pathtrace";
    r->samples = cfg->reference_samples;
    r->seeds[0] = PT_SEED;
    char settings[256], hex[17], name[64];
    snprintf(settings, sizeof settings, "method=pathtrace 1 cell_size=%.17g paths=%" PRIu32 " cells=%" PRIu32
             " bounces=%" PRIu32, cfg->job.cell_size, cfg->reference_samples, cfg->reference_cells,
             cfg->job.sampling.bounces);
    uint64_t key;
    if (!bench_reference_key(cfg, settings, &key) || !bench_make_folder(cfg->cache))
        return ILF_EXIT_USAGE;
    snprintf(hex, sizeof hex, "%016" PRIx64, key);
    snprintf(name, sizeof name, "ref-%s.pt", hex);
    if (!bench_path(r->path, cfg->cache, name))
        return ILF_EXIT_USAGE;
    r->cached = read_cache(r->path, hex, r);
    if (!r->cached) {
        if (!cfg->quiet)
            printf("reference: computing: pathtrace, %" PRIu32 " cells, %" PRIu32 " paths per cell, %" PRIu32
                   " bounces (not in the cache)\n", cfg->reference_cells, cfg->reference_samples,
                   cfg->job.sampling.bounces);
        pt_job job = {scene, cfg, r->path, hex, NULL, NULL, 0};
        bench_result res;
        if (!bench_fork(pathtrace_child, &job, &res) || !res.ok) {
            cli_error(BENCH_SUB, "reference: %s", res.message);
            return ILF_EXIT_FAILED;
        }
        if (!cfg->quiet)
            printf("reference: computed in %.2f s wall, %.2f s cpu, peak %.1f MiB\n", res.wall_seconds,
                   res.cpu_seconds, res.peak_mib);
        if (!read_cache(r->path, hex, r)) {
            cli_error(BENCH_SUB, "reference: cannot read back %s", r->path);
            return ILF_EXIT_FAILED;
        }
    }
    if (!cfg->quiet)
        printf("reference: %s %s: pathtrace, %zu of %zu cells, mean Y %.6g, peak %.6g, standard error (RMS) %.4g "
               "W m^-2 (%.3g%%)\n",
               r->cached ? "cached" : "stored", r->path, r->valued, r->cells, r->mean, r->peak, r->error,
               r->mean > 0 ? 100.0 * r->error / r->mean : NAN);
    return ILF_EXIT_OK;
}
