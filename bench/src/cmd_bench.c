/*
 * cmd_bench.c - `ilf bench`: the speed-accuracy trade of the relighting
 * methods, measured (docs/bench.md). Three modes:
 *
 *   ilf bench SCENE -o DIR            sweep methods and their knobs against a
 *                                     cached reference: bench.csv, bench.json,
 *                                     summary.md, error_vs_time.png and the
 *                                     error images error_<method>.png
 *   ilf bench --rays SCENE [-o DIR]   the ray tracer alone (rl_bench_rays)
 *   ilf bench --scaling SCENE -o DIR  time and memory against cells and n
 *
 * Invariants: every relighting and ray benchmark runs in a forked child
 * (bench_run.c), never in this process, which only loads the scene and the
 * reference and writes reports; settings of one method run in order of
 * nominal cost, and one is skipped when the previous run of its method,
 * scaled by the cost ratio, predicts more than --time-limit; DIR holds no
 * partial file at any time (bench.h); the exit code is 0 only when every
 * run that was not skipped succeeded and every output was written.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"
#include "jsonout.h"

/* Knob values of the sweeps: full, then --quick. */
static const uint32_t PARTITION_NS[] = {8, 16, 32}, PARTITION_NS_QUICK[] = {8, 16};
static const uint32_t RAYS[] = {1, 4, 16}, RAYS_QUICK[] = {1, 4};
static const uint32_t SAMPLES[] = {16, 64, 256, 1024}, SAMPLES_QUICK[] = {16, 64};
/* adaptive: partition n (PARTITION_NS) x these target errors, at 4 rays per solid angle */
static const double TARGETS[] = {0.3, 0.1, 0.03}, TARGETS_QUICK[] = {0.3};
#define ADAPTIVE_RAYS 4u
#define COUNT(a) (sizeof(a) / sizeof((a)[0]))
/* Most settings a sweep may hold. */
#define MAX_SETTINGS 256
/* Defaults of the options. */
#define DEFAULT_REFERENCE_SAMPLES 4096u
#define QUICK_REFERENCE_SAMPLES 256u
#define DEFAULT_REFERENCE_CELLS 256u
#define DEFAULT_TIME_LIMIT 120.0
#define DEFAULT_RAYS_COUNT 10000000u
/* Rays of the ceiling measured alongside a sweep, full and --quick. */
#define SWEEP_CEILING_RAYS 4000000u
#define SWEEP_CEILING_RAYS_QUICK 500000u

enum bench_mode { MODE_SWEEP, MODE_RAYS, MODE_SCALING };

enum bench_option_id {
    OPT_OUTPUT,
    OPT_QUICK,
    OPT_METHODS,
    OPT_THREADS,
    OPT_BOUNCES,
    OPT_CACHE,
    OPT_REFERENCE_SAMPLES,
    OPT_REFERENCE,
    OPT_REFERENCE_CELLS,
    OPT_SCENE_SETTINGS,
    OPT_TIME_LIMIT,
    OPT_RAYS,
    OPT_RAYS_COUNT,
    OPT_SCALING,
    OPT_QUIET
};

static const cli_option bench_options_table[] = {
    {"output", 'o', "DIR", "folder for the results (created; its parent must exist)"},
    {"quick", 0, NULL, "small sweep, 256-sample reference: a smoke run"},
    {"methods", 0, "LIST", "methods to sweep, comma-separated (default culled,naive,area,solidangle,adaptive)"},
    {"threads", 0, "N", "worker threads, 0 = every processor (default 0)"},
    {"bounces", 0, "B", "diffuse passes after the direct one (default 0, not the scene's)"},
    {"cache", 0, "DIR", "reference cache (default $XDG_CACHE_HOME/ilfkit, else DIR/../ilf-cache)"},
    {"reference-samples", 0, "N", "samples per (cell, emitter) of each reference run; pathtrace: paths per cell "
                                  "(default 4096; --quick 256)"},
    {"reference", 0, "KIND",
     "solidangle (default: two converged engine runs) or pathtrace (independent, sampled cells)"},
    {"reference-cells", 0, "N", "cells the pathtrace reference samples, evenly spaced (default 256)"},
    {"scene-settings", 0, NULL, "instead of a sweep, one run at the scene's own sampling settings"},
    {"time-limit", 0, "S", "skip settings predicted to take longer than S seconds (default 120)"},
    {"rays", 0, NULL, "measure the ray tracer alone (rl_bench_rays): the ceiling"},
    {"rays-count", 0, "N", "rays for --rays (default 10000000)"},
    {"scaling", 0, NULL, "time and memory against the number of cells and partition n (culled)"},
    {"quiet", 'q', NULL, "no progress bars and nothing on stdout"},
};

static const cli_usage bench_usage = {
    "bench",
    "SCENE -o DIR [--quick] [--methods LIST] [--threads N] [--bounces B] [--cache DIR]\n"
    "                 [--reference-samples N] [--reference solidangle|pathtrace] [--reference-cells N]\n"
    "                 [--scene-settings] [--time-limit S] [--quiet]\n"
    "       ilf bench --rays SCENE [-o DIR] [--rays-count N] [--threads N]\n"
    "       ilf bench --scaling SCENE -o DIR [--threads N] [--time-limit S]",
    "Measures speed against accuracy. The sweep runs culled and naive over partition n\n"
    "{8,16,32} x rays {1,4,16}, area and solidangle over samples {16,64,256,1024},\n"
    "adaptive over partition n x target error {0.3,0.1,0.03} (--quick: {8,16} x {1,4},\n"
    "{16,64}, {8,16} x {0.3}), each in a child process, against a reference\n"
    "(two converged solidangle runs, cached; or --reference pathtrace: independent\n"
    "path tracing of sampled cells), and writes bench.csv, bench.json,\n"
    "summary.md, error_vs_time.png and error_<method>.png (plots need gnuplot).\n"
    "Errors are on the luminance of irradiance over every cell (docs/bench.md).",
    "ilf bench data/beams_diffuse.json -o out/bench-beams --threads 0\n"
    "ilf bench tiny.json -o out/smoke --quick --methods culled,area --time-limit 5\n"
    "ilf bench --rays data/classroom.json --rays-count 20000000\n"
    "ilf bench --scaling data/beams_diffuse.json -o out/scaling",
};

/* ------------------------------------------------------------ options */

/* Parses a comma-separated method list into cfg. @return 1, or 0 after reporting. */
static int parse_methods(const cli_parser *p, const char *text, bench_config *cfg)
{
    cfg->nmethods = 0;
    const char *field = text;
    for (;;) {
        const char *comma = strchr(field, ',');
        size_t len = comma != NULL ? (size_t)(comma - field) : strlen(field);
        char name[32];
        rl_method m;
        if (len == 0 || len >= sizeof name)
            return cli_bad_value(p, text, "expected method names separated by commas"), 0;
        memcpy(name, field, len);
        name[len] = '\0';
        if (!rl_method_parse(name, &m))
            return cli_bad_value(p, text, "unknown method (culled, naive, area, solidangle)"), 0;
        for (size_t k = 0; k < cfg->nmethods; k++)
            if (cfg->methods[k] == m)
                return cli_bad_value(p, text, "a method is listed twice"), 0;
        if (cfg->nmethods == BENCH_MAX_METHODS)
            return cli_bad_value(p, text, "too many methods"), 0;
        cfg->methods[cfg->nmethods++] = m;
        if (comma == NULL)
            return 1;
        field = comma + 1;
    }
}

/* Fills cfg->command with the command line, for the reports. */
static void record_command(bench_config *cfg, int argc, char **argv)
{
    size_t at = (size_t)snprintf(cfg->command, sizeof cfg->command, "ilf");
    for (int k = 0; k < argc && at < sizeof cfg->command; k++)
        at += (size_t)snprintf(cfg->command + at, sizeof cfg->command - at, " %s", argv[k]);
}

/* What parsing fills: the configuration, the mode, and whether --reference-samples was given. */
typedef struct bench_args {
    bench_config *cfg;
    enum bench_mode *mode;
    int samples_given, bounces_given;
} bench_args;

/* Applies one option to the bench_args ctx. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    bench_args *a = ctx;
    bench_config *cfg = a->cfg;
    enum bench_mode *mode = a->mode;
    switch (opt) {
    case OPT_OUTPUT: cfg->output = value; return 1;
    case OPT_QUICK: cfg->quick = 1; return 1;
    case OPT_METHODS: return parse_methods(p, value, cfg);
    case OPT_THREADS: return sampling_option_apply(p, &cfg->sampling, SAMPLING_OPT_THREADS, value);
    case OPT_BOUNCES:
        a->bounces_given = 1;
        return sampling_option_apply(p, &cfg->sampling, (int)rl_sampling_setting_find("bounces"), value);
    case OPT_CACHE:
        if (snprintf(cfg->cache, sizeof cfg->cache, "%s", value) >= (int)sizeof cfg->cache)
            return cli_bad_value(p, value, "path too long"), 0;
        return 1;
    case OPT_REFERENCE_SAMPLES:
        a->samples_given = 1;
        return cli_value_u32(p, value, 1, 1048576, &cfg->reference_samples);
    case OPT_REFERENCE:
        if (strcmp(value, "pathtrace") != 0 && strcmp(value, "solidangle") != 0)
            return cli_bad_value(p, value, "expected solidangle or pathtrace"), 0;
        cfg->reference_pathtrace = strcmp(value, "pathtrace") == 0;
        return 1;
    case OPT_REFERENCE_CELLS: return cli_value_u32(p, value, 1, 1048576, &cfg->reference_cells);
    case OPT_SCENE_SETTINGS: cfg->scene_settings = 1; return 1;
    case OPT_TIME_LIMIT:
        if (!cli_value_double(p, value, &cfg->time_limit))
            return 0;
        return cfg->time_limit > 0 || (cli_bad_value(p, value, "must be > 0"), 0);
    case OPT_RAYS_COUNT: {
        uint32_t n;
        if (!cli_value_u32(p, value, 1, UINT32_MAX, &n))
            return 0;
        cfg->rays_count = n;
        return 1;
    }
    case OPT_RAYS:
    case OPT_SCALING: {
        enum bench_mode want = opt == OPT_RAYS ? MODE_RAYS : MODE_SCALING;
        if (*mode != MODE_SWEEP && *mode != want) {
            cli_error(BENCH_SUB, "--rays and --scaling cannot be combined");
            return 0;
        }
        *mode = want;
        return 1;
    }
    case OPT_QUIET: cfg->quiet = 1; return 1;
    default: return 0;
    }
}

/* Fills the defaults that depend on other options: reference samples and the cache folder. @return 1, or 0 after reporting. */
static int finish_defaults(bench_config *cfg, int samples_given)
{
    if (!samples_given)
        cfg->reference_samples = cfg->quick ? QUICK_REFERENCE_SAMPLES : DEFAULT_REFERENCE_SAMPLES;
    if (cfg->cache[0] != '\0' || cfg->output == NULL)
        return 1;
    const char *xdg = getenv("XDG_CACHE_HOME");
    int n = xdg != NULL && xdg[0] == '/' ? snprintf(cfg->cache, sizeof cfg->cache, "%s/ilfkit", xdg)
                                         : snprintf(cfg->cache, sizeof cfg->cache, "%s/../ilf-cache", cfg->output);
    if (n < 0 || n >= (int)sizeof cfg->cache) {
        cli_error(BENCH_SUB, "the cache folder's path is too long; give --cache");
        return 0;
    }
    return 1;
}

/* Parses argv into cfg and mode. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(bench_config *cfg, enum bench_mode *mode, int argc, char **argv)
{
    bench_args args = {cfg, mode, 0, 0};
    int code = cli_parse(&bench_usage, bench_options_table, COUNT(bench_options_table), argc, argv, &cfg->scene,
                         apply_option, &args);
    if (code != -1)
        return code;
    const char *problem = NULL;
    if (cfg->scene == NULL)
        problem = "no scene given (see 'ilf bench --help')";
    else if (*mode != MODE_RAYS && (cfg->output == NULL || cfg->output[0] == '\0'))
        problem = "-o DIR is required";
    if (problem != NULL) {
        cli_error(BENCH_SUB, "%s", problem);
        return ILF_EXIT_USAGE;
    }
    if (cfg->scene_settings && !args.bounces_given) /* the scene's own settings include its bounces */
        cfg->sampling.given &= ~(1u << rl_sampling_setting_find("bounces"));
    return finish_defaults(cfg, args.samples_given) ? -1 : ILF_EXIT_USAGE;
}

/* ------------------------------------------------------------ settings */

/* Appends setting s to out (count entries, at most MAX_SETTINGS), keeping one method's settings in cost order. */
static void add_setting(bench_setting *out, size_t *count, size_t first_of_method, bench_setting s)
{
    if (*count == MAX_SETTINGS)
        return;
    size_t k = (*count)++;
    while (k > first_of_method && out[k - 1].cost > s.cost) {
        out[k] = out[k - 1];
        k--;
    }
    out[k] = s;
}

/* Fills out with the sweep's settings, method by method. @return their count, or 0 after reporting. */
static size_t build_settings(const bench_config *cfg, bench_setting *out)
{
    size_t count = 0;
    const uint32_t *ns = cfg->quick ? PARTITION_NS_QUICK : PARTITION_NS, *ks = cfg->quick ? RAYS_QUICK : RAYS;
    const uint32_t *ss = cfg->quick ? SAMPLES_QUICK : SAMPLES;
    size_t nn = cfg->quick ? COUNT(PARTITION_NS_QUICK) : COUNT(PARTITION_NS);
    size_t nk = cfg->quick ? COUNT(RAYS_QUICK) : COUNT(RAYS), ns_count = cfg->quick ? COUNT(SAMPLES_QUICK) : COUNT(SAMPLES);
    for (size_t m = 0; m < cfg->nmethods; m++) {
        rl_method method = cfg->methods[m];
        size_t first = count;
        if (method == RL_METHOD_CULLED || method == RL_METHOD_NAIVE) {
            for (size_t i = 0; i < nn; i++)
                for (size_t j = 0; j < nk; j++)
                    add_setting(out, &count, first,
                                (bench_setting){.method = method, .partition_n = ns[i], .rays = ks[j],
                                                .cost = (double)ns[i] * ns[i] * ks[j]});
        } else if (method == RL_METHOD_AREA || method == RL_METHOD_SOLIDANGLE) {
            for (size_t i = 0; i < ns_count; i++)
                add_setting(out, &count, first, (bench_setting){.method = method, .samples = ss[i], .cost = (double)ss[i]});
        } else if (method == RL_METHOD_ADAPTIVE) {
            const double *ts = cfg->quick ? TARGETS_QUICK : TARGETS;
            size_t nt = cfg->quick ? COUNT(TARGETS_QUICK) : COUNT(TARGETS);
            /* nominal cost: twice culled's (the measuring stage), more as the target tightens */
            for (size_t i = 0; i < nn; i++)
                for (size_t j = 0; j < nt; j++)
                    add_setting(out, &count, first,
                                (bench_setting){.method = method, .partition_n = ns[i], .rays = ADAPTIVE_RAYS,
                                                .target_error = ts[j], .cost =
                                                2.0 * ns[i] * ns[i] * ADAPTIVE_RAYS / sqrt(ts[j] / ts[0])});
        } else {
            cli_error(BENCH_SUB, "--methods: no sweep is defined for '%s'", rl_method_name(method));
            return 0;
        }
    }
    return count;
}

/* @return the job's sampling settings (the scene file's, with --bounces) as the one setting of --scene-settings. */
static bench_setting scene_setting(const rl_job *job)
{
    const rl_sampling *smp = &job->sampling;
    return (bench_setting){.method = smp->method, .partition_n = smp->partition_n, .rays = smp->rays_per_solid_angle,
                           .samples = smp->samples_per_cell, .target_error = smp->target_error, .cost = 1.0};
}

/* ------------------------------------------------------------ the sweep */

/* @return the worker threads a run uses: --threads, or every processor for 0 (the engine's rule). */
static unsigned threads_used(const bench_config *cfg)
{
    return relight_threads_used(&cfg->job.run);
}

/* @return the slot of method m in --methods. */
static size_t method_slot(const bench_config *cfg, rl_method m)
{
    size_t k = 0;
    while (k + 1 < cfg->nmethods && cfg->methods[k] != m)
        k++;
    return k;
}

/* @return the predicted wall time of entry i from the last successful run of its method before it, or 0 if none. */
static double predict(const bench_sweep *s, size_t i)
{
    const bench_entry *e = &s->entries[i];
    for (size_t j = i; j-- > 0;) {
        const bench_entry *prev = &s->entries[j];
        if (prev->setting.method == e->setting.method && prev->ran && prev->result.ok)
            return prev->result.wall_seconds * e->setting.cost / prev->setting.cost;
    }
    return 0.0;
}

/* Prints one run's line to stdout (not with --quiet). */
static void print_entry(const bench_sweep *s, const bench_entry *e)
{
    char label[64];
    const bench_result *r = &e->result;
    if (s->cfg->quiet)
        return;
    bench_setting_label(&e->setting, label, sizeof label);
    if (!e->ran)
        printf("%s: skipped (predicted %.0f s > %.0f s)\n", label, e->predicted, s->cfg->time_limit);
    else if (!r->ok)
        printf("%s: failed: %s\n", label, r->message);
    else
        printf("%s: %.3f s wall, %.3f s cpu, RMSE %.4g (%.3g%%), SNR %.2f dB, %.1f MiB\n", label, r->wall_seconds,
               r->cpu_seconds, r->rmse, 100.0 * r->rel_rmse, r->snr_db, r->peak_mib);
}

/* Keeps the error image of entry i as error_<method>.bin if it is its method's most accurate run so far,
 * else removes it. @return 1, or 0 after reporting. */
static int keep_if_best(bench_sweep *s, size_t i, const char *image)
{
    const bench_entry *e = &s->entries[i];
    size_t m = method_slot(s->cfg, e->setting.method);
    int best = e->ran && e->result.ok &&
               (s->best[m] < 0 || e->result.rmse < s->entries[s->best[m]].result.rmse);
    char name[64], path[BENCH_PATH_MAX];
    snprintf(name, sizeof name, "error_%s.bin", rl_method_name(e->setting.method));
    if (!best || !bench_path(path, s->cfg->output, name)) {
        remove(image);
        return !best;
    }
    if (rename(image, path) != 0) {
        remove(image);
        cli_error(BENCH_SUB, "cannot move the error image to %s", path);
        return 0;
    }
    s->best[m] = (int)i;
    return 1;
}

/* Runs (or skips) entry i in a child. @return 1, or 0 when the run failed. */
static int run_entry(bench_sweep *s, rl_scene *scene, size_t i)
{
    bench_entry *e = &s->entries[i];
    double predicted = predict(s, i);
    if (predicted > s->cfg->time_limit) {
        e->predicted = predicted;
        print_entry(s, e);
        return 1;
    }
    char label[64], image[BENCH_PATH_MAX];
    int camera = s->camera_width > 0 && bench_path(image, s->cfg->output, ".error-run.bin");
    bench_relight_job job = {.scene = scene,
                             .overrides = &s->cfg->sampling,
                             .setting = e->setting,
                             .ref = s->ref,
                             .image_path = camera ? image : NULL,
                             .label = s->cfg->quiet ? NULL : bench_setting_label(&e->setting, label, sizeof label)};
    e->ran = 1;
    if (!bench_fork(bench_relight_child, &job, &e->result))
        e->result.ok = 0;
    print_entry(s, e);
    if (e->result.ok && !(e->result.rmse >= 0)) {
        e->result.ok = 0;
        snprintf(e->result.message, sizeof e->result.message, "no error measured");
    }
    int kept = !camera || keep_if_best(s, i, image);
    return e->result.ok && kept;
}

/* Measures the ray ceiling in a child into s->ceiling (a failure is noted, not fatal). */
static void measure_ceiling(bench_sweep *s, const rl_scene *scene)
{
    bench_rays_job job = {scene, s->cfg->quick ? SWEEP_CEILING_RAYS_QUICK : SWEEP_CEILING_RAYS, s->cfg->job.run};
    bench_fork(bench_rays_child, &job, &s->ceiling);
    if (!s->cfg->quiet && s->ceiling.ok)
        printf("ray ceiling: %" PRIu64 " rays, %.3g rays/s, %.3g rays per cpu second\n", s->ceiling.rays_cast,
               (double)s->ceiling.rays_cast / s->ceiling.wall_seconds,
               (double)s->ceiling.rays_cast / s->ceiling.cpu_seconds);
}

/* Runs the sweep: reference, ceiling, every setting, reports and plots. @return an exit code. */
static int sweep(const bench_config *cfg, rl_scene *scene)
{
    static bench_setting settings[MAX_SETTINGS];
    static bench_entry entries[MAX_SETTINGS];
    size_t count = cfg->scene_settings ? 1 : build_settings(cfg, settings);
    if (cfg->scene_settings)
        settings[0] = scene_setting(&cfg->job);
    if (count == 0)
        return ILF_EXIT_USAGE;
    bench_reference ref;
    int code = bench_reference_obtain(cfg, scene, &ref);
    if (code != ILF_EXIT_OK)
        return code;
    bench_sweep s = {.cfg = cfg, .ref = &ref, .entries = entries, .count = count, .threads = threads_used(cfg),
                     .bounces = cfg->job.sampling.bounces};
    cli_settings(BENCH_SUB, "sweep of %zu settings over %zu method%s, %" PRIu32 " bounce%s, time limit %.0f s per run, "
                 "%u thread%s", count, cfg->nmethods, cfg->nmethods == 1 ? "" : "s", s.bounces,
                 s.bounces == 1 ? "" : "s", cfg->time_limit, s.threads, s.threads == 1 ? "" : "s");
    rl_scene_camera_size(scene, &s.camera_width, &s.camera_height);
    for (size_t m = 0; m < BENCH_MAX_METHODS; m++)
        s.best[m] = -1;
    bench_fork(bench_idle_child, NULL, &s.baseline);
    measure_ceiling(&s, scene);
    int ok = 1;
    for (size_t i = 0; i < count; i++) {
        memset(&entries[i], 0, sizeof entries[i]);
        entries[i].setting = settings[i];
        ok = run_entry(&s, scene, i) && ok;
    }
    bench_mark_fronts(&s);
    code = bench_write_reports(&s);
    ok = bench_plot_error_vs_time(&s) && ok;
    if (s.camera_width > 0)
        ok = bench_plot_error_images(&s) && ok;
    bench_reference_free(&ref);
    return code != ILF_EXIT_OK ? code : ok ? ILF_EXIT_OK : ILF_EXIT_FAILED;
}

/* ------------------------------------------------------------ --rays */

/* Writes DIR/rays.json with the ray benchmark's result. @return 1, or 0 after reporting. */
static int write_rays_json(const bench_config *cfg, const bench_result *r, unsigned threads)
{
    char path[BENCH_PATH_MAX], err[BENCH_PATH_MAX + 256];
    cJSON *root = cJSON_CreateObject();
    int ok = root != NULL && bench_path(path, cfg->output, "rays.json");
    if (ok) {
        cJSON_AddStringToObject(root, "creator", BENCH_CREATOR);
        cJSON_AddStringToObject(root, "scene", cfg->scene);
        cJSON_AddNumberToObject(root, "threads", threads);
        cJSON_AddNumberToObject(root, "rays", (double)r->rays_cast);
        cJSON_AddNumberToObject(root, "unoccluded", (double)r->rays_kept);
        cJSON_AddNumberToObject(root, "wall_seconds", r->wall_seconds);
        cJSON_AddNumberToObject(root, "cpu_seconds", r->cpu_seconds);
        cJSON_AddNumberToObject(root, "rays_per_second", (double)r->rays_cast / r->wall_seconds);
        cJSON_AddNumberToObject(root, "rays_per_cpu_second", (double)r->rays_cast / r->cpu_seconds);
        cJSON_AddNumberToObject(root, "peak_mib", r->peak_mib);
        ok = json_write_file(path, root, err, sizeof err);
        if (!ok)
            cli_error(BENCH_SUB, "%s", err);
        else if (!cfg->quiet)
            printf("wrote %s\n", path);
    }
    cJSON_Delete(root);
    return ok;
}

/* `ilf bench --rays`: the ceiling alone. @return an exit code. */
static int rays_mode(const bench_config *cfg, rl_scene *scene)
{
    if (cfg->output != NULL && !bench_make_folder(cfg->output))
        return ILF_EXIT_FAILED;
    bench_rays_job job = {scene, cfg->rays_count, cfg->job.run};
    cli_settings(BENCH_SUB, "ray benchmark, %" PRIu64 " rays, %u thread%s", cfg->rays_count,
                 threads_used(cfg), threads_used(cfg) == 1 ? "" : "s");
    bench_result r;
    if (!bench_fork(bench_rays_child, &job, &r) || !r.ok) {
        cli_error(BENCH_SUB, "%s", r.message);
        return ILF_EXIT_FAILED;
    }
    unsigned threads = threads_used(cfg);
    if (!cfg->quiet)
        printf("rays: %" PRIu64 " in %.3f s wall, %.3f s cpu, %u thread%s: %.4g rays/s, %.4g rays per cpu second, "
               "%.1f%% blocked\n",
               r.rays_cast, r.wall_seconds, r.cpu_seconds, threads, threads == 1 ? "" : "s",
               (double)r.rays_cast / r.wall_seconds, (double)r.rays_cast / r.cpu_seconds,
               100.0 * (double)(r.rays_cast - r.rays_kept) / (double)r.rays_cast);
    if (cfg->output != NULL && !write_rays_json(cfg, &r, threads))
        return ILF_EXIT_FAILED;
    return ILF_EXIT_OK;
}

/* ------------------------------------------------------------ main */

int ilf_cmd_bench(int argc, char **argv)
{
    static bench_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.time_limit = DEFAULT_TIME_LIMIT;
    cfg.rays_count = DEFAULT_RAYS_COUNT;
    cfg.methods[0] = RL_METHOD_CULLED;
    cfg.methods[1] = RL_METHOD_NAIVE;
    cfg.methods[2] = RL_METHOD_AREA;
    cfg.methods[3] = RL_METHOD_SOLIDANGLE;
    cfg.methods[4] = RL_METHOD_ADAPTIVE;
    cfg.nmethods = 5;
    cfg.reference_cells = DEFAULT_REFERENCE_CELLS;
    cfg.sampling.given = 1u << rl_sampling_setting_find("bounces"); /* bounces 0 unless --bounces */
    enum bench_mode mode = MODE_SWEEP;
    int code = parse_arguments(&cfg, &mode, argc, argv);
    if (code >= 0)
        return code;
    record_command(&cfg, argc, argv);
    cli_set_quiet(cfg.quiet);
    if (mode == MODE_SCALING)
        return bench_scaling(&cfg);
    rl_scene *scene = NULL;
    code = relight_scene_open(BENCH_SUB, cfg.scene, &cfg.sampling, &scene, &cfg.job);
    if (code == ILF_EXIT_OK && cfg.scene_settings) { /* the one method swept is the scene's */
        cfg.methods[0] = cfg.job.sampling.method;
        cfg.nmethods = 1;
    }
    if (code == ILF_EXIT_OK && mode == MODE_RAYS)
        code = rays_mode(&cfg, scene);
    else if (code == ILF_EXIT_OK)
        code = bench_make_folder(cfg.output) ? sweep(&cfg, scene) : ILF_EXIT_FAILED;
    rl_scene_destroy(scene);
    return code;
}
