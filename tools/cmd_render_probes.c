/*
 * cmd_render_probes.c - `ilf render-probes SCENE --plane O:U:V --grid NUxNV
 * --size WxH -o DIR`: a synthetic capture. The scene is relit with the
 * engine (relight/engine.h, its own settings unless overridden), then at
 * every grid position of every plane (--plane may be given several times)
 * the equirectangular probe image of the radiance arriving there is rendered
 * (cap_probe_render with rl_solution_trace) and written as
 * DIR/probe_I_J.exr (one plane) or DIR/probe_K_I_J.exr (plane K of several),
 * and DIR/manifest.json describes them for `ilf capture`: one slab per plane.
 *
 * Invariants: every option, the request's size (ILF_PROBE_MAX_PIXELS and
 * ILF_PROBE_MAX_RAYS) and DIR (a folder that can be written or created,
 * manifest.json a regular file or nothing) are checked before the scene is
 * read; DIR is created (with any missing parents) before any work. Images
 * and the manifest are written into a staging folder inside DIR
 * (".render-probes.tmp-XXXXXX") and placed together once all are written
 * (output_set.h): the probes of an earlier run that this grid does not
 * have are removed in the same step, and a failure or an interruption
 * leaves DIR as it was (removing the folders it created); probes use the identity orientation (camera forward
 * +x, up +z) and the jitter seed is the scene's (or --seed's) seed.
 */
#include <dirent.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "capture/capture.h"
#include "cli.h"
#include "commands.h"
#include "image/image.h"
#include "output_set.h"
#include "relight/engine.h"
#include "relight_cli.h"
#include "ilf/limits.h"

#define PATH_BYTES 4096
/* The staging folder's name template (cli_staging_make()) and the prefix of an earlier file moved aside. */
#define STAGE_TEMPLATE ".render-probes.tmp-XXXXXX"
#define ASIDE_PREFIX ".earlier-"
/* The names of the outputs. */
#define PROBE_NAME "probe_%" PRIu32 "_%" PRIu32 ".exr"
#define PLANE_PROBE_NAME "probe_%zu_%" PRIu32 "_%" PRIu32 ".exr"
#define MANIFEST_NAME "manifest.json"
#define MAX_GRID ILF_PROBE_MAX_GRID
#define MAX_SIDE ILF_PROBE_MAX_SIDE
#define MAX_PLANES ILF_CAPTURE_MAX_PLANES

typedef struct probes_options {
    const char *scene;
    const char *output;
    sampling_overrides sampling;
    lfio_slab_desc planes[MAX_PLANES]; /* plane, grid, n and name of each slab for the manifest */
    int own_grid[MAX_PLANES];          /* 1 where --plane gave the plane's grid */
    size_t nplanes;
    uint32_t grid[2];                  /* --grid: of the planes without their own */
    uint32_t n;
    char name[LFIO_NAME_MAX + 1];
    uint32_t size[2];
    uint32_t strata;
    int quiet;
} probes_options;

/* Options after the shared sampling ones, whose ids come first (relight_cli.h). */
enum probes_option_id { OPT_PLANE = SAMPLING_OPT_COUNT, OPT_GRID, OPT_SIZE, OPT_STRATA, OPT_N, OPT_NAME,
                        OPT_OUTPUT, OPT_QUIET };

/* The sampling options' entries are filled by relight_options_fill() before parsing. */
static cli_option probes_options_table[] = {
    [OPT_PLANE] = {"plane", 0, "O:U:V[:NUxNV]", "capture plane origin:u:v, each X,Y,Z in metres, u and v orthogonal, "
                   "optionally its own grid; repeat for several planes, one slab each (required)"},
    [OPT_GRID] = {"grid", 0, "NUxNV", "probe positions along u and v, at cell centres, of the planes without their own "
                  "(default 1x1, up to 1024 each)"},
    [OPT_SIZE] = {"size", 0, "WxH", "equirectangular probe image size (default 256x128)"},
    [OPT_STRATA] = {"strata", 0, "S", "S*S jittered directions per pixel, 1 .. 64 (default 2)"},
    [OPT_N] = {"n", 0, "N", "partition level written in the manifest for `ilf capture` (default 16)"},
    [OPT_NAME] = {"name", 0, "NAME", "slab name written in the manifest (default probes; NAME0, NAME1, ... for "
                  "several planes)"},
    [OPT_OUTPUT] = {"output", 'o', "DIR", "folder for probe_I_J.exr (probe_K_I_J.exr for plane K of several) and "
                    "manifest.json (required; created)"},
    [OPT_QUIET] = {"quiet", 'q', NULL, "no progress bar and no summary on stdout"},
};

static const cli_usage probes_usage = {
    "render-probes",
    "SCENE --plane O:U:V[:NUxNV] [--plane ...] -o DIR [--grid NUxNV] [--size WxH]\n"
    "                         [--strata S] [--n N] [--name NAME] [relight options] [--quiet]",
    "Relights the scene (docs/scene.md), then renders the equirectangular light probe\n"
    "each grid position of each plane would see (radiance of the first surface along\n"
    "each direction; light field emitters are not surfaces and are not seen), writes\n"
    "them to DIR/probe_I_J.exr (DIR/probe_K_I_J.exr for plane K of several) and a\n"
    "manifest for `ilf capture` to DIR/manifest.json (docs/capture.md), one slab per\n"
    "plane. The light field captured from a plane stores the light crossing it\n"
    "towards its front e3 = u x v.",
    "ilf render-probes data/capture/scene.json --plane -0.5,0.5,1.5:1,0,0:0,-1,0 --grid 2x2 -o probes\n"
    "ilf capture probes/manifest.json -o probes.h5",
};

/* ------------------------------------------------------------ options */

/* Parses a grid "NUxNV", each 1 .. MAX_GRID, into grid. @return 1, or 0 if the text is not one. */
static int parse_grid_text(const char *text, uint32_t grid[2])
{
    char *end = NULL;
    for (int k = 0; k < 2; k++) {
        if (*text < '0' || *text > '9')
            return 0;
        errno = 0;
        unsigned long v = strtoul(text, &end, 10);
        if (errno != 0 || v < 1 || v > MAX_GRID || *end != (k == 0 ? 'x' : '\0'))
            return 0;
        grid[k] = (uint32_t)v;
        text = end + 1;
    }
    return 1;
}

/* Parses "ox,oy,oz:ux,uy,uz:vx,vy,vz[:NUxNV]" into d (and its grid, *own_grid = 1, when given).
 * @return NULL, or why the text is not a plane. */
static const char *plane_problem(const char *text, lfio_slab_desc *d, int *own_grid, char why[128])
{
    char buf[256];
    double *dest[3] = {d->origin, d->u, d->v};
    if (strlen(text) >= sizeof buf)
        return "too long";
    strcpy(buf, text);
    char *part = buf;
    for (int k = 0; k < 3; k++) {
        char *colon = strchr(part, ':');
        if (colon == NULL && k < 2)
            return "expected origin:u:v, three X,Y,Z separated by ':', and optionally :NUxNV";
        if (colon != NULL)
            *colon = '\0';
        if (!cli_parse_doubles(part, dest[k], 3, why, 128))
            return why;
        part = colon != NULL ? colon + 1 : NULL;
    }
    uint32_t grid[2];
    if (part != NULL && !parse_grid_text(part, grid))
        return "the fourth part must be a grid NUxNV, 1 .. 1024 each";
    if (lfio_slab_edges_check(d->u, d->v) != LFIO_EDGES_OK)
        return "u and v must be nonzero and orthogonal";
    *own_grid = part != NULL;
    if (part != NULL) {
        d->nu = grid[0];
        d->nv = grid[1];
    }
    return NULL;
}

/* Adds the plane --plane text gives. @return 1, or 0 after reporting. */
static int parse_plane(const cli_parser *p, const char *text, probes_options *o)
{
    char why[128];
    if (o->nplanes == MAX_PLANES) {
        cli_bad_value(p, text, "too many planes (at most 64)");
        return 0;
    }
    lfio_slab_desc *d = &o->planes[o->nplanes];
    lfio_slab_desc_init(d);
    const char *problem = plane_problem(text, d, &o->own_grid[o->nplanes], why);
    if (problem != NULL) {
        cli_bad_value(p, text, problem);
        return 0;
    }
    o->nplanes++;
    return 1;
}

/* A slab name for the manifest: 1 to 63 of A-Z a-z 0-9 _ - . */
static int parse_name(const cli_parser *p, const char *text, char name[LFIO_NAME_MAX + 1])
{
    if (!lfio_slab_name_valid(text)) {
        cli_bad_value(p, text, "use 1 to 63 of A-Z a-z 0-9 _ - .");
        return 0;
    }
    memcpy(name, text, strlen(text) + 1);
    return 1;
}

/* Applies one non-sampling option. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    probes_options *o = ctx;
    switch (opt) {
    case OPT_PLANE:
        return parse_plane(p, value, o);
    case OPT_GRID:
        return cli_value_u32_pair(p, value, 'x', 1, MAX_GRID, o->grid);
    case OPT_SIZE:
        return cli_value_u32_pair(p, value, 'x', 1, MAX_SIDE, o->size);
    case OPT_STRATA:
        return cli_value_u32(p, value, 1, 64, &o->strata);
    case OPT_N:
        return cli_value_u32(p, value, 1, LFIO_SLAB_MAX_N, &o->n);
    case OPT_NAME:
        return parse_name(p, value, o->name);
    case OPT_OUTPUT:
        o->output = value;
        return 1;
    case OPT_QUIET:
        o->quiet = 1;
        return 1;
    default:
        return sampling_option_apply(p, &o->sampling, opt, value);
    }
}

static void set_defaults(probes_options *o)
{
    memset(o, 0, sizeof *o);
    snprintf(o->name, sizeof o->name, "probes");
    o->n = 16;
    o->grid[0] = o->grid[1] = 1;
    o->size[0] = 256;
    o->size[1] = 128;
    o->strata = 2;
}

/* Gives every plane n, its name (NAME, or NAME0, NAME1, ... for several) and --grid unless it has its own. */
static void finish_planes(probes_options *o)
{
    for (size_t k = 0; k < o->nplanes; k++) {
        lfio_slab_desc *d = &o->planes[k];
        d->n = o->n;
        if (o->nplanes == 1)
            snprintf(d->name, sizeof d->name, "%s", o->name);
        else
            snprintf(d->name, sizeof d->name, "%.61s%zu", o->name, k);
        if (!o->own_grid[k]) {
            d->nu = o->grid[0];
            d->nv = o->grid[1];
        }
    }
}

/* @return the probes over every plane. */
static uint64_t probe_count(const probes_options *o)
{
    uint64_t total = 0;
    for (size_t k = 0; k < o->nplanes; k++)
        total += (uint64_t)o->planes[k].nu * o->planes[k].nv;
    return total;
}

/* Checks that the probes o asks for are within ILF_PROBE_MAX_PIXELS and ILF_PROBE_MAX_RAYS (each option is
 * bounded alone, but not their product). @return -1 to go on, or ILF_EXIT_USAGE after reporting. */
static int check_work(const probes_options *o)
{
    uint64_t probes = probe_count(o);
    uint64_t pixels = probes * o->size[0] * o->size[1]; /* < 64 * 2^20 * 2^28 */
    uint64_t rays = pixels * o->strata * o->strata;                                 /* < 2^60 */
    if (pixels > ILF_PROBE_MAX_PIXELS || rays > ILF_PROBE_MAX_RAYS) {
        cli_error("render-probes", "%" PRIu64 " probes of %" PRIu32 "x%" PRIu32 " pixels with %" PRIu32
                  "x%" PRIu32 " strata are %" PRIu64 " pixels and %" PRIu64 " rays, more than the limits of %" PRIu64
                  " and %" PRIu64 " (ilf/limits.h)", probes, o->size[0], o->size[1], o->strata,
                  o->strata, pixels, rays, (uint64_t)ILF_PROBE_MAX_PIXELS, (uint64_t)ILF_PROBE_MAX_RAYS);
        return ILF_EXIT_USAGE;
    }
    return -1;
}

/* Parses argv into *o. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(probes_options *o, int argc, char **argv)
{
    if (!relight_options_fill("render-probes", probes_options_table))
        return ILF_EXIT_FAILED;
    int code = cli_parse(&probes_usage, probes_options_table,
                         sizeof probes_options_table / sizeof probes_options_table[0], argc, argv, &o->scene,
                         apply_option, o);
    if (code != -1)
        return code;
    const char *problem = NULL;
    if (o->scene == NULL)
        problem = "no scene given (see 'ilf render-probes --help')";
    else if (o->nplanes == 0)
        problem = "--plane O:U:V is required";
    else if (o->output == NULL || o->output[0] == '\0')
        problem = "-o DIR is required";
    if (problem == NULL && o->nplanes > 1 && strlen(o->name) + 2 > LFIO_NAME_MAX)
        problem = "--name: with several planes the name takes a number after it: use at most 61 characters";
    if (problem != NULL) {
        cli_error("render-probes", "%s", problem);
        return ILF_EXIT_USAGE;
    }
    finish_planes(o);
    return check_work(o);
}

/* ------------------------------------------------------------ files */

/* Where the run's files go: DIR, the staging folder in it, and what was created for them. */
typedef struct probes_files {
    const probes_options *o;
    char stage[PATH_BYTES]; /* the staging folder, "" until made */
    size_t created_from;    /* length of the first folder of DIR this run created (cli_folder_make()); 0: none */
    char **stale;           /* probe files of an earlier run in DIR that this grid does not have */
    size_t nstale;
} probes_files;

/* out = "dir/name" (PATH_BYTES). @return 1, or 0 when it does not fit. */
static int join(const char *dir, const char *name, char out[PATH_BYTES])
{
    size_t len = strlen(dir);
    int n = snprintf(out, PATH_BYTES, "%s%s%s", dir, len > 0 && dir[len - 1] == '/' ? "" : "/", name);
    return n > 0 && n < PATH_BYTES;
}

/* out = the staged path of output name. @return 1, or 0 after reporting that it is too long. */
static int output_path(const probes_files *f, const char *name, char out[PATH_BYTES])
{
    if (!join(f->stage, name, out)) {
        cli_error("render-probes", "%s/%s: path too long", f->stage, name);
        return 0;
    }
    return 1;
}

/* Creates DIR (and missing parents) and the staging folder in it, both removed by an interruption.
 * @return 1, or 0 after reporting. */
static int files_open(probes_files *f)
{
    if (!cli_folder_make("render-probes", f->o->output, &f->created_from))
        return 0;
    if (!join(f->o->output, STAGE_TEMPLATE, f->stage) || cli_staging_make(f->stage) == NULL) {
        cli_error("render-probes", "cannot create a staging folder in '%s': %s", f->o->output, strerror(errno));
        f->stage[0] = '\0';
        return 0;
    }
    char manifest[PATH_BYTES];
    if (join(f->o->output, MANIFEST_NAME, manifest))
        cli_output_watch(manifest); /* the set's last name: an interruption says whether the set was placed */
    return 1;
}

/* The file name of probe (i, j) of plane k: PROBE_NAME for one plane, PLANE_PROBE_NAME for several. */
static void probe_name(const probes_options *o, size_t k, uint32_t i, uint32_t j, char out[64])
{
    if (o->nplanes == 1)
        snprintf(out, 64, PROBE_NAME, i, j);
    else
        snprintf(out, 64, PLANE_PROBE_NAME, k, i, j);
}

/* @return 1 if name is a probe file name (either form, exactly) that this run does not write. */
static int stale_probe(const char *name, const probes_options *o)
{
    size_t k = 0;
    uint32_t i, j;
    char again[64];
    if (sscanf(name, "probe_%zu_%" SCNu32 "_%" SCNu32 ".exr", &k, &i, &j) == 3) {
        snprintf(again, sizeof again, PLANE_PROBE_NAME, k, i, j);
        if (strcmp(again, name) != 0)
            return 0;
        return o->nplanes == 1 || k >= o->nplanes || i >= o->planes[k].nu || j >= o->planes[k].nv;
    }
    if (sscanf(name, "probe_%" SCNu32 "_%" SCNu32 ".exr", &i, &j) != 2)
        return 0;
    snprintf(again, sizeof again, PROBE_NAME, i, j);
    return strcmp(again, name) == 0 && (o->nplanes != 1 || i >= o->planes[0].nu || j >= o->planes[0].nv);
}

/* Lists the probe files of an earlier run in DIR that this run's grid does not have. @return 1, or 0 after
 * reporting (out of memory). */
static int find_stale(probes_files *f)
{
    DIR *dir = opendir(f->o->output);
    if (dir == NULL)
        return 1; /* nothing to list: the placing reports what is wrong with DIR */
    int ok = 1;
    size_t cap = 0;
    for (struct dirent *e; ok && (e = readdir(dir)) != NULL;) {
        if (!stale_probe(e->d_name, f->o))
            continue;
        if (f->nstale == cap) {
            size_t more = cap ? 2 * cap : 16;
            char **grown = realloc(f->stale, more * sizeof *grown);
            ok = grown != NULL;
            if (ok)
                f->stale = grown, cap = more;
        }
        if (ok && (f->stale[f->nstale] = strdup(e->d_name)) != NULL)
            f->nstale++;
        else
            ok = 0;
    }
    closedir(dir);
    if (!ok)
        cli_error("render-probes", "out of memory while listing %s", f->o->output);
    return ok;
}

/* output_slot_fn: slot k of the set, the probes plane by plane in grid order, then the manifest, then the stale probes. */
static int probes_slot(void *user, size_t k, output_slot *slot)
{
    const probes_files *f = user;
    const probes_options *o = f->o;
    size_t probes = (size_t)probe_count(o), index = k, plane = 0;
    char name[PATH_BYTES], aside[PATH_BYTES];
    while (plane < o->nplanes && index >= (size_t)o->planes[plane].nu * o->planes[plane].nv)
        index -= (size_t)o->planes[plane].nu * o->planes[plane].nv, plane++;
    if (k < probes)
        probe_name(o, plane, (uint32_t)(index % o->planes[plane].nu), (uint32_t)(index / o->planes[plane].nu), name);
    else
        snprintf(name, sizeof name, "%s", k == probes ? MANIFEST_NAME : f->stale[k - probes - 1]);
    slot->written = k <= probes;
    return snprintf(aside, sizeof aside, "%s%s", ASIDE_PREFIX, name) < (int)sizeof aside &&
           join(f->stage, name, slot->staged) && join(f->o->output, name, slot->placed) &&
           join(f->stage, aside, slot->aside);
}

/* Places every staged file into DIR as one step, with the earlier run's probes outside this grid removed.
 * @return an exit code. */
static int files_place(probes_files *f)
{
    if (!find_stale(f))
        return ILF_EXIT_FAILED;
    size_t count = (size_t)probe_count(f->o) + 1 + f->nstale;
    return output_set_place("render-probes", f->o->output, count, probes_slot, f);
}

/* Removes the staging folder with what is left in it (files moved aside among them), then the folders this run
 * created if they are empty. */
static void files_close(probes_files *f)
{
    if (f->stage[0] != '\0') {
        DIR *dir = opendir(f->stage);
        char victim[PATH_BYTES];
        for (struct dirent *e; dir != NULL && (e = readdir(dir)) != NULL;)
            if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0 && join(f->stage, e->d_name, victim))
                unlink(victim);
        if (dir != NULL)
            closedir(dir);
        rmdir(f->stage);
        cli_staging_forget(f->stage);
    }
    cli_folder_unmake(f->o->output, f->created_from);
    for (size_t k = 0; k < f->nstale; k++)
        free(f->stale[k]);
    free(f->stale);
}

/* The file name pattern of plane k's probes: probe_{i}_{j}.exr for one plane, probe_K_{i}_{j}.exr for several. */
static void probe_pattern(const probes_options *o, size_t k, char out[64])
{
    if (o->nplanes == 1)
        snprintf(out, 64, "probe_{i}_{j}.exr");
    else
        snprintf(out, 64, "probe_%zu_{i}_{j}.exr", k);
}

/* Writes the manifest `ilf capture` reads back (docs/capture.md) through capture's writer: the one-plane form,
 * or "planes" for several; radiance as rendered, equirectangular, linear. @return an exit code. */
static int write_manifest(const probes_files *f)
{
    const probes_options *o = f->o;
    char path[PATH_BYTES], patterns[MAX_PLANES][64];
    if (!output_path(f, MANIFEST_NAME, path))
        return ILF_EXIT_FAILED;
    cap_manifest_plane planes[MAX_PLANES];
    for (size_t k = 0; k < o->nplanes; k++) {
        probe_pattern(o, k, patterns[k]);
        planes[k] = (cap_manifest_plane){&o->planes[k], patterns[k]};
    }
    const cap_manifest_spec spec = {o->n, LFIO_UNITS_RADIANCE, CAP_PROJECTION_EQUIRECTANGULAR, CAP_COLOUR_LINEAR,
                                    o->nplanes, planes};
    cap_status st = cap_manifest_write(path, &spec);
    if (st != CAP_OK) {
        cli_error("render-probes", "%s", cap_error_message());
        return ILF_EXIT_FAILED;
    }
    return ILF_EXIT_OK;
}

/* ------------------------------------------------------------ rendering */

/* cap_radiance_fn over rl_solution_trace. */
static int trace(void *user, const double org[3], const double dir[3], float rgb[3])
{
    return rl_solution_trace(user, org, dir, rgb) == RL_OK;
}

static int relight(const probes_options *o, const rl_scene *scene, const rl_job *given, rl_solution **sol)
{
    cli_progress bar;
    rl_job job = *given;
    cli_set_quiet(o->quiet);
    relight_print_settings("render-probes", &job);
    relight_warn_scene(scene, 0);
    if (!o->quiet)
        cli_progress_start(&bar, "relight", CLI_PROGRESS_STEPS);
    job.run.progress = o->quiet ? NULL : cli_progress_fraction;
    job.run.progress_user = &bar;
    rl_status st = rl_relight(scene, &job, sol);
    if (!o->quiet)
        cli_progress_finish(&bar);
    if (st == RL_OK)
        relight_warn_solution(*sol, 0);
    return st == RL_OK ? ILF_EXIT_OK : relight_failure("render-probes", st);
}

/* Renders the probe of position (i, j) of plane k into pixels and writes it. @return an exit code. */
static int render_probe(const probes_files *f, const rl_solution *sol, const cap_probe_settings *s, size_t k,
                        uint32_t i, uint32_t j, float *pixels)
{
    const lfio_slab_desc *d = &f->o->planes[k];
    double x[3];
    for (int a = 0; a < 3; a++)
        x[a] = d->origin[a] + (i + 0.5) / d->nu * d->u[a] + (j + 0.5) / d->nv * d->v[a];
    cap_status st = cap_probe_render(s, trace, (void *)sol, x, NULL, pixels);
    if (st != CAP_OK)
        return ilf_capture_failure("render-probes", st);
    char name[64], path[PATH_BYTES], err[1024];
    probe_name(f->o, k, i, j, name);
    if (!output_path(f, name, path))
        return ILF_EXIT_FAILED;
    if (img_write(path, s->width, s->height, 3, pixels, err, sizeof err) != IMG_OK) {
        cli_error("render-probes", "%s", err);
        return ILF_EXIT_FAILED;
    }
    return ILF_EXIT_OK;
}

static int render_all(const probes_files *f, const rl_job *job, const rl_solution *sol)
{
    const probes_options *o = f->o;
    cap_probe_settings s = {(int)o->size[0], (int)o->size[1], o->strata, job->sampling.seed, job->run.threads,
                            NULL, NULL};
    float *pixels = malloc((size_t)s.width * s.height * 3 * sizeof *pixels);
    if (pixels == NULL) {
        cli_error("render-probes", "out of memory for a %dx%d probe", s.width, s.height);
        return ILF_EXIT_FAILED;
    }
    /* every probe casts the same rays (pixels times strata squared): the bar counts probes */
    char grid[64];
    if (o->nplanes == 1)
        snprintf(grid, sizeof grid, "%" PRIu32 "x%" PRIu32, o->planes[0].nu, o->planes[0].nv);
    else
        snprintf(grid, sizeof grid, "%zu planes, %" PRIu64, o->nplanes, probe_count(o));
    cli_settings("render-probes", "%s probes of %dx%d pixels, %" PRIu32 " directions per pixel, %u thread%s", grid,
                 s.width, s.height, o->strata * o->strata, relight_threads_used(&job->run),
                 relight_threads_used(&job->run) == 1 ? "" : "s");
    cli_progress bar;
    if (!o->quiet)
        cli_progress_start(&bar, "probes", probe_count(o));
    int code = ILF_EXIT_OK;
    for (size_t k = 0; k < o->nplanes; k++)
        for (uint32_t j = 0; code == ILF_EXIT_OK && j < o->planes[k].nv; j++)
            for (uint32_t i = 0; code == ILF_EXIT_OK && i < o->planes[k].nu; i++) {
                code = render_probe(f, sol, &s, k, i, j, pixels);
                if (!o->quiet)
                    cli_progress_add(&bar, 1);
            }
    if (!o->quiet)
        cli_progress_finish(&bar);
    free(pixels);
    return code;
}

int ilf_cmd_render_probes(int argc, char **argv)
{
    probes_options o;
    set_defaults(&o);
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    rl_scene *scene = NULL;
    rl_job job;
    rl_solution *sol = NULL;
    probes_files files = {.o = &o};
    static const char *const names[] = {MANIFEST_NAME};
    /* DIR before anything is read or computed */
    code = cli_output_folder_check("render-probes", o.output, names, 1);
    if (code == ILF_EXIT_OK)
        code = relight_scene_open("render-probes", o.scene, &o.sampling, &scene, &job);
    if (code == ILF_EXIT_OK && !files_open(&files))
        code = ILF_EXIT_FAILED;
    if (code == ILF_EXIT_OK)
        code = relight(&o, scene, &job, &sol);
    if (code == ILF_EXIT_OK)
        code = render_all(&files, &job, sol);
    if (code == ILF_EXIT_OK)
        code = write_manifest(&files);
    if (code == ILF_EXIT_OK)
        code = files_place(&files);
    if (code == ILF_EXIT_OK && !o.quiet) {
        printf("wrote %s/%s:", o.output, MANIFEST_NAME);
        for (size_t k = 0; k < o.nplanes; k++)
            printf("%s %" PRIu32 "x%" PRIu32 " positions, n %" PRIu32 ", slab '%s'\n", k == 0 ? "" : "     ",
                   o.planes[k].nu, o.planes[k].nv, o.n, o.planes[k].name);
        printf("rendered %" PRIu64 " probe%s of %" PRIu32 "x%" PRIu32 " pixels, %" PRIu32
               " directions per pixel, from %s into %s\n",
               probe_count(&o), probe_count(&o) == 1 ? "" : "s", o.size[0], o.size[1], o.strata * o.strata, o.scene,
               o.output);
    }
    files_close(&files);
    rl_solution_destroy(sol);
    rl_scene_destroy(scene);
    return code;
}
