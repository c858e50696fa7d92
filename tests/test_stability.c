/*
 * test_stability.c - the relighting engine at the numerical extremes: emitter
 * radiance from 0 through subnormal and 1e-30 to 1e30 and the largest a
 * scene accepts; a light field spanning 1e-10 to 1e10; 1e-6 m and 1e5 m
 * polygons in one scene; a scene 1e6 m from the origin; light exactly and
 * nearly (1e-12 rad) parallel to the emitter's and the receiver's plane; an
 * emitter sharing an edge with its receiver; slivers of aspect 1e-6; and
 * every partition level from 1 to 1024.
 *
 * Every case checks three things where they apply: every output is finite
 * and non-negative; culled equals naive bit for bit (with descent off, the
 * paper's plain method, where the promise holds for every pair: the
 * sharpest test that culling is conservative); and the error against
 * Lambert's formula stays within the bound stated at the case. Scenes are
 * built in code and written as JSON into ILF_TEST_TMP, so they go through
 * the real loader. Each case prints what it measured: docs/accuracy.md
 * quotes these lines.
 *
 * Types involved (see docs/accuracy.md): a diffuse emitter's radiance is a
 * float32 in the scene (scene.c stores the JSON double as float), a light
 * field's radiance is float32 (lfio), every accumulator and the geometry are
 * double, Embree's rays are float32 in a frame recentred on the scene, and
 * radiance maps come out as float32 (rl_solution_map_cells), while point
 * queries (rl_irradiance) come out as double.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <lfio/partition.h>

#include "check.h"
#include "relight_scenes.h"

static char tmpdir[512];

/* Materials with an emitter of radiance L (written with 17 digits: the scene reads a double). */
static void materials(char *buf, size_t size, double L)
{
    snprintf(buf, size,
             "{\"light\": {\"albedo\": [0,0,0], \"emission\": [%.17g,%.17g,%.17g]},"
             " \"hot\": {\"albedo\": [0,0,0], \"emission\": [1e6,1e6,1e6]},"
             " \"grey\": {\"albedo\": [0.5,0.5,0.5]}, \"black\": {\"albedo\": [0,0,0]}}",
             L, L, L);
}

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Writes and loads a scene of polygons with emitter radiance L; rest as in ts_write_scene. */
static rl_scene *scene_of(const char *name, double L, const tpoly *p, int n, const char *rest)
{
    char path[700], mats[512];
    snprintf(path, sizeof path, "%s/stability_%s.json", tmpdir, name);
    materials(mats, sizeof mats, L);
    return ts_write_scene(path, mats, p, n, rest) ? ts_load(path) : NULL;
}

/*
 * Runs culled and naive at level n, k rays, descent off, and checks that
 * both are finite and identical bit for bit. @return the culled solution
 * (the caller destroys it), or NULL.
 */
static rl_solution *culled_equals_naive(rl_scene *s, const char *name, uint32_t n, uint32_t k)
{
    ts_set_sampling(s, RL_METHOD_CULLED, n, k, 16, 0, 0);
    rl_solution *a = ts_relight(s, name);
    ts_set_sampling(s, RL_METHOD_NAIVE, n, k, 16, 0, 0);
    rl_solution *b = ts_relight(s, name);
    if (a && b) {
        long total, bad = ts_bad_values(a, &total), totb, badb = ts_bad_values(b, &totb);
        CHECK(bad == 0 && badb == 0, "%s: %ld culled and %ld naive values not finite or negative", name, bad, badb);
        long cmp, differ = ts_differing(a, b, &cmp);
        CHECK(differ == 0, "%s n=%u: culled and naive differ in %ld of %ld values", name, n, differ, cmp);
        rl_pass_stats st;
        rl_solution_pass_stats(a, 0, &st);
        CHECK(st.pairs_descended == 0, "%s: descent is off, yet %llu pairs descended", name,
              (unsigned long long)st.pairs_descended);
    }
    rl_solution_destroy(b);
    return a;
}

/* ------------------------------------------------------------ radiance */

/*
 * Emitter radiance over the whole range a scene can hold. The scene stores
 * emission as float32: 1e-30 and 1e30 are normal floats; 1e-40 is a float
 * subnormal; 1e-310 and 4.9e-324 are double subnormals that the float
 * conversion turns into 0. Expected: 0 gives exactly 0; 1e-30 and 1e30 give
 * the radiance-1 result scaled (relative error < 1e-6, per cell, float
 * output); 1e-40 gives finite, non-negative results (either exactly 0 or the
 * scaled result within float-subnormal precision); the double subnormals
 * give exactly 0, the float they become.
 */
static void check_radiance_range(void)
{
    tpoly p[2] = {ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0), ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1)};
    const char *rest = "\"radiance_maps\": {\"cell_size\": 0.25}";
    const double pts[2][6] = {{0.1, 0.2, 0, 0, 0, 1}, {0.9, -0.7, 0.3, -0.2, 0.1, 1}};
    /* the radiance-1 result every other is compared with */
    rl_scene *s1 = scene_of("radiance_1", 1.0, p, 2, rest);
    if (!s1)
        return;
    rl_solution *one = culled_equals_naive(s1, "radiance 1", 16, 2);
    ts_set_sampling(s1, RL_METHOD_CULLED, 32, 8, 16, 1, 0);
    double pt1[6];
    CHECK(rl_irradiance(s1, &ts_job, &pts[0][0], 2, pt1, NULL) == RL_OK, "points: %s", rl_errmsg());
    if (!one) {
        rl_scene_destroy(s1);
        return;
    }
    long m1 = ts_map_of(one, 1);
    ts_emitter em = {&p[0], 1.0};
    ts_errors err = ts_errors_vs_reference(one, (size_t)m1, &em, 1, 8);
    printf("radiance 1        culled n=16 k=2: RMSE %.4f%%, max %.4f%% of peak %.6g\n", 100 * err.rmse / err.peak,
           100 * err.max / err.peak, err.peak);
    /* measured: RMSE 1.6%, max 5.4% of the peak at these few rays */
    CHECK(err.rmse < 0.03 * err.peak && err.max < 0.08 * err.peak, "radiance 1: RMSE %.3g, max %.3g of peak %.3g",
          err.rmse, err.max, err.peak);
    ts_cells c1 = ts_cells_get(one, (size_t)m1);

    const struct {
        const char *name;
        double L;
        int kind; /* 0: exactly zero; 1: scaled; 2: float subnormal */
    } cases[] = {{"0", 0.0, 0},           {"1e-30", 1e-30, 1},         {"1e30", 1e30, 1},
                 {"1e-40 (float subnormal)", 1e-40, 2}, {"1e-310 (double subnormal)", 1e-310, 0},
                 {"4.9e-324 (smallest double)", 4.9e-324, 0}};
    for (size_t q = 0; q < sizeof cases / sizeof cases[0]; q++) {
        char name[64];
        snprintf(name, sizeof name, "radiance_%zu", q);
        rl_scene *s = scene_of(name, cases[q].L, p, 2, rest);
        if (!s)
            continue;
        snprintf(name, sizeof name, "radiance %s", cases[q].name);
        rl_solution *sol = culled_equals_naive(s, name, 16, 2);
        ts_set_sampling(s, RL_METHOD_CULLED, 32, 8, 16, 1, 0);
        double pt[6] = {NAN, NAN, NAN, NAN, NAN, NAN};
        CHECK(rl_irradiance(s, &ts_job, &pts[0][0], 2, pt, NULL) == RL_OK, "%s points: %s", name, rl_errmsg());
        if (sol) {
            ts_cells c = ts_cells_get(sol, (size_t)ts_map_of(sol, 1));
            double worst = 0; /* largest relative deviation from the scaled radiance-1 result */
            long zero = 0;
            for (uint32_t m = 0; m < c.n && m < c1.n; m++)
                for (int ch = 0; ch < 3; ch++) {
                    double want = (double)c1.e[3 * m + ch] * (double)(float)cases[q].L, got = c.e[3 * m + ch];
                    zero += got == 0;
                    if (want > 0)
                        worst = fmax(worst, fabs(got - want) / want);
                }
            double ptdev = 0;
            for (int k = 0; k < 6; k++) {
                double want = pt1[k] * (double)(float)cases[q].L;
                ptdev = fmax(ptdev, want > 0 ? fabs(pt[k] - want) / want : fabs(pt[k]));
            }
            printf("radiance %-27s: %ld of %u values exactly 0; worst relative deviation from the scaled radiance-1 "
                   "result: maps %.3g, points %.3g (point 0: %.6g W/m2)\n",
                   cases[q].name, zero, 3 * c.n, worst, ptdev, pt[0]);
            if (cases[q].kind == 0) {
                CHECK(zero == 3 * (long)c.n && pt[0] == 0 && pt[3] == 0, "%s: must give exactly 0 (%ld of %u zero)",
                      name, zero, 3 * c.n);
            } else if (cases[q].kind == 1) {
                CHECK(worst < 1e-6 && ptdev < 1e-6,
                      "%s: maps deviate by %.3g, points by %.3g from the scaled result", name, worst, ptdev);
                CHECK(zero == 0, "%s: %ld values underflowed to 0", name, zero);
            } else {
                int all_zero = zero == 3 * (long)c.n;
                int finite = 1;
                for (int k = 0; k < 6; k++)
                    finite &= isfinite(pt[k]) && pt[k] >= 0;
                CHECK(finite && (all_zero || worst < 1e-3), "%s: neither zero nor scaled (%.3g)", name, worst);
                printf("radiance %-27s: %s\n", cases[q].name,
                       all_zero ? "flushed to exactly 0 (the engine's threads run with FTZ/DAZ)"
                                : "kept: the scaled result within subnormal precision");
            }
            ts_cells_free(&c);
        }
        rl_solution_destroy(sol);
        rl_scene_destroy(s);
    }
    ts_cells_free(&c1);
    rl_solution_destroy(one);
    rl_scene_destroy(s1);

    /* Emission beyond RL_MAX_EMISSION (FLT_MAX here) is refused, naming the
     * material; the largest accepted one under a 20 m emitter 1 m up gives
     * finite irradiance in double (points) and in the float32 maps. */
    tpoly big[2] = {ts_rect_z("light", -10, -10, 10, 10, 1.0, 0), ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1)};
    {
        char path[700], mats[512];
        rl_scene *bad = NULL;
        snprintf(path, sizeof path, "%s/stability_radiance_fltmax.json", tmpdir);
        materials(mats, sizeof mats, FLT_MAX);
        CHECK(ts_write_scene(path, mats, big, 2, rest) && rl_scene_load(path, &bad) == RL_ERR_INPUT &&
                  strstr(rl_errmsg(), "emission") && strstr(rl_errmsg(), "at most"),
              "FLT_MAX emission refused with a message: %s", rl_errmsg());
        rl_scene_destroy(bad);
    }
    rl_scene *s = scene_of("radiance_max", RL_MAX_EMISSION, big, 2, rest);
    if (!s)
        return;
    rl_solution *sol = culled_equals_naive(s, "radiance RL_MAX_EMISSION", 8, 1);
    ts_set_sampling(s, RL_METHOD_CULLED, 16, 4, 16, 1, 0);
    double pt[6] = {NAN, NAN, NAN, NAN, NAN, NAN};
    CHECK(rl_irradiance(s, &ts_job, &pts[0][0], 2, pt, NULL) == RL_OK, "FLT_MAX points: %s", rl_errmsg());
    double ref = rl_reference_polygon_irradiance(&big[0].v[0][0], 4, pts[0], (double[3]){0, 0, 1}, RL_MAX_EMISSION);
    printf("radiance 1e30 (20 m emitter)      : point %.6g W/m2 vs Lambert %.6g (rel %.2g)\n", pt[0], ref,
           fabs(pt[0] - ref) / ref);
    CHECK(isfinite(pt[0]) && fabs(pt[0] - ref) < 0.01 * ref, "max emission point: %.6g vs %.6g", pt[0], ref);
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

/* ---------------------------------------------------------- light field */

/* A hash of (direction, position) to [0, 1). */
static double hash01(uint64_t a, uint64_t b)
{
    uint64_t x = a * 0x9E3779B97F4A7C15ull ^ (b + 0x632BE59BD9B4E019ull);
    x ^= x >> 31;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 29;
    return (x >> 11) * (1.0 / 9007199254740992.0);
}

/*
 * A slab whose radiance spans 1e-10 to 1e10 (10^e, e uniform in [-10, 10]
 * by a hash of direction and position), hung face down 1 m over a floor,
 * and the same slab split in two: the values >= 1 and the values < 1 (each
 * zero elsewhere, so each has its own, sparser zero-radiance mask). The
 * engine is linear in radiance, so the whole must equal the sum of the parts
 * within float rounding (each ray's radiance is interpolated in double and
 * rounded to float once, the sum of the cell's rays is double, the map
 * float: a few float ulps); culled == naive for all three, so the masks
 * cull nothing that carries light, even 1e-10 next to 1e10.
 */
static void check_lightfield_range(void)
{
    const uint32_t nu = 4, n = 8;
    uint64_t nd = lfio_part_hemi_count(n), npos = nu * nu;
    float *full = calloc(nd * npos * 3, sizeof *full), *hi = calloc(nd * npos * 3, sizeof *hi),
          *lo = calloc(nd * npos * 3, sizeof *lo);
    double lmin = INFINITY, lmax = 0;
    for (uint64_t d = 0; d < nd; d++)
        for (uint64_t q = 0; q < npos; q++)
            for (int c = 0; c < 3; c++) {
                double e = -10 + 20 * hash01(d, 3 * q + c);
                float L = (float)pow(10.0, e);
                size_t at = (d * npos + q) * 3 + c;
                full[at] = L;
                (L >= 1 ? hi : lo)[at] = L;
                lmin = fmin(lmin, L), lmax = fmax(lmax, L);
            }
    printf("light field range: radiance from %.3g to %.3g\n", lmin, lmax);
    const char *names[3] = {"full", "hi", "lo"};
    float *data[3] = {full, hi, lo};
    rl_solution *sol[3] = {NULL, NULL, NULL};
    rl_scene *sc[3] = {NULL, NULL, NULL};
    tpoly floor = ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1);
    for (int k = 0; k < 3; k++) {
        char lf[700], rest[1024], name[64];
        snprintf(lf, sizeof lf, "%s/stability_lf_%s.h5", tmpdir, names[k]);
        if (!ts_write_slab(lf, "range", 1.0, nu, n, data[k]))
            continue;
        snprintf(rest, sizeof rest,
                 "\"radiance_maps\": {\"cell_size\": 0.25}, \"lightfields\": [{\"file\": \"stability_lf_%s.h5\", "
                 "\"transform\": [[1,0,0,0],[0,-1,0,0],[0,0,-1,1],[0,0,0,1]]}]",
                 names[k]);
        snprintf(name, sizeof name, "lf_%s", names[k]);
        sc[k] = scene_of(name, 1.0, &floor, 1, rest);
        if (sc[k]) {
            snprintf(name, sizeof name, "light field %s", names[k]);
            sol[k] = culled_equals_naive(sc[k], name, 16, 2);
        }
    }
    if (sol[0] && sol[1] && sol[2]) {
        ts_cells c[3];
        for (int k = 0; k < 3; k++)
            c[k] = ts_cells_get(sol[k], 0);
        double worst = 0, emax = 0, lo_max = 0;
        long lit_lo = 0;
        for (uint32_t m = 0; m < c[0].n; m++)
            for (int ch = 0; ch < 3; ch++) {
                double whole = c[0].e[3 * m + ch], a = c[1].e[3 * m + ch], b = c[2].e[3 * m + ch];
                worst = fmax(worst, fabs(whole - (a + b)) / (a + b));
                emax = fmax(emax, whole);
                lo_max = fmax(lo_max, b);
                lit_lo += b > 0;
            }
        printf("light field range: whole vs sum of parts, worst relative difference %.3g (peak %.4g W/m2; the "
               "part < 1 peaks at %.4g W/m2, lights %ld of %u values)\n",
               worst, emax, lo_max, lit_lo, 3 * c[0].n);
        CHECK(worst < 1e-6, "light field: whole and sum of parts differ by %.3g relative", worst);
        CHECK(lit_lo == 3 * (long)c[0].n && lo_max < 3.2, "light field: the part < 1 lights %ld cells, peak %.3g",
              lit_lo, lo_max);
        CHECK(emax > 1e8 && emax < 3.2e10, "light field: peak %.3g out of range", emax);
        rl_pass_stats st;
        rl_solution_pass_stats(sol[1], 0, &st);
        printf("light field range: the part >= 1 culls %llu of %llu leaves\n",
               (unsigned long long)st.solid_angles_culled, (unsigned long long)st.solid_angles_considered);
        for (int k = 0; k < 3; k++)
            ts_cells_free(&c[k]);
    }
    for (int k = 0; k < 3; k++) {
        rl_solution_destroy(sol[k]);
        rl_scene_destroy(sc[k]);
    }
    free(full);
    free(hi);
    free(lo);
}

/* ------------------------------------------------------------- scales */

/*
 * 1e-6 m and 1e5 m polygons in one scene: a 1e5 m emitter 1 m over a 1e5 m
 * floor (cells of 1e4 m), a 1e-6 m receiver 0.5 m up (one cell, the
 * polygon itself), and a 1e-6 m emitter of radiance 1e6 1 mm above the
 * floor at x = 20 m, which a point query there sees next to the sky. The
 * scene's half-extent is 5e4 m, so shadow rays stop short by
 * 1e-6 * 5e4 = 0.05 m (pair_eps in relight/src/pair.c): the 1 mm gap is below what
 * single precision resolves at this size.
 */
static void check_mixed_scales(void)
{
    tpoly p[4] = {ts_rect_z("light", -5e4, -5e4, 5e4, 5e4, 1.0, 0), ts_rect_z("grey", -5e4, -5e4, 5e4, 5e4, 0.0, 1),
                  ts_rect_z("grey", -5e-7, -5e-7, 5e-7, 5e-7, 0.5, 1),
                  ts_rect_z("hot", 20 - 5e-7, -5e-7, 20 + 5e-7, 5e-7, 1e-3, 0)};
    rl_scene *s = scene_of("mixed_scales", 1.0, p, 4, "\"radiance_maps\": {\"cell_size\": 1e4}");
    if (!s)
        return;
    rl_solution *sol = culled_equals_naive(s, "mixed scales", 16, 4);
    ts_emitter em[2] = {{&p[0], 1.0}, {&p[3], 1e6}};
    if (sol) {
        ts_errors tiny = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, 2), em, 2, 4);
        ts_errors floor = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), em, 2, 8);
        printf("mixed scales: 1e-6 m receiver under the 1e5 m emitter: error %.3g%% of %.6g W/m2 (%u cell)\n",
               100 * tiny.max / tiny.peak, tiny.peak, tiny.cells);
        printf("mixed scales: 1e5 m floor, 1e4 m cells: RMSE %.3g%%, max %.3g%% of peak %.6g (%u cells)\n",
               100 * floor.rmse / floor.peak, 100 * floor.max / floor.peak, floor.peak, floor.cells);
        CHECK(tiny.cells == 1 && tiny.max < 0.01 * tiny.peak, "1e-6 m receiver: error %.3g of %.3g", tiny.max,
              tiny.peak);
        CHECK(floor.rmse < 0.01 * floor.peak && floor.max < 0.03 * floor.peak, "1e5 m floor: RMSE %.3g, max %.3g",
              floor.rmse, floor.max);
    }
    rl_solution_destroy(sol);
    /* the 1e-6 m emitter seen from 1 mm below, next to the 1e5 m sky: culled descends */
    const double pt[2][6] = {{20, 0, 0, 0, 0, 1}, {20.0005, 0.0002, 0, 0, 0, 1}};
    ts_set_sampling(s, RL_METHOD_CULLED, 32, 16, 16, 1, 0);
    double out[6] = {NAN, NAN, NAN, NAN, NAN, NAN};
    CHECK(rl_irradiance(s, &ts_job, &pt[0][0], 2, out, NULL) == RL_OK, "mixed scales points: %s", rl_errmsg());
    for (int q = 0; q < 2; q++) {
        double up[3] = {0, 0, 1}, ref = ts_reference_point(em, 2, pt[q], up);
        double tiny_part = rl_reference_polygon_irradiance(&p[3].v[0][0], 4, pt[q], up, 1e6);
        printf("mixed scales: point %d under the 1e-6 m emitter: %.6g vs Lambert %.6g (of which the tiny emitter "
               "%.4g; rel error %.2g)\n",
               q, out[3 * q], ref, tiny_part, fabs(out[3 * q] - ref) / ref);
        CHECK(isfinite(out[3 * q]) && fabs(out[3 * q] - ref) < 0.02 * ref, "point %d: %.6g vs %.6g", q, out[3 * q],
              ref);
    }
    rl_scene_destroy(s);
}

/*
 * The same occluded scene at the origin and moved by (1e6, 1e6, 1e6) m: a
 * 1 m emitter 1 m over a 2 m floor with a blocker halfway. Geometry is
 * double and the tracer recentres on the scene's box, so the moved scene
 * may differ only by the rounding of its coordinates (ulp 1.2e-10 m at
 * 1e6 m): the bound, 1e-4 of the peak per cell, is far above what that can
 * do and far below the estimator's own error.
 */
static void check_offset(void)
{
    tpoly p[3] = {ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0), ts_rect_z("grey", -1, -1, 1, 1, 0.0, 1),
                  ts_rect_z("black", -0.3, -0.2, 0.1, 0.3, 0.5, 0)};
    const double t[3] = {1e6, 1e6, 1e6};
    tpoly q[3];
    for (int k = 0; k < 3; k++)
        q[k] = ts_moved(p[k], t);
    const char *rest = "\"radiance_maps\": {\"cell_size\": 0.125}";
    rl_scene *a = scene_of("offset_0", 1.0, p, 3, rest), *b = scene_of("offset_1e6", 1.0, q, 3, rest);
    rl_solution *sa = a ? culled_equals_naive(a, "at the origin", 16, 2) : NULL;
    rl_solution *sb = b ? culled_equals_naive(b, "offset 1e6 m", 16, 2) : NULL;
    if (sa && sb) {
        ts_cells ca = ts_cells_get(sa, (size_t)ts_map_of(sa, 1)), cb = ts_cells_get(sb, (size_t)ts_map_of(sb, 1));
        double peak = 0, worst = 0;
        long differ = 0;
        for (uint32_t m = 0; m < ca.n && m < cb.n; m++)
            peak = fmax(peak, ca.e[3 * m]);
        for (uint32_t m = 0; m < ca.n && m < cb.n; m++) {
            worst = fmax(worst, fabs(ca.e[3 * m] - cb.e[3 * m]) / peak);
            differ += ca.e[3 * m] != cb.e[3 * m];
        }
        printf("offset 1e6 m: %ld of %u cells differ from the scene at the origin; largest difference %.3g of peak\n",
               differ, ca.n, worst);
        CHECK(ca.n == cb.n && worst < 1e-4, "offset 1e6 m: cells differ by %.3g of peak", worst);
        ts_cells_free(&ca);
        ts_cells_free(&cb);
    }
    rl_solution_destroy(sa);
    rl_solution_destroy(sb);
    /* and without the blocker, against Lambert, far from the origin */
    if (b) {
        rl_scene_destroy(b);
        b = scene_of("offset_1e6_open", 1.0, q, 2, rest);
        sb = b ? culled_equals_naive(b, "offset 1e6 m, open", 16, 2) : NULL;
        if (sb) {
            ts_emitter em = {&q[0], 1.0};
            ts_errors e = ts_errors_vs_reference(sb, (size_t)ts_map_of(sb, 1), &em, 1, 8);
            printf("offset 1e6 m, unoccluded, culled n=16 k=2: RMSE %.4f%%, max %.4f%% of peak\n",
                   100 * e.rmse / e.peak, 100 * e.max / e.peak);
            CHECK(e.rmse < 0.02 * e.peak, "offset 1e6 m: RMSE %.3g of %.3g", e.rmse, e.peak);
        }
        rl_solution_destroy(sb);
    }
    rl_scene_destroy(a);
    rl_scene_destroy(b);
}

/* ----------------------------------------------------------- grazing */

/*
 * One emitter and one receiver; culled == naive; finite; and the cells
 * against Lambert within abs_tol (W m^-2, absolute: some of these answers
 * are exactly 0 or about 1e-12) plus rel_tol of the peak; then culled with
 * descent on (the default) against the same bound. must_be_zero: every
 * value must be exactly 0.
 */
static void grazing_case(const char *name, const tpoly *em, const tpoly *rc, double cell, double abs_tol,
                         double rel_tol, int must_be_zero)
{
    tpoly p[2] = {*em, *rc};
    char rest[128], file[64];
    snprintf(rest, sizeof rest, "\"radiance_maps\": {\"cell_size\": %.17g}", cell);
    snprintf(file, sizeof file, "grazing_%s", name);
    rl_scene *s = scene_of(file, 1.0, p, 2, rest);
    if (!s)
        return;
    rl_solution *sol = culled_equals_naive(s, name, 16, 2);
    ts_emitter e = {&p[0], 1.0};
    for (int pass = 0; sol && pass < 2; pass++) {
        ts_errors r = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), &e, 1, 16);
        ts_cells c = ts_cells_get(sol, (size_t)ts_map_of(sol, 1));
        double emax = 0;
        for (uint32_t m = 0; m < 3 * c.n; m++)
            emax = fmax(emax, c.e[m]);
        printf("%-34s %s: max %.4g W/m2, reference peak %.4g; RMSE %.4g, max error %.4g W/m2 (%.3g%% of peak)\n",
               name, pass ? "culled+descend" : "culled/naive  ", emax, r.peak, r.rmse, r.max,
               r.peak > 0 ? 100 * r.max / r.peak : 0.0);
        CHECK(r.max <= abs_tol + rel_tol * r.peak, "%s (%s): error %.4g, allowed %.4g", name,
              pass ? "descend" : "plain", r.max, abs_tol + rel_tol * r.peak);
        if (must_be_zero)
            CHECK(emax == 0, "%s: light exactly parallel must give exactly 0, got %.4g", name, emax);
        ts_cells_free(&c);
        rl_solution_destroy(sol);
        sol = NULL;
        if (pass == 0) {
            ts_set_sampling(s, RL_METHOD_CULLED, 16, 2, 16, 1, 0);
            sol = ts_relight(s, name);
            long total;
            CHECK(sol && ts_bad_values(sol, &total) == 0, "%s: descend: values not finite", name);
        }
    }
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

/* A polygon from explicit vertices. */
static tpoly poly4(const char *mat, const double v[4][3])
{
    tpoly p = {mat, 4, {{0}}};
    memcpy(p.v, v, 4 * sizeof v[0]);
    return p;
}

static void check_grazing(void)
{
    const double d = 1e-12;
    tpoly floor = ts_rect_z("grey", 0, -1, 2, 1, 0.0, 1); /* 2 m floor facing up, x in [0, 2] */
    /* A wall at x = -0.5 facing +x whose top edge lies in the floor's plane:
     * light reaching the floor from it would travel exactly parallel to the
     * floor, so there is none. */
    const double wall0[4][3] = {{-0.5, -1, -1}, {-0.5, 1, -1}, {-0.5, 1, 0}, {-0.5, -1, 0}};
    tpoly w = poly4("light", wall0);
    grazing_case("parallel to the receiver (exact)", &w, &floor, 0.25, 0, 0, 1);
    /* the wall's top 1e-12 m above the floor's plane: rays within 2e-12 rad of it */
    const double wall1[4][3] = {{-0.5, -1, -1}, {-0.5, 1, -1}, {-0.5, 1, d}, {-0.5, -1, d}};
    w = poly4("light", wall1);
    grazing_case("1e-12 rad to the receiver's plane", &w, &floor, 0.25, 1e-9, 0, 0);
    /* An emitter at z = 1 facing down and a wall at x = 1 facing -x rising from
     * the emitter's plane: light would leave exactly parallel to the emitter. */
    tpoly lamp = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    const double rec0[4][3] = {{1, 1, 1}, {1, -1, 1}, {1, -1, 3}, {1, 1, 3}};
    tpoly r = poly4("grey", rec0);
    grazing_case("parallel to the emitter (exact)", &lamp, &r, 0.25, 0, 0, 1);
    const double rec1[4][3] = {{1, 1, 1 - d}, {1, -1, 1 - d}, {1, -1, 3}, {1, 1, 3}};
    r = poly4("grey", rec1);
    grazing_case("1e-12 rad to the emitter's plane", &lamp, &r, 0.25, 1e-9, 0, 0);
    /* The emitter shares an edge with the receiver: a 1 m emitter at z = 1
     * facing down over x in [-1, 0], a wall at x = 0 facing -x from z = 0 to 1.
     * The integrand has a log singularity along the edge: the reference uses
     * 16 x 16 points per cell. */
    tpoly shelf = ts_rect_z("light", -1, -0.5, 0, 0.5, 1.0, 0);
    const double wall2[4][3] = {{0, 0.5, 0}, {0, -0.5, 0}, {0, -0.5, 1}, {0, 0.5, 1}};
    r = poly4("grey", wall2);
    grazing_case("shared edge", &shelf, &r, 0.125, 0, 0.05, 0);
    /* the same, the wall folded to 1e-12 rad short of the emitter's plane (nearly coplanar) */
    const double wall3[4][3] = {{0, 0.5, 1}, {0, -0.5, 1}, {1, -0.5, 1 - d}, {1, 0.5, 1 - d}};
    r = poly4("grey", wall3);
    grazing_case("shared edge, folded to 1e-12 rad", &shelf, &r, 0.125, 1e-9, 0, 0);
}

/*
 * A sliver emitter over a floor of cells. It is 1e-6 rad wide seen from the
 * floor and 50 degrees long: no partition leaf is that thin, and descent
 * stops before it would need more than 65536 leaves (docs/methods.md), so
 * culled cells see it with the plain method's k rays per solid angle, which
 * almost surely all miss it with descent off: those maps are checked for
 * finiteness and culled == naive only, and their error is printed. With
 * descent (the default) each cell gathers it by Lambert's formula times
 * sampled visibility, within 2% of Lambert (RMSE) at the default k = 4 (k = 1 is printed); an unoccluded point query is Lambert's
 * formula itself (1e-6). Area and solid-angle sampling are checked too.
 */
static void sliver_emitter(const tpoly *lamp, const tpoly *floor)
{
    tpoly p[2] = {*lamp, *floor};
    rl_scene *s = scene_of("sliver_emitter", 1.0, p, 2, "\"radiance_maps\": {\"cell_size\": 0.25}");
    if (!s)
        return;
    ts_emitter em = {&p[0], 1.0};
    rl_solution *sol = culled_equals_naive(s, "sliver emitter", 16, 2);
    if (sol) {
        ts_errors e = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), &em, 1, 16);
        printf("sliver emitter (aspect 1.01e-6)    culled n=16 k=2 : max error %.4g W/m2 = %.3g%% of the peak %.4g "
               "(not bounded: thinner than any leaf)\n",
               e.max, 100 * e.max / e.peak, e.peak);
    }
    rl_solution_destroy(sol);
    /* with descent (the default), cells gather a constant emitter by Lambert's formula times visibility */
    for (uint32_t k = 1; k <= 4; k *= 4) {
        ts_set_sampling(s, RL_METHOD_CULLED, 16, k, 16, 1, 0);
        sol = ts_relight(s, "sliver emitter, descend");
        if (!sol)
            continue;
        ts_errors e = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), &em, 1, 16);
        printf("sliver emitter (aspect 1.01e-6)    culled k=%u descend: RMSE %.3g%%, max %.3g%% of the peak %.4g\n", k,
               100 * e.rmse / e.peak, 100 * e.max / e.peak, e.peak);
        CHECK(k < 4 || e.rmse < 0.02 * e.peak, "sliver emitter, culled with descent, k=%u: RMSE %.3g of peak %.3g", k,
              e.rmse, e.peak);
        rl_solution_destroy(sol);
    }
    const rl_method methods[2] = {RL_METHOD_AREA, RL_METHOD_SOLIDANGLE};
    for (int m = 0; m < 2; m++) {
        ts_set_sampling(s, methods[m], 16, 2, 256, 1, 0);
        sol = ts_relight(s, "sliver emitter");
        if (!sol)
            continue;
        long total;
        CHECK(ts_bad_values(sol, &total) == 0, "sliver emitter %s: values not finite", rl_method_name(methods[m]));
        ts_errors e = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), &em, 1, 16);
        printf("sliver emitter (aspect 1.01e-6)    %-10s 256   : RMSE %.3g%%, max %.3g%% of the peak %.4g\n",
               rl_method_name(methods[m]), 100 * e.rmse / e.peak, 100 * e.max / e.peak, e.peak);
        CHECK(e.max < 0.05 * e.peak, "sliver emitter %s: max error %.3g of peak %.3g", rl_method_name(methods[m]),
              e.max, e.peak);
        rl_solution_destroy(sol);
    }
    const double pts[2][6] = {{0, 0, 0, 0, 0, 1}, {0.3, 0.2, 0, 0, 0, 1}};
    ts_set_sampling(s, RL_METHOD_CULLED, 32, 16, 16, 1, 0);
    double out[6] = {NAN, NAN, NAN, NAN, NAN, NAN};
    CHECK(rl_irradiance(s, &ts_job, &pts[0][0], 2, out, NULL) == RL_OK, "sliver points: %s", rl_errmsg());
    for (int q = 0; q < 2; q++) {
        double up[3] = {0, 0, 1}, ref = ts_reference_point(&em, 1, pts[q], up);
        printf("sliver emitter (aspect 1.01e-6)    culled point %d  : %.6g vs Lambert %.6g (rel %.2g)\n", q,
               out[3 * q], ref, fabs(out[3 * q] - ref) / ref);
        CHECK(isfinite(out[3 * q]) && fabs(out[3 * q] - ref) < 1e-6 * ref, "sliver point %d: %.6g vs %.6g", q,
              out[3 * q], ref);
    }
    rl_scene_destroy(s);
}

/*
 * Slivers. The loader merges vertices closer than 1e-6 of a polygon's
 * diameter (docs/scene.md, steps 2 and 5), so a rectangle of aspect 1e-6 is
 * refused as degenerate, by design; one of aspect 1.01e-6, just above that
 * tolerance, loads. With it: a 1 m x 1.01e-6 m emitter over a 1 m floor,
 * and a 1 m emitter over a 1 m x 1.01e-6 m receiver (cells of 0.25 m x
 * 1.01e-6 m). The sliver emitter subtends less than a solid angle, which is
 * what descent is for: the bound is that of the descended result.
 */
static void check_slivers(void)
{
    tpoly at_tol = ts_rect_z("light", -0.5, -0.5e-6, 0.5, 0.5e-6, 1.0, 0);
    char path[700], mats[512];
    snprintf(path, sizeof path, "%s/stability_sliver_1e-6.json", tmpdir);
    materials(mats, sizeof mats, 1.0);
    rl_scene *s = NULL;
    if (ts_write_scene(path, mats, &at_tol, 1, NULL)) {
        rl_status st = rl_scene_load(path, &s);
        CHECK(st == RL_ERR_INPUT && strstr(rl_errmsg(), "polygons[0]: degenerate"),
              "aspect 1e-6: expected the loader to refuse it as degenerate, got %d: %s", (int)st, rl_errmsg());
        rl_scene_destroy(s);
    }
    const double w = 1.01e-6;
    tpoly thin_lamp = ts_rect_z("light", -0.5, -0.5 * w, 0.5, 0.5 * w, 1.0, 0);
    tpoly floor = ts_rect_z("grey", -0.5, -0.5, 0.5, 0.5, 0.0, 1);
    sliver_emitter(&thin_lamp, &floor);
    tpoly lamp = ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0);
    tpoly thin_floor = ts_rect_z("grey", -0.5, -0.5 * w, 0.5, 0.5 * w, 0.0, 1);
    /* measured: RMSE 2.7%, max 5.3% of the peak, as for a full receiver at these settings */
    grazing_case("sliver receiver (aspect 1.01e-6)", &lamp, &thin_floor, 0.25, 0, 0.08, 0);
}

/* --------------------------------------------------------- partition */

/*
 * One small scene at every partition level from 1 to 1024: a 1 m emitter
 * 1 m over a 0.5 m floor of four cells, one ray per (cell, solid angle).
 * culled == naive at every level; the error against Lambert must fall with
 * the level (at most 1.5 times the previous one, allowing for noise) and
 * end below 0.1% of the peak.
 */
static void check_partition_levels(void)
{
    tpoly p[2] = {ts_rect_z("light", -0.5, -0.5, 0.5, 0.5, 1.0, 0), ts_rect_z("grey", -0.25, -0.25, 0.25, 0.25, 0.0, 1)};
    rl_scene *s = scene_of("levels", 1.0, p, 2, "\"radiance_maps\": {\"cell_size\": 0.25}");
    if (!s)
        return;
    ts_emitter em = {&p[0], 1.0};
    double prev = INFINITY, last = INFINITY;
    for (uint32_t n = 1; n <= 1024; n *= 2) {
        char name[32];
        snprintf(name, sizeof name, "partition n=%u", n);
        double t0 = seconds();
        rl_solution *sol = culled_equals_naive(s, name, n, 1);
        if (!sol)
            continue;
        ts_errors e = ts_errors_vs_reference(sol, (size_t)ts_map_of(sol, 1), &em, 1, 16);
        printf("partition n=%-4u (%7u solid angles): RMSE %.4f%%, max %.4f%% of peak (culled and naive, %.2f s)\n", n,
               4 * n * n, 100 * e.rmse / e.peak, 100 * e.max / e.peak, seconds() - t0);
        CHECK(e.rmse <= 1.5 * prev, "n=%u: RMSE %.3g above 1.5 x %.3g at n/2", n, e.rmse, prev);
        prev = e.rmse;
        last = e.rmse / e.peak;
        rl_solution_destroy(sol);
    }
    CHECK(last < 1e-3, "n=1024: RMSE %.3g of peak", last);
    rl_scene_destroy(s);
}

int main(void)
{
    const char *t = getenv("ILF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s", t ? t : "/tmp");
    double t0 = seconds();
    check_radiance_range();
    check_lightfield_range();
    check_mixed_scales();
    check_offset();
    check_grazing();
    check_slivers();
    check_partition_levels();
    printf("stability: %.1f s\n", seconds() - t0);
    return check_report();
}
