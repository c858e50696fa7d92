/*
 * bench_report.c - what `ilf bench` makes of a sweep (see bench.h): each
 * method's Pareto front of wall time against RMSE, the comparisons of two
 * methods at equal error and at equal time along those fronts, and the
 * reports bench.csv, bench.json and summary.md.
 *
 * A run is on its method's front when no other run of that method is both
 * at least as fast and at least as accurate, and strictly better in one.
 * Between two points of a front, log RMSE is linear in log time. Methods A
 * and B (A listed first in --methods) are compared:
 *   - at equal error: at the smallest RMSE both fronts reach, the ratio of
 *     B's time to A's;
 *   - at equal time: at the longest time both fronts span, the ratio of B's
 *     RMSE to A's.
 * When the fronts do not overlap, the ratio is a bound ('>' or '<') from
 * their nearest ends, on the assumption that more time never makes a
 * method less accurate. Only runs the reference resolves -- RMSE at least
 * 10x the reference's own error estimate -- make fronts: below that, part
 * of a run's measured error is the reference's, and comparing such errors
 * would reward noise.
 *
 * Invariants: every number in a report comes from a run's record or from
 * the interpolation above; a run that failed or was skipped appears in
 * bench.json and summary.md with its reason but never in bench.csv, whose
 * rows hold only finite numbers apart from the method name.
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

/* A method's front: points sorted by time, RMSE strictly falling. */
#define FRONT_MAX 64
typedef struct front {
    size_t n;
    double t[FRONT_MAX], e[FRONT_MAX];
} front;

/* One comparison of B with A: at `at` (an RMSE or a time), A's and B's value and their ratio. */
typedef struct comparison {
    double at, a, b, ratio;
    char bound; /* '=' measured, '>' or '<' a bound, 0 nothing to compare */
} comparison;

/* ------------------------------------------------------------ fronts */

/* @return 1 when the entry ran, succeeded and has a positive time and error. */
static int usable(const bench_entry *e)
{
    return e->ran && e->result.ok && isfinite(e->result.rmse) && e->result.rmse > 0.0 &&
           e->result.wall_seconds > 0.0;
}

/* @return 1 when the reference's own error is at most a tenth of the entry's RMSE
 * (no estimate: always), so that the RMSE measures the run and not the reference. */
static int resolved(const bench_sweep *s, const bench_entry *e)
{
    return !isfinite(s->ref->error) || s->ref->error * 10.0 <= e->result.rmse;
}

/* @return 1 when the entry takes part in fronts and comparisons: usable and resolved. */
static int comparable(const bench_sweep *s, const bench_entry *e)
{
    return usable(e) && resolved(s, e);
}

/* @return 1 when entry a dominates b: no slower, no less accurate, better in one. */
static int dominates(const bench_entry *a, const bench_entry *b)
{
    double ta = a->result.wall_seconds, tb = b->result.wall_seconds, ea = a->result.rmse, eb = b->result.rmse;
    return ta <= tb && ea <= eb && (ta < tb || ea < eb);
}

void bench_mark_fronts(bench_sweep *s)
{
    for (size_t i = 0; i < s->count; i++) {
        bench_entry *e = &s->entries[i];
        e->on_front = comparable(s, e);
        for (size_t j = 0; e->on_front && j < s->count; j++)
            if (j != i && comparable(s, &s->entries[j]) && s->entries[j].setting.method == e->setting.method &&
                dominates(&s->entries[j], e))
                e->on_front = 0;
    }
}

/* Fills f with method m's front, sorted by time. */
static void front_of(const bench_sweep *s, rl_method m, front *f)
{
    f->n = 0;
    for (size_t i = 0; i < s->count && f->n < FRONT_MAX; i++) {
        const bench_entry *e = &s->entries[i];
        if (!e->on_front || e->setting.method != m)
            continue;
        size_t k = f->n++;
        while (k > 0 && f->t[k - 1] > e->result.wall_seconds) {
            f->t[k] = f->t[k - 1];
            f->e[k] = f->e[k - 1];
            k--;
        }
        f->t[k] = e->result.wall_seconds;
        f->e[k] = e->result.rmse;
    }
}

/* @return y at x on the log-log line through (x0, y0) and (x1, y1). */
static double loglog(double x0, double y0, double x1, double y1, double x)
{
    if (x1 == x0)
        return y0;
    double u = (log(x) - log(x0)) / (log(x1) - log(x0));
    return exp(log(y0) + u * (log(y1) - log(y0)));
}

/* @return the front's RMSE at time t, NaN outside its times. */
static double error_at(const front *f, double t)
{
    for (size_t k = 0; k + 1 < f->n; k++)
        if (t >= f->t[k] && t <= f->t[k + 1])
            return loglog(f->t[k], f->e[k], f->t[k + 1], f->e[k + 1], t);
    return f->n > 0 && t == f->t[0] ? f->e[0] : NAN;
}

/* @return the front's time to reach RMSE e, NaN outside its errors. */
static double time_at(const front *f, double e)
{
    for (size_t k = 0; k + 1 < f->n; k++)
        if (e <= f->e[k] && e >= f->e[k + 1])
            return loglog(f->e[k], f->t[k], f->e[k + 1], f->t[k + 1], e);
    return f->n > 0 && e == f->e[0] ? f->t[0] : NAN;
}

/* @return B against A at equal error (see the file's comment). */
static comparison at_equal_error(const front *A, const front *B)
{
    comparison c = {NAN, NAN, NAN, NAN, 0};
    if (A->n == 0 || B->n == 0)
        return c;
    double a_min = A->e[A->n - 1], a_max = A->e[0], b_min = B->e[B->n - 1], b_max = B->e[0];
    if (fmax(a_min, b_min) <= fmin(a_max, b_max)) {
        c.at = fmax(a_min, b_min);
        c.a = time_at(A, c.at);
        c.b = time_at(B, c.at);
        c.bound = '=';
    } else if (a_max < b_min) { /* A beats B's best error already at its fastest */
        c.at = b_min;
        c.a = A->t[0];
        c.b = B->t[B->n - 1];
        c.bound = '>';
    } else {
        c.at = a_min;
        c.a = A->t[A->n - 1];
        c.b = B->t[0];
        c.bound = '<';
    }
    c.ratio = c.b / c.a;
    return c;
}

/* @return B against A at equal time (see the file's comment). */
static comparison at_equal_time(const front *A, const front *B)
{
    comparison c = {NAN, NAN, NAN, NAN, 0};
    if (A->n == 0 || B->n == 0)
        return c;
    double a_min = A->t[0], a_max = A->t[A->n - 1], b_min = B->t[0], b_max = B->t[B->n - 1];
    if (fmax(a_min, b_min) <= fmin(a_max, b_max)) {
        c.at = fmin(a_max, b_max);
        c.a = error_at(A, c.at);
        c.b = error_at(B, c.at);
        c.bound = '=';
    } else if (a_max < b_min) { /* A is done before B starts: A's best error bounds A at B's fastest */
        c.at = b_min;
        c.a = A->e[A->n - 1];
        c.b = B->e[0];
        c.bound = '>';
    } else {
        c.at = a_min;
        c.a = A->e[0];
        c.b = B->e[B->n - 1];
        c.bound = '<';
    }
    c.ratio = c.b / c.a;
    return c;
}

/* ------------------------------------------------------------ shared helpers */

/* @return the best (smallest) RMSE of any usable run, or NaN. */
static double best_rmse(const bench_sweep *s)
{
    double best = NAN;
    for (size_t i = 0; i < s->count; i++)
        if (usable(&s->entries[i]) && !(s->entries[i].result.rmse >= best))
            best = s->entries[i].result.rmse;
    return best;
}

/* @return 1 when the reference's own error is at least 10x below the best RMSE compared. */
static int reference_adequate(const bench_sweep *s)
{
    double best = best_rmse(s);
    return !isfinite(best) || s->ref->error * 10.0 <= best;
}

/* @return the engine's rays per CPU second of a result, 0 without CPU time. */
static double rays_per_cpu_second(const bench_result *r)
{
    return r->cpu_seconds > 0.0 ? (double)r->rays_cast / r->cpu_seconds : 0.0;
}

/* @return a result's rays per CPU second as a fraction of the ray ceiling's, NaN without a ceiling. */
static double of_ceiling(const bench_sweep *s, const bench_result *r)
{
    double ceiling = s->ceiling.ok ? rays_per_cpu_second(&s->ceiling) : 0.0;
    return ceiling > 0.0 ? rays_per_cpu_second(r) / ceiling : NAN;
}

/* @return what happened to an entry: "ok", "failed" or "skipped". */
static const char *entry_status(const bench_entry *e)
{
    return !e->ran ? "skipped" : e->result.ok ? "ok" : "failed";
}

/* Calls visit for every pair (A, B) of methods with A before B in --methods and a front each. */
static void for_each_pair(const bench_sweep *s, void (*visit)(void *user, rl_method a, rl_method b,
                                                           const comparison *err, const comparison *time),
                          void *user)
{
    const bench_config *cfg = s->cfg;
    for (size_t i = 0; i < cfg->nmethods; i++) {
        front A;
        front_of(s, cfg->methods[i], &A);
        for (size_t j = i + 1; A.n > 0 && j < cfg->nmethods; j++) {
            front B;
            front_of(s, cfg->methods[j], &B);
            if (B.n == 0)
                continue;
            comparison e = at_equal_error(&A, &B), t = at_equal_time(&A, &B);
            visit(user, cfg->methods[i], cfg->methods[j], &e, &t);
        }
    }
}

/* ------------------------------------------------------------ bench.csv */

/* The CSV's columns, in order. */
static const char CSV_HEADER[] =
    "method,partition_n,rays_per_solid_angle,samples_per_cell,target_error,bounces,threads,wall_seconds,cpu_seconds,"
    "samples,rays_cast,rays_kept,solid_angles_considered,solid_angles_culled,cells,peak_mib,rays_per_cpu_second,"
    "rmse,rel_rmse,snr_db,pareto,ref_error_rmse,ref_adequate,mottling\n";

/* Appends one CSV row for a usable entry. */
static void csv_row(bench_text *t, const bench_sweep *s, const bench_entry *e)
{
    const bench_setting *st = &e->setting;
    const bench_result *r = &e->result;
    bench_printf(t, "%s,%" PRIu32 ",%" PRIu32 ",%" PRIu32 ",%g,%" PRIu32 ",%u,%.6f,%.6f,", rl_method_name(st->method),
                 st->partition_n, st->rays, st->samples, st->target_error, s->bounces, s->threads, r->wall_seconds,
                 r->cpu_seconds);
    bench_printf(t, "%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%" PRIu64 ",%.2f,%.6g,", r->samples,
                 r->rays_cast, r->rays_kept, r->solid_angles_considered, r->solid_angles_culled, r->cells, r->peak_mib,
                 rays_per_cpu_second(r));
    bench_printf(t, "%.9g,%.9g,%.4f,%d,%.9g,%d,%.6g\n", r->rmse, r->rel_rmse, r->snr_db, e->on_front, s->ref->error,
                 resolved(s, e), r->mottling);
}

/* Writes DIR/bench.csv. @return 1, or 0 after reporting. */
static int write_csv(const bench_sweep *s)
{
    bench_text t = {0};
    char path[BENCH_PATH_MAX];
    bench_printf(&t, "%s", CSV_HEADER);
    size_t rows = 0;
    for (size_t i = 0; i < s->count; i++)
        if (usable(&s->entries[i]) && isfinite(s->entries[i].result.snr_db)) {
            csv_row(&t, s, &s->entries[i]);
            rows++;
        }
    char what[64];
    snprintf(what, sizeof what, "%zu run%s", rows, rows == 1 ? "" : "s");
    int ok = bench_path(path, s->cfg->output, "bench.csv") && bench_write_text(path, &t, what, s->cfg->quiet);
    bench_text_free(&t);
    return ok;
}

/* ------------------------------------------------------------ bench.json */

/* Adds key = number, or null when it is not finite. */
static void add_number(cJSON *obj, const char *key, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(obj, key, v);
    else
        cJSON_AddNullToObject(obj, key);
}

/* @return one entry as a JSON object (NULL when memory runs out). */
static cJSON *entry_json(const bench_sweep *s, const bench_entry *e)
{
    cJSON *j = cJSON_CreateObject();
    if (j == NULL)
        return NULL;
    const bench_result *r = &e->result;
    cJSON_AddStringToObject(j, "method", rl_method_name(e->setting.method));
    cJSON_AddNumberToObject(j, "partition_n", e->setting.partition_n);
    cJSON_AddNumberToObject(j, "rays_per_solid_angle", e->setting.rays);
    cJSON_AddNumberToObject(j, "samples_per_cell", e->setting.samples);
    cJSON_AddNumberToObject(j, "target_error", e->setting.target_error);
    cJSON_AddStringToObject(j, "status", entry_status(e));
    if (!e->ran) {
        add_number(j, "predicted_seconds", e->predicted);
        return j;
    }
    if (!r->ok)
        cJSON_AddStringToObject(j, "message", r->message);
    add_number(j, "wall_seconds", r->wall_seconds);
    add_number(j, "cpu_seconds", r->cpu_seconds);
    cJSON_AddNumberToObject(j, "samples", (double)r->samples);
    cJSON_AddNumberToObject(j, "rays_cast", (double)r->rays_cast);
    cJSON_AddNumberToObject(j, "rays_kept", (double)r->rays_kept);
    cJSON_AddNumberToObject(j, "solid_angles_considered", (double)r->solid_angles_considered);
    cJSON_AddNumberToObject(j, "solid_angles_culled", (double)r->solid_angles_culled);
    cJSON_AddNumberToObject(j, "cells", (double)r->cells);
    add_number(j, "peak_mib", r->peak_mib);
    add_number(j, "rays_per_cpu_second", rays_per_cpu_second(r));
    add_number(j, "fraction_of_ray_ceiling", of_ceiling(s, r));
    add_number(j, "rmse", r->rmse);
    add_number(j, "rel_rmse", r->rel_rmse);
    add_number(j, "mottling", r->mottling);
    add_number(j, "snr_db", r->snr_db);
    cJSON_AddBoolToObject(j, "pareto", e->on_front);
    return j;
}

/* @return a comparison as a JSON object (NULL when memory runs out). */
static cJSON *comparison_json(const comparison *c, const char *at_key, const char *value_key)
{
    cJSON *j = cJSON_CreateObject();
    if (j == NULL)
        return NULL;
    char bound[2] = {c->bound, '\0'};
    char a_key[48], b_key[48];
    snprintf(a_key, sizeof a_key, "a_%s", value_key);
    snprintf(b_key, sizeof b_key, "b_%s", value_key);
    add_number(j, at_key, c->at);
    add_number(j, a_key, c->a);
    add_number(j, b_key, c->b);
    add_number(j, "ratio_b_over_a", c->ratio);
    cJSON_AddStringToObject(j, "ratio_is", c->bound == '=' ? "measured" : c->bound == '>' ? "lower bound" : "upper bound");
    cJSON_AddStringToObject(j, "bound", bound);
    return j;
}

/* for_each_pair visitor: appends the pair's comparisons to a JSON array. */
static void pair_json(void *user, rl_method a, rl_method b, const comparison *err, const comparison *time)
{
    cJSON *arr = user, *j = cJSON_CreateObject();
    if (j == NULL)
        return;
    cJSON_AddStringToObject(j, "a", rl_method_name(a));
    cJSON_AddStringToObject(j, "b", rl_method_name(b));
    cJSON *e = comparison_json(err, "rmse", "seconds"), *t = comparison_json(time, "seconds", "rmse");
    if (e != NULL)
        cJSON_AddItemToObject(j, "equal_error", e);
    if (t != NULL)
        cJSON_AddItemToObject(j, "equal_time", t);
    cJSON_AddItemToArray(arr, j);
}

/* @return the reference as a JSON object. */
static cJSON *reference_json(const bench_sweep *s)
{
    const bench_reference *ref = s->ref;
    cJSON *j = cJSON_CreateObject();
    if (j == NULL)
        return NULL;
    double seeds[2] = {(double)ref->seeds[0], (double)ref->seeds[1]};
    cJSON_AddStringToObject(j, "path", ref->path);
    cJSON_AddBoolToObject(j, "cached", ref->cached);
    cJSON_AddStringToObject(j, "method", ref->method);
    cJSON_AddNumberToObject(j, "cells_with_values", (double)ref->valued);
    cJSON_AddNumberToObject(j, "samples_per_cell", ref->samples);
    json_add_doubles(j, "seeds", seeds, 2);
    cJSON_AddNumberToObject(j, "cells", (double)ref->cells);
    add_number(j, "mean", ref->mean);
    add_number(j, "peak", ref->peak);
    add_number(j, "error_estimate_rmse", ref->error);
    add_number(j, "wall_seconds", ref->wall_seconds);
    cJSON_AddBoolToObject(j, "ten_times_below_best", reference_adequate(s));
    return j;
}

/* @return the ray ceiling as a JSON object, or JSON null without one. */
static cJSON *ceiling_json(const bench_sweep *s)
{
    const bench_result *c = &s->ceiling;
    if (!c->ok)
        return cJSON_CreateNull();
    cJSON *j = cJSON_CreateObject();
    if (j == NULL)
        return NULL;
    cJSON_AddNumberToObject(j, "rays", (double)c->rays_cast);
    add_number(j, "wall_seconds", c->wall_seconds);
    add_number(j, "cpu_seconds", c->cpu_seconds);
    add_number(j, "rays_per_second", c->wall_seconds > 0 ? (double)c->rays_cast / c->wall_seconds : NAN);
    add_number(j, "rays_per_cpu_second", rays_per_cpu_second(c));
    return j;
}

/* @return the whole bench.json document, or NULL when memory runs out. */
static cJSON *sweep_json(const bench_sweep *s)
{
    cJSON *root = cJSON_CreateObject();
    if (root == NULL)
        return NULL;
    cJSON_AddStringToObject(root, "creator", BENCH_CREATOR);
    cJSON_AddStringToObject(root, "scene", s->cfg->scene);
    cJSON_AddStringToObject(root, "command", s->cfg->command);
    cJSON_AddNumberToObject(root, "threads", s->threads);
    cJSON_AddNumberToObject(root, "bounces", s->bounces);
    cJSON_AddBoolToObject(root, "quick", s->cfg->quick);
    cJSON_AddNumberToObject(root, "time_limit_seconds", s->cfg->time_limit);
    cJSON_AddStringToObject(root, "metric", "luminance Y = 0.2126 R + 0.7152 G + 0.0722 B of irradiance, every cell");
    cJSON_AddStringToObject(root, "snr_definition", "10 log10(sum Yref^2 / sum (Y - Yref)^2) dB");
    cJSON *ref = reference_json(s), *ceiling = ceiling_json(s), *runs = cJSON_CreateArray(),
          *pairs = cJSON_CreateArray();
    if (ref == NULL || ceiling == NULL || runs == NULL || pairs == NULL) {
        cJSON_Delete(ref);
        cJSON_Delete(ceiling);
        cJSON_Delete(runs);
        cJSON_Delete(pairs);
        cJSON_Delete(root);
        return NULL;
    }
    cJSON_AddItemToObject(root, "reference", ref);
    cJSON_AddItemToObject(root, "ray_ceiling", ceiling);
    add_number(root, "baseline_peak_mib", s->baseline.ok ? s->baseline.peak_mib : NAN);
    cJSON_AddItemToObject(root, "runs", runs);
    cJSON_AddItemToObject(root, "comparisons", pairs);
    for (size_t i = 0; i < s->count; i++)
        cJSON_AddItemToArray(runs, entry_json(s, &s->entries[i]));
    for_each_pair(s, pair_json, pairs);
    return root;
}

/* Writes DIR/bench.json. @return 1, or 0 after reporting. */
static int write_json(const bench_sweep *s)
{
    char path[BENCH_PATH_MAX], err[BENCH_PATH_MAX + 256];
    cJSON *root = sweep_json(s);
    int ok = root != NULL && bench_path(path, s->cfg->output, "bench.json");
    if (root == NULL)
        cli_error(BENCH_SUB, "out of memory while building bench.json");
    else if (ok && !json_write_file(path, root, err, sizeof err)) {
        cli_error(BENCH_SUB, "%s", err);
        ok = 0;
    } else if (ok && !s->cfg->quiet) {
        printf("wrote %s: settings, reference, every run and the comparisons\n", path);
    }
    cJSON_Delete(root);
    return ok;
}

/* ------------------------------------------------------------ summary.md */

/* Appends the header: scene, command, machine settings and the reference. */
static void md_header(bench_text *t, const bench_sweep *s)
{
    const bench_reference *ref = s->ref;
    bench_printf(t, "# ilf bench: %s\n\n", s->cfg->scene);
    bench_printf(t, "Command: `%s`\n\n", s->cfg->command);
    bench_printf(t, "%u thread%s, %" PRIu32 " bounce%s, time limit %.0f s per run%s.\n\n", s->threads,
                 s->threads == 1 ? "" : "s", s->bounces, s->bounces == 1 ? "" : "s", s->cfg->time_limit,
                 s->cfg->quick ? ", --quick" : "");
    bench_printf(t, "## Reference\n\n");
    if (strcmp(ref->method, "pathtrace") == 0) {
        bench_printf(t, "Independent path tracing (`--reference pathtrace`), %" PRIu32 " paths per cell on %zu of the "
                        "%zu cells, %.1f s wall to compute; %s `%s`. Errors are over these cells alone.\n\n",
                     ref->samples, ref->valued, ref->cells, ref->wall_seconds,
                     ref->cached ? "read from the cache" : "computed by this run and cached in", ref->path);
        bench_printf(t, "- mean Y %.6g W m^-2, peak %.6g W m^-2 over the sampled cells\n", ref->mean, ref->peak);
        bench_printf(t, "- own error estimate: RMS standard error %.4g W m^-2 (%.3g%% of the mean)\n\n", ref->error,
                     ref->mean > 0 ? 100.0 * ref->error / ref->mean : NAN);
    } else {
        bench_printf(t, "Mean of two `solidangle` runs, %" PRIu32 " samples per (cell, emitter), seeds %" PRIu64
                        " and %" PRIu64 ", %.1f s wall to compute; %s `%s`.\n\n",
                     ref->samples, ref->seeds[0], ref->seeds[1], ref->wall_seconds,
                     ref->cached ? "read from the cache" : "computed by this run and cached in", ref->path);
        bench_printf(t, "- cells: %zu; mean Y %.6g W m^-2, peak %.6g W m^-2\n", ref->cells, ref->mean, ref->peak);
        bench_printf(t, "- own error estimate RMSE(a - b) / 2 = %.4g W m^-2 (%.3g%% of the mean)\n\n", ref->error,
                     ref->mean > 0 ? 100.0 * ref->error / ref->mean : NAN);
    }
    size_t unresolved = 0;
    for (size_t i = 0; i < s->count; i++)
        unresolved += usable(&s->entries[i]) && !resolved(s, &s->entries[i]);
    if (unresolved > 0)
        bench_printf(t, "**Note:** %zu run%s reached an RMSE below 10x the reference's error estimate (best %.4g): "
                        "their errors are partly the reference's own, so they are listed as `unresolved` and left "
                        "out of the fronts and comparisons. Raise --reference-samples to compare them.\n\n",
                     unresolved, unresolved == 1 ? "" : "s", best_rmse(s));
}

/* Appends the ray ceiling section. */
static void md_ceiling(bench_text *t, const bench_sweep *s)
{
    const bench_result *c = &s->ceiling;
    bench_printf(t, "## Ray ceiling\n\n");
    if (!c->ok) {
        bench_printf(t, "Not measured%s%s.\n\n", c->message[0] ? ": " : "", c->message);
        return;
    }
    bench_printf(t, "`rl_bench_rays`: %" PRIu64 " random shadow rays in %.3f s wall, %.3f s cpu: %.3g rays/s, %.3g "
                    "rays per cpu second.\n\n",
                 c->rays_cast, c->wall_seconds, c->cpu_seconds, (double)c->rays_cast / c->wall_seconds,
                 rays_per_cpu_second(c));
}

/* Appends the table of runs and the skipped and failed settings. */
static void md_runs(bench_text *t, const bench_sweep *s)
{
    bench_printf(t, "## Runs\n\n| setting | wall s | cpu s | rays cast | rays kept | rays / cpu s | of ceiling | "
                    "peak MiB | RMSE | rel. RMSE | SNR dB | mottling | front |\n"
                    "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:-:|\n");
    for (size_t i = 0; i < s->count; i++) {
        const bench_entry *e = &s->entries[i];
        const bench_result *r = &e->result;
        char label[64];
        if (!usable(e))
            continue;
        bench_printf(t, "| %s | %.3f | %.3f | %" PRIu64 " | %" PRIu64 " | %.3g | %.0f%% | %.1f | %.4g | %.3g%% | %.2f | %.3g%% | %s |\n",
                     bench_setting_label(&e->setting, label, sizeof label), r->wall_seconds, r->cpu_seconds,
                     r->rays_cast, r->rays_kept, rays_per_cpu_second(r), 100.0 * of_ceiling(s, r), r->peak_mib,
                     r->rmse, 100.0 * r->rel_rmse, r->snr_db, 100.0 * r->mottling, e->on_front ? "yes" : resolved(s, e) ? "" : "unresolved");
    }
    bench_printf(t, "\n");
    for (size_t i = 0; i < s->count; i++) {
        const bench_entry *e = &s->entries[i];
        char label[64];
        bench_setting_label(&e->setting, label, sizeof label);
        if (!e->ran)
            bench_printf(t, "- skipped %s: predicted %.0f s > the time limit\n", label, e->predicted);
        else if (!e->result.ok)
            bench_printf(t, "- **failed** %s: %s\n", label, e->result.message);
    }
    bench_printf(t, "\n");
}

/* Appends a comparison's ratio, with its bound sign, to t. */
static void md_ratio(bench_text *t, const comparison *c)
{
    const char *sign = c->bound == '>' ? "> " : c->bound == '<' ? "< " : "";
    bench_printf(t, "%s%.3g", sign, c->ratio);
}

/* for_each_pair visitor: one table row. */
static void pair_md(void *user, rl_method a, rl_method b, const comparison *err, const comparison *time)
{
    bench_text *t = user;
    bench_printf(t, "| %s | %s | %.4g | %.3f | %.3f | ", rl_method_name(a), rl_method_name(b), err->at, err->a,
                 err->b);
    md_ratio(t, err);
    bench_printf(t, " | %.3f | %.4g | %.4g | ", time->at, time->a, time->b);
    md_ratio(t, time);
    bench_printf(t, " |\n");
}

/* for_each_pair visitor: the headline sentence of a pair with the first method. */
static void pair_headline(void *user, rl_method a, rl_method b, const comparison *err, const comparison *time)
{
    bench_text *t = user;
    const char *an = rl_method_name(a), *bn = rl_method_name(b);
    bench_printf(t, "- **%s vs %s**: at equal error (RMSE %.4g) %s takes ", an, bn, err->at, bn);
    md_ratio(t, err);
    bench_printf(t, "x the time of %s; at equal time (%.3f s) its RMSE is ", an, time->at);
    md_ratio(t, time);
    bench_printf(t, "x %s's.\n", an);
}

/* Appends the comparisons: headlines and the full table. */
static void md_comparisons(bench_text *t, const bench_sweep *s)
{
    bench_printf(t, "## Comparisons\n\nAlong each method's Pareto front, log-log interpolated; \"B/A\" > 1 means A "
                    "is ahead. A bound (> or <) means the fronts do not overlap and the figure comes from their "
                    "nearest ends.\n\n");
    for_each_pair(s, pair_headline, t);
    bench_printf(t, "\n| A | B | equal error: RMSE | A s | B s | B/A time | equal time: s | A RMSE | B RMSE | B/A "
                    "RMSE |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for_each_pair(s, pair_md, t);
    bench_printf(t, "\n");
}

/* Appends the definitions and the list of files. */
static void md_definitions(bench_text *t, const bench_sweep *s)
{
    bench_printf(t, "## Definitions\n\n"
                    "Errors are over every cell of every radiance map (with `--reference pathtrace`, over its "
                    "sampled cells), on the luminance Y = 0.2126 R + 0.7152 G + "
                    "0.0722 B of irradiance (W m^-2): RMSE = sqrt(mean (Y - Yref)^2); relative RMSE = RMSE / mean "
                    "Yref; SNR = 10 log10(sum Yref^2 / sum (Y - Yref)^2) dB. Times are the relighting alone (wall, "
                    "and CPU over all threads); rays / cpu s = rays cast / CPU seconds; \"of ceiling\" divides it "
                    "by the ray ceiling's rays per CPU second. Peak MiB is the run's process's maximum resident "
                    "set (it includes the loaded scene and the reference it inherits).\n\n");
    if (s->baseline.ok)
        bench_printf(t, "Baseline: a child that does nothing peaks at %.1f MiB (the program's libraries, the loaded "
                        "scene and the reference); a run's own memory is its peak minus that.\n\n",
                     s->baseline.peak_mib);
    bench_printf(t, "Files: bench.csv, bench.json, error_vs_time.png (.gp)");
    for (size_t m = 0; m < s->cfg->nmethods; m++)
        if (s->best[m] >= 0)
            bench_printf(t, ", error_%s.png (.gp, .bin)", rl_method_name(s->cfg->methods[m]));
    bench_printf(t, ".\n");
}

/* Writes DIR/summary.md. @return 1, or 0 after reporting. */
static int write_summary(const bench_sweep *s)
{
    bench_text t = {0};
    char path[BENCH_PATH_MAX];
    md_header(&t, s);
    md_ceiling(&t, s);
    md_comparisons(&t, s);
    md_runs(&t, s);
    md_definitions(&t, s);
    int ok = bench_path(path, s->cfg->output, "summary.md") &&
             bench_write_text(path, &t, "tables, comparisons and definitions", s->cfg->quiet);
    bench_text_free(&t);
    return ok;
}

int bench_write_reports(const bench_sweep *s)
{
    int ok = write_csv(s);
    ok = write_json(s) && ok;
    ok = write_summary(s) && ok;
    return ok ? ILF_EXIT_OK : ILF_EXIT_FAILED;
}

/* ------------------------------------------------------------ fits */

int bench_fit_power(const double *x, const double *y, size_t n, double *a, double *b)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        if (!(x[k] > 0) || !(y[k] > 0))
            continue;
        double lx = log(x[k]), ly = log(y[k]);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
        m++;
    }
    double det = (double)m * sxx - sx * sx;
    if (m < 2 || !(fabs(det) > 1e-12))
        return 0;
    *b = ((double)m * sxy - sx * sy) / det;
    *a = (sy - *b * sx) / (double)m;
    return 1;
}
