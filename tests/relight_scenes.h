/*
 * relight_scenes.h - helpers the engine's tests share for building scenes in
 * code and judging solutions: polygons written out as scene JSON (so that
 * each test states its geometry in full and goes through the real loader),
 * light field files from radiance arrays, sampling settings, the cells of a
 * solution, culled == naive comparison bit for bit, and Lambert's formula
 * (rl_reference_polygon_irradiance) averaged over each cell.
 *
 * Everything is static: a test includes this once, after check.h.
 */
#ifndef ILF_TEST_RELIGHT_SCENES_H
#define ILF_TEST_RELIGHT_SCENES_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lfio/lightfield.h>
#include <relight/engine.h>
#include <relight/reference.h>

#include "check.h"

/* A convex polygon for a test scene, counter-clockwise seen from its front. */
typedef struct tpoly {
    const char *material;
    int n;
    double v[8][3];
} tpoly;

/* An axis-aligned rectangle at height z facing up (+z) or down (-z). */
static inline tpoly ts_rect_z(const char *mat, double x0, double y0, double x1, double y1, double z, int up)
{
    tpoly p = {mat, 4, {{0}}};
    double c[4][2] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    for (int k = 0; k < 4; k++) {
        int s = up ? k : 3 - k;
        p.v[k][0] = c[s][0];
        p.v[k][1] = c[s][1];
        p.v[k][2] = z;
    }
    return p;
}

/* p moved by t. */
static inline tpoly ts_moved(tpoly p, const double t[3])
{
    for (int k = 0; k < p.n; k++)
        for (int c = 0; c < 3; c++)
            p.v[k][c] += t[c];
    return p;
}

/* A deterministic uniform number in [0, 1) (a 64-bit LCG's top 53 bits). */
static uint64_t ts_rnd_state = 77;
static inline double ts_rnd(void)
{
    ts_rnd_state = ts_rnd_state * 6364136223846793005ull + 1442695040888963407ull;
    return (ts_rnd_state >> 11) * (1.0 / 9007199254740992.0);
}

/* A random quad facing a random direction: centre in a 4 m box centred on
 * the origin, sides 0.3 to 1.5 m. */
static inline tpoly ts_random_quad(const char *mat)
{
    double c[3] = {4 * ts_rnd() - 2, 4 * ts_rnd() - 2, 4 * ts_rnd() - 2}, a[3], b[3], n[3];
    double z = 2 * ts_rnd() - 1, phi = 6.283185307179586 * ts_rnd(), r = sqrt(1 - z * z);
    n[0] = r * cos(phi);
    n[1] = r * sin(phi);
    n[2] = z;
    double h[3] = {fabs(n[0]) < 0.9 ? 1 : 0, fabs(n[0]) < 0.9 ? 0 : 1, 0};
    a[0] = h[1] * n[2] - h[2] * n[1];
    a[1] = h[2] * n[0] - h[0] * n[2];
    a[2] = h[0] * n[1] - h[1] * n[0];
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int k = 0; k < 3; k++)
        a[k] /= la;
    b[0] = n[1] * a[2] - n[2] * a[1];
    b[1] = n[2] * a[0] - n[0] * a[2];
    b[2] = n[0] * a[1] - n[1] * a[0];
    double su = 0.3 + 1.2 * ts_rnd(), sv = 0.3 + 1.2 * ts_rnd();
    tpoly p = {mat, 4, {{0}}};
    const double corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 4; k++)
        for (int q = 0; q < 3; q++)
            p.v[k][q] = c[q] + 0.5 * su * corner[k][0] * a[q] + 0.5 * sv * corner[k][1] * b[q];
    return p;
}

/* Writes a scene file: materials JSON, polygons, and the other top-level keys
 * (rest, without braces; may be NULL). Numbers are written with 17 digits, so
 * the loader sees exactly the doubles given. @return 1, or 0 if it cannot be written. */
static inline int ts_write_scene(const char *path, const char *materials, const tpoly *p, int n, const char *rest)
{
    FILE *f = fopen(path, "w");
    CHECK(f != NULL, "cannot write %s", path);
    if (!f)
        return 0;
    fprintf(f, "{\"materials\": %s,\n \"polygons\": [", materials);
    for (int k = 0; k < n; k++) {
        fprintf(f, "%s\n  {\"material\": \"%s\", \"vertices\": [", k ? "," : "", p[k].material);
        for (int i = 0; i < p[k].n; i++)
            fprintf(f, "%s[%.17g, %.17g, %.17g]", i ? ", " : "", p[k].v[i][0], p[k].v[i][1], p[k].v[i][2]);
        fprintf(f, "]}");
    }
    fprintf(f, "]%s%s}\n", rest && *rest ? ",\n " : "", rest ? rest : "");
    return fclose(f) == 0;
}

/* Loads a scene, failing the test with the loader's message. @return the scene or NULL. */
static inline rl_scene *ts_load(const char *path)
{
    rl_scene *s = NULL;
    rl_status st = rl_scene_load(path, &s);
    CHECK(st == RL_OK, "load %s: %s", path, rl_errmsg());
    return st == RL_OK ? s : NULL;
}

/* The job of ts_relight() and of the calls that follow ts_set_sampling(). */
static rl_job ts_job;

/* Makes ts_job the job scene s's file suggests with method, level, rays per solid angle, samples per cell,
 * descent and threads (0: every core). */
static inline void ts_set_sampling(const rl_scene *s, rl_method m, uint32_t n, uint32_t k, uint32_t samples,
                                   uint32_t descend, uint32_t threads)
{
    rl_job_default(s, &ts_job);
    ts_job.sampling.method = m;
    ts_job.sampling.partition_n = n;
    ts_job.sampling.rays_per_solid_angle = k;
    ts_job.sampling.samples_per_cell = samples;
    ts_job.sampling.descend = descend;
    ts_job.run.threads = threads;
    CHECK(rl_job_check(&ts_job) == RL_OK, "set_sampling: %s", rl_errmsg());
}

/* Relights s with ts_job (ts_set_sampling() on s). @return the solution, or NULL (a failed check). */
static inline rl_solution *ts_relight(const rl_scene *s, const char *what)
{
    rl_solution *sol = NULL;
    rl_status st = rl_relight(s, &ts_job, &sol);
    CHECK(st == RL_OK, "%s: relight: %s", what, rl_errmsg());
    return st == RL_OK ? sol : NULL;
}

/* The cells of one map, copied out of a solution. */
typedef struct ts_cells {
    rl_map_info info;
    uint32_t n;
    uint32_t *ij;      /* [n][2] */
    double *area;      /* [n] */
    float *e;          /* [n][3] irradiance */
    float *b;          /* [n][3] radiosity */
} ts_cells;

/* Copies map k of sol. Free with ts_cells_free(). */
static inline ts_cells ts_cells_get(const rl_solution *sol, size_t k)
{
    ts_cells c;
    memset(&c, 0, sizeof c);
    rl_solution_map_info(sol, k, &c.info);
    c.n = c.info.ncells;
    c.ij = malloc((c.n + 1) * 2 * sizeof *c.ij);
    c.area = malloc((c.n + 1) * sizeof *c.area);
    c.e = malloc((c.n + 1) * 3 * sizeof *c.e);
    c.b = malloc((c.n + 1) * 3 * sizeof *c.b);
    rl_solution_map_cells(sol, k, c.ij, c.area, NULL, c.e, c.b);
    return c;
}

static inline void ts_cells_free(ts_cells *c)
{
    free(c->ij);
    free(c->area);
    free(c->e);
    free(c->b);
    memset(c, 0, sizeof *c);
}

/* @return the index of the map of scene polygon poly, or -1. */
static inline long ts_map_of(const rl_solution *sol, uint32_t poly)
{
    for (size_t k = 0; k < rl_solution_map_count(sol); k++) {
        rl_map_info info;
        rl_solution_map_info(sol, k, &info);
        if (info.polygon == poly)
            return (long)k;
    }
    return -1;
}

/* @return the number of irradiance and radiosity values of a solution, over
 * every map, that are not finite or negative (they must all be finite and >= 0);
 * *total gets the number of values looked at. */
static inline long ts_bad_values(const rl_solution *sol, long *total)
{
    long bad = 0;
    *total = 0;
    for (size_t k = 0; k < rl_solution_map_count(sol); k++) {
        ts_cells c = ts_cells_get(sol, k);
        for (uint32_t q = 0; q < 3 * c.n; q++) {
            bad += !(isfinite(c.e[q]) && c.e[q] >= 0) + !(isfinite(c.b[q]) && c.b[q] >= 0);
            *total += 2;
        }
        ts_cells_free(&c);
    }
    return bad;
}

/* @return the number of irradiance values (every map, cell and channel) in
 * which a and b differ in any bit, or -1 when their maps do not match;
 * *total gets the number compared. */
static inline long ts_differing(const rl_solution *a, const rl_solution *b, long *total)
{
    *total = 0;
    if (rl_solution_map_count(a) != rl_solution_map_count(b))
        return -1;
    long differ = 0;
    for (size_t k = 0; k < rl_solution_map_count(a); k++) {
        ts_cells ca = ts_cells_get(a, k), cb = ts_cells_get(b, k);
        if (ca.n != cb.n)
            differ = -1;
        for (uint32_t q = 0; differ >= 0 && q < 3 * ca.n; q++) {
            differ += memcmp(&ca.e[q], &cb.e[q], sizeof(float)) != 0;
            (*total)++;
        }
        ts_cells_free(&ca);
        ts_cells_free(&cb);
        if (differ < 0)
            return -1;
    }
    return differ;
}

/* Emitters for the reference: each a convex polygon and its radiance. */
typedef struct ts_emitter {
    const tpoly *p;
    double radiance;
} ts_emitter;

/* Lambert's irradiance at x (unit normal nrm) from every emitter, no occlusion. */
static inline double ts_reference_point(const ts_emitter *em, int nem, const double x[3], const double nrm[3])
{
    double sum = 0;
    for (int k = 0; k < nem; k++)
        sum += rl_reference_polygon_irradiance(&em[k].p->v[0][0], (size_t)em[k].p->n, x, nrm, em[k].radiance);
    return sum;
}

/*
 * The mean of Lambert's irradiance over cell (i, j) of the map described by
 * info, clipped to the map's polygon: q x q points on the part of the cell
 * inside the polygon's bounding box, those inside the polygon averaged. So a
 * polygon much smaller than a cell is still sampled where it is.
 */
static inline double ts_reference_cell(const ts_emitter *em, int nem, const rl_map_info *info, uint32_t i,
                                       uint32_t j, int q)
{
    double pu[64], pv[64], lo_u = INFINITY, hi_u = -INFINITY, lo_v = INFINITY, hi_v = -INFINITY;
    uint32_t nv = info->nvertices < 64 ? info->nvertices : 64;
    for (uint32_t k = 0; k < nv; k++) {
        double d[3];
        for (int c = 0; c < 3; c++)
            d[c] = info->vertices[3 * k + c] - info->origin[c];
        pu[k] = d[0] * info->e1[0] + d[1] * info->e1[1] + d[2] * info->e1[2];
        pv[k] = d[0] * info->e2[0] + d[1] * info->e2[1] + d[2] * info->e2[2];
        lo_u = fmin(lo_u, pu[k]), hi_u = fmax(hi_u, pu[k]);
        lo_v = fmin(lo_v, pv[k]), hi_v = fmax(hi_v, pv[k]);
    }
    double u0 = fmax(lo_u, info->u0 + i * info->cell_size), u1 = fmin(hi_u, info->u0 + (i + 1) * info->cell_size);
    double v0 = fmax(lo_v, info->v0 + j * info->cell_size), v1 = fmin(hi_v, info->v0 + (j + 1) * info->cell_size);
    double sum = 0;
    long count = 0;
    for (int a = 0; a < q; a++)
        for (int b = 0; b < q; b++) {
            double u = u0 + (a + 0.5) / q * (u1 - u0), v = v0 + (b + 0.5) / q * (v1 - v0);
            int inside = 1;
            for (uint32_t k = 0; k < nv && inside; k++) {
                uint32_t l = (k + 1) % nv;
                inside = (pu[l] - pu[k]) * (v - pv[k]) - (pv[l] - pv[k]) * (u - pu[k]) >= 0;
            }
            if (!inside)
                continue;
            double x[3];
            for (int c = 0; c < 3; c++)
                x[c] = info->origin[c] + u * info->e1[c] + v * info->e2[c];
            sum += ts_reference_point(em, nem, x, info->normal);
            count++;
        }
    return count ? sum / count : 0.0;
}

/* Errors of one map against Lambert (channel 1): RMSE and largest error
 * over cells, and the peak reference value. */
typedef struct ts_errors {
    double rmse, max, peak;
    uint32_t cells;
} ts_errors;

static inline ts_errors ts_errors_vs_reference(const rl_solution *sol, size_t k, const ts_emitter *em, int nem, int q)
{
    ts_cells c = ts_cells_get(sol, k);
    ts_errors r = {0, 0, 0, c.n};
    double se = 0;
    for (uint32_t m = 0; m < c.n; m++) {
        double ref = ts_reference_cell(em, nem, &c.info, c.ij[2 * m], c.ij[2 * m + 1], q);
        double d = c.e[3 * m + 1] - ref;
        r.peak = fmax(r.peak, ref);
        se += d * d;
        r.max = fmax(r.max, fabs(d));
    }
    r.rmse = c.n ? sqrt(se / c.n) : 0;
    ts_cells_free(&c);
    return r;
}

/* Writes a one-slab light field file: a len x len slab at the origin facing
 * +z, nu x nu positions, partition level n, radiance rgb laid out
 * [dir][j][i][3], and coverage cov in the same layout (NULL: none).
 * @return 1, or 0 (a failed check). */
static inline int ts_write_slab_covered(const char *path, const char *name, double len, uint32_t nu, uint32_t n,
                                        const float *rgb, const uint8_t *cov)
{
    lfio_slab_desc d;
    lfio_slab *slab = NULL;
    lfio_lightfield *lf = NULL;
    lfio_slab_desc_init(&d);
    snprintf(d.name, sizeof d.name, "%s", name);
    d.origin[0] = d.origin[1] = -0.5 * len;
    d.u[0] = d.v[1] = len;
    d.nu = d.nv = nu;
    d.n = n;
    int ok = lfio_slab_new(&d, &slab) == LFIO_OK;
    uint64_t nd = ok ? lfio_slab_dir_count(slab) : 0;
    for (uint64_t k = 0; ok && k < nd; k++)
        ok = lfio_slab_write_direction(slab, k, rgb + k * nu * nu * 3) == LFIO_OK;
    ok = ok && lfio_lightfield_new(&lf) == LFIO_OK && lfio_lightfield_take_slab(lf, slab) == LFIO_OK;
    if (!ok)
        lfio_slab_destroy(slab); /* not taken */
    ok = ok && (cov == NULL || lfio_lightfield_set_coverage(lf, 0, cov) == LFIO_OK);
    ok = ok && lfio_lightfield_write(lf, path) == LFIO_OK;
    CHECK(ok, "write %s: %s", path, lfio_errmsg());
    lfio_lightfield_destroy(lf);
    return ok;
}

/* ts_write_slab_covered() without coverage. */
static inline int ts_write_slab(const char *path, const char *name, double len, uint32_t nu, uint32_t n,
                                const float *rgb)
{
    return ts_write_slab_covered(path, name, len, nu, n, rgb, NULL);
}

#endif
