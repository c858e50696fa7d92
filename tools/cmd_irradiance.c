/*
 * cmd_irradiance.c - `ilf irradiance SCENE --points FILE`: the irradiance
 * at given points of a scene, like Radiance's rtrace -I. FILE ("-" for
 * standard input) has one point per line, "x y z nx ny nz" (position, then
 * the normal the receiver faces); blank lines and lines whose first
 * non-blank character is '#' are skipped. stdout gets "r g b" in W m^-2 for
 * each point, in order, printed with %.6g (with --lux, one illuminance in lux).
 * stderr gets the settings line, the progress bar and warnings (cli.h), none
 * with --quiet.
 *
 * Invariants: the whole file is read and checked before the engine runs
 * (every malformed line is bad input, reported as FILE:LINE); all points go
 * to one rl_irradiance() call, so the scene is set up once; stdout carries
 * only the results, one line per point.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "job.h"
#include "points_file.h"
#include "relight/engine.h"
#include "relight_cli.h"
#include "tonemap.h"

typedef struct irradiance_options {
    const char *scene;
    const char *points;
    sampling_overrides sampling;
    int quiet;
    int lux; /* print illuminance in lux instead of irradiance */
} irradiance_options;

/* Options after the shared sampling ones, whose ids come first (relight_cli.h). */
enum irradiance_option_id { OPT_POINTS = SAMPLING_OPT_COUNT, OPT_QUIET, OPT_LUX };

/* The sampling options' entries are filled by relight_options_fill() before parsing. */
static cli_option irradiance_options_table[] = {
    [OPT_POINTS] = {"points", 'p', "FILE", "points, one 'x y z nx ny nz' per line; '-' reads standard input (required)"},
    [OPT_QUIET] = {"quiet", 'q', NULL, "no settings line, progress bar or warnings on stderr"},
    [OPT_LUX] = {"lux", 0, NULL,
                 "print the illuminance in lux, 179 lm/W times the Rec.709 luminance of r g b, one number a point"},
};

static const cli_usage irradiance_usage = {
    "irradiance",
    "SCENE --points FILE [--lux] [--quiet] [--method M] [--threads N] [--seed S]\n"
    "                      [--partition-n N] [--rays K] [--samples N] [--bounces B]",
    "Prints the irradiance (W m^-2, r g b) at each point of FILE, like Radiance's\n"
    "rtrace -I: a point 'x y z nx ny nz' is a receiver of zero area at (x, y, z)\n"
    "facing the normal (nx, ny, nz), which need not be unit length. Blank lines and\n"
    "lines starting with # are skipped. With bounces > 0 the light reflected by the\n"
    "scene is included. Sampling options replace the scene's own settings. stderr\n"
    "gets the settings used (method, samples, bounces, threads), a progress bar and\n"
    "warnings (a scene without emitters, most points unlit) unless --quiet.",
    "ilf irradiance data/beams_diffuse.json --points sensors.txt   # one x y z nx ny nz a line\n"
    "printf '2.5 2.5 0 0 0 1\\n' | ilf irradiance data/beams_diffuse.json --points - --bounces 1\n"
    "printf '2.5 2.5 0 0 0 1\\n' | ilf irradiance data/beams_diffuse.json --points - --lux --quiet",
};

/* ------------------------------------------------------------ options */

/* Applies one option to the irradiance_options ctx. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    irradiance_options *o = ctx;
    if (opt == OPT_POINTS)
        o->points = value;
    else if (opt == OPT_QUIET)
        o->quiet = 1;
    else if (opt == OPT_LUX)
        o->lux = 1;
    else
        return sampling_option_apply(p, &o->sampling, opt, value);
    return 1;
}

/* Parses argv into *o. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(irradiance_options *o, int argc, char **argv)
{
    if (!relight_options_fill("irradiance", irradiance_options_table))
        return ILF_EXIT_FAILED;
    int code = cli_parse(&irradiance_usage, irradiance_options_table,
                         sizeof irradiance_options_table / sizeof irradiance_options_table[0], argc, argv,
                         &o->scene, apply_option, o);
    if (code != -1)
        return code;
    const char *problem = o->scene == NULL    ? "no scene given (see 'ilf irradiance --help')"
                          : o->points == NULL ? "--points FILE is required"
                                              : NULL;
    if (problem != NULL) {
        cli_error("irradiance", "%s", problem);
        return ILF_EXIT_USAGE;
    }
    return -1;
}

/* ------------------------------------------------------------ main */

/* Collective: gives every rank rank 0's points. @return an exit code. */
static int share_points(point_list *points)
{
    unsigned long long count = points->count;
    if (!job_share("irradiance", &count, sizeof count))
        return job_fail(ILF_EXIT_FAILED);
    if (job_rank() != 0) {
        points->values = malloc((count ? count : 1) * 6 * sizeof *points->values);
        if (points->values == NULL) {
            cli_error("irradiance", "out of memory for %llu points", count);
            return job_fail(ILF_EXIT_FAILED);
        }
        points->count = points->capacity = (size_t)count;
    }
    if (count > 0 && !job_share("irradiance", points->values, (size_t)count * 6 * sizeof *points->values))
        return job_fail(ILF_EXIT_FAILED);
    return ILF_EXIT_OK;
}

/* Warns when most of the count points (rgb, [count][3]) received nothing. */
static void warn_unlit(const char *scene, const double *rgb, size_t count)
{
    size_t dark = 0;
    for (size_t k = 0; k < count; k++)
        dark += !(rgb[3 * k] > 0 || rgb[3 * k + 1] > 0 || rgb[3 * k + 2] > 0);
    if (2 * dark > count)
        cli_warn("%s: %zu of the %zu points (%.1f%%) received no light (normals facing away from the light?)",
                 scene, dark, count, 100.0 * (double)dark / (double)count);
}

/* Prints point k's result: r g b in W m^-2, or with lux the illuminance in lux. */
static void print_point(const double *rgb, int lux)
{
    if (lux)
        printf("%.6g\n", tone_lux(rgb));
    else
        printf("%.6g %.6g %.6g\n", rgb[0], rgb[1], rgb[2]);
}

/* Computes and prints the irradiance of every point. @return an exit code. */
static int print_irradiance(const rl_scene *scene, const rl_job *given, const irradiance_options *o,
                            const point_list *points)
{
    if (points->count == 0)
        return ILF_EXIT_OK;
    double *rgb = malloc(3 * points->count * sizeof *rgb);
    if (rgb == NULL) {
        cli_error("irradiance", "out of memory for %zu points", points->count);
        return ILF_EXIT_FAILED;
    }
    rl_job job = *given;
    relight_print_settings("irradiance", &job);
    cli_progress bar;
    cli_progress_start(&bar, "irradiance", CLI_PROGRESS_STEPS);
    job.run.progress = bar.enabled ? cli_progress_fraction : NULL;
    job.run.progress_user = &bar;
    rl_status st = rl_irradiance_cluster(scene, job_cluster(), &job, points->values, points->count, rgb, NULL);
    cli_progress_finish(&bar);
    /* the other ranks may be waiting in an exchange this rank will not reach: end the job */
    int code = st == RL_OK ? ILF_EXIT_OK : job_fail(relight_failure("irradiance", st));
    if (code == ILF_EXIT_OK && job_rank() == 0)
        warn_unlit(o->scene, rgb, points->count);
    for (size_t k = 0; code == ILF_EXIT_OK && job_rank() == 0 && k < points->count; k++)
        print_point(rgb + 3 * k, o->lux);
    free(rgb);
    if (code == ILF_EXIT_OK && fflush(stdout) != 0) {
        cli_error("irradiance", "cannot write the results: %s", strerror(errno));
        code = ILF_EXIT_FAILED;
    }
    return code;
}

int ilf_cmd_irradiance(int argc, char **argv)
{
    irradiance_options o = {0};
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    point_list points = {NULL, 0, 0};
    rl_scene *scene = NULL;
    rl_job job;
    cli_set_quiet(o.quiet || job_rank() != 0);
    code = job_agree(relight_scene_open("irradiance", o.scene, &o.sampling, &scene, &job));
    if (code == ILF_EXIT_OK && job_rank() == 0)
        relight_warn_scene(scene, 0);
    /* rank 0 alone reads the points (standard input reaches it only) and shares them */
    if (code == ILF_EXIT_OK && job_rank() == 0)
        code = points_read(o.points, &points);
    code = job_agree(code);
    if (code == ILF_EXIT_OK && job_ranks() > 1)
        code = job_agree(share_points(&points));
    if (code == ILF_EXIT_OK)
        code = print_irradiance(scene, &job, &o, &points);
    points_free(&points);
    rl_scene_destroy(scene);
    return code;
}
