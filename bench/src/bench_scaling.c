/*
 * bench_scaling.c - `ilf bench --scaling SCENE -o DIR` (see bench.h): the
 * culled method's wall time and peak memory against the number of cells
 * (the scene's cell size times 2, 1.41, 1, 0.71 and 0.5) and against the
 * partition level n (8, 16, 32, 64, at the scene's cell size), each run in
 * its own child that loads its own scene, so its peak memory covers the
 * scene, the light fields, the maps and the engine's working memory.
 *
 * A run's cell size and partition level are fields of its job
 * (bench_relight_job.cell_size and its setting): the scene file is only read.
 * Exponents are least-squares fits of log time (and log memory) on log
 * cells and on log n. Outputs: scaling.csv, scaling.json, and the plots
 * scaling_cells.png and scaling_n.png (bench_plot.c).
 *
 * Invariants: this process only reads and writes files; as in the sweep, a
 * setting is skipped when the previous run of its series, scaled by the
 * nominal cost ratio (cells: 1 / factor^2; n: n^2), predicts more than
 * --time-limit.
 */
#include <cjson/cJSON.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"
#include "jsonout.h"

static const double CELL_FACTORS[] = {2.0, 1.41, 1.0, 0.71, 0.5};
static const uint32_t PARTITION_NS[] = {8, 16, 32, 64};
#define NFACTORS (sizeof CELL_FACTORS / sizeof CELL_FACTORS[0])
#define NPARTITIONS (sizeof PARTITION_NS / sizeof PARTITION_NS[0])

/* One run of a series. */
typedef struct scaling_point {
    double cell_size;
    uint32_t partition_n;
    double cost;          /* nominal, for predictions within the series */
    double predicted;     /* when skipped */
    int ran;
    bench_result result;
} scaling_point;

/* What the whole mode works with. */
typedef struct scaling_run {
    const bench_config *cfg;
    double cell_size;      /* the job's: the scene file's */
    uint32_t partition_n;  /* the job's: the scene file's or --partition-n */
    scaling_point cells[NFACTORS], ns[NPARTITIONS];
} scaling_run;

/* ------------------------------------------------------------ running */

/* Runs point p of a series (its cell size and partition level), unless the previous run predicts too long. */
static void run_point(const scaling_run *run, scaling_point *p, const scaling_point *prev)
{
    const bench_config *cfg = run->cfg;
    char label[96];
    if (prev != NULL && prev->ran && prev->result.ok)
        p->predicted = prev->result.wall_seconds * p->cost / prev->cost;
    snprintf(label, sizeof label, "culled n=%" PRIu32 " cell %.4g m", p->partition_n, p->cell_size);
    if (p->predicted > cfg->time_limit) {
        if (!cfg->quiet)
            printf("%s: skipped (predicted %.0f s > %.0f s)\n", label, p->predicted, cfg->time_limit);
        return;
    }
    bench_relight_job job = {.scene_path = cfg->scene,
                             .overrides = &cfg->sampling,
                             .cell_size = p->cell_size,
                             .setting = {.method = RL_METHOD_CULLED, .partition_n = p->partition_n, .cost = p->cost},
                             .label = cfg->quiet ? NULL : label};
    p->ran = 1;
    if (!bench_fork(bench_relight_child, &job, &p->result))
        p->result.ok = 0;
    if (cfg->quiet)
        return;
    if (p->result.ok)
        printf("%s: %" PRIu64 " cells, %.3f s wall, %.3f s cpu, %.1f MiB\n", label, p->result.cells,
               p->result.wall_seconds, p->result.cpu_seconds, p->result.peak_mib);
    else
        printf("%s: failed: %s\n", label, p->result.message);
}

/* Runs the cell-size series. @return 1, or 0 when a run failed. */
static int run_cells(scaling_run *run)
{
    int ok = 1;
    for (size_t k = 0; k < NFACTORS; k++) {
        scaling_point *p = &run->cells[k];
        p->cell_size = run->cell_size * CELL_FACTORS[k];
        p->partition_n = run->partition_n;
        p->cost = 1.0 / (CELL_FACTORS[k] * CELL_FACTORS[k]);
        run_point(run, p, k > 0 ? &run->cells[k - 1] : NULL);
        ok = ok && (!p->ran || p->result.ok);
    }
    return ok;
}

/* Runs the partition series at the job's cell size. @return 1, or 0 when a run failed. */
static int run_partitions(scaling_run *run)
{
    int ok = 1;
    for (size_t k = 0; k < NPARTITIONS; k++) {
        scaling_point *p = &run->ns[k];
        p->cell_size = run->cell_size;
        p->partition_n = PARTITION_NS[k];
        p->cost = (double)PARTITION_NS[k] * PARTITION_NS[k];
        run_point(run, p, k > 0 ? &run->ns[k - 1] : NULL);
        ok = ok && (!p->ran || p->result.ok);
    }
    return ok;
}

/* ------------------------------------------------------------ outputs */

/* Appends the CSV rows of a series. */
static void csv_series(bench_text *t, const char *series, const scaling_point *p, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        const bench_result *r = &p[k].result;
        if (!p[k].ran || !r->ok)
            continue;
        bench_printf(t, "%s,%.9g,%" PRIu32 ",%" PRIu64 ",%.6f,%.6f,%.2f,%" PRIu64 ",%.6g\n", series, p[k].cell_size,
                     p[k].partition_n, r->cells, r->wall_seconds, r->cpu_seconds, r->peak_mib, r->rays_cast,
                     r->cpu_seconds > 0 ? (double)r->rays_cast / r->cpu_seconds : 0.0);
    }
}

/* Fits and plots one series against x = cells or n. @return 1, or 0 after reporting. */
static int fit_and_plot(const scaling_run *run, const scaling_point *p, size_t n, int by_cells,
                        bench_scaling_series *s)
{
    double x[NFACTORS + NPARTITIONS], time[NFACTORS + NPARTITIONS], mib[NFACTORS + NPARTITIONS];
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        if (!p[k].ran || !p[k].result.ok)
            continue;
        x[m] = by_cells ? (double)p[k].result.cells : (double)p[k].partition_n;
        time[m] = p[k].result.wall_seconds;
        mib[m] = p[k].result.peak_mib;
        m++;
    }
    s->name = by_cells ? "scaling_cells" : "scaling_n";
    s->xlabel = by_cells ? "radiance-map cells" : "partition n (4 n^2 solid angles per hemisphere)";
    s->x = x;
    s->time = time;
    s->mib = mib;
    s->n = m;
    s->fitted = bench_fit_power(x, time, m, &s->time_a, &s->time_b) && bench_fit_power(x, mib, m, &s->mib_a, &s->mib_b);
    if (!run->cfg->quiet && s->fitted)
        printf("%s: time ~ x^%.3f, peak memory ~ x^%.3f (least squares in log-log over %zu runs)\n", s->name,
               s->time_b, s->mib_b, m);
    int ok = m == 0 || bench_plot_scaling(run->cfg->output, s, run->cfg->quiet);
    s->x = s->time = s->mib = NULL; /* they lived on this stack frame */
    return ok;
}

/* Adds a series' fit to the JSON object. */
static void fit_json(cJSON *root, const bench_scaling_series *s)
{
    cJSON *j = cJSON_AddObjectToObject(root, s->name);
    if (j == NULL)
        return;
    cJSON_AddNumberToObject(j, "runs", (double)s->n);
    if (s->fitted) {
        cJSON_AddNumberToObject(j, "time_exponent", s->time_b);
        cJSON_AddNumberToObject(j, "memory_exponent", s->mib_b);
    }
}

/* Writes scaling.csv and scaling.json, and draws both plots. @return 1, or 0 after reporting. */
static int write_outputs(const scaling_run *run)
{
    const bench_config *cfg = run->cfg;
    bench_text t = {0};
    char path[BENCH_PATH_MAX], err[BENCH_PATH_MAX + 256];
    bench_printf(&t, "series,cell_size,partition_n,cells,wall_seconds,cpu_seconds,peak_mib,rays_cast,"
                     "rays_per_cpu_second\n");
    csv_series(&t, "cells", run->cells, NFACTORS);
    csv_series(&t, "partition_n", run->ns, NPARTITIONS);
    int ok = bench_path(path, cfg->output, "scaling.csv") && bench_write_text(path, &t, "every scaling run", cfg->quiet);
    bench_text_free(&t);
    bench_scaling_series by_cells, by_n;
    memset(&by_cells, 0, sizeof by_cells);
    memset(&by_n, 0, sizeof by_n);
    ok = fit_and_plot(run, run->cells, NFACTORS, 1, &by_cells) && ok;
    ok = fit_and_plot(run, run->ns, NPARTITIONS, 0, &by_n) && ok;
    cJSON *root = cJSON_CreateObject();
    if (root != NULL) {
        cJSON_AddStringToObject(root, "creator", BENCH_CREATOR);
        cJSON_AddStringToObject(root, "scene", cfg->scene);
        cJSON_AddStringToObject(root, "command", cfg->command);
        cJSON_AddStringToObject(root, "fit", "least squares of log y on log x; y = wall seconds or peak MiB");
        fit_json(root, &by_cells);
        fit_json(root, &by_n);
    }
    if (root == NULL || !bench_path(path, cfg->output, "scaling.json") ||
        !json_write_file(path, root, err, sizeof err)) {
        cli_error(BENCH_SUB, "%s", root == NULL ? "out of memory" : err);
        ok = 0;
    } else if (!cfg->quiet) {
        printf("wrote %s: the fitted exponents\n", path);
    }
    cJSON_Delete(root);
    return ok;
}

/* ------------------------------------------------------------ entry */

/* Reads the job's cell size and partition level (loading the scene here and releasing it before any
 * fork). @return an exit code. */
static int prepare(scaling_run *run)
{
    rl_scene *scene = NULL;
    rl_job job;
    int code = relight_scene_open(BENCH_SUB, run->cfg->scene, &run->cfg->sampling, &scene, &job);
    if (code != ILF_EXIT_OK)
        return code;
    run->cell_size = job.cell_size;
    run->partition_n = job.sampling.partition_n;
    rl_scene_destroy(scene);
    return bench_make_folder(run->cfg->output) ? ILF_EXIT_OK : ILF_EXIT_FAILED;
}

int bench_scaling(const bench_config *cfg)
{
    static scaling_run run;
    memset(&run, 0, sizeof run);
    run.cfg = cfg;
    int code = prepare(&run);
    if (code == ILF_EXIT_OK) {
        int ok = run_cells(&run);
        ok = run_partitions(&run) && ok;
        ok = write_outputs(&run) && ok;
        code = ok ? ILF_EXIT_OK : ILF_EXIT_FAILED;
    }
    return code;
}
