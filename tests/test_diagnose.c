/*
 * test_diagnose.c - the engine's findings about scenes that run but are not
 * what was meant (rl_scene_diagnose, rl_solution_diagnose, relight/engine.h),
 * the covered share of a slab's etendue (lfio_coverage_share), and the
 * progress a run reports: shared between passes by their expected work.
 *
 * Usage: test_diagnose SCENES_DIR (tests/scenes: the warn_room*.json rooms);
 * light fields and their scenes are written into $ILF_TEST_TMP.
 * Each case asserts both ways: the room as modelled gives no finding, the
 * same room turned inside out, without its lamp or camera, gives exactly the
 * finding for it, with the share it measured.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lfio/lightfield.h>
#include <lfio/partition.h>
#include <relight/engine.h>

#include "check.h"
#include "engine_internal.h" /* rl__solve_work(): the progress weights */
#include "relight_scenes.h"

static char tmpdir[512];

#define MAX 8

/* @return the index of the finding of kind among d[0 .. n), or -1. */
static int find(const rl_diagnostic *d, size_t n, rl_diagnostic_kind kind)
{
    for (size_t k = 0; k < n && k < MAX; k++)
        if (d[k].kind == kind)
            return (int)k;
    return -1;
}

/* Loads scene dir/name, checks its scene findings are exactly the kinds want[0 .. nwant) and its solution's
 * exactly sol_want[0 .. nsol), each solution finding measuring share sol_share. */
static void check_room(const char *dir, const char *name, const rl_diagnostic_kind *want, size_t nwant,
                       const rl_diagnostic_kind *sol_want, size_t nsol, double sol_share)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    rl_diagnostic d[MAX];
    size_t n = rl_scene_diagnose(s, d, MAX);
    CHECK(n == nwant, "%s: %zu scene findings, expected %zu (first: %s)", name, n, nwant, n ? d[0].text : "none");
    for (size_t k = 0; k < nwant; k++) {
        int at = find(d, n, want[k]);
        CHECK(at >= 0, "%s: no finding of kind %d", name, (int)want[k]);
        if (at >= 0)
            CHECK(strstr(d[at].text, name) != NULL, "%s: the finding does not name the scene: %s", name, d[at].text);
    }
    rl_job job;
    rl_job_default(s, &job);
    job.run.threads = 2;
    rl_solution *sol = NULL;
    CHECK(rl_relight(s, &job, &sol) == RL_OK, "%s: %s", name, rl_errmsg());
    n = rl_solution_diagnose(sol, d, MAX);
    CHECK(n == nsol, "%s: %zu solution findings, expected %zu (first: %s)", name, n, nsol, n ? d[0].text : "none");
    for (size_t k = 0; k < nsol; k++) {
        int at = find(d, n, sol_want[k]);
        CHECK(at >= 0 && fabs(d[at].quantity - sol_share) < 1e-12, "%s: kind %d: share %g, expected %g", name,
              (int)sol_want[k], at >= 0 ? d[at].quantity : -1.0, sol_share);
    }
    /* the room lit: with the findings' room, a quick look that they do not over-reach */
    CHECK(rl_solution_diagnose(sol, NULL, 0) == n, "%s: counting without room differs", name);
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

static void check_rooms(const char *dir)
{
    const rl_diagnostic_kind outward[] = {RL_DIAG_NOT_FACING}, dark_back[] = {RL_DIAG_DARK_CELLS, RL_DIAG_BACK_FACES};
    const rl_diagnostic_kind no_emitter[] = {RL_DIAG_NO_EMITTER}, dark[] = {RL_DIAG_DARK_CELLS};
    const rl_diagnostic_kind no_camera[] = {RL_DIAG_NO_CAMERA};
    check_room(dir, "warn_room.json", NULL, 0, NULL, 0, 0.0);
    /* every wall's normal points out of the room, as a cube modelled in Blender: nothing is lit, and all the
     * camera (inside) sees is backs */
    check_room(dir, "warn_room_outward.json", outward, 1, dark_back, 2, 1.0);
    check_room(dir, "warn_room_no_emitter.json", no_emitter, 1, dark, 1, 1.0);
    check_room(dir, "warn_room_no_camera.json", no_camera, 1, NULL, 0, 0.0);
}

/* Writes a one-slab light field: 4 x 4 positions over a 1 m square at the origin facing +z, radiance 1 in
 * every direction, with coverage cov (NULL: none). */
static void write_slab(const char *path, uint32_t n, const uint8_t *cov)
{
    uint64_t values = 4ull * n * n * 4 * 4 * 3; /* [dir][j][i][rgb] */
    float *rgb = malloc(values * sizeof *rgb);
    CHECK(rgb != NULL, "out of memory");
    for (uint64_t k = 0; rgb && k < values; k++)
        rgb[k] = 1.0f;
    if (rgb)
        ts_write_slab_covered(path, "light", 1.0, 4, n, rgb, cov);
    free(rgb);
}

#define FLIPPED "{\"file\": \"diag_lf.h5\", \"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}"
#define UNFLIPPED "{\"file\": \"diag_lf.h5\", \"transform\": [[1,0,0,0],[0,1,0,0],[0,0,1,1],[0,0,0,1]]}"

/* Writes a scene of a 2 m floor at z = 0 facing up and the slab of lf.h5 at z = 1, turned to face the floor
 * (flip 1) or left facing up, away from it (flip 0), or both (flip 2: the turned one first); diagnoses it
 * into d. @return the number of findings. */
static size_t diagnose_slab_scene(int flip, rl_diagnostic *d)
{
    char path[600], rest[512];
    snprintf(path, sizeof path, "%s/diag_lf.json", tmpdir);
    tpoly p[1] = {ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1)};
    snprintf(rest, sizeof rest, "\"radiance_maps\": {\"cell_size\": 0.25}, \"lightfields\": [%s]",
             flip == 2 ? FLIPPED ", " UNFLIPPED : flip ? FLIPPED : UNFLIPPED);
    ts_write_scene(path, "{\"grey\": {\"albedo\": [0.5, 0.5, 0.5]}}", p, 1, rest);
    rl_scene *s = ts_load(path);
    size_t n = s ? rl_scene_diagnose(s, d, MAX) : 0;
    rl_scene_destroy(s);
    return n;
}

static void check_lightfields(void)
{
    const uint32_t n = 4;
    const uint64_t nd = 4ull * n * n, npos = 16;
    uint8_t *cov = malloc(nd * npos);
    char lfpath[600];
    snprintf(lfpath, sizeof lfpath, "%s/diag_lf.h5", tmpdir);
    rl_diagnostic d[MAX];

    /* full coverage, facing the floor: nothing to say; facing away (placed without its flip): no light */
    memset(cov, 1, nd * npos);
    write_slab(lfpath, n, cov);
    size_t found = diagnose_slab_scene(1, d);
    CHECK(find(d, found, RL_DIAG_COVERAGE) < 0 && find(d, found, RL_DIAG_NOT_FACING) < 0,
          "a fully covered slab facing the floor: %zu findings (%s)", found, found ? d[0].text : "");
    found = diagnose_slab_scene(0, d);
    CHECK(find(d, found, RL_DIAG_NOT_FACING) >= 0, "a slab facing away from the floor is not reported");
    /* two lamps, one turned the wrong way: the room is lit, the lamp that lights nothing is named */
    found = diagnose_slab_scene(2, d);
    int at = find(d, found, RL_DIAG_EMITTER_UNSEEN);
    /* (the scene has no camera: that is the other finding) */
    CHECK(found == 2 && find(d, found, RL_DIAG_NO_CAMERA) >= 0 && at >= 0 && fabs(d[at].quantity - 0.5) < 1e-12 &&
              strstr(d[at].text, "lightfields[1]") != NULL,
          "one of two lamps facing away: %zu findings, first %s", found, found ? d[0].text : "none");

    /* half the positions captured in every direction: half the etendue, exactly (positions weigh alike) */
    for (uint64_t dir = 0; dir < nd; dir++)
        for (uint64_t p = 0; p < npos; p++)
            cov[dir * npos + p] = p % 4 < 2;
    write_slab(lfpath, n, cov);
    found = diagnose_slab_scene(1, d);
    at = find(d, found, RL_DIAG_COVERAGE);
    CHECK(at >= 0 && fabs(d[at].quantity - 0.5) < 1e-12, "half covered: missing %g, expected 0.5",
          at >= 0 ? d[at].quantity : -1.0);
    CHECK(at >= 0 && strstr(d[at].text, "50.00%") != NULL, "half covered: the finding does not give 50.00%%: %s",
          at >= 0 ? d[at].text : "");

    /* one direction captured: its projected solid angle's share of the hemisphere's */
    memset(cov, 0, nd * npos);
    memset(cov, 1, npos);
    const double pole[3] = {0, 0, 1};
    double all = 0.0;
    for (uint64_t dir = 0; dir < nd; dir++)
        all += lfio_part_projected_solid_angle(n, dir, pole);
    double expect = 1.0 - lfio_part_projected_solid_angle(n, 0, pole) / all;
    write_slab(lfpath, n, cov);
    found = diagnose_slab_scene(1, d);
    at = find(d, found, RL_DIAG_COVERAGE);
    CHECK(at >= 0 && fabs(d[at].quantity - expect) < 1e-12, "one direction covered: missing %.15g, expected %.15g",
          at >= 0 ? d[at].quantity : -1.0, expect);
    lfio_slab_desc desc;
    lfio_slab_desc_init(&desc);
    desc.nu = desc.nv = 4;
    desc.n = n;
    uint64_t covered = 0;
    lfio_coverage_share(&desc, cov, &covered);
    CHECK(covered == npos, "covered samples %llu, expected %llu", (unsigned long long)covered,
          (unsigned long long)npos);
    free(cov);
}

/* Records the progress a run reports. */
typedef struct progress_log {
    double last;
    int calls, backwards;
} progress_log;

static void log_progress(void *user, double done)
{
    progress_log *l = user;
    l->backwards += done < l->last;
    l->last = done;
    l->calls++;
}

/* A direct pass of 256 shadow rays per cell against a bounce of 16 rays on cells 4 times larger (16 times
 * fewer): the direct pass's share of the bar is its share of the rays, not half. The bar never goes back and
 * ends at 1. */
static void check_progress(const char *dir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/warn_room.json", dir);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    rl_job job;
    rl_job_default(s, &job);
    job.sampling.method = RL_METHOD_AREA;
    job.sampling.samples_per_cell = 256;
    job.sampling.bounces = 1;
    job.sampling.bounce_rays = 16;
    job.sampling.bounce_cell_factor = 4;
    rl__run run;
    CHECK(rl__job_resolve(s, &job, &run) == RL_OK, "job: %s", rl_errmsg());
    double per_pass[2] = {0, 0};
    double total = rl__solve_work(s, &run, 2, per_pass);
    /* room: 6 walls, 1 emitter; per cell 256 rays against 16 rays per larger cell of 16 cells */
    CHECK(total > 0 && fabs(per_pass[0] / total - 256.0 / (256.0 + 1.0)) < 0.01,
          "the direct pass's share %g, expected about %g", per_pass[0] / total, 256.0 / 257.0);
    progress_log log = {0, 0, 0};
    job.run.threads = 2;
    job.run.progress = log_progress;
    job.run.progress_user = &log;
    rl_solution *sol = NULL;
    CHECK(rl_relight(s, &job, &sol) == RL_OK, "relight: %s", rl_errmsg());
    CHECK(log.calls > 0 && log.last == 1.0 && log.backwards == 0, "progress: %d calls, last %g, %d backwards",
          log.calls, log.last, log.backwards);
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_diagnose SCENES_DIR\n");
        return 2;
    }
    const char *t = getenv("ILF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", t ? t : "/tmp");
    check_rooms(argv[1]);
    check_lightfields();
    check_progress(argv[1]);
    return check_report();
}
