/*
 * cmd_irradiance.c - `ilf irradiance SCENE --points FILE`: the irradiance
 * at given points of a scene, like Radiance's rtrace -I. FILE ("-" for
 * standard input) has one point per line, "x y z nx ny nz" (position, then
 * the normal the receiver faces); blank lines and lines whose first
 * non-blank character is '#' are skipped. stdout gets "r g b" in W m^-2 for
 * each point, in order, printed with %.6g.
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
#include "relight/engine.h"
#include "relight_cli.h"

typedef struct irradiance_options {
    const char *scene;
    const char *points;
    sampling_overrides sampling;
} irradiance_options;

/* Options after the shared sampling ones, whose ids come first (relight_cli.h). */
enum irradiance_option_id { OPT_POINTS = SAMPLING_OPT_COUNT };

static const cli_option irradiance_options_table[] = {
    RELIGHT_SAMPLING_OPTIONS,
    {"points", 'p', "FILE", "points, one 'x y z nx ny nz' per line; '-' reads standard input (required)"},
};

static const cli_usage irradiance_usage = {
    "irradiance",
    "SCENE --points FILE [--method M] [--threads N] [--seed S] [--partition-n N]\n"
    "                      [--rays K] [--samples N] [--bounces B]",
    "Prints the irradiance (W m^-2, r g b) at each point of FILE, like Radiance's\n"
    "rtrace -I: a point 'x y z nx ny nz' is a receiver of zero area at (x, y, z)\n"
    "facing the normal (nx, ny, nz), which need not be unit length. Blank lines and\n"
    "lines starting with # are skipped. With bounces > 0 the light reflected by the\n"
    "scene is included. Sampling options replace the scene's own settings.",
    "ilf irradiance data/beams_diffuse.json --points sensors.txt\n"
    "printf '2.5 2.5 0 0 0 1\\n' | ilf irradiance data/beams_diffuse.json --points - --bounces 1",
};

/* Points read from a file: 6 doubles each. */
typedef struct point_list {
    double *values;
    size_t count, capacity;
} point_list;

/* ------------------------------------------------------------ options */

/* Applies one option to the irradiance_options ctx. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    irradiance_options *o = ctx;
    if (opt != OPT_POINTS)
        return sampling_option_apply(p, &o->sampling, opt, value);
    o->points = value;
    return 1;
}

/* Parses argv into *o. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(irradiance_options *o, int argc, char **argv)
{
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

/* ------------------------------------------------------------ points */

/* @return 1 if line holds only blanks, or a comment starting with '#' after them. */
static int skippable(const char *line)
{
    line += strspn(line, " \t\r\n\v\f");
    return *line == '\0' || *line == '#';
}

/*
 * Parses one point line into out[6]: exactly six finite numbers separated
 * by blanks, with a nonzero normal. @return 1, or 0 with a reason in why.
 */
static int parse_point(char *line, double out[6], char *why, size_t why_size)
{
    static const char blanks[] = " \t\r\n\v\f";
    char *save = NULL;
    int found = 0;
    for (char *field = strtok_r(line, blanks, &save); field != NULL; field = strtok_r(NULL, blanks, &save)) {
        if (found == 6) {
            snprintf(why, why_size, "more than 6 numbers (expected x y z nx ny nz)");
            return 0;
        }
        char inner[160];
        if (!cli_parse_double(field, &out[found], inner, sizeof inner)) {
            snprintf(why, why_size, "value %d: %s", found + 1, inner);
            return 0;
        }
        found++;
    }
    if (found < 6) {
        snprintf(why, why_size, "%d number%s, expected 6 (x y z nx ny nz)", found, found == 1 ? "" : "s");
        return 0;
    }
    if (out[3] == 0.0 && out[4] == 0.0 && out[5] == 0.0) {
        snprintf(why, why_size, "the normal (nx ny nz) is zero");
        return 0;
    }
    return 1;
}

/* Appends one point to list. @return 1, or 0 when memory runs out. */
static int append_point(point_list *list, const double p[6])
{
    if (list->count == list->capacity) {
        size_t grown = list->capacity ? 2 * list->capacity : 256;
        double *more = realloc(list->values, grown * 6 * sizeof *more);
        if (more == NULL)
            return 0;
        list->values = more;
        list->capacity = grown;
    }
    memcpy(list->values + 6 * list->count++, p, 6 * sizeof *p);
    return 1;
}

/* Reads every point of path ("-": stdin) into list. @return an exit code, after reporting any problem. */
static int read_points(const char *path, point_list *list)
{
    int from_stdin = strcmp(path, "-") == 0;
    const char *shown = from_stdin ? "<stdin>" : path;
    FILE *f = from_stdin ? stdin : fopen(path, "r");
    if (f == NULL) {
        cli_error("irradiance", "%s: cannot open: %s", path, strerror(errno));
        return ILF_EXIT_USAGE;
    }
    char *line = NULL;
    size_t cap = 0;
    unsigned long number = 0;
    int code = ILF_EXIT_OK;
    while (code == ILF_EXIT_OK && getline(&line, &cap, f) >= 0) {
        number++;
        double p[6];
        char why[256];
        if (skippable(line))
            continue;
        if (!parse_point(line, p, why, sizeof why)) {
            cli_error("irradiance", "%s:%lu: %s", shown, number, why);
            code = ILF_EXIT_USAGE;
        } else if (!append_point(list, p)) {
            cli_error("irradiance", "out of memory after %zu points", list->count);
            code = ILF_EXIT_FAILED;
        }
    }
    if (code == ILF_EXIT_OK && ferror(f)) {
        cli_error("irradiance", "%s: cannot read: %s", shown, strerror(errno));
        code = ILF_EXIT_USAGE;
    }
    free(line);
    if (!from_stdin)
        fclose(f);
    return code;
}

/* ------------------------------------------------------------ main */

/* Computes and prints the irradiance of every point. @return an exit code. */
static int print_irradiance(const rl_scene *scene, const point_list *points)
{
    if (points->count == 0)
        return ILF_EXIT_OK;
    double *rgb = malloc(3 * points->count * sizeof *rgb);
    if (rgb == NULL) {
        cli_error("irradiance", "out of memory for %zu points", points->count);
        return ILF_EXIT_FAILED;
    }
    rl_status st = rl_irradiance(scene, points->values, points->count, rgb, NULL);
    int code = st == RL_OK ? ILF_EXIT_OK : relight_failure("irradiance", st);
    for (size_t k = 0; code == ILF_EXIT_OK && k < points->count; k++)
        printf("%.6g %.6g %.6g\n", rgb[3 * k], rgb[3 * k + 1], rgb[3 * k + 2]);
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
    code = relight_scene_open("irradiance", o.scene, &o.sampling, &scene);
    if (code == ILF_EXIT_OK)
        code = read_points(o.points, &points);
    if (code == ILF_EXIT_OK)
        code = print_irradiance(scene, &points);
    free(points.values);
    rl_scene_destroy(scene);
    return code;
}
