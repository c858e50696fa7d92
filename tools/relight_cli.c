/*
 * relight_cli.c - the sampling options, scene loading, failure reporting and
 * pass statistics shared by `ilf relight` and `ilf irradiance` (see
 * relight_cli.h).
 *
 * Invariants: option values are parsed strictly (cli.c's parsers), with the
 * ranges of docs/scene.md; overrides are applied in one
 * rl_scene_set_sampling() call after loading, so the scene's own values
 * stay for every field not given.
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

/* Largest seed: the integers a JSON number (and so a scene file or stats.json) holds exactly. */
#define SEED_MAX ((uint64_t)1 << 53)

/* Parses a seed: digits only, 0 .. SEED_MAX. @return 1, or 0 after reporting. */
static int parse_seed(const cli_parser *p, const char *text, uint64_t *seed)
{
    size_t len = strlen(text);
    int digits = len > 0 && len <= 20;
    for (size_t k = 0; digits && k < len; k++)
        digits = isdigit((unsigned char)text[k]);
    errno = 0;
    unsigned long long value = digits ? strtoull(text, NULL, 10) : 0;
    if (!digits || errno == ERANGE || value > SEED_MAX)
        return cli_bad_value(p, text, "expected a whole number from 0 to 2^53 (9007199254740992)"), 0;
    *seed = value;
    return 1;
}

/* Parses a partition level: a power of two from lo (0 or 1) to 4096. @return 1, or 0 after reporting. */
static int parse_partition_n(const cli_parser *p, const char *text, uint32_t lo, uint32_t *n)
{
    if (!cli_value_u32(p, text, lo, 4096, n))
        return 0;
    if ((*n & (*n - 1)) != 0)
        return cli_bad_value(p, text, "must be a power of two"), 0;
    return 1;
}

int sampling_option_apply(const cli_parser *p, sampling_overrides *o, int opt, const char *value)
{
    rl_sampling *v = &o->values;
    int ok = 0;
    switch (opt) {
    case SAMPLING_OPT_METHOD:
        ok = rl_method_parse(value, &v->method);
        if (!ok)
            cli_bad_value(p, value, "expected culled, naive, area, solidangle or adaptive");
        break;
    case SAMPLING_OPT_THREADS: ok = cli_value_u32(p, value, 0, RL_MAX_THREADS, &o->threads); break;
    case SAMPLING_OPT_SEED: ok = parse_seed(p, value, &v->seed); break;
    case SAMPLING_OPT_PARTITION_N: ok = parse_partition_n(p, value, 1, &v->partition_n); break;
    case SAMPLING_OPT_BOUNCE_PARTITION_N: ok = parse_partition_n(p, value, 0, &v->bounce_partition_n); break;
    case SAMPLING_OPT_BOUNCE_CELL_FACTOR: ok = cli_value_u32(p, value, 0, 64, &v->bounce_cell_factor); break;
    case SAMPLING_OPT_DESCEND: ok = cli_value_u32(p, value, 0, 1, &v->descend); break;
    case SAMPLING_OPT_ZERO_CULLING: ok = cli_value_u32(p, value, 0, 1, &v->zero_culling); break;
    case SAMPLING_OPT_TARGET_ERROR:
        ok = cli_value_double(p, value, &v->target_error);
        if (ok && !(v->target_error > 0 && v->target_error <= 1))
            ok = 0, cli_bad_value(p, value, "must be in (0, 1]");
        break;
    case SAMPLING_OPT_TIME_BUDGET:
        ok = cli_value_double(p, value, &o->time_budget);
        if (ok && !(o->time_budget >= 0))
            ok = 0, cli_bad_value(p, value, "must be >= 0 seconds");
        break;
    case SAMPLING_OPT_RAYS: ok = cli_value_u32(p, value, 1, 65536, &v->rays_per_solid_angle); break;
    case SAMPLING_OPT_SAMPLES: ok = cli_value_u32(p, value, 1, 1048576, &v->samples_per_cell); break;
    case SAMPLING_OPT_BOUNCES: ok = cli_value_u32(p, value, 0, 64, &v->bounces); break;
    default: break;
    }
    if (ok)
        o->given |= 1u << opt;
    return ok;
}

/* @return the scene's settings with every given override applied. */
static rl_sampling merged_sampling(const rl_sampling *scene, const sampling_overrides *o)
{
    rl_sampling s = *scene;
    const rl_sampling *v = &o->values;
    if (o->given & (1u << SAMPLING_OPT_METHOD))
        s.method = v->method;
    if (o->given & (1u << SAMPLING_OPT_SEED))
        s.seed = v->seed;
    if (o->given & (1u << SAMPLING_OPT_PARTITION_N))
        s.partition_n = v->partition_n;
    if (o->given & (1u << SAMPLING_OPT_RAYS))
        s.rays_per_solid_angle = v->rays_per_solid_angle;
    if (o->given & (1u << SAMPLING_OPT_SAMPLES))
        s.samples_per_cell = v->samples_per_cell;
    if (o->given & (1u << SAMPLING_OPT_BOUNCES))
        s.bounces = v->bounces;
    if (o->given & (1u << SAMPLING_OPT_BOUNCE_PARTITION_N))
        s.bounce_partition_n = v->bounce_partition_n;
    if (o->given & (1u << SAMPLING_OPT_BOUNCE_CELL_FACTOR))
        s.bounce_cell_factor = v->bounce_cell_factor;
    if (o->given & (1u << SAMPLING_OPT_DESCEND))
        s.descend = v->descend;
    if (o->given & (1u << SAMPLING_OPT_ZERO_CULLING))
        s.zero_culling = v->zero_culling;
    if (o->given & (1u << SAMPLING_OPT_TARGET_ERROR))
        s.target_error = v->target_error;
    return s;
}

int relight_failure(const char *sub, rl_status st)
{
    char line[1024];
    const char *msg = cli_one_line(rl_errmsg(), line, sizeof line);
    cli_error(sub, "%s", msg[0] != '\0' ? msg : "relighting failed");
    return st == RL_ERR_ARG || st == RL_ERR_IO || st == RL_ERR_INPUT ? ILF_EXIT_USAGE : ILF_EXIT_FAILED;
}

int relight_scene_open(const char *sub, const char *path, const sampling_overrides *o, rl_scene **out)
{
    *out = NULL;
    rl_scene *scene = NULL;
    rl_status st = rl_scene_load(path, &scene);
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
    rl_sampling s = merged_sampling(rl_scene_sampling(scene), o);
    st = rl_scene_set_sampling(scene, &s);
    if (st != RL_OK) {
        int code = relight_failure(sub, st);
        rl_scene_destroy(scene);
        return code;
    }
    *out = scene;
    return ILF_EXIT_OK;
}

void relight_run_options(const sampling_overrides *o, const rl_scene *scene, rl_run_options *out)
{
    rl_run_options_default(out);
    unsigned given = o != NULL ? o->given : 0u;
    if (given & (1u << SAMPLING_OPT_THREADS))
        out->threads = o->threads;
    /* Several ranks on one machine share its cores instead of each taking them all. */
    if (out->threads == 0 && job_ranks() > 1)
        out->threads = job_threads_per_rank();
    out->time_budget = (given & (1u << SAMPLING_OPT_TIME_BUDGET)) ? o->time_budget : rl_scene_time_budget(scene);
}

unsigned relight_threads_used(const rl_run_options *ro)
{
    return ilf_thread_count(ro->threads);
}

void relight_print_pass(FILE *out, uint32_t k, const rl_pass_stats *s)
{
    fprintf(out, "pass %" PRIu32 " (%s): %.3f s wall, %.3f s cpu, %" PRIu32 " emitter%s\n", k,
            k == 0 ? "direct" : "bounce", s->wall_seconds, s->cpu_seconds, s->emitters, s->emitters == 1 ? "" : "s");
    fprintf(out, "  samples %" PRIu64 ", rays cast %" PRIu64 ", rays kept %" PRIu64 "\n", s->samples, s->rays_cast,
            s->rays_kept);
    fprintf(out, "  solid angles considered %" PRIu64 ", culled %" PRIu64 "; pairs %" PRIu64 ", descended %" PRIu64
                 "\n",
            s->solid_angles_considered, s->solid_angles_culled, s->pairs, s->pairs_descended);
    if (s->refinements > 0 || s->estimated_rmse > 0)
        fprintf(out, "  adaptive: %" PRIu64 " refinements, estimated RMSE %.4g W m^-2%s\n", s->refinements,
                s->estimated_rmse, s->budget_reached ? ", time budget reached" : "");
}
