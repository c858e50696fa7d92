/*
 * cmd_relight.c - `ilf relight SCENE -o DIR`: relights a scene with the
 * engine of relight/engine.h and writes what it found to DIR:
 *
 *   radiance.h5  every receiving polygon's radiance map (lfio/radmap.h)
 *   stats.json   settings, times, per-pass counters and memory (docs/cli.md)
 *   view.exr     the camera's view, raw radiance         } only when the scene
 *   view.png     the same, tone mapped and sRGB-encoded  } has a camera or the
 *                                                          camera options make one
 *   falsecolor.png  with --falsecolor: the view's illuminance in false colour,
 *                with a legend (falsecolor.h)
 *
 * Invariants: DIR and the four names in it are checked before the scene is
 * read (DIR a folder that can be written or created, each name a regular
 * file or nothing), and DIR exists (it is created) before the engine runs,
 * so a long run never ends in an output that cannot be placed. Outputs are
 * written into a staging folder inside DIR (".relight.tmp-XXXXXX", each file
 * atomically: lfio, image/image.h, jsonout.h) and placed together only once
 * every one is written (output_set.h): the four names of an earlier run are
 * moved aside, this run's files renamed in, and a failure puts everything
 * back, so DIR describes one run (a view of an earlier run is removed when
 * this one writes none) and a run that fails (out of memory, a full disk, an
 * output that cannot be placed, an interruption) leaves DIR as it found it,
 * removing the staging folder and any folder it created;
 * stdout carries the summary (nothing with --quiet), stderr errors and the
 * progress bar (only on a terminal, never with --quiet). The view's camera
 * is the scene's with the camera options (camera_cli.h) in place of its
 * parts, passed to the render calls: the scene is never changed.
 *
 * As a rank of `ilf-mpi` (job.h), every rank loads the scene and runs the
 * engine on its share of the work; rank 0 alone creates DIR and the staging
 * folder (whose name it shares), writes stats.json and the view, and places
 * the outputs; radiance.h5 is written by every rank together. A failure on
 * any rank fails the job, and DIR is left as it was.
 */
#include <cjson/cJSON.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "camera_cli.h"
#include "cli.h"
#include "commands.h"
#include "falsecolor.h"
#include "image/image.h"
#include "job.h"
#include "jsonout.h"
#include "lfio/radmap.h"
#include "output_set.h"
#include "relight/engine.h"
#include "relight_cli.h"
#include "tonemap.h"

/* The PNG maps the 90th percentile of the lit pixels' luminance to this value: low enough that
 * visible emitters (a few per cent of a view) saturate instead of setting the exposure. */
#define PNG_PERCENTILE 0.90
#define PNG_TARGET 0.8
/* The program named in radiance.h5 and stats.json. */
#define RELIGHT_CREATOR "ilf relight (ilfkit " ILFKIT_VERSION ")"
/* Camera size from docs/scene.md when the scene file does not give it. */

typedef struct relight_options {
    const char *scene;
    const char *output;
    sampling_overrides sampling;
    int quiet;
    int no_view; /* skip view.exr/png */
    int flat_view; /* each cell's own value in the view, no interpolation */
    tone_fixed tone; /* view.png's scale: --exposure or --scale, else automatic */
    int falsecolor;  /* write falsecolor.png */
    double falsecolor_max; /* its top, lux; 0: automatic */
    camera_overrides camera; /* --position ... --size: the view's camera over the scene's */
} relight_options;

/* Options after the shared sampling ones, whose ids come first (relight_cli.h). */
enum relight_option_id {
    OPT_OUTPUT = SAMPLING_OPT_COUNT, OPT_QUIET, OPT_NO_VIEW, OPT_FLAT_VIEW, OPT_EXPOSURE, OPT_SCALE, OPT_FALSECOLOR,
    OPT_FALSECOLOR_MAX, OPT_CAMERA, OPT_COUNT = OPT_CAMERA + CAMERA_OPT_COUNT
};

/* The sampling options' entries are filled by relight_options_fill(), the camera's by camera_options_fill(),
 * before parsing. */
static cli_option relight_options_table[OPT_COUNT] = {
    [OPT_OUTPUT] = {"output", 'o', "DIR", "folder for radiance.h5, stats.json and view.exr/png (required; created)"},
    [OPT_QUIET] = {"quiet", 'q', NULL, "nothing on stdout; no settings line, progress bar or warnings (still in stats.json)"},
    [OPT_NO_VIEW] = {"no-view", 0, NULL, "write no view.exr/png even when the scene has a camera"},
    [OPT_FLAT_VIEW] = {"flat-view", 0, NULL, "show each cell's own value in the view (default: interpolated between cells)"},
    [OPT_EXPOSURE] = {"exposure", 0, "EV", "view.png: radiance times 2^EV (default: 90th percentile of luminance -> 0.8)"},
    [OPT_SCALE] = {"scale", 0, "W", "view.png: radiance W (W sr^-1 m^-2) shows as white, the same in every run"},
    [OPT_FALSECOLOR] = {"falsecolor", 0, NULL, "also write falsecolor.png: the view's illuminance in lux, with a legend"},
    [OPT_FALSECOLOR_MAX] = {"falsecolor-max", 0, "LUX",
                            "top of falsecolor.png's scale (default: 99th percentile rounded up to 1, 2 or 5 x 10^k)"},
};

static const cli_usage relight_usage = {
    "relight",
    "SCENE -o DIR [--method M] [--threads N] [--seed S] [--partition-n N] [--rays K]\n"
    "                   [--samples N] [--bounces B] [--no-view] [--flat-view] [--quiet]\n"
    "                   [--exposure EV | --scale W] [--falsecolor [--falsecolor-max LUX]]\n"
    "                   [--position X,Y,Z] [--look-at X,Y,Z] [--up X,Y,Z] [--fov DEG] [--size WxH]",
    "Relights the scene (docs/scene.md) and writes to DIR: radiance.h5, the irradiance\n"
    "and radiosity of every receiving polygon's cells (docs/format.md); stats.json, the\n"
    "settings, times and per-pass counters (docs/cli.md); and, when the scene has a\n"
    "camera or the camera options make one, view.exr (radiance) and view.png (exposed\n"
    "so that the 90th percentile of the lit pixels' luminance shows as 0.8, unless\n"
    "--exposure or --scale fixes it; sRGB), and with --falsecolor falsecolor.png\n"
    "(illuminance in lux, with a legend). Sampling options replace the scene's own\n"
    "settings; camera options replace those parts of the scene's camera for the view\n"
    "(for a scene without one, --position and --look-at make one). stderr gets the\n"
    "settings used, a progress bar and warnings (no emitter, walls facing away, dark\n"
    "cells, back faces, partial light field coverage, no camera), also kept in\n"
    "stats.json.",
    "ilf relight data/beams_diffuse.json -o out/beams\n"
    "ilf relight data/classroom.json -o out/classroom --partition-n 16 --rays 2 --bounces 1\n"
    "ilf relight data/beams_diffuse.json -o out/naive --method naive --threads 4 --quiet\n"
    "ilf relight data/beams_diffuse.json -o out/beams --scale 5 --falsecolor --falsecolor-max 2000\n"
    "ilf relight data/beams_diffuse.json -o out/corner --position 4.5,0.5,2.5 --look-at 2.5,2.5,1 --fov 70",
};

/* The outputs, in the order they are written and renamed into place. */
enum relight_output { OUT_RADIANCE, OUT_STATS, OUT_VIEW_EXR, OUT_VIEW_PNG, OUT_FALSECOLOR, OUT_COUNT };
static const char *const output_names[OUT_COUNT] = {"radiance.h5", "stats.json", "view.exr", "view.png",
                                                    "falsecolor.png"};

/* Everything one run produced, for the outputs and the summary. */
typedef struct relight_run {
    const relight_options *o;
    rl_scene *scene;
    rl_solution *solution;
    rl_job job;                       /* what the engine computes, and how: threads, time budget (no progress) */
    double wall_seconds, cpu_seconds; /* of the engine, on this rank */
    double write_seconds;              /* writing radiance.h5, after the engine when written beside it */
    size_t maps;
    uint64_t cells;
    size_t created_from;         /* length of the first folder of DIR this run created; 0: none */
    char *stage;                 /* the staging folder, or NULL */
    char *staged[OUT_COUNT];     /* each output's path in the staging folder */
    char *placed[OUT_COUNT];     /* and in DIR */
    char *aside[OUT_COUNT];      /* where an earlier run's file of that name waits, in the staging folder */
    int written[OUT_COUNT];      /* staged and complete */
    char report[OUT_COUNT][192]; /* what each holds, printed once they are in place */
    int has_camera;              /* camera is the view's: the scene's, with the camera options */
    rl_camera camera;
} relight_run;

/* ------------------------------------------------------------ options */

/* Applies one option to the relight_options ctx. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    relight_options *o = ctx;
    if (opt >= OPT_CAMERA && opt < OPT_CAMERA + CAMERA_OPT_COUNT)
        return camera_option_apply(p, &o->camera, opt - OPT_CAMERA, value);
    if (opt == OPT_OUTPUT)
        o->output = value;
    else if (opt == OPT_QUIET)
        o->quiet = 1;
    else if (opt == OPT_NO_VIEW)
        o->no_view = 1;
    else if (opt == OPT_FLAT_VIEW)
        o->flat_view = 1;
    else if (opt == OPT_EXPOSURE || opt == OPT_SCALE)
        return cli_value_tone(p, value, opt == OPT_EXPOSURE, &o->tone);
    else if (opt == OPT_FALSECOLOR)
        o->falsecolor = 1;
    else if (opt == OPT_FALSECOLOR_MAX) {
        o->falsecolor = 1;
        if (!cli_value_double(p, value, &o->falsecolor_max))
            return 0;
        if (!(o->falsecolor_max > 0))
            return cli_bad_value(p, value, "must be an illuminance > 0 lux"), 0;
    }
    else
        return sampling_option_apply(p, &o->sampling, opt, value);
    return 1;
}

/* Parses argv into *o. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(relight_options *o, int argc, char **argv)
{
    if (!relight_options_fill("relight", relight_options_table))
        return ILF_EXIT_FAILED;
    camera_options_fill(relight_options_table + OPT_CAMERA, 1);
    int code = cli_parse(&relight_usage, relight_options_table, OPT_COUNT, argc, argv, &o->scene, apply_option, o);
    if (code != -1)
        return code;
    const char *problem = NULL;
    if (o->scene == NULL)
        problem = "no scene given (see 'ilf relight --help')";
    else if (o->output == NULL || o->output[0] == '\0')
        problem = "-o DIR is required";
    else if (o->falsecolor && o->no_view)
        problem = "--falsecolor shows the view: it cannot be given with --no-view";
    else if (o->camera.given != 0 && o->no_view)
        problem = "the camera options are for the view: they cannot be given with --no-view";
    if (problem != NULL) {
        cli_error("relight", "%s", problem);
        return ILF_EXIT_USAGE;
    }
    return -1;
}

/* ------------------------------------------------------------ files */

/* @return "dir/name" (malloc'd), or NULL when memory runs out. */
static char *join_path(const char *dir, const char *name)
{
    size_t len = strlen(dir);
    char *path = malloc(len + strlen(name) + 2);
    if (path != NULL)
        sprintf(path, "%s%s%s", dir, len > 0 && dir[len - 1] == '/' ? "" : "/", name);
    return path;
}

/* The staging folder's name template; mkdtemp replaces the X's. */
#define STAGE_TEMPLATE ".relight.tmp-XXXXXX"
/* What an earlier run's file is called while it waits aside in the staging folder. */
#define ASIDE_PREFIX ".earlier-"

/* Makes every output's paths (staged, placed, aside) for the staging folder named `stage` (the template's
 * length): nothing is allocated once outputs are placed. @return an exit code. */
static int stage_paths(relight_run *run, const char *stage)
{
    run->stage = join_path(run->o->output, stage);
    int ok = run->stage != NULL;
    char aside[64];
    for (int k = 0; ok && k < OUT_COUNT; k++)
        ok = (run->staged[k] = join_path(run->stage, output_names[k])) != NULL
             && (run->placed[k] = join_path(run->o->output, output_names[k])) != NULL
             && snprintf(aside, sizeof aside, "%s%s", ASIDE_PREFIX, output_names[k]) > 0
             && (run->aside[k] = join_path(run->stage, aside)) != NULL;
    if (!ok) {
        cli_error("relight", "out of memory");
        return ILF_EXIT_FAILED;
    }
    return ILF_EXIT_OK;
}

/* Creates the staging folder in DIR, registered so that an interruption removes it (cli.h), and
 * every output's two paths. @return an exit code. */
static int stage_open(relight_run *run)
{
    if (stage_paths(run, STAGE_TEMPLATE) != ILF_EXIT_OK)
        return ILF_EXIT_FAILED;
    if (cli_staging_make(run->stage) == NULL) {
        cli_error("relight", "cannot create a staging folder in '%s': %s", run->o->output, strerror(errno));
        free(run->stage);
        run->stage = NULL;
        return ILF_EXIT_FAILED;
    }
    /* mkdtemp replaced the X's in the folder's name; the staged paths must follow. */
    size_t len = strlen(run->stage);
    for (int k = 0; k < OUT_COUNT; k++) {
        memcpy(run->staged[k], run->stage, len);
        memcpy(run->aside[k], run->stage, len);
        cli_output_watch(run->placed[k]); /* so that an interruption says whether it was placed */
    }
    return ILF_EXIT_OK;
}

/* Collective: rank 0 creates DIR and the staging folder, and every other rank learns the staging
 * folder's name (they write radiance.h5 into it together). @return the job's exit code. */
static int stage_open_job(relight_run *run)
{
    int code = ILF_EXIT_OK;
    if (job_rank() == 0) {
        if (!cli_folder_make("relight", run->o->output, &run->created_from))
            code = ILF_EXIT_FAILED;
        if (code == ILF_EXIT_OK)
            code = stage_open(run);
    }
    code = job_agree(code);
    if (code != ILF_EXIT_OK || job_ranks() == 1)
        return code;
    char name[sizeof STAGE_TEMPLATE] = STAGE_TEMPLATE;
    if (job_rank() == 0)
        memcpy(name, run->stage + strlen(run->stage) - (sizeof name - 1), sizeof name);
    if (!job_share("relight", name, sizeof name))
        return job_fail(ILF_EXIT_FAILED);
    return job_agree(job_rank() == 0 ? ILF_EXIT_OK : stage_paths(run, name));
}

/* Records that output k is staged and complete, holding what. */
static void stage_done(relight_run *run, int k, const char *what)
{
    run->written[k] = 1;
    snprintf(run->report[k], sizeof run->report[k], "%s", what);
}

/* output_slot_fn over a relight_run's outputs. */
static int relight_slot(void *user, size_t k, output_slot *slot)
{
    const relight_run *run = user;
    slot->written = run->written[k];
    return snprintf(slot->staged, sizeof slot->staged, "%s", run->staged[k]) < (int)sizeof slot->staged
           && snprintf(slot->placed, sizeof slot->placed, "%s", run->placed[k]) < (int)sizeof slot->placed
           && snprintf(slot->aside, sizeof slot->aside, "%s", run->aside[k]) < (int)sizeof slot->aside;
}

/* Places the staged outputs into DIR as one step (output_set.h: an earlier run's files of the four names are
 * removed, a failure puts DIR back as it was), then prints "wrote PATH: what" for each unless quiet.
 * @return an exit code. */
static int stage_commit(relight_run *run)
{
    int code = output_set_place("relight", run->o->output, OUT_COUNT, relight_slot, run);
    for (int k = 0; k < OUT_COUNT && !run->o->quiet && code == ILF_EXIT_OK; k++)
        if (run->written[k])
            printf("wrote %s: %s\n", run->placed[k], run->report[k]);
    return code;
}

/* Frees the staging folder's and the outputs' paths. */
static void free_paths(relight_run *run)
{
    free(run->stage);
    for (int k = 0; k < OUT_COUNT; k++) {
        free(run->staged[k]);
        free(run->placed[k]);
        free(run->aside[k]);
    }
}

/* Removes the staging folder and what is left in it (an earlier run's files moved aside among them), then the
 * folders of DIR this run created if they are empty, and frees the paths. */
static void stage_close(relight_run *run)
{
    if (run->stage != NULL) {
        for (int k = 0; k < OUT_COUNT; k++) {
            if (run->staged[k] != NULL)
                unlink(run->staged[k]);
            if (run->aside[k] != NULL)
                unlink(run->aside[k]);
        }
        rmdir(run->stage);
        cli_staging_forget(run->stage);
    }
    cli_folder_unmake(run->o->output, run->created_from);
    free_paths(run);
}

/* ------------------------------------------------------------ relighting */


/* Runs the engine on run->scene, timing it, with a progress bar unless quiet. @return an exit code. */
static int relight(relight_run *run)
{
    cli_progress bar;
    int show = !run->o->quiet;
    if (show)
        cli_progress_start(&bar, "relight", CLI_PROGRESS_STEPS);
    double wall0 = cli_clock_seconds(CLOCK_MONOTONIC), cpu0 = cli_clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
    rl_job job = run->job;
    job.run.progress = show ? cli_progress_fraction : NULL;
    job.run.progress_user = &bar;
    rl_status st = rl_relight_cluster(run->scene, job_cluster(), &job, &run->solution);
    run->wall_seconds = cli_clock_seconds(CLOCK_MONOTONIC) - wall0;
    run->cpu_seconds = cli_clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
    if (show)
        cli_progress_finish(&bar);
    /* the other ranks may be waiting in an exchange this rank will not reach: end the job */
    if (st != RL_OK)
        return job_fail(relight_failure("relight", st));
    run->maps = rl_solution_map_count(run->solution);
    return ILF_EXIT_OK;
}


/* ------------------------------------------------------------ radiance.h5 */

/*
 * radiance.h5 beside the engine (one process): the engine tells which maps
 * are final as its last pass goes (rl_maps_ready_fn), and a thread of its
 * own hands them to lfio in order meanwhile, so that checking, compressing
 * and storing their cells overlaps the engine (lfio describes every map
 * first: a description does not change during the run). That
 * thread prints nothing: it keeps its messages, and the main thread reports
 * the write once both end.
 */
/* Longest message the writer thread keeps for the main thread. */
#define WRITER_MSG 1024

typedef struct map_writer {
    pthread_mutex_t lock;
    pthread_cond_t moved;
    const rl_solution *solution; /* NULL until the first maps are ready */
    size_t ready;                /* maps [0, ready) are final */
    int over;                    /* the engine has returned, or withdrawn the solution: no more maps will come */
    int reading;                 /* the writer thread is reading the solution (writer_wait() to writer_done()) */
    relight_run *run;
    pthread_t thread;
    lfio_status st;              /* the write's, once the thread is joined */
    char msg[WRITER_MSG];        /* lfio's message for it (lfio's messages are per thread) */
    char held[WRITER_MSG];       /* a failure describing a map, to print (describe_failed()) */
    int reported;                /* its failure was reported on that thread */
    uint64_t cells;              /* written */
    double end;                  /* when the write ended (CLOCK_MONOTONIC) */
} map_writer;

/* rl_maps_ready_fn: the engine's news, for the writer thread; solution NULL withdraws it (the run failed),
 * returning once the writer thread no longer reads it. */
static void writer_told(void *user, const rl_solution *solution, size_t ready)
{
    map_writer *w = user;
    pthread_mutex_lock(&w->lock);
    w->solution = solution;
    w->ready = ready;
    w->over |= solution == NULL;
    pthread_cond_broadcast(&w->moved);
    while (solution == NULL && w->reading)
        pthread_cond_wait(&w->moved, &w->lock);
    pthread_mutex_unlock(&w->lock);
}

/* Waits until map k is final, or the engine has returned. @return 1, the solution then being read until
 * writer_done(); or 0 if the engine returned without map k (it failed, or there is no such map).
 * *solution (if not NULL): the solution told of, or NULL. */
static int writer_wait(map_writer *w, size_t k, const rl_solution **solution)
{
    pthread_mutex_lock(&w->lock);
    while (!(w->solution != NULL && k < w->ready) && !w->over)
        pthread_cond_wait(&w->moved, &w->lock);
    int ok = w->solution != NULL && k < w->ready;
    w->reading = ok;
    if (solution)
        *solution = w->solution;
    pthread_mutex_unlock(&w->lock);
    return ok;
}

/* Ends the reading that writer_wait() began: the engine may now free the solution if it fails. */
static void writer_done(map_writer *w)
{
    pthread_mutex_lock(&w->lock);
    w->reading = 0;
    pthread_cond_broadcast(&w->moved);
    pthread_mutex_unlock(&w->lock);
}

/* Tells the writer thread that the engine has returned. */
static void writer_over(map_writer *w)
{
    pthread_mutex_lock(&w->lock);
    w->over = 1;
    pthread_cond_broadcast(&w->moved);
    pthread_mutex_unlock(&w->lock);
}

/* The arrays of the slice of cells lfio_radmap_write_rows() is writing, grown to the largest slice so far
 * (at most LFIO_RADMAP_ROWS_MAX cells; a whole map through MPI). */
typedef struct patch_arrays {
    const rl_solution *solution;
    struct map_writer *beside; /* the write goes beside the engine: wait for each map (NULL: all are done) */
    char *held;                /* beside the engine: a failure's message, kept for the main thread to print */
    size_t capacity; /* cells */
    uint32_t *ij;
    double *area, *centre;
    float *irradiance, *radiosity;
    uint64_t cells;  /* over the patches described so far */
    size_t described; /* patches [0, described) counted in cells (an MPI write describes some twice) */
    int reported;    /* describe_map reported a failure */
} patch_arrays;

/* Grows a's arrays to hold n cells. @return 1, or 0 when memory runs out (a keeps what it had). */
static int patch_reserve(patch_arrays *a, size_t n)
{
    if (n <= a->capacity)
        return 1;
    void *p;
    if ((p = realloc(a->ij, 2 * n * sizeof *a->ij)) == NULL)
        return 0;
    a->ij = p;
    if ((p = realloc(a->area, n * sizeof *a->area)) == NULL)
        return 0;
    a->area = p;
    if ((p = realloc(a->centre, 3 * n * sizeof *a->centre)) == NULL)
        return 0;
    a->centre = p;
    if ((p = realloc(a->irradiance, 3 * n * sizeof *a->irradiance)) == NULL)
        return 0;
    a->irradiance = p;
    if ((p = realloc(a->radiosity, 3 * n * sizeof *a->radiosity)) == NULL)
        return 0;
    a->radiosity = p;
    a->capacity = n;
    return 1;
}

/* Reports a failure of describe_map(): printed, or held for the main thread when a->held is set (the
 * engine's progress bar may be drawing). */
static void describe_failed(patch_arrays *a, const char *msg)
{
    if (a->held != NULL)
        snprintf(a->held, WRITER_MSG, "%s", msg);
    else
        cli_error("relight", "%s", msg);
    a->reported = 1;
}

/* describe_map()'s reading of map k of a's solution: all but its cells. */
static lfio_status describe_solution_map(patch_arrays *a, size_t k, lfio_radmap_patch *p)
{
    rl_map_info m;
    char msg[WRITER_MSG];
    if (rl_solution_map_info(a->solution, k, &m) != RL_OK) {
        describe_failed(a, relight_failure_text(msg, sizeof msg));
        return LFIO_ERR_ARG;
    }
    p->label = m.label;
    p->polygon = m.polygon;
    p->nverts = m.nvertices;
    p->vertices = m.vertices;
    memcpy(p->origin, m.origin, sizeof p->origin);
    memcpy(p->e1, m.e1, sizeof p->e1);
    memcpy(p->e2, m.e2, sizeof p->e2);
    memcpy(p->normal, m.normal, sizeof p->normal);
    p->cell_size = m.cell_size;
    p->u0 = m.u0;
    p->v0 = m.v0;
    p->nu = m.nu;
    p->nv = m.nv;
    p->ncells = m.ncells;
    /* lfio describes the maps in order, and again some of them (an MPI write, reading a rank's chunks) */
    if (k == a->described)
        a->cells += m.ncells, a->described++;
    memcpy(p->albedo, m.albedo, sizeof p->albedo);
    memcpy(p->emission, m.emission, sizeof p->emission);
    return LFIO_OK;
}

/* Begins a reading of map k of a's solution: beside the engine, waits until the map is final.
 * @return 1, to be ended by read_end(); 0 if the engine failed first (it says so itself: a->reported). */
static int read_begin(patch_arrays *a, size_t k)
{
    if (a->beside == NULL || writer_wait(a->beside, k, NULL))
        return 1;
    a->reported = 1;
    return 0;
}

/* Ends the reading read_begin() began. */
static void read_end(patch_arrays *a)
{
    if (a->beside != NULL)
        writer_done(a->beside);
}

/* lfio_radmap_write_rows()'s describe: map k of the solution but its cells (map_rows() gives those), once
 * the engine has told of its solution (a map's description is fixed before the run: lfio asks for every
 * map's before any cells). Reports its own failures (cli.h). @return LFIO_OK, or LFIO_ERR_ARG after
 * reporting. */
static lfio_status describe_map(void *user, size_t k, lfio_radmap_patch *p)
{
    patch_arrays *a = user;
    if (!read_begin(a, 0))
        return LFIO_ERR_ARG;
    lfio_status st = describe_solution_map(a, k, p);
    read_end(a);
    return st;
}

/* map_rows()'s reading of cells [first, first + count) of map k of a's solution into a's arrays.
 * @return LFIO_OK, or LFIO_ERR_NOMEM / LFIO_ERR_ARG after reporting. */
static lfio_status solution_map_rows(patch_arrays *a, size_t k, uint32_t first, uint32_t count,
                                     lfio_radmap_rows *out)
{
    char msg[WRITER_MSG];
    if (!patch_reserve(a, count ? count : 1)) {
        snprintf(msg, sizeof msg, "out of memory for %u cells of map %zu", count, k);
        describe_failed(a, msg);
        return LFIO_ERR_NOMEM;
    }
    rl_status st = rl_solution_map_rows(a->solution, k, first, count, a->ij, a->area, a->centre, a->irradiance,
                                        a->radiosity);
    if (st != RL_OK) {
        describe_failed(a, relight_failure_text(msg, sizeof msg));
        return st == RL_ERR_NOMEM ? LFIO_ERR_NOMEM : LFIO_ERR_ARG;
    }
    *out = (lfio_radmap_rows){a->ij, a->area, a->centre, a->irradiance, a->radiosity};
    return LFIO_OK;
}

/* lfio_radmap_write_rows()'s rows: cells [first, first + count) of map k, once it is final, in the arrays
 * of user (a patch_arrays). Reports its own failures, as describe_map().
 * @return LFIO_OK, or LFIO_ERR_NOMEM / LFIO_ERR_ARG after reporting (or after the engine's failure). */
static lfio_status map_rows(void *user, size_t k, uint32_t first, uint32_t count, lfio_radmap_rows *out)
{
    patch_arrays *a = user;
    if (!read_begin(a, k))
        return LFIO_ERR_ARG;
    lfio_status st = solution_map_rows(a, k, first, count, out);
    read_end(a);
    return st;
}

/* Writes the n maps of solution to the staged radiance.h5, a slice of one map's cells in memory at a time, each once
 * it is final when beside is given (the engine still running). Prints nothing but describe_map()'s and
 * map_rows()'s own failures. @return lfio's status; *cells the cells written, *reported whether a failure was reported. */
static lfio_status radiance_write(relight_run *run, const rl_solution *solution, size_t n, map_writer *beside,
                                  uint64_t *cells, int *reported)
{
    patch_arrays arrays = {solution, beside, beside ? beside->held : NULL, 0, NULL, NULL, NULL, NULL, NULL, 0, 0, 0};
    lfio_radmap_write_options opt;
    lfio_radmap_write_options_init(&opt);
    /* lfio describes every map first, then asks for the cells map by map and stores them a batch of
     * chunks at a time (beside the engine: as the maps become final), compressed on the threads the engine
     * uses */
    opt.threads = relight_threads_used(&run->job.run);
    lfio_status st = job_radmap_write(run->staged[OUT_RADIANCE], RELIGHT_CREATOR, run->o->scene, n, describe_map,
                                      map_rows, &arrays, &opt);
    *cells = arrays.cells;
    *reported = arrays.reported;
    free(arrays.ij);
    free(arrays.area);
    free(arrays.centre);
    free(arrays.irradiance);
    free(arrays.radiosity);
    return st;
}

/* Reports the write of radiance.h5 (status st and lfio's message msg, cells, reported as radiance_write()
 * says) and records the seconds it took. @return an exit code. */
static int radiance_written(relight_run *run, lfio_status st, const char *msg, uint64_t cells, int reported,
                            double seconds)
{
    const char *path = run->staged[OUT_RADIANCE];
    int code = ILF_EXIT_OK;
    /* describe_map reported its own failures; lfio's are reported here */
    if (st != LFIO_OK)
        code = reported ? ILF_EXIT_FAILED : cli_lfio_failure_msg("relight", st, CLI_OUTPUT, path, msg);
    run->cells = cells;
    run->write_seconds = seconds;
    if (code == ILF_EXIT_OK) {
        char what[128], size[32];
        size_t n = run->maps;
        snprintf(what, sizeof what, "%zu map%s, %" PRIu64 " cells, %s", n, n == 1 ? "" : "s", run->cells,
                 cli_format_bytes(cli_file_size(path), size, sizeof size));
        stage_done(run, OUT_RADIANCE, what);
    }
    return code;
}

/* Writes every map of the solution to the staged radiance.h5 after the engine. @return an exit code. */
static int write_radiance(relight_run *run)
{
    double t0 = cli_clock_seconds(CLOCK_MONOTONIC);
    uint64_t cells = 0;
    int reported = 0;
    lfio_status st = radiance_write(run, run->solution, run->maps, NULL, &cells, &reported);
    return radiance_written(run, st, lfio_errmsg(), cells, reported, cli_clock_seconds(CLOCK_MONOTONIC) - t0);
}

/* The writer thread: radiance.h5 from the first maps the engine tells on (none if it fails first). */
static void *writer_main(void *arg)
{
    map_writer *w = arg;
    const rl_solution *solution = NULL;
    size_t n = 0;
    w->st = LFIO_ERR_ARG;
    /* a scene without maps is told of with none ready: the engine returns with it (not withdrawn) */
    if (writer_wait(w, 0, &solution)) {
        n = rl_solution_map_count(solution);
        writer_done(w);
    }
    if (solution != NULL)
        w->st = radiance_write(w->run, solution, n, w, &w->cells, &w->reported);
    snprintf(w->msg, sizeof w->msg, "%s", w->st != LFIO_OK ? lfio_errmsg() : "");
    w->end = cli_clock_seconds(CLOCK_MONOTONIC);
    return NULL;
}

/* Starts writing radiance.h5 beside the engine, whose options then tell w. @return 1, or 0 if no thread
 * could be started (the write then follows the engine). */
static int writer_start(map_writer *w, relight_run *run)
{
    memset(w, 0, sizeof *w);
    w->run = run;
    if (pthread_mutex_init(&w->lock, NULL) != 0)
        return 0;
    if (pthread_cond_init(&w->moved, NULL) != 0) {
        pthread_mutex_destroy(&w->lock);
        return 0;
    }
    run->job.run.maps_ready = writer_told;
    run->job.run.maps_ready_user = w;
    if (pthread_create(&w->thread, NULL, writer_main, w) != 0) {
        run->job.run.maps_ready = NULL;
        pthread_cond_destroy(&w->moved);
        pthread_mutex_destroy(&w->lock);
        return 0;
    }
    return 1;
}

/* Waits for the writer thread, the engine having returned with code, and reports its write (only if the
 * engine succeeded). @return an exit code. */
static int writer_finish(map_writer *w, int code, double engine_end)
{
    writer_over(w);
    pthread_join(w->thread, NULL);
    pthread_cond_destroy(&w->moved);
    pthread_mutex_destroy(&w->lock);
    relight_run *run = w->run;
    run->job.run.maps_ready = NULL;
    if (code != ILF_EXIT_OK)
        return code;
    if (w->held[0] != '\0')
        cli_error("relight", "%s", w->held);
    /* the time the write added to the run: from the engine's end to its own */
    double added = w->end > engine_end ? w->end - engine_end : 0.0;
    return radiance_written(run, w->st, w->msg, w->cells, w->reported, added);
}

/* ------------------------------------------------------------ view.exr, view.png */

/* Writes pixels ([y][x][rgb]) to output k. @return an exit code. */
static int write_view_image(relight_run *run, int k, int width, int height, const float *pixels, const char *what)
{
    char err[512];
    img_status st = img_write(run->staged[k], width, height, 3, pixels, err, sizeof err);
    if (st != IMG_OK)
        cli_error("relight", "%s", err);
    else
        stage_done(run, k, what);
    return st == IMG_OK ? ILF_EXIT_OK : ILF_EXIT_FAILED;
}

/* Renders the illuminance the camera sees into work ([height][width][3] floats, overwritten) and writes
 * falsecolor.png of it with its legend. @return an exit code. */
static int write_falsecolor(relight_run *run, int width, int height, float *work)
{
    const size_t count = (size_t)width * (size_t)height;
    rl_status rs = rl_solution_render_irradiance_camera(run->solution, &run->camera, &run->job.run, work);
    if (rs != RL_OK)
        return relight_failure("relight", rs);
    /* lux in place, into the first count floats: pixel k's value is read before it is overwritten */
    for (size_t k = 0; k < count; k++) {
        const double e[3] = {work[3 * k], work[3 * k + 1], work[3 * k + 2]};
        work[k] = e[0] < 0 ? -1.0f : (float)tone_lux(e);
    }
    double top = run->o->falsecolor_max > 0 ? run->o->falsecolor_max : falsecolor_auto_top(work, count);
    int w = 0, h = 0;
    float *image = top > 0 ? falsecolor_image(work, width, height, top, "lux", &w, &h) : NULL;
    if (image == NULL) {
        cli_error("relight", "out of memory for a %dx%d false-colour image", width, height);
        return ILF_EXIT_FAILED;
    }
    char what[192];
    snprintf(what, sizeof what, "%dx%d, illuminance 0 to %g lux (%s), %g lm/W; magenta above, grey no surface", w, h,
             top, run->o->falsecolor_max > 0 ? "--falsecolor-max" : "99th percentile rounded up",
             TONE_LUMENS_PER_WATT);
    int code = write_view_image(run, OUT_FALSECOLOR, w, h, image, what);
    free(image);
    return code;
}

/* Renders the camera's view and writes view.exr (radiance) and view.png (tone mapped), and falsecolor.png when
 * asked. @return an exit code. */
static int write_view(relight_run *run)
{
    int width = (int)run->camera.width, height = (int)run->camera.height;
    const size_t count = (size_t)width * (size_t)height;
    float *pixels = malloc(count * 3 * sizeof *pixels);
    if (pixels == NULL) {
        cli_error("relight", "out of memory for a %dx%d view", width, height);
        return ILF_EXIT_FAILED;
    }
    rl_status rs = rl_solution_set_smooth(run->solution, !run->o->flat_view);
    if (rs == RL_OK)
        rs = rl_solution_render_camera(run->solution, &run->camera, &run->job.run, pixels);
    int code = rs == RL_OK ? ILF_EXIT_OK : relight_failure("relight", rs);
    char what[160];
    snprintf(what, sizeof what, "%dx%d, radiance in W sr^-1 m^-2", width, height);
    if (code == ILF_EXIT_OK)
        code = write_view_image(run, OUT_VIEW_EXR, width, height, pixels, what);
    if (code == ILF_EXIT_OK) {
        double scale = 1.0;
        char how[96], auto_text[64];
        snprintf(auto_text, sizeof auto_text, "90th percentile of luminance -> %.1f", PNG_TARGET);
        if (!tone_fixed_scale(&run->o->tone, &scale)
            && !tone_percentile_scale(pixels, count, 3, TONE_LUMINANCE, PNG_PERCENTILE, PNG_TARGET, &scale)) {
            cli_error("relight", "out of memory for the exposure of a %dx%d view", width, height);
            code = ILF_EXIT_FAILED;
        }
        tone_apply(pixels, count, 3, scale);
        snprintf(what, sizeof what, "%dx%d, sRGB, scale %.6g (%s)", width, height, scale,
                 tone_fixed_describe(&run->o->tone, auto_text, how, sizeof how));
        if (code == ILF_EXIT_OK)
            code = write_view_image(run, OUT_VIEW_PNG, width, height, pixels, what);
    }
    if (code == ILF_EXIT_OK && run->o->falsecolor)
        code = write_falsecolor(run, width, height, pixels);
    free(pixels);
    return code;
}

/* ------------------------------------------------------------ stats.json */

/* Adds key = value for a counter; exact up to 2^53. */
static void add_count(cJSON *obj, const char *key, uint64_t value)
{
    cJSON_AddNumberToObject(obj, key, (double)value);
}

/* @return pass k's statistics as a JSON object, or NULL when memory runs out. */
static cJSON *pass_json(uint32_t k, const rl_pass_stats *s)
{
    cJSON *p = cJSON_CreateObject();
    if (p == NULL)
        return NULL;
    add_count(p, "pass", k);
    cJSON_AddNumberToObject(p, "wall_seconds", s->wall_seconds);
    cJSON_AddNumberToObject(p, "cpu_seconds", s->cpu_seconds);
    add_count(p, "samples", s->samples);
    add_count(p, "rays_cast", s->rays_cast);
    add_count(p, "rays_kept", s->rays_kept);
    add_count(p, "rays_free", s->rays_free);
    add_count(p, "solid_angles_considered", s->solid_angles_considered);
    add_count(p, "solid_angles_culled", s->solid_angles_culled);
    add_count(p, "pairs", s->pairs);
    add_count(p, "pairs_descended", s->pairs_descended);
    add_count(p, "emitters", s->emitters);
    add_count(p, "refinements", s->refinements);
    add_count(p, "cells_direct", s->cells_direct);
    cJSON_AddNumberToObject(p, "estimated_rmse", s->estimated_rmse);
    cJSON_AddBoolToObject(p, "budget_reached", s->budget_reached != 0);
    cJSON *e = cJSON_AddObjectToObject(p, "cell_error");
    if (e == NULL) {
        cJSON_Delete(p);
        return NULL;
    }
    add_count(e, "cells", s->cell_error_cells);
    cJSON_AddNumberToObject(e, "median", s->cell_error_median);
    cJSON_AddNumberToObject(e, "p95", s->cell_error_p95);
    cJSON_AddNumberToObject(e, "max", s->cell_error_max);
    return p;
}

/* @return every sampling setting (the settings table's keys and order) as a JSON object, or NULL when
 * memory runs out. */
static cJSON *settings_json(const rl_sampling *s)
{
    cJSON *j = cJSON_CreateObject();
    for (size_t k = 0; j != NULL && k < rl_sampling_setting_count(); k++) {
        const rl_setting_info *info = rl_sampling_setting(k);
        double v = 0.0;
        rl_sampling_get(s, k, &v);
        if (info->type == RL_SETTING_METHOD)
            cJSON_AddStringToObject(j, info->key, rl_method_name(s->method));
        else
            cJSON_AddNumberToObject(j, info->key, v);
    }
    return j;
}

/* Appends every pass's statistics to array passes. @return 1, or 0 when memory runs out. */
static int add_passes(cJSON *passes, const rl_solution *sol)
{
    for (uint32_t k = 0; k < rl_solution_pass_count(sol); k++) {
        rl_pass_stats ps;
        cJSON *p = rl_solution_pass_stats(sol, k, &ps) == RL_OK ? pass_json(k, &ps) : NULL;
        if (p == NULL || !cJSON_AddItemToArray(passes, p)) {
            cJSON_Delete(p);
            return 0;
        }
    }
    return 1;
}

/* @return this process's peak resident memory so far in bytes (the kernel's count, which Linux gives in KiB),
 * or 0 if it cannot be read. */
static uint64_t peak_resident_bytes(void)
{
    struct rusage u;
    return getrusage(RUSAGE_SELF, &u) == 0 && u.ru_maxrss > 0 ? (uint64_t)u.ru_maxrss * 1024u : 0;
}

/* What the run's light held against the whole process, in bytes: stats.json's "memory". */
typedef struct run_memory {
    uint64_t accumulators, lightfields;
    uint64_t peak; /* the process's peak when it was taken */
} run_memory;

/* @return run's memory figures now. */
static run_memory run_memory_now(const relight_run *run)
{
    return (run_memory){rl_solution_accumulator_bytes(run->solution), rl_scene_lightfield_bytes(run->scene),
                        peak_resident_bytes()};
}

/* @return stats.json's "memory" of mem, or NULL when memory runs out. */
static cJSON *memory_json(const run_memory *mem)
{
    cJSON *m = cJSON_CreateObject();
    if (m != NULL) {
        add_count(m, "accumulator_bytes", mem->accumulators);
        add_count(m, "lightfield_bytes", mem->lightfields);
        add_count(m, "peak_resident_bytes", mem->peak);
    }
    return m;
}

/* @return the whole stats.json document (schema in docs/cli.md) with the memory figures mem, or NULL when
 * memory runs out. */
static cJSON *stats_json(const relight_run *run, const run_memory *mem)
{
    const rl_sampling *s = &run->job.sampling;
    cJSON *root = cJSON_CreateObject();
    if (root == NULL)
        return NULL;
    cJSON_AddStringToObject(root, "scene", run->o->scene);
    cJSON_AddStringToObject(root, "creator", RELIGHT_CREATOR);
    cJSON_AddStringToObject(root, "method", rl_method_name(s->method));
    cJSON *settings = settings_json(s);
    int ok = settings != NULL && cJSON_AddItemToObject(root, "settings", settings);
    if (settings != NULL && !ok)
        cJSON_Delete(settings);
    add_count(root, "threads", relight_threads_used(&run->job.run));
    cJSON_AddNumberToObject(root, "wall_seconds", run->wall_seconds);
    cJSON_AddNumberToObject(root, "cpu_seconds", run->cpu_seconds);
    add_count(root, "maps", run->maps);
    add_count(root, "cells", run->cells);
    add_count(root, "ranks", (uint64_t)job_ranks());
    cJSON_AddNumberToObject(root, "radiance_write_seconds", run->write_seconds);
    cJSON *memory = memory_json(mem);
    if (memory == NULL || !cJSON_AddItemToObject(root, "memory", memory)) {
        cJSON_Delete(memory);
        cJSON_Delete(root);
        return NULL;
    }
    const job_exchange *log = NULL;
    size_t nlog = job_exchange_log(&log);
    cJSON *exchanges = nlog > 0 ? cJSON_AddArrayToObject(root, "exchanges") : NULL;
    for (size_t k = 0; exchanges != NULL && k < nlog; k++) {
        cJSON *x = cJSON_CreateObject();
        if (x == NULL || !cJSON_AddItemToArray(exchanges, x)) {
            cJSON_Delete(x);
            break;
        }
        add_count(x, "bytes", log[k].bytes);
        cJSON_AddNumberToObject(x, "wait_seconds", log[k].wait_seconds);
        cJSON_AddNumberToObject(x, "move_seconds", log[k].move_seconds);
        add_count(x, "tiles_claimed", log[k].tiles_claimed);
    }
    cJSON *warnings = cJSON_AddArrayToObject(root, "warnings");
    for (size_t k = 0; warnings != NULL && k < cli_warning_count(); k++)
        ok = ok && cJSON_AddItemToArray(warnings, cJSON_CreateString(cli_warning(k)));
    cJSON *passes = ok && warnings != NULL ? cJSON_AddArrayToObject(root, "passes") : NULL;
    if (passes == NULL || !add_passes(passes, run->solution)) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

/* Writes DIR/stats.json. @return an exit code. */
static int write_stats(relight_run *run)
{
    char err[1024];
    const run_memory mem = run_memory_now(run);
    cJSON *root = stats_json(run, &mem);
    const char *path = run->staged[OUT_STATS];
    int code = ILF_EXIT_OK;
    if (root == NULL) {
        cli_error("relight", "out of memory while building stats.json");
        code = ILF_EXIT_FAILED;
    } else if (!json_write_file(path, root, err, sizeof err)) {
        cli_error("relight", "%s", err);
        code = ILF_EXIT_FAILED;
    } else {
        char what[sizeof run->report[OUT_STATS]];
        snprintf(what, sizeof what,
                 "settings, times, pass statistics; peak memory %.1f MiB (accumulators and light fields %.1f MiB)",
                 (double)mem.peak / 1048576.0, (double)(mem.accumulators + mem.lightfields) / 1048576.0);
        stage_done(run, OUT_STATS, what);
    }
    cJSON_Delete(root);
    return code;
}

/* ------------------------------------------------------------ main */

/* Makes the view's camera: the scene's with the camera options over it (the scene itself is not changed).
 * @return an exit code. */
static int view_camera(relight_run *run)
{
    rl_camera scene_camera;
    int has = rl_scene_camera(run->scene, &scene_camera);
    int made = camera_resolve("relight", &run->o->camera, has ? &scene_camera : NULL, &run->camera);
    run->has_camera = made == 1;
    return made < 0 ? ILF_EXIT_USAGE : ILF_EXIT_OK;
}

/* Prints the run's summary and every pass's statistics (not with --quiet). */
static void print_run(const relight_run *run)
{
    if (run->o->quiet)
        return;
    char what[256];
    unsigned threads = relight_threads_used(&run->job.run);
    printf("relit %s: %s, %u thread%s: %.3f s wall, %.3f s cpu\n", run->o->scene,
           relight_describe(&run->job.sampling, what, sizeof what), threads, threads == 1 ? "" : "s",
           run->wall_seconds, run->cpu_seconds);
    if (job_ranks() > 1)
        printf("job of %d ranks, each with the threads above; times are rank 0's, pass counts and cpu summed\n",
               job_ranks());
    for (uint32_t k = 0; k < rl_solution_pass_count(run->solution); k++) {
        rl_pass_stats ps;
        if (rl_solution_pass_stats(run->solution, k, &ps) == RL_OK)
            relight_print_pass(stdout, k, &ps);
    }
}

int ilf_cmd_relight(int argc, char **argv)
{
    relight_options o = {0};
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    relight_run run = {.o = &o};
    /* ranks other than 0 only compute and write their part of radiance.h5 */
    o.quiet |= job_rank() != 0;
    cli_set_quiet(o.quiet);
    /* DIR and its four names before anything is read or computed (rank 0 places the outputs) */
    code = job_agree(job_rank() == 0 ? cli_output_folder_check("relight", o.output, output_names, OUT_COUNT)
                                     : ILF_EXIT_OK);
    if (code == ILF_EXIT_OK)
        code = job_agree(relight_scene_open("relight", o.scene, &o.sampling, &run.scene, &run.job));
    if (code == ILF_EXIT_OK)
        code = job_agree(view_camera(&run));
    /* the scene's camera is not the view's when options change it: its findings are left out */
    const int scene_view = !o.no_view && o.camera.given == 0;
    if (code == ILF_EXIT_OK && job_rank() == 0) {
        relight_print_settings("relight", &run.job);
        relight_warn_scene(run.scene, scene_view);
    }
    if (code == ILF_EXIT_OK)
        code = stage_open_job(&run);
    map_writer writer;
    int beside = code == ILF_EXIT_OK && job_write_beside() && writer_start(&writer, &run);
    if (code == ILF_EXIT_OK)
        code = relight(&run);
    double engine_end = cli_clock_seconds(CLOCK_MONOTONIC);
    int rank0 = job_rank() == 0, view = rank0 && run.has_camera && !o.no_view;
    if (code == ILF_EXIT_OK && rank0)
        relight_warn_solution(run.solution, scene_view);
    if (code == ILF_EXIT_OK)
        print_run(&run);
    if (beside)
        code = writer_finish(&writer, code, engine_end);
    else if (code == ILF_EXIT_OK)
        code = write_radiance(&run);
    if (code == ILF_EXIT_OK && view)
        code = write_view(&run);
    if (code == ILF_EXIT_OK && rank0)
        code = write_stats(&run);
    if (code == ILF_EXIT_OK && rank0)
        code = stage_commit(&run);
    code = job_agree(code);
    if (rank0)
        stage_close(&run);
    else
        free_paths(&run);
    rl_solution_destroy(run.solution);
    rl_scene_destroy(run.scene);
    return code;
}
