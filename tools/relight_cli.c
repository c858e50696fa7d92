/*
 * relight_cli.c - the sampling options, scene loading and jobs, failure
 * reporting and pass statistics shared by `ilf relight` and `ilf irradiance`
 * (see relight_cli.h).
 *
 * Invariants: option values are parsed strictly (cli.c's parsers), with the
 * bounds of relight's one table of sampling settings (rl_sampling_setting),
 * which also names the options and gives their help; overrides are applied to
 * the job the scene file suggests (rl_job_default()), so the file's own
 * values stay for every field not given, and the scene is never changed.
 */
#include "relight_cli.h"
#include "job.h"

#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "ilf/pool.h"
#include "relight/scene.h"

/* Parses a seed: digits only, 0 .. max (2^53, what a JSON number holds exactly). @return 1, or 0 after reporting. */
static int parse_seed(const cli_parser *p, const char *text, double max, uint64_t *seed)
{
    size_t len = strlen(text);
    int digits = len > 0 && len <= 20;
    for (size_t k = 0; digits && k < len; k++)
        digits = isdigit((unsigned char)text[k]);
    errno = 0;
    unsigned long long value = digits ? strtoull(text, NULL, 10) : 0;
    if (!digits || errno == ERANGE || value > (unsigned long long)max)
        return cli_bad_value(p, text, "expected a whole number from 0 to 2^53 (9007199254740992)"), 0;
    *seed = value;
    return 1;
}

int relight_options_fill(const char *sub, cli_option *table)
{
    static char help[SAMPLING_OPT_SETTINGS][320];
    if (rl_sampling_setting_count() != SAMPLING_OPT_SETTINGS) {
        cli_error(sub, "internal error: %zu sampling settings, the command line knows %d", rl_sampling_setting_count(),
                  SAMPLING_OPT_SETTINGS);
        return 0;
    }
    for (size_t k = 0; k < SAMPLING_OPT_SETTINGS; k++) {
        const rl_setting_info *set = rl_sampling_setting(k);
        char rule[128];
        snprintf(help[k], sizeof help[k], "%s (%s; default: the scene's)", set->help,
                 rl_sampling_setting_rule(k, rule, sizeof rule));
        table[k] = (cli_option){set->option, 0, set->meta, help[k]};
    }
    table[SAMPLING_OPT_THREADS] = (cli_option){"threads", 0, "N", "worker threads, 0 = every processor (default 0)"};
    table[SAMPLING_OPT_TIME_BUDGET] =
        (cli_option){"time-budget", 0, "S", "adaptive: stop refining after S seconds, 0 = never (default: the scene's)"};
    return 1;
}

/* Parses the value of setting k into v. @return 1, or 0 after reporting. */
static int parse_setting(const cli_parser *p, size_t k, const char *text, rl_sampling *v)
{
    const rl_setting_info *set = rl_sampling_setting(k);
    char rule[128], why[160];
    rl_sampling_setting_rule(k, rule, sizeof rule);
    switch (set->type) {
    case RL_SETTING_METHOD:
        if (rl_method_parse(text, &v->method))
            return 1;
        snprintf(why, sizeof why, "expected %s", rule);
        return cli_bad_value(p, text, why), 0;
    case RL_SETTING_UINT64: {
        uint64_t value = 0;
        return parse_seed(p, text, set->hi, &value) && rl_sampling_set(v, k, (double)value);
    }
    case RL_SETTING_UINT32: {
        uint32_t value = 0;
        if (!cli_value_u32(p, text, (uint32_t)set->lo, (uint32_t)set->hi, &value))
            return 0;
        if (!rl_sampling_setting_allows(k, value, 1))
            return cli_bad_value(p, text, "must be a power of two"), 0; /* the only rule besides the range */
        return rl_sampling_set(v, k, value);
    }
    case RL_SETTING_REAL: {
        double value = 0;
        if (!cli_value_double(p, text, &value))
            return 0;
        if (!rl_sampling_setting_allows(k, value, 1)) {
            snprintf(why, sizeof why, "must be %s", rule);
            return cli_bad_value(p, text, why), 0;
        }
        return rl_sampling_set(v, k, value);
    }
    }
    return 0;
}

int sampling_option_apply(const cli_parser *p, sampling_overrides *o, int opt, const char *value)
{
    int ok = 0;
    if (opt >= 0 && opt < SAMPLING_OPT_SETTINGS)
        ok = parse_setting(p, (size_t)opt, value, &o->values);
    else if (opt == SAMPLING_OPT_THREADS)
        ok = cli_value_threads(p, value, &o->threads);
    else if (opt == SAMPLING_OPT_TIME_BUDGET) {
        ok = cli_value_double(p, value, &o->time_budget);
        if (ok && !(o->time_budget >= 0))
            ok = 0, cli_bad_value(p, value, "must be >= 0 seconds");
    }
    if (ok)
        o->given |= 1u << opt;
    return ok;
}

/* @return the scene's settings with every given override applied. */
static rl_sampling merged_sampling(const rl_sampling *scene, const sampling_overrides *o)
{
    rl_sampling s = *scene;
    for (size_t k = 0; k < SAMPLING_OPT_SETTINGS; k++) {
        double value = 0;
        if ((o->given & (1u << k)) && rl_sampling_get(&o->values, k, &value))
            rl_sampling_set(&s, k, value);
    }
    return s;
}

const char *relight_failure_text(char *buf, size_t size)
{
    const char *msg = cli_one_line(rl_errmsg(), buf, size);
    return msg[0] != '\0' ? msg : "relighting failed";
}

int relight_failure(const char *sub, rl_status st)
{
    char line[1024];
    cli_error(sub, "%s", relight_failure_text(line, sizeof line));
    return st == RL_ERR_ARG || st == RL_ERR_IO || st == RL_ERR_INPUT ? ILF_EXIT_USAGE : ILF_EXIT_FAILED;
}

/* @return the threads a run asks for with options o: --threads, else 0 (every processor), but a share of
 * the machine's processors for each of several ranks. */
static unsigned threads_asked(const sampling_overrides *o)
{
    unsigned threads = o != NULL && (o->given & (1u << SAMPLING_OPT_THREADS)) ? o->threads : 0u;
    /* Several ranks on one machine share its cores instead of each taking them all. */
    return threads == 0 && job_ranks() > 1 ? job_threads_per_rank() : threads;
}

void relight_job(const sampling_overrides *o, const rl_scene *scene, rl_job *job)
{
    rl_job_default(scene, job);
    unsigned given = o != NULL ? o->given : 0u;
    if (o != NULL)
        job->sampling = merged_sampling(&job->sampling, o);
    job->run.threads = threads_asked(o);
    if (given & (1u << SAMPLING_OPT_TIME_BUDGET))
        job->run.time_budget = o->time_budget;
}

int relight_scene_open(const char *sub, const char *path, const sampling_overrides *o, rl_scene **out, rl_job *job)
{
    *out = NULL;
    rl_scene *scene = NULL;
    /* the scene's light fields inflate on the threads the run will use */
    rl_scene_load_options lo;
    rl_scene_load_options_default(&lo);
    lo.threads = threads_asked(o);
    rl_status st = rl_scene_load_with(path, &lo, &scene);
    if (st != RL_OK) {
        /* The loader names the file in its messages; a bare errno text gets the path added. */
        char line[1024];
        const char *msg = cli_one_line(rl_errmsg(), line, sizeof line);
        if (strstr(msg, path) == NULL)
            cli_error(sub, "%s: %s", path, msg[0] != '\0' ? msg : "cannot load the scene");
        else
            cli_error(sub, "%s", msg);
        return st == RL_ERR_NOMEM ? ILF_EXIT_FAILED : ILF_EXIT_USAGE;
    }
    if (job != NULL)
        relight_job(o, scene, job);
    st = job != NULL ? rl_job_check(job) : RL_OK;
    if (st != RL_OK) {
        int code = relight_failure(sub, st);
        rl_scene_destroy(scene);
        return code;
    }
    *out = scene;
    return ILF_EXIT_OK;
}

unsigned relight_threads_used(const rl_run_options *ro)
{
    return ilf_thread_count(ro->threads);
}

void relight_print_pass(FILE *out, uint32_t k, const rl_pass_stats *s)
{
    fprintf(out, "pass %" PRIu32 " (%s): %.3f s wall, %.3f s cpu, %" PRIu32 " emitter%s\n", k,
            k == 0 ? "direct" : "bounce", s->wall_seconds, s->cpu_seconds, s->emitters, s->emitters == 1 ? "" : "s");
    fprintf(out, "  samples %" PRIu64 ", rays cast %" PRIu64 ", rays kept %" PRIu64 ", rays known free %" PRIu64 "\n",
            s->samples, s->rays_cast, s->rays_kept, s->rays_free);
    fprintf(out, "  solid angles considered %" PRIu64 ", culled %" PRIu64 "; pairs %" PRIu64 ", descended %" PRIu64
                 "\n",
            s->solid_angles_considered, s->solid_angles_culled, s->pairs, s->pairs_descended);
    if (s->cells_direct > 0)
        fprintf(out, "  cells gathered on their own, not interpolated: %" PRIu64 "\n", s->cells_direct);
    if (s->refinements > 0 || s->estimated_rmse > 0)
        fprintf(out, "  adaptive: %" PRIu64 " refinements, estimated RMSE %.4g W m^-2%s\n", s->refinements,
                s->estimated_rmse, s->budget_reached ? ", time budget reached" : "");
}

const char *relight_describe(const rl_sampling *s, char *buf, size_t size)
{
    char what[96], bounces[96] = "";
    if (s->method == RL_METHOD_AREA || s->method == RL_METHOD_SOLIDANGLE)
        snprintf(what, sizeof what, "%" PRIu32 " sample%s per cell and emitter", s->samples_per_cell,
                 s->samples_per_cell == 1 ? "" : "s");
    else
        snprintf(what, sizeof what, "partition n %" PRIu32 ", %" PRIu32 " ray%s per solid angle", s->partition_n,
                 s->rays_per_solid_angle, s->rays_per_solid_angle == 1 ? "" : "s");
    if (s->bounces > 0 && s->bounce_rays > 0)
        snprintf(bounces, sizeof bounces, " (%" PRIu32 " ray%s per bounce cell)", s->bounce_rays,
                 s->bounce_rays == 1 ? "" : "s");
    else if (s->bounces > 0)
        snprintf(bounces, sizeof bounces, " (by the method)");
    snprintf(buf, size, "method %s, %s, %" PRIu32 " bounce%s%s", rl_method_name(s->method), what, s->bounces,
             s->bounces == 1 ? "" : "s", bounces);
    return buf;
}

void relight_print_settings(const char *sub, const rl_job *job)
{
    char what[256];
    unsigned threads = relight_threads_used(&job->run);
    cli_settings(sub, "%s, %u thread%s", relight_describe(&job->sampling, what, sizeof what), threads,
                 threads == 1 ? "" : "s");
}

/* Warns of each of the n findings d (at most max kept) but those of kind skip (-1: none). */
static void warn_findings(const rl_diagnostic *d, size_t n, size_t max, int skip)
{
    for (size_t k = 0; k < n && k < max; k++)
        if ((int)d[k].kind != skip)
            cli_warn("%s", d[k].text);
    if (n > max)
        cli_warn("%zu more findings left out", n - max);
}

/* Findings shown of one check: a scene with many light fields lists a few, then their count. */
#define MAX_FINDINGS 8

void relight_warn_scene(const rl_scene *scene, int want_view)
{
    rl_diagnostic d[MAX_FINDINGS];
    size_t n = rl_scene_diagnose(scene, d, MAX_FINDINGS);
    warn_findings(d, n, MAX_FINDINGS, want_view ? -1 : (int)RL_DIAG_NO_CAMERA);
}

void relight_warn_solution(const rl_solution *solution, int want_view)
{
    rl_diagnostic d[MAX_FINDINGS];
    size_t n = rl_solution_diagnose(solution, d, MAX_FINDINGS);
    warn_findings(d, n, MAX_FINDINGS, want_view ? -1 : (int)RL_DIAG_BACK_FACES);
}
