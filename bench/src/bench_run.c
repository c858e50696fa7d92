/*
 * bench_run.c - one measured job of `ilf bench` in a forked child (see
 * bench.h): a relighting with its error against the reference, or the ray
 * ceiling. The child does the work and writes one fixed-size bench_result
 * to a pipe; the parent reads it and adds the child's peak resident memory
 * from wait4().
 *
 * Metrics, over every cell of every map, on the luminance Y of irradiance:
 * RMSE = sqrt(mean (Y - Yref)^2); relative RMSE = RMSE / mean Yref;
 * SNR = 10 log10(sum Yref^2 / sum (Y - Yref)^2) dB.
 *
 * Invariants: a child never returns into the parent's code: it ends with
 * _exit() right after its one write, so no atexit handler or stdio buffer
 * of the parent runs twice; the parent flushes its streams before forking;
 * a child that dies without a complete record is a failed run, never a hang
 * (the parent sees end of file on the pipe when the child is gone).
 */
#define _DEFAULT_SOURCE /* wait4 */

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bench.h"
#include "ilf/message.h"
#include "cli.h"
#include "ilf/atomic_file.h"
#include "jsonout.h"


const char *bench_setting_label(const bench_setting *s, char *buf, size_t size)
{
    if (s->method == RL_METHOD_CULLED || s->method == RL_METHOD_NAIVE)
        snprintf(buf, size, "%s n=%" PRIu32 " k=%" PRIu32, rl_method_name(s->method), s->partition_n, s->rays);
    else if (s->method == RL_METHOD_ADAPTIVE)
        snprintf(buf, size, "%s n=%" PRIu32 " e=%g", rl_method_name(s->method), s->partition_n, s->target_error);
    else
        snprintf(buf, size, "%s s=%" PRIu32, rl_method_name(s->method), s->samples);
    return buf;
}

void bench_reference_free(bench_reference *r)
{
    free(r->polygon);
    free(r->offset);
    free(r->y);
    r->polygon = NULL;
    r->offset = NULL;
    r->y = NULL;
}

/* ------------------------------------------------------------ forking */

/* Reads up to size bytes from fd until end of file. @return the bytes read. */
static size_t read_record(int fd, void *data, size_t size)
{
    char *p = data;
    size_t got = 0;
    while (got < size) {
        ssize_t n = read(fd, p + got, size - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        got += (size_t)n;
    }
    return got;
}

/* Fills r with the state a job starts from: nothing done, metrics unknown. */
static void result_init(bench_result *r)
{
    memset(r, 0, sizeof *r);
    r->rmse = r->rel_rmse = r->snr_db = r->mottling = NAN;
    r->ref_error = r->ref_mean = r->ref_peak = NAN;
}

/* Describes how a child that sent no record ended, in r->message. */
static void describe_death(bench_result *r, int status)
{
    r->ok = 0;
    if (WIFSIGNALED(status))
        snprintf(r->message, sizeof r->message, "the run was killed by signal %d (%s)", WTERMSIG(status),
                 WTERMSIG(status) == SIGKILL ? "out of memory?" : "crash");
    else
        snprintf(r->message, sizeof r->message, "the run ended with status %d without a result",
                 WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

int bench_fork(bench_job_fn job, void *arg, bench_result *out)
{
    int fds[2];
    result_init(out);
    if (pipe(fds) != 0) {
        snprintf(out->message, sizeof out->message, "cannot create a pipe: %s", strerror(errno));
        return 0;
    }
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(out->message, sizeof out->message, "cannot start a process: %s", strerror(errno));
        close(fds[0]);
        close(fds[1]);
        return 0;
    }
    if (pid == 0) {
        close(fds[0]);
        job(arg, out);
        int sent = ilf_write_all(fds[1], out, sizeof *out) == 0;
        fflush(NULL);
        _exit(sent ? 0 : 1);
    }
    close(fds[1]);
    size_t got = read_record(fds[0], out, sizeof *out);
    close(fds[0]);
    int status = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    while (wait4(pid, &status, 0, &ru) < 0 && errno == EINTR)
        ;
    if (got != sizeof *out) {
        result_init(out);
        describe_death(out, status);
    }
    out->peak_mib = (double)ru.ru_maxrss / 1024.0; /* Linux reports KiB */
    return 1;
}

/* ------------------------------------------------------------ in the child */


/* Records a failure of the engine in r, from rl_errmsg(). */
static void engine_failed(bench_result *r, const char *what)
{
    char line[sizeof r->message];
    r->ok = 0;
    snprintf(r->message, sizeof r->message, "%s: %s", what, cli_one_line(rl_errmsg(), line, sizeof line));
}

/* Applies setting s to the job's sampling. @return 1, or 0 with the reason in r. */
static int apply_setting(rl_job *job, const bench_setting *s, bench_result *r)
{
    rl_sampling smp = job->sampling;
    smp.method = s->method;
    if (s->partition_n > 0)
        smp.partition_n = s->partition_n;
    if (s->rays > 0)
        smp.rays_per_solid_angle = s->rays;
    if (s->samples > 0)
        smp.samples_per_cell = s->samples;
    if (s->target_error > 0)
        smp.target_error = s->target_error;
    job->sampling = smp;
    if (rl_job_check(job) != RL_OK) {
        engine_failed(r, "invalid settings");
        return 0;
    }
    return 1;
}

/* Relights scene, timing it and summing every pass's counters into r. @return the solution, or NULL (r says why). */
static rl_solution *timed_relight(const rl_scene *scene, const rl_job *job, const char *label, bench_result *r)
{
    cli_progress bar;
    if (label != NULL)
        cli_progress_start(&bar, label, CLI_PROGRESS_STEPS);
    rl_solution *sol = NULL;
    double wall0 = cli_clock_seconds(CLOCK_MONOTONIC), cpu0 = cli_clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
    rl_job shown = *job; /* with the bar */
    shown.run.progress = label != NULL ? cli_progress_fraction : NULL;
    shown.run.progress_user = &bar;
    rl_status st = rl_relight(scene, &shown, &sol);
    r->wall_seconds = cli_clock_seconds(CLOCK_MONOTONIC) - wall0;
    r->cpu_seconds = cli_clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
    if (label != NULL)
        cli_progress_finish(&bar);
    if (st != RL_OK) {
        engine_failed(r, "relighting failed");
        return NULL;
    }
    for (uint32_t k = 0; k < rl_solution_pass_count(sol); k++) {
        rl_pass_stats ps;
        if (rl_solution_pass_stats(sol, k, &ps) != RL_OK)
            continue;
        r->samples += ps.samples;
        r->rays_cast += ps.rays_cast;
        r->rays_kept += ps.rays_kept;
        r->solid_angles_considered += ps.solid_angles_considered;
        r->solid_angles_culled += ps.solid_angles_culled;
    }
    r->maps = rl_solution_map_count(sol);
    return sol;
}

/* Appends to d (room for two a cell) the relative second differences |y - (left + right) / 2| / y of
 * the n cells of a map of grid nu x nv, cells at ij ([n][2]), along rows and columns, for each lit cell
 * with both neighbours. grid is scratch of nu * nv entries. @return the number appended. */
static size_t second_differences(const uint32_t *ij, const double *y, size_t n, uint32_t nu, uint32_t nv,
                                 int32_t *grid, double *d)
{
    size_t k = 0;
    for (size_t g = 0; g < (size_t)nu * nv; g++)
        grid[g] = -1;
    for (size_t c = 0; c < n; c++)
        grid[(size_t)ij[2 * c + 1] * nu + ij[2 * c]] = (int32_t)c;
    for (size_t c = 0; c < n; c++) {
        uint32_t i = ij[2 * c], j = ij[2 * c + 1];
        size_t at = (size_t)j * nu + i;
        int32_t along[2][2] = {{i > 0 ? grid[at - 1] : -1, i + 1 < nu ? grid[at + 1] : -1},
                               {j > 0 ? grid[at - nu] : -1, j + 1 < nv ? grid[at + nu] : -1}};
        for (int a = 0; a < 2 && y[c] > 0.0; a++)
            if (along[a][0] >= 0 && along[a][1] >= 0)
                d[k++] = fabs(y[c] - 0.5 * (y[along[a][0]] + y[along[a][1]])) / y[c];
    }
    return k;
}

/* @return the order of two doubles (qsort()). */
static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, z = *(const double *)b;
    return (x > z) - (x < z);
}

/* Sets r->mottling from the relative second differences d[0, n) (sorted here). */
static void set_mottling(double *d, size_t n, bench_result *r)
{
    qsort(d, n, sizeof *d, by_value);
    r->mottling = n == 0 ? NAN : n % 2 ? d[n / 2] : 0.5 * (d[n / 2 - 1] + d[n / 2]);
}

/* Fills y (ref->cells entries) with the luminance of every cell's irradiance, checking that the
 * maps match the reference's, and sets r's mottling. @return 1, or 0 with the reason in r. */
static int solution_luminance(const rl_solution *sol, const bench_reference *ref, double *y, bench_result *r)
{
    if (rl_solution_map_count(sol) != ref->maps) {
        snprintf(r->message, sizeof r->message, "%zu maps, the reference has %zu", rl_solution_map_count(sol),
                 ref->maps);
        return 0;
    }
    float *rgb = NULL;
    uint32_t *ij = NULL;
    int32_t *grid = NULL;
    double *d = malloc(2 * (ref->cells ? ref->cells : 1) * sizeof *d);
    size_t nd = 0;
    int ok = d != NULL;
    if (!ok)
        snprintf(r->message, sizeof r->message, "out of memory for %zu cells", ref->cells);
    for (size_t m = 0; ok && m < ref->maps; m++) {
        rl_map_info info;
        size_t n = ref->offset[m + 1] - ref->offset[m];
        ok = rl_solution_map_info(sol, m, &info) == RL_OK && info.ncells == n && info.polygon == ref->polygon[m];
        if (!ok) {
            snprintf(r->message, sizeof r->message, "map %zu differs from the reference's", m);
            break;
        }
        float *grown = realloc(rgb, 3 * (n ? n : 1) * sizeof *rgb);
        rgb = grown != NULL ? grown : rgb;
        uint32_t *grown_ij = realloc(ij, 2 * (n ? n : 1) * sizeof *ij);
        ij = grown_ij != NULL ? grown_ij : ij;
        int32_t *grown_grid = realloc(grid, ((size_t)info.nu * info.nv + 1) * sizeof *grid);
        grid = grown_grid != NULL ? grown_grid : grid;
        ok = grown != NULL && grown_ij != NULL && grown_grid != NULL &&
             rl_solution_map_cells(sol, m, ij, NULL, NULL, rgb, NULL) == RL_OK;
        if (!ok) {
            snprintf(r->message, sizeof r->message, "cannot read the cells of map %zu", m);
            break;
        }
        for (size_t c = 0; c < n; c++)
            y[ref->offset[m] + c] = bench_luminance(rgb + 3 * c);
        nd += second_differences(ij, y + ref->offset[m], n, info.nu, info.nv, grid, d + nd);
    }
    if (ok)
        set_mottling(d, nd, r);
    free(rgb);
    free(ij);
    free(grid);
    free(d);
    return ok;
}

/* Sets r's RMSE, relative RMSE and SNR of y against the reference, over the cells it has a value for. */
static void error_metrics(const double *y, const bench_reference *ref, bench_result *r)
{
    double sum_err2 = 0.0, sum_ref2 = 0.0;
    size_t n = 0;
    for (size_t c = 0; c < ref->cells; c++) {
        if (!isfinite(ref->y[c]))
            continue; /* a cell the reference did not sample (pathtrace) */
        double d = y[c] - ref->y[c];
        sum_err2 += d * d;
        sum_ref2 += ref->y[c] * ref->y[c];
        n++;
    }
    r->cells = n;
    r->rmse = n > 0 ? sqrt(sum_err2 / (double)n) : 0.0;
    r->rel_rmse = ref->mean > 0.0 ? r->rmse / ref->mean : NAN;
    r->snr_db = sum_err2 > 0.0 ? 10.0 * log10(sum_ref2 / sum_err2) : INFINITY;
}

/* Writes the camera's view of |y - yref| / peak as float32 [height][width] (NaN where no cell is
 * seen) to path. @return 1, or 0 with the reason in r. */
static int write_error_image(const rl_solution *sol, const rl_scene *scene, const rl_run_options *ro,
                             const bench_reference *ref, const double *y, const char *path, bench_result *r)
{
    uint32_t w = 0, h = 0;
    if (!rl_scene_camera_size(scene, &w, &h))
        return 1;
    size_t count = (size_t)w * h;
    int32_t *map_ids = malloc(count * sizeof *map_ids), *cell_ids = malloc(count * sizeof *cell_ids);
    float *pixels = malloc(count * sizeof *pixels);
    int ok = map_ids && cell_ids && pixels && rl_solution_render_cells(sol, ro, map_ids, cell_ids) == RL_OK;
    double scale = ref->peak > 0.0 ? 1.0 / ref->peak : 0.0;
    for (size_t p = 0; ok && p < count; p++) {
        int seen = map_ids[p] >= 0 && (size_t)map_ids[p] < ref->maps && cell_ids[p] >= 0;
        size_t c = seen ? ref->offset[map_ids[p]] + (size_t)cell_ids[p] : 0;
        seen = seen && c < ref->offset[map_ids[p] + 1];
        pixels[p] = seen ? (float)(fabs(y[c] - ref->y[c]) * scale) : NAN;
    }
    char err[BENCH_PATH_MAX + 256] = "out of memory for the error image";
    if (ok && !file_write_atomic(path, pixels, count * sizeof *pixels, err, sizeof err))
        ok = 0;
    if (!ok)
        ilf_format_cut(r->message, sizeof r->message, "%s", err);
    free(map_ids);
    free(cell_ids);
    free(pixels);
    return ok;
}

/* Compares the solution with the reference: metrics, and the error image when asked. @return 1, or 0 (r says why). */
static int compare(const rl_solution *sol, const bench_relight_job *job, rl_scene *scene, const rl_run_options *ro,
                   bench_result *r)
{
    const bench_reference *ref = job->ref;
    double *y = malloc((ref->cells ? ref->cells : 1) * sizeof *y);
    int ok = y != NULL;
    if (!ok)
        snprintf(r->message, sizeof r->message, "out of memory for %zu cells", ref->cells);
    ok = ok && solution_luminance(sol, ref, y, r);
    if (ok)
        error_metrics(y, ref, r);
    if (ok && job->image_path != NULL)
        ok = write_error_image(sol, scene, ro, ref, y, job->image_path, r);
    free(y);
    return ok;
}

/* @return the number of cells of the solution. */
static uint64_t solution_cells(const rl_solution *sol)
{
    uint64_t cells = 0;
    for (size_t m = 0; m < rl_solution_map_count(sol); m++) {
        rl_map_info info;
        if (rl_solution_map_info(sol, m, &info) == RL_OK)
            cells += info.ncells;
    }
    return cells;
}

rl_solution *bench_relight_timed(const rl_scene *scene, const rl_job *job, const bench_setting *s, const char *label,
                                 bench_result *r)
{
    rl_job set = *job;
    return apply_setting(&set, s, r) ? timed_relight(scene, &set, label, r) : NULL;
}

void bench_relight_child(void *arg, bench_result *out)
{
    bench_relight_job *job = arg;
    rl_scene *scene = job->scene;
    rl_job rj;
    if (scene != NULL) {
        relight_job(job->overrides, scene, &rj);
    } else if (relight_scene_open(BENCH_SUB, job->scene_path, job->overrides, &scene, &rj) != ILF_EXIT_OK) {
        snprintf(out->message, sizeof out->message, "cannot load %s", job->scene_path);
        return;
    }
    if (job->cell_size > 0)
        rj.cell_size = job->cell_size;
    rl_solution *sol = bench_relight_timed(scene, &rj, &job->setting, job->label, out);
    if (sol != NULL) {
        out->cells = solution_cells(sol);
        out->ok = job->ref == NULL || compare(sol, job, scene, &rj.run, out);
    }
    rl_solution_destroy(sol);
    if (job->scene == NULL)
        rl_scene_destroy(scene);
}

void bench_rays_child(void *arg, bench_result *out)
{
    const bench_rays_job *job = arg;
    rl_ray_bench rb;
    rl_status st = rl_bench_rays(job->scene, &job->run, job->rays, &rb);
    out->cpu_seconds = rb.cpu_seconds; /* the tracing alone, not drawing the rays */
    if (st != RL_OK) {
        engine_failed(out, "ray benchmark failed");
        return;
    }
    out->wall_seconds = rb.wall_seconds;
    out->rays_cast = rb.rays;
    out->rays_kept = rb.rays - rb.occluded;
    out->ok = 1;
}

void bench_idle_child(void *arg, bench_result *out)
{
    (void)arg;
    out->ok = 1;
}
