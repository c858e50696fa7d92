/*
 * test_relight.c - the relighting engine against closed-form answers, and
 * its promises: culled and naive are bit-identical, results do not depend
 * on the thread count nor on the ranks of a job (simulated by threads, each
 * claiming tiles as it becomes free), and errors shrink as samples grow.
 *
 * Scenes are written as JSON into the test's temporary folder, so each
 * test states its geometry in full. The reference is Lambert's formula for
 * an unoccluded polygon (rl_reference_polygon_irradiance), averaged over
 * each cell on a fine grid of points. With --extremes the test runs the
 * stability cases instead: grazing and touching geometry, tiny, huge and
 * distant emitters, and a light field slab seen edge-on.
 */
#include <dirent.h>
#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lfio/lightfield.h>
#include <lfio/partition.h>
#include <relight/engine.h>
#include <relight/reference.h>

#include "check.h"
#include "relight_scenes.h"

static char tmpdir[512];

static int no_descent; /* set by the random-scene test */

/* Makes ts_job the job of the calls on scene s that follow: its file's, with method, level, rays, samples
 * and threads, and descent unless no_descent. */
static void set_sampling(const rl_scene *s, rl_method m, uint32_t n, uint32_t k, uint32_t samples, uint32_t threads)
{
    ts_set_sampling(s, m, n, k, samples, !no_descent, threads);
}

/* The cells of map k: count, irradiance copy (caller frees), and centres. */
static float *map_irradiance(const rl_solution *sol, size_t k, uint32_t *ncells, double **centre, uint32_t **ij)
{
    rl_map_info info;
    rl_solution_map_info(sol, k, &info);
    float *e = malloc((info.ncells + 1) * 3 * sizeof *e);
    *centre = malloc((info.ncells + 1) * 3 * sizeof **centre);
    *ij = malloc((info.ncells + 1) * 2 * sizeof **ij);
    rl_solution_map_cells(sol, k, *ij, NULL, *centre, e, NULL);
    *ncells = info.ncells;
    return e;
}

/* Mean analytic irradiance over a full square cell (8x8 points). */
static double cell_reference(const tpoly *em, double radiance, const rl_map_info *info, uint32_t i, uint32_t j)
{
    double sum = 0;
    for (int a = 0; a < 8; a++)
        for (int b = 0; b < 8; b++) {
            double u = info->u0 + (i + (a + 0.5) / 8) * info->cell_size;
            double v = info->v0 + (j + (b + 0.5) / 8) * info->cell_size;
            double x[3];
            for (int c = 0; c < 3; c++)
                x[c] = info->origin[c] + u * info->e1[c] + v * info->e2[c];
            sum += rl_reference_polygon_irradiance(&em->v[0][0], em->n, x, info->normal, radiance);
        }
    return sum / 64;
}

/* RMSE and max error of map k of sol against the analytic answer, relative to the peak. */
static void errors_vs_reference(const rl_solution *sol, size_t k, const tpoly *em, double radiance, double *rmse,
                                double *maxerr)
{
    rl_map_info info;
    rl_solution_map_info(sol, k, &info);
    uint32_t n, *ij;
    double *centre;
    float *e = map_irradiance(sol, k, &n, &centre, &ij);
    double peak = 0, se = 0, mx = 0;
    double *ref = malloc((n + 1) * sizeof *ref);
    for (uint32_t c = 0; c < n; c++) {
        ref[c] = cell_reference(em, radiance, &info, ij[2 * c], ij[2 * c + 1]);
        peak = fmax(peak, ref[c]);
    }
    for (uint32_t c = 0; c < n; c++) {
        double d = e[3 * c + 1] - ref[c];
        se += d * d;
        mx = fmax(mx, fabs(d));
    }
    *rmse = sqrt(se / n) / peak;
    *maxerr = mx / peak;
    free(ref);
    free(e);
    free(centre);
    free(ij);
}

static const char *MATS = "{\"light\": {\"albedo\": [0,0,0], \"emission\": [2,2,2]},"
                          " \"grey\": {\"albedo\": [0.5,0.5,0.5]}, \"black\": {\"albedo\": [0,0,0]}}";

/* A 1 m emitter 1 m above a 2 m receiver: every method against Lambert. */
static void check_unoccluded(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/square.json", tmpdir);
    tpoly p[2] = {ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0), ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1)};
    ts_write_scene(path, MATS, p, 2, "\"radiance_maps\": {\"cell_size\": 0.25}");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    const rl_method methods[] = {RL_METHOD_CULLED, RL_METHOD_NAIVE, RL_METHOD_AREA, RL_METHOD_SOLIDANGLE,
                                 RL_METHOD_ADAPTIVE};
    for (int m = 0; m < 5; m++) {
        set_sampling(s, methods[m], 32, 4, 128, 0);
        rl_solution *sol = NULL;
        CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "%s: %s", rl_method_name(methods[m]), rl_errmsg());
        if (!sol)
            continue;
        long k = ts_map_of(sol, 1);
        double rmse, mx;
        errors_vs_reference(sol, (size_t)k, &p[0], 2.0, &rmse, &mx);
        printf("unoccluded %-10s defaults: RMSE %.4f%%, max %.4f%% of peak\n", rl_method_name(methods[m]),
               100 * rmse, 100 * mx);
        CHECK(rmse < 0.01 && mx < 0.03, "%s: RMSE %.4g, max %.4g of peak", rl_method_name(methods[m]), rmse, mx);
        rl_pass_stats st;
        rl_solution_pass_stats(sol, 0, &st);
        CHECK(st.rays_kept + st.rays_free > 0 && st.rays_kept <= st.rays_cast && st.rays_cast <= st.samples,
              "stats consistent");
        /* nothing lies between the two: Lambert's gather (culled's and naive's for a constant emitter)
         * knows every ray arrives and traces none */
        if (methods[m] == RL_METHOD_CULLED || methods[m] == RL_METHOD_NAIVE)
            CHECK(st.rays_cast == 0 && st.rays_free > 0, "%s, unoccluded: %llu rays cast, %llu known free",
                  rl_method_name(methods[m]), (unsigned long long)st.rays_cast, (unsigned long long)st.rays_free);
        if (methods[m] == RL_METHOD_CULLED) /* a constant emitter needs no solid angle (docs/methods.md) */
            CHECK(st.solid_angles_considered == 0, "culled, constant emitter: %llu solid angles",
                  (unsigned long long)st.solid_angles_considered);
        rl_solution_destroy(sol);
    }
    /* the paper's plain method culls solid angles */
    no_descent = 1;
    set_sampling(s, RL_METHOD_CULLED, 32, 4, 128, 0);
    no_descent = 0;
    rl_solution *plain = NULL;
    CHECK(rl_relight(s, &ts_job, &plain) == RL_OK, "plain: %s", rl_errmsg());
    if (plain) {
        rl_pass_stats st;
        rl_solution_pass_stats(plain, 0, &st);
        CHECK(st.solid_angles_culled > 0, "culling culls: %llu of %llu", (unsigned long long)st.solid_angles_culled,
              (unsigned long long)st.solid_angles_considered);
        rl_solution_destroy(plain);
    }
    /* error shrinks as rays per solid angle grow */
    double prev = INFINITY;
    const uint32_t ks[] = {1, 4, 16};
    for (int q = 0; q < 3; q++) {
        set_sampling(s, RL_METHOD_CULLED, 16, ks[q], 64, 0);
        rl_solution *sol = NULL;
        rl_relight(s, &ts_job, &sol);
        double rmse, mx;
        errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), &p[0], 2.0, &rmse, &mx);
        printf("culled n=16 k=%-2u: RMSE %.4f%%\n", ks[q], 100 * rmse);
        CHECK(rmse < prev, "k=%u: RMSE %.4g not below %.4g", ks[q], rmse, prev);
        prev = rmse;
        rl_solution_destroy(sol);
    }
    /* and as samples per cell grow, for area sampling */
    prev = INFINITY;
    const uint32_t ns[] = {4, 64, 1024};
    for (int q = 0; q < 3; q++) {
        set_sampling(s, RL_METHOD_AREA, 16, 1, ns[q], 0);
        rl_solution *sol = NULL;
        rl_relight(s, &ts_job, &sol);
        double rmse, mx;
        errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), &p[0], 2.0, &rmse, &mx);
        printf("area samples=%-4u: RMSE %.4f%%\n", ns[q], 100 * rmse);
        CHECK(rmse < prev, "samples=%u: RMSE %.4g not below %.4g", ns[q], rmse, prev);
        prev = rmse;
        rl_solution_destroy(sol);
    }
    /* points: every method agrees with Lambert at a few points */
    double pts[4][6] = {{0, 0, 0, 0, 0, 1}, {0.7, -0.3, 0, 0, 0, 1}, {0.2, 0.1, 0.4, 0.3, 0.1, 1}, {0, 0, 2, 0, 0, 1}};
    for (int m = 0; m < 4; m++) {
        set_sampling(s, methods[m], 32, 16, 4096, 0);
        double out[12];
        CHECK(rl_irradiance(s, &ts_job, &pts[0][0], 4, out, NULL) == RL_OK, "irradiance: %s", rl_errmsg());
        for (int q = 0; q < 4; q++) {
            double nrm[3] = {pts[q][3], pts[q][4], pts[q][5]}, l = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
            for (int c = 0; c < 3; c++)
                nrm[c] /= l;
            double ref = rl_reference_polygon_irradiance(&p[0].v[0][0], 4, pts[q], nrm, 2.0);
            CHECK(fabs(out[3 * q] - ref) <= 0.01 * 2.0 * 3.14159 + 1e-12, "%s point %d: %.6g vs %.6g",
                  rl_method_name(methods[m]), q, out[3 * q], ref);
        }
    }
    rl_scene_destroy(s);
}

/* @return the area-weighted mean irradiance (channel 0) of map k of sol. */
static double map_mean(const rl_solution *sol, long k)
{
    if (k < 0)
        return NAN;
    ts_cells c = ts_cells_get(sol, (size_t)k);
    double sum = 0, area = 0;
    for (uint32_t i = 0; i < c.n; i++) {
        sum += c.area[i] * c.e[3 * i];
        area += c.area[i];
    }
    ts_cells_free(&c);
    return area > 0 ? sum / area : NAN;
}

/* A panel modelled as two polygons back to back, lit on its top by a lamp below the ceiling: the
 * ceiling's light is all bounce light off the panel's top. The first-hit gather meets the panel's
 * coincident faces in whichever order Embree finds them, and must read the top's front however it
 * does (it once read the bottom's back: 0); both bounce gathers are unbiased and must agree. */
static void check_back_to_back(void)
{
    for (int order = 0; order < 2; order++) {
        char path[600];
        snprintf(path, sizeof path, "%s/back_to_back.json", tmpdir);
        tpoly p[] = {
            ts_rect_z("grey", -3, -3, 3, 3, 3.0, 0),          /* the ceiling, facing down */
            ts_rect_z("light", -0.3, -0.3, 0.3, 0.3, 2.9, 0), /* the lamp under it, facing down */
            ts_rect_z("grey", -1, -1, 1, 1, 1.5, order),      /* the panel's bottom, then its top, */
            ts_rect_z("grey", -1, -1, 1, 1, 1.5, !order),     /* or the other way round */
        };
        ts_write_scene(path, MATS, p, 4, "\"radiance_maps\": {\"cell_size\": 0.2}, \"sampling\": {\"bounces\": 1}");
        rl_scene *s = ts_load(path);
        if (!s)
            return;
        /* first hits and the method's transfer on every cell, then first hits on the default larger
         * cells, which gather the ceiling around the lamp (0.1 m under it) on its own cells */
        double ceiling[3] = {NAN, NAN, NAN};
        for (int k = 0; k < 3; k++) {
            set_sampling(s, RL_METHOD_CULLED, 16, 4, 64, 2);
            ts_job.sampling.bounce_rays = k == 1 ? 0 : 256;
            ts_job.sampling.bounce_cell_factor = k == 2 ? 0 : 1;
            CHECK(rl_job_check(&ts_job) == RL_OK, "set_sampling: %s", rl_errmsg());
            rl_solution *sol = NULL;
            CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "back to back: %s", rl_errmsg());
            if (sol)
                ceiling[k] = map_mean(sol, ts_map_of(sol, 0));
            rl_solution_destroy(sol);
        }
        printf("back to back (%s first): the ceiling's bounce light %.5g by first hits, %.5g by the method's "
               "transfer, %.5g by first hits on larger cells\n", order ? "top" : "bottom", ceiling[0], ceiling[1],
               ceiling[2]);
        CHECK(ceiling[1] > 0 && fabs(ceiling[0] / ceiling[1] - 1) < 0.03, "back to back, order %d: %.5g against %.5g",
              order, ceiling[0], ceiling[1]);
        /* interpolated cells that read the larger cells gathered on their own counted that light twice
         * (+4% here, before they were left out) */
        CHECK(fabs(ceiling[2] / ceiling[0] - 1) < 0.015, "back to back, order %d: %.5g on larger cells against %.5g",
              order, ceiling[2], ceiling[0]);
        rl_scene_destroy(s);
    }
}

/*
 * Bounce light at a contact: a fin stands on a floor, lit on its left face
 * only. After one bounce the floor right of the fin sees nothing that
 * re-emits (the fin's right face is dark), so its bounce light is exactly
 * zero there, while left of the fin it is brightest. Bounce passes gather on
 * cells four times larger and interpolate; interpolating across the fin
 * would carry the left's light onto the right. The first gather finds the
 * cells whose rays meet the fin within half a (larger) cell above the
 * floor's interior, and the floor's cells of those larger cells and of
 * their neighbours are gathered on their own: the right side must stay
 * zero, and only cells near the fin may be gathered so.
 */
static void check_contact_bounce(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/contact.json", tmpdir);
    tpoly fin_left = {"grey", 4, {{1, 0.3, 0}, {1, 0.3, 0.5}, {1, 1.7, 0.5}, {1, 1.7, 0}}};
    tpoly fin_right = {"grey", 4, {{1, 1.7, 0}, {1, 1.7, 0.5}, {1, 0.3, 0.5}, {1, 0.3, 0}}};
    tpoly p[] = {ts_rect_z("grey", 0, 0, 2, 2, 0, 1), fin_left, fin_right,
                 ts_rect_z("light", 0.2, 0.3, 0.8, 1.7, 1.0, 0)};
    ts_write_scene(path, MATS, p, 4, "\"radiance_maps\": {\"cell_size\": 0.05}");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    ts_cells floor[2];
    rl_pass_stats bounce = {0};
    for (int b = 0; b < 2; b++) {
        set_sampling(s, RL_METHOD_CULLED, 16, 4, 64, 2);
        ts_job.sampling.bounces = (uint32_t)b;
        ts_job.sampling.bounce_cell_factor = 4;
        ts_job.sampling.bounce_rays = 64;
        CHECK(rl_job_check(&ts_job) == RL_OK, "set_sampling: %s", rl_errmsg());
        rl_solution *sol = NULL;
        CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "contact: %s", rl_errmsg());
        if (!sol) {
            rl_scene_destroy(s);
            if (b == 1)
                ts_cells_free(&floor[0]);
            return;
        }
        floor[b] = ts_cells_get(sol, (size_t)ts_map_of(sol, 0));
        if (b == 1)
            CHECK(rl_solution_pass_stats(sol, 1, &bounce) == RL_OK, "pass stats: %s", rl_errmsg());
        rl_solution_destroy(sol);
    }
    long right = 0, lit_right = 0, left = 0, lit_left = 0;
    for (uint32_t k = 0; k < floor[1].n && floor[0].n == floor[1].n; k++) {
        double x = floor[1].info.u0 + (floor[1].ij[2 * k] + 0.5) * floor[1].info.cell_size;
        double y = floor[1].info.v0 + (floor[1].ij[2 * k + 1] + 0.5) * floor[1].info.cell_size;
        double light = (double)floor[1].e[3 * k + 1] - floor[0].e[3 * k + 1];
        if (y < 0.5 || y > 1.5)
            continue; /* round the fin's ends light reaches the right side */
        if (x > 1.0)
            right++, lit_right += light != 0.0;
        else if (x > 0.8)
            left++, lit_left += light > 0.0;
    }
    printf("contact: bounce light on %ld of %ld floor cells right of the fin, on %ld of %ld left of it; %" PRIu64
           " cells gathered on their own\n", lit_right, right, lit_left, left, bounce.cells_direct);
    CHECK(right > 0 && lit_right == 0, "contact: %ld of %ld floor cells right of the fin got bounce light", lit_right,
          right);
    CHECK(left > 0 && lit_left == left, "contact: %ld of %ld floor cells left of the fin lit", lit_left, left);
    /* near the fin only: a larger cell (0.2 m) is flagged when its rays meet the fin within 0.1 m, so
     * those touching x = 1 (columns 4 and 5 of 10) within the fin's length (rows 1 to 8); they and
     * their neighbours are gathered on their own: columns 3 to 6, every row, 16 x 40 of the floor's
     * cells, and none of the fin's own (the floor meets it at its edge) */
    CHECK(bounce.cells_direct == 16 * 40, "contact: %" PRIu64
          " cells gathered on their own of %u on the floor", bounce.cells_direct, floor[1].n);
    ts_cells_free(&floor[0]);
    ts_cells_free(&floor[1]);
    rl_scene_destroy(s);
}

/*
 * A wall meeting a floor at the floor's edge does not make either gather on
 * its own cells (interpolation carries light to an edge, and it varies
 * slowly along one); a low wall there, under three larger cells high, does:
 * its whole height lies within a larger cell of the floor, so all of its
 * cells are gathered on their own, and still none of the floor's.
 */
static void check_narrow_wall(void)
{
    for (int low = 0; low < 2; low++) {
        char path[600];
        snprintf(path, sizeof path, "%s/narrow.json", tmpdir);
        double h = low ? 0.3 : 1.0;
        tpoly wall = {"grey", 4, {{2, 0, 0}, {2, 0, h}, {2, 2, h}, {2, 2, 0}}}; /* faces -x, at the floor's edge */
        tpoly p[] = {ts_rect_z("grey", 0, 0, 2, 2, 0, 1), wall, ts_rect_z("light", 0.5, 0.5, 1.5, 1.5, 1.5, 0)};
        ts_write_scene(path, MATS, p, 3, "\"radiance_maps\": {\"cell_size\": 0.05}");
        rl_scene *s = ts_load(path);
        if (!s)
            return;
        set_sampling(s, RL_METHOD_CULLED, 16, 4, 64, 2);
        ts_job.sampling.bounces = 1;
        ts_job.sampling.bounce_cell_factor = 4;
        ts_job.sampling.bounce_rays = 64;
        CHECK(rl_job_check(&ts_job) == RL_OK, "set_sampling: %s", rl_errmsg());
        rl_solution *sol = NULL;
        rl_pass_stats bounce = {0};
        CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "narrow wall: %s", rl_errmsg());
        if (sol)
            CHECK(rl_solution_pass_stats(sol, 1, &bounce) == RL_OK, "pass stats: %s", rl_errmsg());
        /* the low wall: 6 rows of 40 cells */
        uint64_t want = low ? 6 * 40 : 0;
        printf("narrow wall: %.1f m high, %" PRIu64 " cells gathered on their own\n", h, bounce.cells_direct);
        CHECK(sol && bounce.cells_direct == want, "narrow wall %.1f m high: %" PRIu64 " cells on their own, not %"
              PRIu64, h, bounce.cells_direct, want);
        rl_solution_destroy(sol);
        rl_scene_destroy(s);
    }
}

/* The closed box [x0, x0 + 2] x [0, 2] x [0, 2] as six inward-facing quads into p (returns the count; the
 * floor first, then the ceiling), with, when
 * door is set, an opening y in [0.8, 1.2], z in [0, 1.2] through its wall at x = x0 + 2 (if door > 0) or at
 * x = x0 (door < 0), that wall then in three pieces; and a lamp of material lamp, 0.4 m square, 0.1 m under
 * its ceiling, facing down. */
static int room_quads(tpoly *p, double x0, int door, const char *lamp)
{
    double x1 = x0 + 2, h = 2;
    int n = 0;
    p[n++] = ts_rect_z("grey", x0, 0, x1, 2, 0, 1);
    p[n++] = ts_rect_z("grey", x0, 0, x1, 2, h, 0);
    p[n++] = (tpoly){"grey", 4, {{x0, 0, 0}, {x0, 0, h}, {x1, 0, h}, {x1, 0, 0}}}; /* y = 0, facing +y */
    p[n++] = (tpoly){"grey", 4, {{x0, 2, 0}, {x1, 2, 0}, {x1, 2, h}, {x0, 2, h}}}; /* y = 2, facing -y */
    /* the x walls: facing +x at x0, -x at x1, each whole or in three pieces around the door */
    for (int side = 0; side < 2; side++) {
        double x = side ? x1 : x0;
        int pieces = (door > 0 && side) || (door < 0 && !side);
        double ya[3] = {0, 1.2, 0.8}, yb[3] = {0.8, 2, 1.2}, za[3] = {0, 0, 1.2};
        for (int k = 0; k < (pieces ? 3 : 1); k++) {
            double y0 = pieces ? ya[k] : 0, y1 = pieces ? yb[k] : 2, z0 = pieces ? za[k] : 0;
            tpoly w = side ? (tpoly){"grey", 4, {{x, y0, z0}, {x, y0, h}, {x, y1, h}, {x, y1, z0}}}
                           : (tpoly){"grey", 4, {{x, y0, z0}, {x, y1, z0}, {x, y1, h}, {x, y0, h}}};
            p[n++] = w;
        }
    }
    p[n++] = ts_rect_z(lamp, x0 + 0.8, 0.8, x0 + 1.2, 1.2, h - 0.1, 0);
    return n;
}

/* Relights the rooms p (n) as the test's scene with method m. @return the solution (or NULL), *st its direct
 * pass's statistics, *scene the scene it reads (destroy it after the solution). */
static rl_solution *rooms_relight(const tpoly *p, int n, rl_method m, rl_pass_stats *st, rl_scene **scene)
{
    char path[600];
    snprintf(path, sizeof path, "%s/rooms.json", tmpdir);
    ts_write_scene(path, MATS, p, n, "\"radiance_maps\": {\"cell_size\": 0.25}, \"sampling\": {\"bounces\": 0}");
    memset(st, 0, sizeof *st);
    *scene = ts_load(path);
    if (!*scene)
        return NULL;
    set_sampling(*scene, m, 8, 2, 16, 2);
    rl_solution *sol = ts_relight(*scene, "rooms");
    if (sol)
        CHECK(rl_solution_pass_stats(sol, 0, st) == RL_OK, "rooms: pass stats: %s", rl_errmsg());
    return sol;
}

/*
 * Emitters a tile cannot reach are left out before any per-pair work
 * (emitter_tree.h), exactly. Two closed rooms 0.2 m apart, each with a
 * lamp: every receiving polygon of a room (one tile each) exchanges light
 * with its own room's lamp alone, so the pairs counted are the maps of the
 * room of the lit lamp (the other room's maps would double them), and the
 * first room's maps are the same, bit for bit, as with the second lamp
 * dark. So also with the second room moved diagonally off, where its lamp
 * is hidden from the first room by no single wall, only by a corner's two
 * (shadow.h). With doors in line through both rooms' facing walls, the second
 * lamp lights the first room through them, though each wall's plane parts
 * the rooms: no single polygon hides it, so it must not be left out, and the
 * first room's floor is lit.
 */
static void check_rooms_cull(void)
{
    tpoly p[24];
    for (int m = 0; m < 2; m++) {
        rl_method method = m ? RL_METHOD_NAIVE : RL_METHOD_CULLED;
        const char *name = m ? "naive" : "culled";
        rl_pass_stats both, one;
        rl_scene *scenes[5] = {NULL, NULL, NULL, NULL, NULL};
        int na = 0, n = 0;
        for (int diagonal = 0; diagonal < 2; diagonal++) {
            na = room_quads(p, 0, 0, "light");
            n = na + room_quads(p + na, 2.2, 0, "light");
            const double off[3] = {0, 2.2, 0};
            for (int k = na; k < n && diagonal; k++)
                p[k] = ts_moved(p[k], off);
            const char *layout = diagonal ? "diagonally" : "side by side";
            rl_solution *lit = rooms_relight(p, n, method, &both, &scenes[2 * diagonal]);
            p[n - 1].material = "black"; /* the second room's lamp dark */
            rl_solution *dark = rooms_relight(p, n, method, &one, &scenes[2 * diagonal + 1]);
            if (lit && dark) {
                /* each room's maps in front of its own lamp: all but the ceiling's (and the lamps') */
                uint64_t maps[2] = {0, 0};
                long differ = 0;
                for (int k = 0; k < n; k++) {
                    long a = ts_map_of(lit, (uint32_t)k), b = ts_map_of(dark, (uint32_t)k);
                    if (a < 0 || k == 1 || k == na + 1 || k == na - 1 || k == n - 1)
                        continue;
                    maps[k >= na]++;
                    if (k >= na)
                        continue;
                    ts_cells ca = ts_cells_get(lit, (size_t)a), cb = ts_cells_get(dark, (size_t)b);
                    differ += ca.n != cb.n || memcmp(ca.e, cb.e, 3 * ca.n * sizeof *ca.e) != 0;
                    ts_cells_free(&ca);
                    ts_cells_free(&cb);
                }
                printf("two closed rooms %s, %s: %llu pairs with both lamps lit, %llu with one, of %llu + %llu maps\n",
                       layout, name, (unsigned long long)both.pairs, (unsigned long long)one.pairs,
                       (unsigned long long)maps[0], (unsigned long long)maps[1]);
                CHECK(maps[0] > 0 && one.pairs == maps[0] && both.pairs == maps[0] + maps[1],
                      "two closed rooms %s, %s: %llu and %llu pairs, not %llu and %llu: a lamp paired with the other "
                      "room", layout, name, (unsigned long long)one.pairs, (unsigned long long)both.pairs,
                      (unsigned long long)maps[0], (unsigned long long)(maps[0] + maps[1]));
                CHECK(differ == 0, "two closed rooms %s, %s: %ld maps of the first room change with the second lamp",
                      layout, name, differ);
            }
            rl_solution_destroy(lit);
            rl_solution_destroy(dark);
        }
        /* doors in line; the first room's lamp dark */
        na = room_quads(p, 0, 1, "black");
        n = na + room_quads(p + na, 2.2, -1, "light");
        rl_solution *door = rooms_relight(p, n, method, &one, &scenes[4]);
        long floor = door ? ts_map_of(door, 0) : -1;
        double lit_floor = NAN;
        if (floor >= 0) {
            ts_cells c = ts_cells_get(door, (size_t)floor);
            lit_floor = 0;
            for (uint32_t i = 0; i < c.n; i++)
                lit_floor += c.e[3 * i] > 0;
            ts_cells_free(&c);
        }
        printf("rooms with doors, %s: %.0f cells of the first room's floor lit through them, %llu pairs\n", name,
               lit_floor, (unsigned long long)one.pairs);
        CHECK(lit_floor > 0, "rooms with doors, %s: the first room's floor is dark: the lamp seen through the doors "
              "was left out", name);
        rl_solution_destroy(door);
        for (int k = 0; k < 5; k++)
            rl_scene_destroy(scenes[k]);
    }
}

/* An occluded room: culled and naive must agree bit for bit, and thread counts must not matter, with the
 * bounce pass gathered by each method's own transfer (bounce_rays 0) or by first-hit rays (bounce_rays). */
static void check_identities(uint32_t bounce_rays)
{
    char path[600], rest[200];
    snprintf(path, sizeof path, "%s/occluded.json", tmpdir);
    tpoly p[] = {
        ts_rect_z("light", -0.4, -0.4, 0.4, 0.4, 2.0, 0),
        ts_rect_z("grey", -2, -2, 2, 2, 0.0, 1),
        ts_rect_z("grey", -2, -2, 2, 2, 2.2, 0),
        ts_rect_z("grey", -0.5, -0.3, 0.3, 0.5, 1.0, 0), /* a blocker facing down */
        ts_rect_z("grey", -0.5, -0.3, 0.3, 0.5, 1.0, 1), /* and its top */
        {"grey", 4, {{-2, -2, 0}, {-2, 2, 0}, {-2, 2, 2.2}, {-2, -2, 2.2}}}, /* a wall facing +x */
    };
    snprintf(rest, sizeof rest, "\"radiance_maps\": {\"cell_size\": 0.2}, \"sampling\": {\"bounces\": 1, \"bounce_rays\": %u}",
             bounce_rays);
    ts_write_scene(path, MATS, p, 6, rest);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    rl_solution *sol[4] = {NULL};
    set_sampling(s, RL_METHOD_CULLED, 16, 2, 16, 1);
    rl_relight(s, &ts_job, &sol[0]);
    set_sampling(s, RL_METHOD_NAIVE, 16, 2, 16, 2);
    rl_relight(s, &ts_job, &sol[1]);
    set_sampling(s, RL_METHOD_CULLED, 16, 2, 16, 3);
    rl_relight(s, &ts_job, &sol[2]);
    set_sampling(s, RL_METHOD_AREA, 16, 2, 16, 1);
    rl_relight(s, &ts_job, &sol[3]);
    if (sol[0] && sol[1] && sol[2] && sol[3]) {
        /* the bounce pass gathers by solid angles (the direct one from this
         * constant emitter by Lambert's formula, the same code for both), or
         * by first hits, the same for every method */
        rl_pass_stats a, b, a1;
        rl_solution_pass_stats(sol[0], 1, &a1);
        rl_solution_pass_stats(sol[1], 1, &b);
        if (bounce_rays == 0) {
            CHECK(a1.solid_angles_culled > 0 && b.solid_angles_culled == 0, "culled culls, naive does not");
            CHECK(a1.samples < b.samples, "culling saves rays: %llu vs %llu", (unsigned long long)a1.samples,
                  (unsigned long long)b.samples);
        } else {
            CHECK(a1.pairs == 0 && a1.samples == b.samples && a1.samples % bounce_rays == 0 &&
                      a1.rays_kept > 0 && a1.rays_kept < a1.rays_cast,
                  "first-hit bounce: %llu samples, %llu of %llu rays kept", (unsigned long long)a1.samples,
                  (unsigned long long)a1.rays_kept, (unsigned long long)a1.rays_cast);
        }
        rl_solution_pass_stats(sol[0], 0, &a);
        CHECK(a.pairs_descended == 0 && a1.pairs_descended == 0, "no pair descends in this scene: %llu, %llu",
              (unsigned long long)a.pairs_descended, (unsigned long long)a1.pairs_descended);
        long same = 0, nonzero = 0, total = 0, thread_same = 0;
        for (size_t k = 0; k < rl_solution_map_count(sol[0]); k++) {
            uint32_t n0, n1, n2, *ij;
            double *centre;
            float *e0 = map_irradiance(sol[0], k, &n0, &centre, &ij);
            free(centre); free(ij);
            float *e1 = map_irradiance(sol[1], k, &n1, &centre, &ij);
            free(centre); free(ij);
            float *e2 = map_irradiance(sol[2], k, &n2, &centre, &ij);
            free(centre); free(ij);
            for (uint32_t c = 0; c < 3 * n0; c++) {
                same += memcmp(&e0[c], &e1[c], sizeof(float)) == 0;
                thread_same += memcmp(&e0[c], &e2[c], sizeof(float)) == 0;
                nonzero += e0[c] != 0;
                total++;
            }
            free(e0); free(e1); free(e2);
        }
        CHECK(same == total, "culled == naive: %ld of %ld values differ", total - same, total);
        CHECK(thread_same == total, "1 vs 3 threads: %ld of %ld values differ", total - thread_same, total);
        CHECK(nonzero > total / 2, "the scene is lit (%ld of %ld nonzero)", nonzero, total);
        CHECK(rl_solution_pass_count(sol[0]) == 2, "direct pass and one bounce");
        /* the blocker casts a shadow: the floor under it is darker than beside it */
        long fk = ts_map_of(sol[0], 1);
        uint32_t n, *ij;
        double *centre;
        float *e = map_irradiance(sol[0], (size_t)fk, &n, &centre, &ij);
        double under = 0, beside = 0;
        for (uint32_t c = 0; c < n; c++) {
            double x = centre[3 * c], y = centre[3 * c + 1];
            if (fabs(x + 0.1) < 0.15 && fabs(y - 0.1) < 0.15)
                under = e[3 * c];
            if (fabs(x - 1.3) < 0.1 && fabs(y + 1.3) < 0.1)
                beside = e[3 * c];
        }
        CHECK(under < 0.5 * beside, "umbra %.4g vs lit %.4g", under, beside);
        free(e); free(centre); free(ij);
    }
    for (int k = 0; k < 4; k++)
        rl_solution_destroy(sol[k]);
    if (bounce_rays > 0) {
        rl_scene_destroy(s);
        return;
    }
    /* adaptive refines where samples disagree, deterministically, for any thread count */
    rl_solution *ad[2] = {NULL, NULL};
    for (int k = 0; k < 2; k++) {
        set_sampling(s, RL_METHOD_ADAPTIVE, 16, 4, 16, k + 1);
        ts_job.sampling.target_error = 0.02;
        ts_job.sampling.bounces = 0;
        rl_relight(s, &ts_job, &ad[k]);
    }
    if (ad[0] && ad[1]) {
        rl_pass_stats st;
        rl_solution_pass_stats(ad[0], 0, &st);
        CHECK(st.refinements > 0 && st.estimated_rmse > 0 && !st.budget_reached, "adaptive refines: %llu, %.3g",
              (unsigned long long)st.refinements, st.estimated_rmse);
        long differ = 0;
        for (size_t k = 0; k < rl_solution_map_count(ad[0]); k++) {
            uint32_t n0, n1, *ij;
            double *centre;
            float *e0 = map_irradiance(ad[0], k, &n0, &centre, &ij);
            free(centre); free(ij);
            float *e1 = map_irradiance(ad[1], k, &n1, &centre, &ij);
            free(centre); free(ij);
            differ += memcmp(e0, e1, 3 * n0 * sizeof *e0) != 0;
            free(e0);
            free(e1);
        }
        CHECK(differ == 0, "adaptive: 1 vs 2 threads differ in %ld maps", differ);
    }
    rl_solution_destroy(ad[0]);
    rl_solution_destroy(ad[1]);
    rl_scene_destroy(s);
}

/* @return a new slab "light" of partition n: 4 x 4 positions over a 1 m square at the origin facing +z, all zero. */
static lfio_slab *test_slab_new(uint32_t n)
{
    lfio_slab_desc d;
    lfio_slab *slab = NULL;
    lfio_slab_desc_init(&d);
    strcpy(d.name, "light");
    d.origin[0] = d.origin[1] = -0.5;
    d.nu = d.nv = 4;
    d.n = n;
    CHECK(lfio_slab_new(&d, &slab) == LFIO_OK, "new slab: %s", lfio_errmsg());
    return slab;
}

/* Writes slab (taken) as the one slab of the light field file path. */
static void test_slab_write(const char *path, lfio_slab *slab)
{
    lfio_lightfield *lf = NULL;
    lfio_lightfield_new(&lf);
    lfio_lightfield_take_slab(lf, slab);
    CHECK(lfio_lightfield_write(lf, path) == LFIO_OK, "write %s: %s", path, lfio_errmsg());
    lfio_lightfield_destroy(lf);
}

/* Writes a one-slab light field: a 1 m square at the origin facing +z, constant
 * radiance c in a cone around +z of half-angle cone_deg (every direction if >= 90).
 * sparse: each direction lights only one column of positions, a different
 * one per direction, so that each solid angle's support is a strip of the slab. */
static void write_lightfield(const char *path, float c, double cone_deg, uint32_t n, int sparse)
{
    lfio_slab *slab = test_slab_new(n);
    uint64_t nd = lfio_slab_dir_count(slab);
    float *rgb = calloc(nd * 3, sizeof *rgb);
    for (uint64_t k = 0; k < nd; k++) {
        double w[3];
        lfio_part_centroid(n, k, w);
        float v = (cone_deg >= 90 || w[2] > cos(cone_deg * 3.14159265358979 / 180)) ? c : 0.0f;
        rgb[3 * k] = rgb[3 * k + 1] = rgb[3 * k + 2] = v;
    }
    for (uint32_t j = 0; j < 4; j++)
        for (uint32_t i = 0; i < 4; i++)
            lfio_slab_write_position(slab, i, j, rgb);
    for (uint64_t k = 0; sparse && k < nd; k++)
        for (uint32_t j = 0; j < 4; j++)
            for (uint32_t i = 0; i < 4; i++)
                if (i != k % 4)
                    lfio_slab_write(slab, k, i, j, (const float[3]){0, 0, 0});
    test_slab_write(path, slab);
    free(rgb);
}

/* Relights s culled and naive, and culled without zero-radiance culling:
 * the three must agree bit for bit, the floor be lit, and the mask cull
 * most solid angles. @return culled's sample count. */
static uint64_t check_culled_naive(rl_scene *s, const char *what)
{
    rl_solution *a = NULL, *b = NULL, *c = NULL;
    uint64_t samples = 0;
    set_sampling(s, RL_METHOD_CULLED, 16, 2, 16, 0);
    rl_relight(s, &ts_job, &a);
    set_sampling(s, RL_METHOD_NAIVE, 16, 2, 16, 0);
    rl_relight(s, &ts_job, &b);
    set_sampling(s, RL_METHOD_CULLED, 16, 2, 16, 0);
    ts_job.sampling.zero_culling = 0;
    CHECK(rl_job_check(&ts_job) == RL_OK, "zero_culling 0: %s", rl_errmsg());
    rl_relight(s, &ts_job, &c);
    long total;
    if (a && c) {
        CHECK(ts_differing(a, c, &total) == 0, "%s: zero culling changes nothing", what);
        rl_pass_stats sa, sc;
        rl_solution_pass_stats(a, 0, &sa);
        rl_solution_pass_stats(c, 0, &sc);
        CHECK(sa.samples < sc.samples, "%s: zero culling saves samples: %llu vs %llu", what,
              (unsigned long long)sa.samples, (unsigned long long)sc.samples);
    }
    rl_solution_destroy(c);
    if (a && b) {
        CHECK(ts_differing(a, b, &total) == 0, "%s: culled == naive", what);
        ts_cells floor = ts_cells_get(a, 0);
        double sum = 0;
        for (uint32_t q = 0; q < floor.n; q++)
            sum += floor.e[3 * q];
        ts_cells_free(&floor);
        CHECK(sum > 0, "%s: the beam lights the floor", what);
        rl_pass_stats st;
        rl_solution_pass_stats(a, 0, &st);
        samples = st.samples;
        CHECK(st.solid_angles_culled > st.solid_angles_considered / 2, "%s: the mask culls most solid angles: %llu/%llu",
              what, (unsigned long long)st.solid_angles_culled, (unsigned long long)st.solid_angles_considered);
    }
    rl_solution_destroy(a);
    rl_solution_destroy(b);
    return samples;
}

/* Writes a slab of n (test_slab_new()) whose grey radiance along direction
 * centroid w at position (i, j) is radiance(w, i, j). */
static void write_slab_by(const char *path, uint32_t n, float (*radiance)(const double w[3], uint32_t i, uint32_t j))
{
    lfio_slab *slab = test_slab_new(n);
    uint64_t nd = lfio_slab_dir_count(slab);
    for (uint64_t k = 0; k < nd; k++) {
        double w[3];
        lfio_part_centroid(n, k, w);
        for (uint32_t j = 0; j < 4; j++)
            for (uint32_t i = 0; i < 4; i++) {
                float v = radiance(w, i, j);
                lfio_slab_write(slab, k, i, j, (const float[3]){v, v, v});
            }
    }
    test_slab_write(path, slab);
}

/* A lobe tilted off the slab's normal, varying across its 4 x 4 positions: every interpolation weight shows. */
static float lobe_radiance(const double w[3], uint32_t i, uint32_t j)
{
    double lobe = fmax(0.0, 0.6 * w[0] + 0.8 * w[2]);
    return (float)((1.0 + 0.5 * i - 0.2 * j) * pow(lobe, 8.0));
}

/* Writes a slab of n whose radiance is lobe_radiance(). */
static void write_lobe_lightfield(const char *path, uint32_t n)
{
    write_slab_by(path, n, lobe_radiance);
}

/* Culled's solid angles below the slab's level draw their directions once for
 * all cells, with the slab's interpolation weights: on a slab whose radiance
 * varies with direction and position they must agree with area sampling,
 * which reads the slab at each point's own direction, within both
 * estimators' noise. The scene at path reads the slab from lfpath. */
static void check_shared_directions(const char *path, const char *lfpath)
{
    write_lobe_lightfield(lfpath, 8);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    rl_solution *a = NULL, *b = NULL;
    set_sampling(s, RL_METHOD_CULLED, 32, 4, 16, 0);
    CHECK(rl_relight(s, &ts_job, &a) == RL_OK, "lobe, culled: %s", rl_errmsg());
    set_sampling(s, RL_METHOD_AREA, 32, 4, 16384, 0);
    CHECK(rl_relight(s, &ts_job, &b) == RL_OK, "lobe, area: %s", rl_errmsg());
    if (a && b) {
        ts_cells ca = ts_cells_get(a, 0), cb = ts_cells_get(b, 0);
        double peak = 0, sq = 0, sum_a = 0, sum_b = 0;
        for (uint32_t q = 0; q < ca.n; q++) {
            peak = fmax(peak, cb.e[3 * q]);
            sq += (ca.e[3 * q] - cb.e[3 * q]) * (ca.e[3 * q] - cb.e[3 * q]);
            sum_a += ca.e[3 * q];
            sum_b += cb.e[3 * q];
        }
        double rmse = ca.n ? sqrt(sq / ca.n) / peak : 1.0;
        printf("tilted lobe, culled n = 32 against area sampling: RMSE %.3f%% of the peak, sums %.4g vs %.4g\n",
               100 * rmse, sum_a, sum_b);
        CHECK(peak > 0 && rmse < 0.01, "shared directions: RMSE %.4g of the peak against area sampling", rmse);
        CHECK(fabs(sum_a - sum_b) < 0.005 * sum_b, "shared directions: total %.6g against %.6g", sum_a, sum_b);
        ts_cells_free(&ca);
        ts_cells_free(&cb);
    }
    rl_solution_destroy(a);
    rl_solution_destroy(b);
    rl_scene_destroy(s);
}

/* Lambert's formula at x (normal +z, below z = 1) for the part of the slab square
 * [-0.5, 0.5]^2 at z = 1 (radiance L, facing down) that blocker q (a convex quad
 * between them) leaves visible: the slab minus its part inside q's shadow from x. */
static double blocked_slab_irradiance(const tpoly *q, const double x[3], double L)
{
    const double up[3] = {0, 0, 1};
    tpoly slab = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    double whole = rl_reference_polygon_irradiance(&slab.v[0][0], 4, x, up, L);
    /* the blocker's shadow on the slab's plane, seen from x, counter-clockwise seen from below */
    double sh[16][2], tmp[16][2];
    int n = 0;
    for (int k = 0; k < 4; k++) {
        double t = (1.0 - x[2]) / (q->v[k][2] - x[2]);
        sh[n][0] = x[0] + (q->v[k][0] - x[0]) * t;
        sh[n][1] = x[1] + (q->v[k][1] - x[1]) * t;
        n++;
    }
    double area = 0;
    for (int k = 0; k < n; k++)
        area += sh[k][0] * sh[(k + 1) % n][1] - sh[(k + 1) % n][0] * sh[k][1];
    /* clipped to the slab's square, one side at a time */
    const double lim[4][3] = {{1, 0, 0.5}, {-1, 0, 0.5}, {0, 1, 0.5}, {0, -1, 0.5}}; /* a u + b v <= c */
    for (int e = 0; e < 4 && n > 0; e++) {
        int m = 0;
        for (int k = 0; k < n; k++) {
            const double *a = sh[k], *b = sh[(k + 1) % n];
            double da = lim[e][2] - lim[e][0] * a[0] - lim[e][1] * a[1];
            double db = lim[e][2] - lim[e][0] * b[0] - lim[e][1] * b[1];
            if (da >= 0)
                tmp[m][0] = a[0], tmp[m][1] = a[1], m++;
            if ((da >= 0) != (db >= 0)) {
                double t = da / (da - db);
                tmp[m][0] = a[0] + (b[0] - a[0]) * t, tmp[m][1] = a[1] + (b[1] - a[1]) * t, m++;
            }
        }
        memcpy(sh, tmp, (size_t)m * sizeof sh[0]);
        n = m;
    }
    if (n < 3)
        return whole;
    /* the emitter's orientation: counter-clockwise seen from below, where x is */
    double v[16][3];
    for (int k = 0; k < n; k++) {
        int from = area < 0 ? k : n - 1 - k;
        v[k][0] = sh[from][0], v[k][1] = sh[from][1], v[k][2] = 1.0;
    }
    return whole - rl_reference_polygon_irradiance(&v[0][0], (size_t)n, x, up, L);
}

/* A constant light field over a floor, a tilted quad between them: every
 * solid angle's shared directions meet shadows (relight/src/leaf_shadow.c).
 * Culled and naive must still agree bit for bit, and culled must match
 * Lambert's formula for the part of the slab each point of a cell sees. */
static void check_lightfield_blocker(void)
{
    char lfpath[600], path[600];
    snprintf(lfpath, sizeof lfpath, "%s/blocker_lf.h5", tmpdir);
    write_lightfield(lfpath, 2.0f, 180, 8, 0);
    snprintf(path, sizeof path, "%s/lf_blocker.json", tmpdir);
    tpoly p[2] = {ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1), ts_rect_z("black", -0.3, -0.35, 0.25, 0.2, 0.5, 1)};
    p[1].v[1][2] = p[1].v[2][2] = 0.6; /* tilted: its plane is parallel to neither the floor nor the slab */
    char rest[1024];
    snprintf(rest, sizeof rest,
             "\"radiance_maps\": {\"cell_size\": 0.1}, \"lightfields\": [{\"file\": \"blocker_lf.h5\", \"slab\": "
             "\"light\", \"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]");
    ts_write_scene(path, MATS, p, 2, rest);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    rl_solution *a = NULL, *b = NULL;
    set_sampling(s, RL_METHOD_CULLED, 32, 8, 16, 0);
    CHECK(rl_relight(s, &ts_job, &a) == RL_OK, "blocked light field, culled: %s", rl_errmsg());
    set_sampling(s, RL_METHOD_NAIVE, 32, 8, 16, 0);
    CHECK(rl_relight(s, &ts_job, &b) == RL_OK, "blocked light field, naive: %s", rl_errmsg());
    long total;
    if (a && b)
        CHECK(ts_differing(a, b, &total) == 0, "blocked light field: culled == naive");
    if (a) {
        rl_pass_stats st;
        rl_solution_pass_stats(a, 0, &st);
        CHECK(st.rays_free > st.samples / 4 && st.rays_cast < st.samples / 100,
              "blocked light field: shadows decide (%llu samples, %llu free, %llu traced)",
              (unsigned long long)st.samples, (unsigned long long)st.rays_free, (unsigned long long)st.rays_cast);
        rl_map_info info;
        rl_solution_map_info(a, 0, &info);
        uint32_t n, *ij;
        double *centre;
        float *e = map_irradiance(a, 0, &n, &centre, &ij);
        double peak = 0, se = 0, shade = 0;
        for (uint32_t c = 0; c < n; c++) {
            double ref = 0;
            for (int i = 0; i < 8; i++)
                for (int j = 0; j < 8; j++) {
                    double u = info.u0 + (ij[2 * c] + (i + 0.5) / 8) * info.cell_size;
                    double v = info.v0 + (ij[2 * c + 1] + (j + 0.5) / 8) * info.cell_size, x[3];
                    for (int k = 0; k < 3; k++)
                        x[k] = info.origin[k] + u * info.e1[k] + v * info.e2[k];
                    ref += blocked_slab_irradiance(&p[1], x, 2.0) / 64;
                }
            tpoly slab = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
            double xc[3] = {centre[3 * c], centre[3 * c + 1], 0}, up[3] = {0, 0, 1};
            shade = fmax(shade, rl_reference_polygon_irradiance(&slab.v[0][0], 4, xc, up, 2.0) - ref);
            peak = fmax(peak, ref);
            se += (e[3 * c + 1] - ref) * (e[3 * c + 1] - ref);
        }
        double rmse = n ? sqrt(se / n) / peak : 1;
        printf("constant light field behind a tilted blocker, culled: RMSE %.4f%% of the peak (deepest shade %.3g)\n",
               100 * rmse, shade);
        CHECK(shade > 0.3 * peak, "the blocker shades the floor: %.3g of %.3g", shade, peak);
        CHECK(rmse < 0.015, "blocked light field: RMSE %.4g of the peak against Lambert's formula", rmse);
        free(e);
        free(centre);
        free(ij);
    }
    rl_solution_destroy(a);
    rl_solution_destroy(b);
    rl_scene_destroy(s);
}

/* One relighting of a shared scene on a thread of its own. */
typedef struct job_thread {
    const rl_scene *scene;
    rl_job job;
    rl_solution *sol;
    rl_status st;
} job_thread;

static void *run_job_thread(void *arg)
{
    job_thread *t = arg;
    t->st = rl_relight(t->scene, &t->job, &t->sol);
    return NULL;
}

/* A scene is only read by the engine: two jobs on it at once, of different methods and cell sizes (so
 * different maps, and each run its own light field tables), give bit for bit what each gives alone, and
 * the scene's suggested job is unchanged after them. */
static void check_concurrent_jobs(const rl_scene *s)
{
    job_thread t[2] = {{.scene = s}, {.scene = s}};
    rl_job file;
    rl_job_default(s, &file);
    set_sampling(s, RL_METHOD_CULLED, 16, 2, 16, 2);
    t[0].job = ts_job;
    set_sampling(s, RL_METHOD_AREA, 16, 2, 64, 2);
    t[1].job = ts_job;
    t[1].job.cell_size = file.cell_size / 2;
    rl_solution *alone[2] = {NULL, NULL};
    for (int k = 0; k < 2; k++)
        CHECK(rl_relight(s, &t[k].job, &alone[k]) == RL_OK, "job %d alone: %s", k, rl_errmsg());
    pthread_t th[2];
    int started[2];
    for (int k = 0; k < 2; k++)
        started[k] = pthread_create(&th[k], NULL, run_job_thread, &t[k]) == 0;
    for (int k = 0; k < 2; k++) {
        if (started[k])
            pthread_join(th[k], NULL);
        CHECK(started[k] && t[k].st == RL_OK, "job %d at once: status %d", k, (int)t[k].st);
    }
    long total[2] = {0, 0};
    for (int k = 0; k < 2; k++)
        if (alone[k] && t[k].sol)
            CHECK(ts_differing(alone[k], t[k].sol, &total[k]) == 0 && total[k] > 0,
                  "job %d: the run beside another differs from the run alone", k);
    if (alone[0] && alone[1]) {
        rl_map_info a, b;
        CHECK(rl_solution_map_info(alone[0], 0, &a) == RL_OK && rl_solution_map_info(alone[1], 0, &b) == RL_OK &&
                  a.cell_size == file.cell_size && b.cell_size == file.cell_size / 2 && b.ncells > a.ncells,
              "each job's cell size: %g and %g", a.cell_size, b.cell_size);
    }
    rl_job after;
    rl_job_default(s, &after);
    CHECK(memcmp(&after.sampling, &file.sampling, sizeof file.sampling) == 0 && after.cell_size == file.cell_size,
          "the scene's job unchanged by the runs");
    for (int k = 0; k < 2; k++) {
        rl_solution_destroy(alone[k]);
        rl_solution_destroy(t[k].sol);
    }
}

/* A constant light field is a diffuse emitter; a sparse one is culled by its mask. */
static void check_lightfield(void)
{
    char lfpath[600], path[600];
    snprintf(lfpath, sizeof lfpath, "%s/constant_lf.h5", tmpdir);
    write_lightfield(lfpath, 2.0f, 180, 8, 0);
    snprintf(path, sizeof path, "%s/lf.json", tmpdir);
    /* the slab faces +z at the origin; turned over (180 degrees about x) and lifted to z = 1 */
    tpoly p[1] = {ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1)};
    char rest[1024];
    snprintf(rest, sizeof rest,
             "\"radiance_maps\": {\"cell_size\": 0.25}, \"lightfields\": [{\"file\": \"constant_lf.h5\", \"slab\": "
             "\"light\", \"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]");
    ts_write_scene(path, MATS, p, 1, rest);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    tpoly em = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    const rl_method methods[] = {RL_METHOD_CULLED, RL_METHOD_AREA};
    for (int m = 0; m < 2; m++) {
        set_sampling(s, methods[m], 32, 4, 256, 0);
        rl_solution *sol = NULL;
        CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "light field relight: %s", rl_errmsg());
        if (!sol)
            continue;
        double rmse, mx;
        errors_vs_reference(sol, 0, &em, 2.0, &rmse, &mx);
        printf("constant light field %-10s: RMSE %.4f%%, max %.4f%% of peak\n", rl_method_name(methods[m]),
               100 * rmse, 100 * mx);
        CHECK(rmse < 0.015, "%s: constant light field RMSE %.4g of peak", rl_method_name(methods[m]), rmse);
        rl_solution_destroy(sol);
    }
    rl_scene_destroy(s);
    /* a narrow beam: the mask culls most solid angles, and culled == naive
     * still; then the same beam lit from one strip of the slab per
     * direction, culled against each solid angle's strip */
    uint64_t samples[2] = {0, 0};
    for (int sparse = 0; sparse < 2; sparse++) {
        write_lightfield(lfpath, 5.0f, 12, 16, sparse);
        s = ts_load(path);
        if (!s)
            return;
        samples[sparse] = check_culled_naive(s, sparse ? "sparse light field" : "masked light field");
        if (sparse)
            check_concurrent_jobs(s);
        rl_scene_destroy(s);
    }
    check_shared_directions(path, lfpath);
    check_lightfield_blocker();
    printf("light field samples, culled: %llu dense, %llu one strip per direction\n",
           (unsigned long long)samples[0], (unsigned long long)samples[1]);
    /* without the support both would draw exactly as many samples */
    CHECK(samples[1] < 0.9 * samples[0], "the support culls the sparse field's cells: %llu vs %llu samples",
          (unsigned long long)samples[1], (unsigned long long)samples[0]);
}

/* Lit in a 40 degree cone about the slab's normal from the two columns of
 * positions on its -x half only: a receiver's lit part of it is that half at most. */
static float half_radiance(const double w[3], uint32_t i, uint32_t j)
{
    (void)j;
    return i < 2 && w[2] > cos(40 * 3.14159265358979 / 180) ? 5.0f : 0.0f;
}

/* @return RMSE of map 0 of a against b's, over the mean of b's (green). */
static double cells_rmse(const rl_solution *a, const rl_solution *b, double *sum_a, double *sum_b)
{
    ts_cells ca = ts_cells_get(a, 0), cb = ts_cells_get(b, 0);
    double sq = 0;
    *sum_a = *sum_b = 0;
    for (uint32_t q = 0; q < ca.n && q < cb.n; q++) {
        double d = ca.e[3 * q + 1] - cb.e[3 * q + 1];
        sq += d * d;
        *sum_a += ca.e[3 * q + 1];
        *sum_b += cb.e[3 * q + 1];
    }
    double r = ca.n == cb.n && ca.n > 0 && *sum_b > 0 ? sqrt(sq / cb.n) / (*sum_b / cb.n) : 1.0;
    ts_cells_free(&ca);
    ts_cells_free(&cb);
    return r;
}

/* Relights s with anchor_stride stride, k rays and threads threads (0: all).
 * @return the solution (NULL on failure), its samples in *samples. */
static rl_solution *relight_anchored(rl_scene *s, uint32_t stride, uint32_t k, unsigned threads, uint64_t *samples)
{
    set_sampling(s, RL_METHOD_CULLED, 8, k, 16, threads);
    ts_job.sampling.anchor_stride = stride;
    CHECK(rl_job_check(&ts_job) == RL_OK, "anchor_stride %u: %s", stride, rl_errmsg());
    rl_solution *sol = NULL;
    CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "anchors %u, k %u: %s", stride, k, rl_errmsg());
    rl_pass_stats st = {0};
    if (sol)
        rl_solution_pass_stats(sol, 0, &st);
    *samples = st.samples;
    return sol;
}

/* The tilted lobe (written to lfpath) over a floor that a tilted blocker
 * shades: cells a shadow may cross take the anchors' unoccluded light times
 * the visible share of their samples' radiance, their rays in two stages
 * (lambert.c). Against every cell sampled at 16x the rays, that must beat
 * every cell sampled on its own at the same k, keep the total, and trace
 * fewer rays (most such cells are wholly lit or wholly shaded). */
static void check_anchored_shadow(const char *lfpath)
{
    char path[600];
    snprintf(path, sizeof path, "%s/anchors_shadow.json", tmpdir);
    tpoly p[2] = {ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1), ts_rect_z("black", -0.3, -0.35, 0.25, 0.2, 0.1, 1)};
    p[1].v[1][2] = p[1].v[2][2] = 0.15; /* tilted, low: an umbra, a penumbra and light all round */
    char rest[512];
    snprintf(rest, sizeof rest,
             "\"radiance_maps\": {\"cell_size\": 0.03125}, \"lightfields\": [{\"file\": \"%s\", \"slab\": "
             "\"light\", \"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]",
             strrchr(lfpath, '/') + 1);
    ts_write_scene(path, MATS, p, 2, rest);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    uint64_t n_ref, n_a, n_c;
    rl_solution *ref = relight_anchored(s, 1, 64, 0, &n_ref), *a = relight_anchored(s, 0, 4, 0, &n_a),
                *c = relight_anchored(s, 1, 4, 0, &n_c);
    if (ref && a && c) {
        rl_pass_stats sta = {0}, stc = {0};
        rl_solution_pass_stats(a, 0, &sta);
        rl_solution_pass_stats(c, 0, &stc);
        double sa, sc, sr;
        double ra = cells_rmse(a, ref, &sa, &sr), rc = cells_rmse(c, ref, &sc, &sr);
        printf("tilted lobe over a shaded floor: anchors RMSE %.3f%% (%llu rays), every cell %.3f%% (%llu rays); "
               "sums %.5g, %.5g, %.5g\n",
               100 * ra, (unsigned long long)sta.rays_cast, 100 * rc, (unsigned long long)stc.rays_cast, sa, sc, sr);
        CHECK(ra <= rc, "anchors in shadow: RMSE %.4g against %.4g sampling every cell", ra, rc);
        CHECK(fabs(sa - sr) < 0.003 * sr, "anchors in shadow: total %.6g against %.6g", sa, sr);
        CHECK(sta.rays_cast < 0.8 * stc.rays_cast, "anchors in shadow: %llu rays against %llu",
              (unsigned long long)sta.rays_cast, (unsigned long long)stc.rays_cast);
    }
    rl_solution_destroy(ref);
    rl_solution_destroy(a);
    rl_solution_destroy(c);
    rl_scene_destroy(s);
}

/* What rl_run_options.maps_ready told: the maps, in order, whose values it copied when told. */
typedef struct told_maps {
    const rl_solution *solution;
    size_t calls, ready, backwards;
    float *e[16]; /* map k's irradiance when told */
} told_maps;

static void on_maps_ready(void *user, const rl_solution *solution, size_t ready)
{
    told_maps *t = user;
    t->backwards += ready < t->ready;
    t->solution = solution;
    t->calls++;
    for (size_t k = t->ready; k < ready && k < 16; k++) {
        ts_cells c = ts_cells_get(solution, k);
        t->e[k] = c.e; /* kept: freed by the caller */
        c.e = NULL;
        ts_cells_free(&c);
    }
    t->ready = ready > t->ready ? ready : t->ready;
}

/* rl_solution_map_rows(): a slice of map 0 is the same slice of rl_solution_map_cells()'s copy, every
 * output; a range past the map's cells is refused. */
static void check_map_rows(const rl_solution *sol)
{
    rl_map_info m;
    if (rl_solution_map_info(sol, 0, &m) != RL_OK) {
        CHECK(0, "map_rows: %s", rl_errmsg());
        return;
    }
    if (m.ncells < 40) {
        CHECK(0, "map_rows: map 0 has %u cells", m.ncells);
        return;
    }
    const uint32_t n = m.ncells, first = 17, count = 21;
    uint32_t *ij = malloc(2 * n * sizeof *ij), rij[2 * 21];
    double *area = malloc(n * sizeof *area), *centre = malloc(3 * n * sizeof *centre), rarea[21], rcentre[3 * 21];
    float *e = malloc(3 * n * sizeof *e), *b = malloc(3 * n * sizeof *b), re[3 * 21], rb[3 * 21];
    if (!ij || !area || !centre || !e || !b) {
        CHECK(0, "map_rows: out of memory");
        free(ij), free(area), free(centre), free(e), free(b);
        return;
    }
    CHECK(rl_solution_map_cells(sol, 0, ij, area, centre, e, b) == RL_OK, "map_rows: %s", rl_errmsg());
    CHECK(rl_solution_map_rows(sol, 0, first, count, rij, rarea, rcentre, re, rb) == RL_OK, "map_rows: %s",
          rl_errmsg());
    CHECK(memcmp(rij, ij + 2 * first, sizeof rij) == 0 && memcmp(rarea, area + first, sizeof rarea) == 0 &&
              memcmp(rcentre, centre + 3 * first, sizeof rcentre) == 0 && memcmp(re, e + 3 * first, sizeof re) == 0 &&
              memcmp(rb, b + 3 * first, sizeof rb) == 0,
          "map_rows: cells %u to %u differ from map_cells' copy", first, first + count);
    CHECK(rl_solution_map_rows(sol, 0, n - 1, 2, rij, NULL, NULL, NULL, NULL) == RL_ERR_ARG &&
              rl_solution_map_rows(sol, 0, UINT32_MAX, 2, rij, NULL, NULL, NULL, NULL) == RL_ERR_ARG &&
              rl_solution_map_rows(sol, 0, n, 0, NULL, NULL, NULL, NULL, NULL) == RL_OK,
          "map_rows: a range past the map's %u cells", n);
    free(ij);
    free(area);
    free(centre);
    free(e);
    free(b);
}

/* maps_ready: ten floor strips under a lamp, a wall beside the last facing them, and a small panel 1 cm over
 * the sixth, facing down. A direct run tells the maps as they are finished, more than once, in order, each
 * with its final values; so do runs of one and two bounces in their last pass, whose last gather is of the
 * cells near the panel with one bounce (which marks them), with two of the larger cells and those near the
 * panel together, map by map. */
static void check_maps_ready(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/maps_ready.json", tmpdir);
    tpoly p[13];
    for (int k = 0; k < 10; k++)
        p[k] = ts_rect_z("grey", -1 + 0.2 * k, -1, -0.8 + 0.2 * k, 1, 0.0, 1);
    p[10] = (tpoly){"grey", 4, {{1, 1, 0}, {1, -1, 0}, {1, -1, 0.5}, {1, 1, 0.5}}}; /* at x = 1, facing -x */
    p[11] = ts_rect_z("grey", 0.02, -0.1, 0.18, 0.1, 0.01, 0);
    p[12] = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    ts_write_scene(path, MATS, p, 13, "\"radiance_maps\": {\"cell_size\": 0.01}");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    for (int trial = 0; trial < 5; trial++) {
        /* 0, 1 and 2 bounces on one thread, whose tiles finish in order, so that each map is told on its own;
         * then 1 and 2 on four threads, where maps are completed side by side (the first tile may finish last,
         * and all be told at once) */
        uint32_t bounces = trial < 3 ? (uint32_t)trial : (uint32_t)trial - 2, threads = trial < 3 ? 1 : 4;
        set_sampling(s, RL_METHOD_CULLED, 8, 2, 16, threads);
        ts_job.sampling.bounces = bounces;
        CHECK(rl_job_check(&ts_job) == RL_OK, "maps_ready: %s", rl_errmsg());
        told_maps t;
        memset(&t, 0, sizeof t);
        ts_job.run.maps_ready = on_maps_ready;
        ts_job.run.maps_ready_user = &t;
        rl_solution *sol = NULL;
        CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "maps_ready: %s", rl_errmsg());
        ts_job.run.maps_ready = NULL;
        if (sol && bounces == 0)
            check_map_rows(sol);
        size_t n = sol ? rl_solution_map_count(sol) : 0, same = 0;
        for (size_t k = 0; k < n && k < 16; k++) {
            ts_cells c = ts_cells_get(sol, k);
            same += t.e[k] != NULL && memcmp(t.e[k], c.e, 3 * c.n * sizeof *c.e) == 0;
            ts_cells_free(&c);
        }
        printf("maps_ready, %u bounce%s, %u thread%s: told %zu times, %zu of %zu maps, %zu with their final values\n",
               bounces, bounces == 1 ? "" : "s", threads, threads == 1 ? "" : "s", t.calls, t.ready, n, same);
        CHECK(sol && n == 12 && t.solution == sol && t.ready == n && t.backwards == 0 && same == n,
              "maps_ready, %u bounces: told %zu of %zu maps, %zu final, %zu backwards", bounces, t.ready, n, same,
              t.backwards);
        CHECK(threads > 1 || t.calls >= 2, "maps_ready, %u bounces: told %zu times", bounces, t.calls);
        for (size_t k = 0; k < 16; k++)
            free(t.e[k]);
        rl_solution_destroy(sol);
    }
    rl_scene_destroy(s);
}

/* A light field's cells that see all of it take their light bilinearly
 * between anchors (lambert.c), here 2 cells apart (1 m under the slab of
 * partition 4, cells of 1/32 m). A constant slab is Lambertian, so each
 * anchor is exact to float radiance and the cells must follow Lambert's
 * means to within interpolation (0.15% of the peak; a cell placed half a
 * cell off is out by 1.4%); a lobe
 * that varies with direction and over the slab must be estimated as well as
 * by sampling every cell, against a finer run, with fewer samples. */
static void check_lightfield_anchors(void)
{
    char lfpath[600], path[600];
    snprintf(lfpath, sizeof lfpath, "%s/anchor_lf.h5", tmpdir);
    snprintf(path, sizeof path, "%s/anchors.json", tmpdir);
    tpoly p[1] = {ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1)};
    ts_write_scene(path, MATS, p, 1,
                   "\"radiance_maps\": {\"cell_size\": 0.03125}, \"lightfields\": [{\"file\": \"anchor_lf.h5\", "
                   "\"slab\": \"light\", \"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]");
    write_lightfield(lfpath, 2.0f, 180, 4, 0);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    uint64_t n_anchored = 0, n_cells = 0;
    rl_solution *a = relight_anchored(s, 0, 4, 0, &n_anchored), *c = relight_anchored(s, 1, 4, 0, &n_cells);
    tpoly em = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    if (a && c) {
        double rmse[2], mx[2];
        errors_vs_reference(a, 0, &em, 2.0, &rmse[0], &mx[0]);
        errors_vs_reference(c, 0, &em, 2.0, &rmse[1], &mx[1]);
        printf("constant light field, anchors 2 cells apart: RMSE %.4f%%, max %.4f%% of peak, %llu samples; "
               "every cell: %.4f%%, %.4f%%, %llu samples\n",
               100 * rmse[0], 100 * mx[0], (unsigned long long)n_anchored, 100 * rmse[1], 100 * mx[1],
               (unsigned long long)n_cells);
        CHECK(mx[0] < 0.003, "anchors: constant light field off Lambert by %.4g of the peak", mx[0]);
        CHECK(n_anchored < n_cells / 3, "anchors: %llu samples against %llu per cell", (unsigned long long)n_anchored,
              (unsigned long long)n_cells);
    }
    rl_solution_destroy(a);
    rl_solution_destroy(c);
    rl_scene_destroy(s);

    /* a lobe varying with direction and over the slab; a cone lit from half the slab, of which each anchor
     * samples (and takes Lambert's formula over) only the part that can light it */
    for (int field = 0; field < 2; field++) {
        const char *what = field ? "half a slab" : "tilted lobe";
        if (field)
            write_slab_by(lfpath, 4, half_radiance);
        else
            write_lobe_lightfield(lfpath, 4);
        if (!(s = ts_load(path)))
            return;
        rl_solution *ref = relight_anchored(s, 1, 64, 0, &n_cells);
        a = relight_anchored(s, 0, 4, 0, &n_anchored);
        c = relight_anchored(s, 1, 4, 0, &n_cells);
        if (ref && a && c) {
            double sa, sc, sr;
            double ra = cells_rmse(a, ref, &sa, &sr), rc = cells_rmse(c, ref, &sc, &sr);
            printf("%s against every cell at 16x the rays: anchors RMSE %.3f%% of the mean (%llu samples), "
                   "every cell %.3f%% (%llu); sums %.5g, %.5g, %.5g\n",
                   what, 100 * ra, (unsigned long long)n_anchored, 100 * rc, (unsigned long long)n_cells, sa, sc, sr);
            CHECK(ra <= rc, "anchors, %s: RMSE %.4g against %.4g sampling every cell", what, ra, rc);
            CHECK(fabs(sa - sr) < 0.002 * sr, "anchors, %s: total %.6g against %.6g", what, sa, sr);
        }
        rl_solution_destroy(ref);
        rl_solution_destroy(a);
        rl_solution_destroy(c);
        rl_scene_destroy(s);
    }

    /* the lobe on a receiver whose edges cut cells, anchors 3 cells apart: its two tiles (of 128 and 64
     * rows: 8192 cells a tile) meet between anchor rows, and the last column's cells reach past the last
     * full stride */
    snprintf(path, sizeof path, "%s/anchors_cut.json", tmpdir);
    tpoly cut[1] = {ts_rect_z("grey", -0.97, -0.99, 1.01, 4.985, 0.0, 1)};
    ts_write_scene(path, MATS, cut, 1,
                   "\"radiance_maps\": {\"cell_size\": 0.03125}, \"lightfields\": [{\"file\": \"anchor_lf.h5\", "
                   "\"slab\": \"light\", \"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]");
    write_lobe_lightfield(lfpath, 4);
    if (!(s = ts_load(path)))
        return;
    rl_solution *ref = relight_anchored(s, 1, 64, 0, &n_cells);
    a = relight_anchored(s, 3, 4, 0, &n_anchored);
    rl_solution *one = relight_anchored(s, 3, 4, 1, &n_anchored);
    c = relight_anchored(s, 1, 4, 0, &n_cells);
    if (ref && a && one && c) {
        double sa, sc, sr;
        double ra = cells_rmse(a, ref, &sa, &sr), rc = cells_rmse(c, ref, &sc, &sr);
        long total;
        printf("tilted lobe, cut receiver: anchors 3 apart RMSE %.3f%% (%llu samples), every cell %.3f%% (%llu); "
               "sums %.5g, %.5g, %.5g\n",
               100 * ra, (unsigned long long)n_anchored, 100 * rc, (unsigned long long)n_cells, sa, sc, sr);
        CHECK(ra <= rc, "anchors, cut receiver: RMSE %.4g against %.4g sampling every cell", ra, rc);
        /* 3 is wider than the 2 the distance would choose here: the blend's bend shows in the total (0.26%) */
        CHECK(fabs(sa - sr) < 0.005 * sr, "anchors, cut receiver: total %.6g against %.6g", sa, sr);
        CHECK(ts_differing(a, one, &total) == 0, "anchors: 1 and 2 threads differ");
    }
    rl_solution_destroy(ref);
    rl_solution_destroy(a);
    rl_solution_destroy(one);
    rl_solution_destroy(c);
    rl_scene_destroy(s);
    check_anchored_shadow(lfpath);
}

/* A constant light field slab seen edge-on: the point lies just below the
 * slab's plane, facing across it, so every direction that reaches it from the
 * slab grazes the slab. A constant slab is a Lambertian emitter, so Lambert's
 * formula is the answer. */
static void check_slab_edge_on(void)
{
    char lfpath[600], path[600];
    snprintf(lfpath, sizeof lfpath, "%s/edge_lf.h5", tmpdir);
    write_lightfield(lfpath, 2.0f, 180, 16, 0);
    snprintf(path, sizeof path, "%s/edge_on.json", tmpdir);
    ts_write_scene(path, MATS, NULL, 0,
                "\"lightfields\": [{\"file\": \"edge_lf.h5\", \"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    tpoly em = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    const double pts[3][6] = {{1.0, 0.0, 0.999, -1, 0, 0}, {0.5001, 0.2, 0.9999, -1, 0, 0.01}, {3.0, 0.0, 0.99, -1, 0, 0}};
    const rl_method methods[] = {RL_METHOD_CULLED, RL_METHOD_SOLIDANGLE};
    for (int m = 0; m < 2; m++)
        for (int q = 0; q < 3; q++) {
            set_sampling(s, methods[m], 32, 16, 4096, 0);
            double out[3] = {NAN, NAN, NAN}, nrm[3] = {pts[q][3], pts[q][4], pts[q][5]};
            double l = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
            for (int c = 0; c < 3; c++)
                nrm[c] /= l;
            CHECK(rl_irradiance(s, &ts_job, pts[q], 1, out, NULL) == RL_OK, "edge-on: %s", rl_errmsg());
            double ref = rl_reference_polygon_irradiance(&em.v[0][0], 4, pts[q], nrm, 2.0);
            printf("extreme slab_edge_on[%d]          %-10s: %.6g vs %.6g (rel %.2g)\n", q, rl_method_name(methods[m]),
                   out[0], ref, fabs(out[0] - ref) / ref);
            CHECK(isfinite(out[0]) && fabs(out[0] - ref) <= 0.05 * ref, "slab edge-on %d %s: %.6g vs %.6g", q,
                  rl_method_name(methods[m]), out[0], ref);
        }
    rl_scene_destroy(s);
}

/* The extremes as point queries, every method at its defaults. */
#define EXTREME_POINTS 64
#define NMETHODS 5
static const rl_method all_methods[NMETHODS] = {RL_METHOD_CULLED, RL_METHOD_NAIVE, RL_METHOD_ADAPTIVE,
                                                RL_METHOD_AREA, RL_METHOD_SOLIDANGLE};

/* A deterministic uniform number in [0, 1) (an LCG: the cases must not depend on libc's rand). */
static double uniform01(unsigned long long *state)
{
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*state >> 11) / 9007199254740992.0;
}

static void normalize3(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int c = 0; c < 3; c++)
        v[c] /= l;
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* The normal at x that is perpendicular to the direction u to c, in the vertical
 * plane holding u, then tilted by angle a toward c: c sits on x's horizon for a = 0. */
static void grazing_normal(const double x[3], const double c[3], double a, double out[3])
{
    double u[3] = {c[0] - x[0], c[1] - x[1], c[2] - x[2]}, up[3] = {0, 0, 1}, side[3], m[3];
    normalize3(u);
    cross3(u, up, side);
    cross3(side, u, m);
    normalize3(m);
    for (int k = 0; k < 3; k++)
        out[k] = cos(a) * m[k] + sin(a) * u[k];
}

/*
 * Irradiance at EXTREME_POINTS points (x, y, z, normal) from one emitter of
 * radiance 2 and nothing else, every method at the defaults (n = 32, k = 4,
 * 128 samples): RMSE over the points relative to the largest Lambert value
 * must be within tol[m] (culled, naive, adaptive, area, solidangle); a
 * negative bound asserts only finite, non-negative values (a baseline that
 * cannot see the case by construction, printed so that it is on record).
 */
static void extreme_points(const char *name, const tpoly *em, const double (*pts)[6], const double tol[NMETHODS])
{
    char path[600];
    snprintf(path, sizeof path, "%s/extreme_%s.json", tmpdir, name);
    ts_write_scene(path, MATS, em, 1, "\"radiance_maps\": {\"cell_size\": 1}");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    double ref[EXTREME_POINTS], peak = 0;
    for (int i = 0; i < EXTREME_POINTS; i++) {
        double nrm[3] = {pts[i][3], pts[i][4], pts[i][5]};
        normalize3(nrm);
        ref[i] = rl_reference_polygon_irradiance(&em->v[0][0], (size_t)em->n, pts[i], nrm, 2.0);
        peak = fmax(peak, ref[i]);
    }
    for (int m = 0; m < NMETHODS; m++) {
        set_sampling(s, all_methods[m], 32, 4, 128, 2);
        double out[3 * EXTREME_POINTS];
        for (int i = 0; i < 3 * EXTREME_POINTS; i++)
            out[i] = NAN;
        CHECK(rl_irradiance(s, &ts_job, &pts[0][0], EXTREME_POINTS, out, NULL) == RL_OK, "%s: %s", name,
              rl_errmsg());
        double se = 0, worst = 0;
        int bad = 0;
        for (int i = 0; i < EXTREME_POINTS; i++) {
            for (int c = 0; c < 3; c++)
                bad += !(isfinite(out[3 * i + c]) && out[3 * i + c] >= 0);
            double d = out[3 * i + 1] - ref[i];
            se += d * d;
            worst = fmax(worst, fabs(d));
        }
        double rel = sqrt(se / EXTREME_POINTS) / peak;
        printf("extreme points %-19s %-10s: RMSE %.3g%%, max %.3g%% of peak %.4g%s\n", name,
               rl_method_name(all_methods[m]), 100 * rel, 100 * worst / peak, peak,
               tol[m] < 0 ? " (not bounded)" : "");
        CHECK(bad == 0, "%s %s: %d values not finite or negative", name, rl_method_name(all_methods[m]), bad);
        CHECK(tol[m] < 0 || rel <= tol[m], "%s %s: RMSE %.3g of peak above %.3g", name,
              rl_method_name(all_methods[m]), rel, tol[m]);
    }
    rl_scene_destroy(s);
}

/*
 * The cases of issue #13's table as point queries, spread as bench/points.sh
 * spreads them, around a 1 m square 1 m up facing down (centre (0, 0, 1)).
 * The default method is held to the product's targets: 1% on the ordinary
 * case, 2% on every extreme. Area sampling is not bounded next to an edge
 * (its estimator's variance is infinite there: 1/r^2 with r -> 0) nor under a
 * 1e4 m emitter (almost every uniform sample lands where it carries nothing).
 */
static void check_extremes(void)
{
    static double pts[EXTREME_POINTS][6];
    unsigned long long rng = 7;
    const double centre[3] = {0, 0, 1};
    const double ordinary[NMETHODS] = {0.01, 0.01, 0.01, 0.02, 0.01};
    const double extreme[NMETHODS] = {0.02, 0.02, 0.02, 0.02, 0.02};
    const double area_blind[NMETHODS] = {0.02, 0.02, 0.02, -1, 0.02};
    tpoly unit = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);

    for (int i = 0; i < EXTREME_POINTS; i++) { /* on the floor under and around it */
        double p[6] = {-1.5 + 3 * uniform01(&rng), -1.5 + 3 * uniform01(&rng), 0, 0, 0, 1};
        memcpy(pts[i], p, sizeof p);
    }
    extreme_points("floor", &unit, pts, ordinary);
    tpoly far = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1000.0, 0);
    extreme_points("emitter_1km_away", &far, pts, extreme);
    tpoly tiny = ts_rect_z("light", -5e-6, -5e-6, 5e-6, 5e-6, 1.0, 0);
    extreme_points("tiny_emitter_1e-5m", &tiny, pts, extreme);
    tpoly huge = ts_rect_z("light", -5e3, -5e3, 5e3, 5e3, 1.0, 0);
    extreme_points("huge_emitter_1e4m", &huge, pts, area_blind);
    /* 1 m by 1.01e-6 m: the loader refuses aspect 1e-6 as degenerate (docs/scene.md) */
    tpoly sliver = ts_rect_z("light", -0.5, -0.505e-6, 0.5, 0.505e-6, 1.0, 0);
    extreme_points("sliver_emitter", &sliver, pts, extreme);

    for (int i = 0; i < EXTREME_POINTS; i++) { /* 3 m away, 0.5 m under its plane, horizons through it */
        double p[6] = {3, -0.5 + uniform01(&rng), 0.5, 0, 0, 0};
        grazing_normal(p, centre, pow(10, -6 + 5 * uniform01(&rng)), p + 3);
        memcpy(pts[i], p, sizeof p);
    }
    extreme_points("grazing_1e-6_to_0.1", &unit, pts, extreme);

    for (int i = 0; i < EXTREME_POINTS; i++) { /* 1e-6 m under its plane, 0.5 .. 1.4 m off, facing it */
        double p[6] = {1 + 0.9 * uniform01(&rng), -0.5 + uniform01(&rng), 1 - 1e-6, -1, 0, 0};
        memcpy(pts[i], p, sizeof p);
    }
    extreme_points("edge_on", &unit, pts, extreme);

    /* a vertical square standing on the floor (facing +x), points 1e-4 .. 1 m from its lower edge */
    tpoly wall = {"light", 4, {{0, -0.5, 0}, {0, 0.5, 0}, {0, 0.5, 1}, {0, -0.5, 1}}};
    for (int i = 0; i < EXTREME_POINTS; i++) {
        double p[6] = {pow(10, -4 + 4 * uniform01(&rng)), -0.5 + uniform01(&rng), 0, 0, 0, 1};
        memcpy(pts[i], p, sizeof p);
    }
    extreme_points("near_an_edge", &wall, pts, area_blind);
}

/*
 * The extremes as radiance maps: one emitter of radiance 2 and one
 * receiving polygon of 0.25 m cells, every method at the default settings
 * (n = 32, k = 4, 128 samples, descent on), RMSE of the peak against
 * Lambert's mean over each cell. tol[m]: the bound asserted for method m
 * (culled, naive, adaptive, area, solidangle); a negative bound asserts
 * only finite, non-negative values (a baseline that cannot see the case,
 * printed so that its failure is on record).
 */
/* lf: NULL, or the scene's "lightfields" entry standing for em (a constant
 * slab of radiance 2, which Lambert's formula describes as well). */
static void extreme_map(const char *name, const tpoly *em, const tpoly *rcv, const double tol[5], const char *lf)
{
    char path[600], rest[600];
    snprintf(path, sizeof path, "%s/extreme_map_%s.json", tmpdir, name);
    tpoly p[2] = {*em, *rcv};
    snprintf(rest, sizeof rest, "\"radiance_maps\": {\"cell_size\": 0.25}%s%s", lf ? ", " : "", lf ? lf : "");
    ts_write_scene(path, MATS, lf ? rcv : p, lf ? 1 : 2, rest);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    ts_emitter ref = {em, 2.0};
    const rl_method methods[5] = {RL_METHOD_CULLED, RL_METHOD_NAIVE, RL_METHOD_ADAPTIVE, RL_METHOD_AREA,
                                  RL_METHOD_SOLIDANGLE};
    for (int m = 0; m < 5; m++) {
        set_sampling(s, methods[m], 32, 4, 128, 0);
        rl_solution *sol = NULL;
        CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "%s: %s", name, rl_errmsg());
        if (!sol)
            continue;
        long total;
        CHECK(ts_bad_values(sol, &total) == 0, "%s %s: values not finite or negative", name,
              rl_method_name(methods[m]));
        ts_errors e = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, lf ? 0 : 1), &ref, 1, 24);
        double rel = e.peak > 0 ? e.rmse / e.peak : e.rmse;
        printf("extreme map %-20s %-10s: RMSE %.3g%%, max %.3g%% of peak %.4g (%u cells)%s\n", name,
               rl_method_name(methods[m]), 100 * rel, 100 * (e.peak > 0 ? e.max / e.peak : e.max), e.peak, e.cells,
               tol[m] < 0 ? " (not bounded)" : "");
        CHECK(tol[m] < 0 || rel <= tol[m], "%s %s: RMSE %.3g of peak above %.3g", name, rl_method_name(methods[m]),
              rel, tol[m]);
        rl_solution_destroy(sol);
    }
    rl_scene_destroy(s);
}

static void check_map_extremes(void)
{
    tpoly floor = ts_rect_z("grey", -0.5, -0.5, 0.5, 0.5, 0.0, 1);
    /* culled, naive, adaptive, area, solidangle */
    const double ordinary[5] = {0.01, 0.01, 0.01, 0.03, 0.01}, small[5] = {0.02, 0.02, 0.04, 0.02, 0.02};
    tpoly unit = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    extreme_map("unit_over_floor", &unit, &floor, ordinary, NULL);
    tpoly tiny = ts_rect_z("light", -5e-6, -5e-6, 5e-6, 5e-6, 1.0, 0);
    extreme_map("tiny_emitter_1e-5m", &tiny, &floor, small, NULL);
    tpoly huge = ts_rect_z("light", -5e3, -5e3, 5e3, 5e3, 1.0, 0);
    const double huge_tol[5] = {0.02, 0.02, 0.02, -1, 0.03};
    extreme_map("huge_emitter_1e4m", &huge, &floor, huge_tol, NULL);
    tpoly far = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1000.0, 0);
    extreme_map("emitter_1km_away", &far, &floor, small, NULL);
    /* a vertical receiver at x = 3 facing the emitter, its top 1 mm under the
     * emitter's plane: the emitter is seen from 1 mm to 0.5 m off edge-on */
    tpoly edge_on = {"grey", 4, {{3, 0.5, 0.499}, {3, -0.5, 0.499}, {3, -0.5, 0.999}, {3, 0.5, 0.999}}};
    extreme_map("edge_on_from_3m", &unit, &edge_on, small, NULL);
    /* a floor touching a vertical emitter's lower edge: cells from 0 to 1 m away */
    tpoly wall = {"light", 4, {{0, -0.5, 0}, {0, 0.5, 0}, {0, 0.5, 1}, {0, -0.5, 1}}};
    tpoly beside = ts_rect_z("grey", 0, -0.5, 1, 0.5, 0.0, 1);
    const double touch_tol[5] = {0.02, 0.02, 0.02, -1, 0.02};
    extreme_map("touching_edge", &wall, &beside, touch_tol, NULL);
    /* a 1 m by 1.01e-6 m sliver over the floor: thinner than any leaf */
    tpoly sliver = ts_rect_z("light", -0.5, -0.505e-6, 0.5, 0.505e-6, 1.0, 0);
    extreme_map("sliver_emitter", &sliver, &floor, small, NULL);
    /* a 0.5 m square 3 m away, 0.5 m under the emitter's plane, whose plane holds the direction
     * to the emitter's centre tilted 1e-3 rad toward it: the emitter straddles its horizon */
    {
        const double c[3] = {3, 0, 0.5}, centre[3] = {0, 0, 1}, up[3] = {0, 0, 1};
        double nrm[3], side[3], t[3];
        grazing_normal(c, centre, 1e-3, nrm);
        cross3(up, nrm, side); /* side, t, nrm right-handed: corners counter-clockwise about nrm */
        normalize3(side);
        cross3(nrm, side, t);
        const double uv[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        tpoly grazing = {"grey", 4, {{0}}};
        for (int k = 0; k < 4; k++)
            for (int a = 0; a < 3; a++)
                grazing.v[k][a] = c[a] + 0.25 * (uv[k][0] * side[a] + uv[k][1] * t[a]);
        extreme_map("grazing_receiver", &unit, &grazing, small, NULL);
    }
    /* the same as light fields: a constant slab over the floor, seen edge-on
     * from 3 m, and 1 km away (a pair that descends: Lambert's formula times
     * the weighted mean of radiance and visibility) */
    {
        char lfpath[600];
        snprintf(lfpath, sizeof lfpath, "%s/extreme_lf.h5", tmpdir);
        write_lightfield(lfpath, 2.0f, 180, 16, 0);
        const char *slab_at_1m = "\"lightfields\": [{\"file\": \"extreme_lf.h5\", "
                                 "\"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]";
        const char *slab_at_1km = "\"lightfields\": [{\"file\": \"extreme_lf.h5\", "
                                  "\"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1000],[0,0,0,1]]}]";
        /* Seen edge-on the slab subtends a few solid angles at most, so culled
         * and naive take Lambert's formula (0.2% measured); adaptive keeps its
         * leaves, blind inside a solid angle for light fields (4.7% measured),
         * bounded so that it gets no worse (docs/accuracy.md). */
        const double lf_ordinary[5] = {0.01, 0.01, 0.01, 0.03, 0.01}, lf_edge[5] = {0.02, 0.02, 0.1, 0.03, 0.02},
                     lf_far[5] = {0.02, 0.02, 0.02, 0.03, 0.02};
        extreme_map("lf_over_floor", &unit, &floor, lf_ordinary, slab_at_1m);
        extreme_map("lf_edge_on_from_3m", &unit, &edge_on, lf_edge, slab_at_1m);
        extreme_map("lf_1km_away", &far, &floor, lf_far, slab_at_1km);
    }
}

/*
 * Shading of solved maps (rl_solution_trace, which renders use): flat gives
 * each cell's own irradiance; smooth (the default) interpolates between cell
 * centres, so at a cell's centre it is that cell's value, halfway between
 * two neighbours it is their mean, and it never leaves the range of the
 * cells around the point.
 */
static void check_shading(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/shading.json", tmpdir);
    tpoly p[2] = {ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0), ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1)};
    ts_write_scene(path, MATS, p, 2, "\"radiance_maps\": {\"cell_size\": 0.25}");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    set_sampling(s, RL_METHOD_CULLED, 16, 4, 64, 0);
    rl_solution *sol = NULL;
    CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "shading: %s", rl_errmsg());
    if (sol) {
        ts_cells c = ts_cells_get(sol, (size_t)ts_map_of(sol, 1));
        double *centre = malloc(3 * sizeof(double) * (c.n + 1));
        rl_solution_map_cells(sol, (size_t)ts_map_of(sol, 1), NULL, NULL, centre, NULL, NULL);
        const double down[3] = {0, 0, -1};
        double albedo = 0.5 / 3.14159265358979323846; /* grey: radiance = 0.5 E / pi */
        long centres = 0, halves = 0, flat = 0, bounded = 0;
        for (uint32_t k = 0; k < c.n; k++) {
            double org[3] = {centre[3 * k], centre[3 * k + 1], 0.5};
            float rgb[3];
            rl_solution_set_smooth(sol, 0);
            rl_solution_trace(sol, org, down, rgb);
            flat += fabs(rgb[1] - albedo * c.e[3 * k + 1]) <= 1e-6 * (1 + rgb[1]);
            rl_solution_set_smooth(sol, 1);
            rl_solution_trace(sol, org, down, rgb);
            centres += fabs(rgb[1] - albedo * c.e[3 * k + 1]) <= 1e-5 * (1 + rgb[1]);
            /* halfway to the neighbour in +x, when it exists */
            for (uint32_t m = 0; m < c.n; m++) {
                if (c.ij[2 * m] != c.ij[2 * k] + 1 || c.ij[2 * m + 1] != c.ij[2 * k + 1])
                    continue;
                double mid[3] = {0.5 * (centre[3 * k] + centre[3 * m]), centre[3 * k + 1], 0.5};
                rl_solution_trace(sol, mid, down, rgb);
                double want = albedo * 0.5 * (c.e[3 * k + 1] + c.e[3 * m + 1]);
                halves += fabs(rgb[1] - want) <= 1e-5 * (1 + want);
                bounded += rgb[1] >= albedo * fmin(c.e[3 * k + 1], c.e[3 * m + 1]) * (1 - 1e-6) &&
                           rgb[1] <= albedo * fmax(c.e[3 * k + 1], c.e[3 * m + 1]) * (1 + 1e-6);
            }
        }
        CHECK(c.n == 64 && flat == c.n && centres == c.n, "shading: %ld flat and %ld smooth of %u cell centres exact",
              flat, centres, c.n);
        CHECK(halves == 56 && bounded == 56, "shading: %ld of 56 midpoints the neighbours' mean, %ld in range", halves,
              bounded);
        CHECK(rl_solution_set_smooth(NULL, 1) == RL_ERR_ARG, "set_smooth(NULL)");
        free(centre);
        ts_cells_free(&c);
    }
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

/* A camera's view through rl_solution_render_camera(): a constant light field slab (2 W sr^-1 m^-2, 1 m at z = 0,
 * facing up) seen straight on from above shows its constant inside its rectangle and the glowing floor 1 m below
 * outside it; from below (its back) it is not seen; the scene-camera shorthand renders the same camera bit for
 * bit; rl_camera_check() refuses what a scene file may not hold. */
static void check_camera_views(void)
{
    char lfpath[600], path[600], rest[1024];
    snprintf(lfpath, sizeof lfpath, "%s/view_lf.h5", tmpdir);
    write_lightfield(lfpath, 2.0f, 180, 4, 0);
    snprintf(path, sizeof path, "%s/view_lf.json", tmpdir);
    tpoly floor = ts_rect_z("glow", -4, -4, 4, 4, -1.0, 1);
    snprintf(rest, sizeof rest,
             "\"radiance_maps\": {\"cell_size\": 0.5}, \"lightfields\": [{\"file\": \"view_lf.h5\"}], "
             "\"camera\": {\"position\": [0, 0, 2], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"fov_deg\": 90, "
             "\"width\": 40, \"height\": 40}");
    ts_write_scene(path, "{\"glow\": {\"albedo\": [0.5,0.5,0.5], \"emission\": [0.25,0.5,0.75]}}", &floor, 1, rest);
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    set_sampling(s, RL_METHOD_CULLED, 4, 1, 1, 0);
    rl_solution *sol = NULL;
    CHECK(rl_relight(s, &ts_job, &sol) == RL_OK, "camera views: %s", rl_errmsg());
    rl_camera cam;
    CHECK(rl_scene_camera(s, &cam) && cam.width == 40 && cam.fov_deg == 90, "the scene's camera");
    float *a = calloc(40 * 40 * 3, sizeof *a), *b = calloc(40 * 40 * 3, sizeof *b);
    if (sol && a && b) {
        CHECK(rl_solution_render_camera(sol, &cam, &ts_job.run, a) == RL_OK, "render_camera: %s", rl_errmsg());
        CHECK(rl_solution_render(sol, &ts_job.run, b) == RL_OK, "render: %s", rl_errmsg());
        CHECK(memcmp(a, b, 40 * 40 * 3 * sizeof *a) == 0, "the scene camera's render is render_camera's");
        /* at the slab's plane a pixel is 0.1 m: pixels 15 .. 24 lie inside [-0.5, 0.5], 0 .. 13 and 26 .. 39
         * outside */
        const float glow[3] = {0.25f, 0.5f, 0.75f};
        long inside = 0, outside = 0, in_ok = 0, out_ok = 0;
        for (int y = 0; y < 40; y++)
            for (int x = 0; x < 40; x++) {
                const float *px = a + 3 * (40 * y + x);
                int in = x >= 15 && x <= 24 && y >= 15 && y <= 24;
                int out = x <= 13 || x >= 26 || y <= 13 || y >= 26;
                int slab = 1, lit = 1;
                for (int c = 0; c < 3; c++) {
                    slab &= fabsf(px[c] - 2.0f) <= 1e-5f;
                    lit &= px[c] == glow[c];
                }
                inside += in;
                in_ok += in && slab;
                outside += out;
                out_ok += out && lit;
            }
        CHECK(inside == 100 && in_ok == inside, "the slab seen straight on: %ld of %ld pixels its constant", in_ok,
              inside);
        CHECK(out_ok == outside, "around it the floor: %ld of %ld pixels", out_ok, outside);
        /* a camera moved, the scene's unchanged */
        rl_camera low = cam;
        low.position[2] = -0.5;
        low.look_at[2] = 1.0;
        CHECK(rl_solution_render_camera(sol, &low, &ts_job.run, b) == RL_OK, "render from below: %s", rl_errmsg());
        CHECK(b[3 * (40 * 20 + 20)] == 0.0f, "the back of the slab is not seen (%g)", b[3 * (40 * 20 + 20)]);
        rl_camera again;
        CHECK(rl_scene_camera(s, &again) && memcmp(&again, &cam, sizeof cam) == 0, "the scene's camera is unchanged");
        float rgb[3] = {-1, -1, -1};
        const double org[3] = {0.1, 0.2, 3}, down[3] = {0, 0, -2};
        CHECK(rl_scene_trace_lightfields(s, org, down, INFINITY, rgb) && fabsf(rgb[1] - 2.0f) <= 1e-5f,
              "trace_lightfields finds the slab: %g", rgb[1]);
        CHECK(!rl_scene_trace_lightfields(s, org, down, 2.5, rgb), "nor beyond t_max");
        rl_camera bad = cam;
        bad.up[0] = 0, bad.up[1] = 0, bad.up[2] = 1;
        CHECK(rl_camera_check(&bad) == RL_ERR_ARG && strstr(rl_errmsg(), "up must not"), "up along the view: %s",
              rl_errmsg());
        CHECK(rl_solution_render_camera(sol, &bad, &ts_job.run, a) == RL_ERR_ARG, "render refuses a bad camera");
        bad = cam, bad.width = 0;
        CHECK(rl_camera_check(&bad) == RL_ERR_ARG, "width 0");
        bad = cam, bad.fov_deg = 180;
        CHECK(rl_camera_check(&bad) == RL_ERR_ARG, "fov 180");
        bad = cam, bad.look_at[2] = 2;
        CHECK(rl_camera_check(&bad) == RL_ERR_ARG, "look_at at the position");
        CHECK(rl_camera_check(&cam) == RL_OK && rl_camera_check(NULL) == RL_ERR_ARG, "check a good camera, NULL");
    }
    free(a);
    free(b);
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

/* A fixed generator for the random scenes. */
/* Random scenes of arbitrarily oriented quads: culled must equal naive bit for
 * bit whenever no pair descends (the sharpest test that culling is conservative). */
static void check_random_scenes(int count)
{
    long compared = 0;
    for (int sc = 0; sc < count; sc++) {
        char path[600];
        snprintf(path, sizeof path, "%s/random_%d.json", tmpdir, sc);
        tpoly p[16];
        int n = 6 + sc % 6; /* plus the floor and the wall: at most 13 */
        for (int k = 0; k < n; k++)
            p[k] = ts_random_quad(k < 2 ? "light" : "grey");
        /* a floor that everything can shadow, sharing an edge with a wall */
        p[n] = ts_rect_z("grey", -3, -3, 3, 3, -2.5, 1);
        tpoly wall = {"grey", 4, {{-3, -3, -2.5}, {-3, 3, -2.5}, {-3, 3, 2.5}, {-3, -3, 2.5}}};
        p[n + 1] = wall;
        ts_write_scene(path, MATS, p, n + 2, "\"radiance_maps\": {\"cell_size\": 0.3}, \"sampling\": {\"bounces\": 1}");
        rl_scene *s = ts_load(path);
        if (!s)
            continue;
        rl_solution *a = NULL, *b = NULL;
        no_descent = sc % 2; /* half the scenes with the paper's plain method: every pair comparable */
        set_sampling(s, RL_METHOD_CULLED, 8, 1, 16, 0);
        rl_relight(s, &ts_job, &a);
        set_sampling(s, RL_METHOD_NAIVE, 8, 1, 16, 0);
        rl_relight(s, &ts_job, &b);
        uint64_t descended = 0;
        for (uint32_t q = 0; a && q < rl_solution_pass_count(a); q++) {
            rl_pass_stats st;
            rl_solution_pass_stats(a, q, &st);
            descended += st.pairs_descended;
        }
        if (a && b && descended == 0) {
            long differ = 0;
            for (size_t k = 0; k < rl_solution_map_count(a); k++) {
                uint32_t na, nb, *ij;
                double *centre;
                float *ea = map_irradiance(a, k, &na, &centre, &ij);
                free(centre); free(ij);
                float *eb = map_irradiance(b, k, &nb, &centre, &ij);
                free(centre); free(ij);
                for (uint32_t c = 0; c < 3 * na; c++)
                    differ += memcmp(&ea[c], &eb[c], sizeof(float)) != 0;
                free(ea);
                free(eb);
            }
            CHECK(differ == 0, "random scene %d: culled and naive differ in %ld values", sc, differ);
            compared++;
        }
        rl_solution_destroy(a);
        rl_solution_destroy(b);
        rl_scene_destroy(s);
    }
    no_descent = 0;
    printf("random scenes: %ld of %d compared bit for bit (the rest had descending pairs)\n", compared, count);
    CHECK(compared >= count / 2, "at least the plain-method half is comparable: %ld of %d", compared, count);
}

/* Threads of this process now, from /proc/self/task (0 where there is no /proc). */
static unsigned task_count(void)
{
    DIR *d = opendir("/proc/self/task");
    unsigned n = 0;
    for (struct dirent *e; d && (e = readdir(d)) != NULL;)
        n += e->d_name[0] != '.';
    if (d)
        closedir(d);
    return n;
}

/* rl_progress_fn: the most threads the process had while the engine ran. */
static void count_tasks(void *user, double done)
{
    (void)done;
    unsigned *most = user, n = task_count();
    *most = n > *most ? n : *most;
}

/* `--threads 1` means one thread everywhere, Embree's hierarchy builder included: while a relight on
 * one worker runs (its progress callback comes from the calling thread), the process has at most the
 * caller and that worker; Embree, left to itself, starts one thread per hardware thread and keeps them. */
static void check_one_thread(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/one_thread.json", tmpdir);
    tpoly p[] = {
        ts_rect_z("light", -0.4, -0.4, 0.4, 0.4, 2.0, 0),
        ts_rect_z("grey", -2, -2, 2, 2, 0.0, 1),
        ts_rect_z("grey", -0.5, -0.3, 0.3, 0.5, 1.0, 0),
    };
    ts_write_scene(path, MATS, p, 3, "\"radiance_maps\": {\"cell_size\": 0.02}, \"sampling\": {\"bounces\": 1}");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    unsigned before = task_count(), most = 0;
    rl_job one;
    rl_job_default(s, &one);
    one.run = (rl_run_options){.threads = 1, .progress = count_tasks, .progress_user = &most};
    rl_solution *sol = NULL;
    CHECK(rl_relight(s, &one, &sol) == RL_OK, "one thread: %s", rl_errmsg());
    if (before > 0) {
        printf("one thread: at most %u threads while relighting (%u before)\n", most, before);
        CHECK(most >= 1 && most <= before + 1, "--threads 1 ran %u threads besides the caller's %u", most - before,
              before);
    }
    rl_ray_bench rb;
    CHECK(rl_bench_rays(s, &one.run, 1000, &rb) == RL_OK && rb.rays >= 1000, "bench on one thread: %s", rl_errmsg());
    CHECK(task_count() == 0 || task_count() <= before + 1, "threads left after a one-thread bench: %u", task_count());
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

/* ------------------------------------------------------------ ranks simulated by threads */

#define SIM_RANKS 3

/* What the simulated ranks of a job share: a barrier, each rank's buffer during an exchange, and the
 * two slots of the count of claims (as tools/job_mpi.c keeps them on rank 0). */
typedef struct sim_job {
    pthread_barrier_t barrier;
    double *buffer[SIM_RANKS];
    atomic_uint_fast64_t count[2];
    int honest; /* 0: each rank counts its claims on its own, so every rank claims every tile */
} sim_job;

/* One simulated rank: its rl_cluster, its claims and its run. */
typedef struct sim_rank {
    sim_job *job;
    uint32_t rank;
    rl_cluster cl;
    int claiming;          /* claimed since the last exchange */
    uint64_t round, own;   /* passes claimed; the dishonest count */
    uint64_t claimed, offered; /* tiles claimed; tiles of the passes claimed from */
    const rl_scene *scene;
    rl_solution *sol;
    rl_status st;
} sim_rank;

/* rl_cluster.allgather: each rank copies every other rank's block from that rank's buffer. */
static int sim_allgather(void *user, double *values, const uint64_t *counts, const uint64_t *offsets)
{
    sim_rank *r = user;
    r->claiming = 0;
    r->job->buffer[r->rank] = values;
    pthread_barrier_wait(&r->job->barrier);
    for (uint32_t q = 0; q < SIM_RANKS; q++)
        if (q != r->rank && counts[q] > 0)
            memcpy(values + offsets[q], r->job->buffer[q] + offsets[q], counts[q] * sizeof *values);
    pthread_barrier_wait(&r->job->barrier);
    return 0;
}

/* rl_cluster.sum: every rank adds the ranks' values in rank order, so all get the same sums. */
static int sim_sum(void *user, double *values, size_t n)
{
    sim_rank *r = user;
    r->claiming = 0;
    double *sums = calloc(n ? n : 1, sizeof *sums);
    r->job->buffer[r->rank] = values;
    pthread_barrier_wait(&r->job->barrier);
    for (uint32_t q = 0; sums && q < SIM_RANKS; q++)
        for (size_t k = 0; k < n; k++)
            sums[k] += r->job->buffer[q][k];
    pthread_barrier_wait(&r->job->barrier);
    if (sums)
        memcpy(values, sums, n * sizeof *values);
    free(sums);
    return sums ? 0 : -1;
}

/* rl_cluster.next: the job's count, the slot of the pass; rank 0 resets the other slot as it starts a pass. */
static uint64_t sim_next(void *user, uint64_t n)
{
    sim_rank *r = user;
    if (!r->claiming) {
        r->claiming = 1;
        r->round++;
        r->own = 0;
        r->offered += n;
        if (r->rank == 0)
            atomic_store(&r->job->count[(r->round + 1) % 2], 0);
    }
    uint64_t t = r->job->honest ? atomic_fetch_add(&r->job->count[r->round % 2], 1) : r->own++;
    r->claimed += t < n;
    return t < n ? t : n;
}

static void *sim_run(void *arg)
{
    sim_rank *r = arg;
    rl_job job = ts_job; /* set_sampling()'s job, read only while the ranks run */
    job.run.threads = 1 + r->rank % 2; /* ranks of 1 and 2 threads */
    r->st = rl_relight_cluster(r->scene, &r->cl, &job, &r->sol);
    return NULL;
}

/* Runs scene s on SIM_RANKS ranks simulated by threads (honest: one count of claims for the job).
 * @return 1 when every rank ran. */
static int sim_relight(const rl_scene *s, int honest, sim_rank *ranks)
{
    sim_job job;
    memset(&job, 0, sizeof job);
    job.honest = honest;
    atomic_init(&job.count[0], 0);
    atomic_init(&job.count[1], 0);
    pthread_barrier_init(&job.barrier, NULL, SIM_RANKS);
    pthread_t th[SIM_RANKS];
    int started = 0;
    for (uint32_t q = 0; q < SIM_RANKS; q++) {
        ranks[q] = (sim_rank){.job = &job, .rank = q, .scene = s, .st = RL_ERR_INTERNAL};
        ranks[q].cl = (rl_cluster){q, SIM_RANKS, sim_allgather, sim_sum, sim_next, &ranks[q]};
    }
    for (uint32_t q = 0; q < SIM_RANKS; q++)
        started += pthread_create(&th[q], NULL, sim_run, &ranks[q]) == 0;
    CHECK(started == SIM_RANKS, "cluster: %d of %d rank threads started", started, SIM_RANKS);
    if (started != SIM_RANKS)
        exit(check_report()); /* the started ranks wait for the others at the barrier */
    for (uint32_t q = 0; q < SIM_RANKS; q++)
        pthread_join(th[q], NULL);
    pthread_barrier_destroy(&job.barrier);
    return 1;
}

/* Tiles claimed as ranks become free (rl_cluster.next): 3 ranks of 1 and 2 threads give the maps of one
 * process bit for bit, claiming every tile of every pass once between them; a count that lets every rank
 * claim every tile is caught (RL_ERR_IO on every rank), not written. */
static void check_cluster(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/cluster.json", tmpdir);
    tpoly p[] = {
        ts_rect_z("light", -0.4, -0.4, 0.4, 0.4, 2.0, 0),
        ts_rect_z("grey", -2, -2, 2, 2, 0.0, 1),
        ts_rect_z("grey", -2, -2, 2, 2, 2.2, 0),
        ts_rect_z("grey", -0.5, -0.3, 0.3, 0.5, 1.0, 0),
        ts_rect_z("grey", -0.5, -0.3, 0.3, 0.5, 1.0, 1),
        {"grey", 4, {{-2, -2, 0}, {-2, 2, 0}, {-2, 2, 2.2}, {-2, -2, 2.2}}},
    };
    ts_write_scene(path, MATS, p, 6, "\"radiance_maps\": {\"cell_size\": 0.05}, \"sampling\": {\"bounces\": 2}");
    rl_scene *s = ts_load(path);
    if (!s)
        return;
    set_sampling(s, RL_METHOD_CULLED, 8, 2, 16, 1);
    rl_solution *ref = NULL;
    CHECK(rl_relight(s, &ts_job, &ref) == RL_OK, "cluster: reference: %s", rl_errmsg());
    sim_rank ranks[SIM_RANKS];
    if (ref && sim_relight(s, 1, ranks)) {
        uint64_t claimed = 0;
        for (uint32_t q = 0; q < SIM_RANKS; q++) {
            long total = 0;
            CHECK(ranks[q].st == RL_OK, "cluster: rank %u failed: %d", q, (int)ranks[q].st);
            CHECK(ranks[q].sol && ts_differing(ref, ranks[q].sol, &total) == 0 && total > 0,
                  "cluster: rank %u's maps differ from one process's", q);
            CHECK(ranks[q].offered == ranks[0].offered && ranks[q].claimed > 0,
                  "cluster: rank %u claimed %llu of %llu", q, (unsigned long long)ranks[q].claimed,
                  (unsigned long long)ranks[q].offered);
            claimed += ranks[q].claimed;
            rl_solution_destroy(ranks[q].sol);
        }
        printf("cluster: %d ranks claimed %llu tiles in all, %llu, %llu and %llu each\n", SIM_RANKS,
               (unsigned long long)claimed, (unsigned long long)ranks[0].claimed,
               (unsigned long long)ranks[1].claimed, (unsigned long long)ranks[2].claimed);
        CHECK(claimed == ranks[0].offered && claimed > 3 * SIM_RANKS, "cluster: %llu tiles claimed of %llu",
              (unsigned long long)claimed, (unsigned long long)ranks[0].offered);
    }
    if (ref && sim_relight(s, 0, ranks))
        for (uint32_t q = 0; q < SIM_RANKS; q++) {
            CHECK(ranks[q].st == RL_ERR_IO && ranks[q].sol == NULL,
                  "cluster: every tile claimed by every rank: rank %u returned %d", q, (int)ranks[q].st);
            rl_solution_destroy(ranks[q].sol);
        }
    rl_solution_destroy(ref);
    rl_scene_destroy(s);
}

int main(int argc, char **argv)
{
    const char *t = getenv("ILF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", t ? t : "/tmp");
    if (argc > 1 && strcmp(argv[1], "--extremes") == 0) {
        check_extremes();
        check_map_extremes();
        check_slab_edge_on();
        check_random_scenes(24);
    } else {
        check_one_thread(); /* first, before any other run has started threads */
        check_unoccluded();
        check_shading();
        check_camera_views();
        check_identities(0);
        check_identities(64);
        check_back_to_back();
        check_contact_bounce();
        check_narrow_wall();
        check_rooms_cull();
        check_lightfield();
        check_lightfield_anchors();
        check_maps_ready();
        check_cluster();
    }
    return check_report();
}
