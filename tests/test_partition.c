/*
 * test_partition.c - the sphere partition, checked by exhaustive round trips
 * and by geometry computed independently of the lookup.
 *
 * The central check: every direction lies inside the spherical triangle
 * that lfio_part_id() names, tested with the triangle's own edge planes.
 * The transcribed pseudocode's product test fails it for about half of all
 * directions; the corrected sum passes it everywhere, including on axes,
 * octant borders, triangle edges and corners, -0.0, subnormal and huge
 * components. Without arguments the test covers n = 1..64 and powers of two
 * to 512 exhaustively; with --extremes it covers n up to 4096 (sums over
 * every id) and ids beyond 2^31.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "lfio/partition.h"

#define PI 3.14159265358979323846

/* splitmix64: a small, fixed, reproducible generator for test directions. */
static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
static double rng_unit(void) { return (rng_next() >> 11) * (1.0 / 9007199254740992.0); }

/* A uniformly random unit direction. */
static void random_dir(double d[3])
{
    double z = 2.0 * rng_unit() - 1.0, phi = 2.0 * PI * rng_unit(), r = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = r * cos(phi);
    d[1] = r * sin(phi);
    d[2] = z;
}

static void cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* @return the smallest signed distance-like margin of unit-ised d to the
 * three edge planes of the triangle v (counter-clockwise): >= 0 inside. */
static double inside_margin(const double v[3][3], const double d[3])
{
    double len = sqrt(dot(d, d)), u[3] = {d[0] / len, d[1] / len, d[2] / len}, m = INFINITY;
    for (int k = 0; k < 3; k++) {
        double c[3];
        cross(v[k], v[(k + 1) % 3], c);
        m = fmin(m, dot(c, u) / sqrt(dot(c, c)));
    }
    return m;
}

/* @return 1 if lookup of d at level n gives an id whose triangle contains d. */
static int lookup_contains(uint32_t n, const double d[3], uint64_t *id_out)
{
    uint64_t id;
    double v[3][3], scaled[3];
    if (!lfio_part_id(n, d, &id) || !lfio_part_vertices(n, id, v))
        return 0;
    if (id_out)
        *id_out = id;
    /* scale into a range where the margin arithmetic itself is exact enough */
    double m = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2])));
    for (int k = 0; k < 3; k++)
        scaled[k] = d[k] / m;
    return inside_margin(v, scaled) >= -1e-12;
}

/* Kahan-compensated sum, so the sum's own error stays far below 1e-12. */
typedef struct { double sum, c; } ksum;
static void kadd(ksum *k, double x)
{
    double y = x - k->c, t = k->sum + y;
    k->c = (t - k->sum) - y;
    k->sum = t;
}

/* Exhaustive checks over every id of level n. full = also per-id geometry. */
static void check_level(uint32_t n, int full)
{
    uint64_t count = lfio_part_count(n);
    const double pole[3] = {0, 0, 1};
    ksum omega = {0, 0}, proj = {0, 0};
    long bad_round = 0, bad_orient = 0, bad_nb = 0, bad_children = 0;
    CHECK(count == 8ull * n * n, "n=%u count=%llu", n, (unsigned long long)count);
    CHECK(lfio_part_hemi_count(n) == 4ull * n * n, "n=%u", n);
    for (uint64_t id = 0; id < count; id++) {
        double v[3][3], c[3];
        uint64_t back;
        lfio_part_vertices(n, id, v);
        lfio_part_centroid(n, id, c);
        kadd(&omega, lfio_part_solid_angle(n, id));
        if (id < lfio_part_hemi_count(n))
            kadd(&proj, lfio_part_projected_solid_angle(n, id, pole));
        if (!lfio_part_id(n, c, &back) || back != id)
            bad_round++;
        if (!full)
            continue;
        double bc[3];
        cross(v[1], v[2], bc);
        if (!(dot(v[0], bc) > 0.0) || inside_margin(v, c) < 0.0)
            bad_orient++;
        /* neighbours: symmetric, and sharing exactly two corners */
        uint64_t nb[3];
        lfio_part_neighbours(n, id, nb);
        for (int k = 0; k < 3; k++) {
            uint64_t nb2[3];
            double w[3][3];
            lfio_part_neighbours(n, nb[k], nb2);
            lfio_part_vertices(n, nb[k], w);
            int back_link = nb2[0] == id || nb2[1] == id || nb2[2] == id, shared = 0;
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++)
                    shared += fabs(v[a][0] - w[b][0]) + fabs(v[a][1] - w[b][1]) + fabs(v[a][2] - w[b][2]) < 1e-12;
            /* the edge opposite corner k is the one without corner k */
            int has_k = 0;
            for (int b = 0; b < 3; b++)
                has_k |= fabs(v[k][0] - w[b][0]) + fabs(v[k][1] - w[b][1]) + fabs(v[k][2] - w[b][2]) < 1e-12;
            if (!back_link || shared != 2 || has_k || nb[k] == id)
                bad_nb++;
        }
        /* children tile the parent: solid angles add up and parents match */
        if (2 * n <= 512) {
            uint64_t ch[4], par;
            double sum = 0.0, parent_omega = lfio_part_solid_angle(n, id);
            lfio_part_children(n, id, ch);
            for (int k = 0; k < 4; k++) {
                double cc[3];
                sum += lfio_part_solid_angle(2 * n, ch[k]);
                lfio_part_centroid(2 * n, ch[k], cc);
                if (!lfio_part_parent(2 * n, ch[k], &par) || par != id || inside_margin(v, cc) < 0.0)
                    bad_children++;
            }
            if (fabs(sum - parent_omega) > 1e-13 * parent_omega)
                bad_children++;
        }
    }
    CHECK(bad_round == 0, "n=%u: %ld centroids do not look up to their own id", n, bad_round);
    CHECK(fabs(omega.sum - 4 * PI) < 1e-12 * 4 * PI, "n=%u: solid angles sum to %.17g", n, omega.sum);
    CHECK(fabs(proj.sum - PI) < 1e-12 * PI, "n=%u: projected solid angles sum to %.17g", n, proj.sum);
    if (full) {
        CHECK(bad_orient == 0, "n=%u: %ld triangles wrongly wound or centroid outside", n, bad_orient);
        CHECK(bad_nb == 0, "n=%u: %ld bad neighbour links", n, bad_nb);
        CHECK(bad_children == 0, "n=%u: %ld bad parent/child relations", n, bad_children);
    }
}

/* Random directions must land in a triangle that contains them. */
static void check_random(uint32_t n, int samples)
{
    long bad = 0;
    for (int k = 0; k < samples; k++) {
        double d[3];
        random_dir(d);
        if (!lookup_contains(n, d, NULL))
            bad++;
    }
    CHECK(bad == 0, "n=%u: %ld of %d random directions outside their triangle", n, bad, samples);
}

/* The product test from the transcribed pseudocode, kept only to show that
 * the containment check above would catch it. @return the id it gives. */
static uint64_t erratum_id(uint32_t n, const double d[3])
{
    double s = fabs(d[0]) + fabs(d[1]) + fabs(d[2]);
    double x = n * fabs(d[0]) / s, z = n * fabs(d[2]) / s;
    uint32_t xi = (uint32_t)fmin(floor(x), n - 1), zi = (uint32_t)fmin(floor(z), n - 1);
    if (xi + zi > n - 1)
        xi = n - 1 - zi;
    uint64_t id = (uint64_t)zi * (2 * n - zi) + 2 * xi;
    if ((x - xi) * (z - zi) > 1 && xi + zi + 2 <= n)
        id++;
    return id;
}

static void check_erratum_is_caught(void)
{
    const uint32_t n = 16;
    long differ = 0, outside = 0;
    for (int k = 0; k < 20000; k++) {
        double d[3], v[3][3];
        random_dir(d);
        d[0] = fabs(d[0]); d[1] = fabs(d[1]); d[2] = fabs(d[2]); /* positive octant */
        uint64_t good, wrong = erratum_id(n, d);
        lfio_part_id(n, d, &good);
        lfio_part_vertices(n, wrong, v);
        differ += good != wrong;
        outside += inside_margin(v, d) < -1e-12;
    }
    /* the design notes measured 48% at n = 16 */
    CHECK(outside > 8000 && outside < 11000, "the product test should misplace about half, got %ld", outside);
    CHECK(differ == outside, "every id that differs is a misplaced one (%ld vs %ld)", differ, outside);
}

/* Directions on axes, borders, edges and corners, with signed zeros and
 * extreme magnitudes. */
static void check_adversarial(uint32_t n)
{
    long bad = 0, tried = 0;
    const double scales[] = {1.0, 1e-300, 4.9e-324 * 3, 1e300, 1.7e308};
    /* axes and octant borders, every sign including -0.0 */
    const double comps[] = {0.0, -0.0, 1.0, -1.0, 0.5, -0.25};
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
            for (int c = 0; c < 6; c++)
                for (int s = 0; s < 5; s++) {
                    double d[3] = {comps[a] * scales[s], comps[b] * scales[s], comps[c] * scales[s]};
                    if (d[0] == 0 && d[1] == 0 && d[2] == 0) {
                        uint64_t id;
                        CHECK(!lfio_part_id(n, d, &id), "zero direction must be refused");
                        continue;
                    }
                    tried++;
                    bad += !lookup_contains(n, d, NULL);
                }
    /* every lattice corner and edge midpoint of the first octant, mirrored */
    for (uint32_t zi = 0; zi <= n && n <= 64; zi++)
        for (uint32_t xi = 0; xi + zi <= n; xi++)
            for (int half = 0; half < 3; half++)
                for (uint32_t o = 0; o < 8; o++) {
                    double x = xi + (half == 1 ? 0.5 : 0.0), z = zi + (half == 2 ? 0.5 : 0.0);
                    double y = n - x - z;
                    if (y < 0)
                        continue;
                    double d[3] = {(o & 1) ? -x : x, (o & 2) ? -y : y, (o & 4) ? -z : z};
                    if (d[0] == 0 && d[1] == 0 && d[2] == 0)
                        continue;
                    tried++;
                    bad += !lookup_contains(n, d, NULL);
                }
    /* mixtures of extreme magnitudes */
    const double mix[][3] = {{1e308, 1e-308, 0}, {4.9e-324, 4.9e-324, 4.9e-324}, {1e-320, 1, -1e-320},
                             {-1e308, 1e308, -1e308}, {1, 1e-17, 1e-17}, {1e-17, 1e-17, -1}};
    for (size_t k = 0; k < sizeof mix / sizeof mix[0]; k++) {
        tried++;
        bad += !lookup_contains(n, mix[k], NULL);
    }
    CHECK(bad == 0, "n=%u: %ld of %ld adversarial directions outside their triangle", n, bad, tried);
}

static void check_invalid(void)
{
    uint64_t id = 12345, ids[4];
    double w[4], v[3][3];
    const double nan3[3] = {NAN, 0, 1}, inf3[3] = {INFINITY, 0, 0}, zero[3] = {0, -0.0, 0}, ok[3] = {0, 0, 1};
    CHECK(!lfio_part_id(4, nan3, &id) && id == 12345, "NaN refused, output untouched");
    CHECK(!lfio_part_id(4, inf3, &id), "Inf refused");
    CHECK(!lfio_part_id(4, zero, &id), "zero refused");
    CHECK(!lfio_part_id(0, ok, &id), "n = 0 refused");
    CHECK(!lfio_part_id(LFIO_PART_MAX_N + 1, ok, &id), "n too large refused");
    CHECK(!lfio_part_vertices(4, 128, v), "id out of range refused");
    CHECK(lfio_part_solid_angle(4, 128) == 0.0, "solid angle of invalid id is 0");
    CHECK(!lfio_part_parent(3, 0, &id), "odd n has no parent level");
    CHECK(!lfio_part_parent(1, 0, &id), "n = 1 has no parent level");
    CHECK(!lfio_part_children(LFIO_PART_MAX_N, 0, ids), "no level beyond the maximum");
    CHECK(!lfio_part_interp(4, nan3, ids, w), "interp refuses NaN");
    CHECK(lfio_part_count(0) == 0 && lfio_part_hemi_count(0) == 0, "counts of invalid n are 0");
}

/* Interpolation weights: a partition of unity, exact at centroids, halves on
 * edges, and continuous across edges. */
static void check_interp(uint32_t n)
{
    long bad = 0;
    for (int k = 0; k < 5000; k++) {
        double d[3], w[4];
        uint64_t ids[4], id, nb[3];
        random_dir(d);
        lfio_part_interp(n, d, ids, w);
        lfio_part_id(n, d, &id);
        lfio_part_neighbours(n, id, nb);
        double s = w[0] + w[1] + w[2] + w[3];
        if (fabs(s - 1) > 1e-12 || w[0] < -1e-15 || w[1] < 0 || w[2] < 0 || w[3] < 0 || ids[0] != id ||
            ids[1] != nb[0] || ids[2] != nb[1] || ids[3] != nb[2])
            bad++;
    }
    CHECK(bad == 0, "n=%u: %ld bad weight sets", n, bad);
    /* the weights from barycentric coordinates (corners as lfio_part_vertices)
     * are those of the located direction */
    bad = 0;
    for (int k = 0; k < 5000; k++) {
        double d[3], w[4], wb[4], v[3][3], p[3], lam[3], a[3], b[3], c[3], nrm[3];
        uint64_t ids[4];
        random_dir(d);
        lfio_part_interp(n, d, ids, w);
        lfio_part_vertices(n, ids[0], v);
        double l1 = fabs(d[0]) + fabs(d[1]) + fabs(d[2]);
        for (int q = 0; q < 3; q++) {
            double vl1 = fabs(v[q][0]) + fabs(v[q][1]) + fabs(v[q][2]);
            for (int r = 0; r < 3; r++)
                v[q][r] /= vl1;
            p[q] = d[q] / l1;
        }
        for (int r = 0; r < 3; r++) {
            a[r] = v[1][r] - v[0][r];
            b[r] = v[2][r] - v[0][r];
        }
        cross(a, b, nrm);
        double nn = dot(nrm, nrm);
        for (int q = 0; q < 3; q++) { /* lam[q]: the sub-triangle opposite corner q */
            double e1[3], e2[3];
            for (int r = 0; r < 3; r++) {
                e1[r] = v[(q + 1) % 3][r] - p[r];
                e2[r] = v[(q + 2) % 3][r] - p[r];
            }
            cross(e1, e2, c);
            lam[q] = dot(c, nrm) / nn;
        }
        lfio_part_interp_weights(lam, wb);
        for (int q = 0; q < 4; q++)
            bad += fabs(wb[q] - w[q]) > 1e-9;
    }
    CHECK(bad == 0, "n=%u: %ld weights from barycentrics differ from located ones", n, bad);
    /* at a centroid the containing solid angle has all the weight */
    bad = 0;
    for (uint64_t id = 0; id < lfio_part_count(n); id += 7 + lfio_part_count(n) / 100000) {
        double c[3], w[4];
        uint64_t ids[4];
        lfio_part_centroid(n, id, c);
        lfio_part_interp(n, c, ids, w);
        bad += ids[0] != id || fabs(w[0] - 1) > 1e-9;
    }
    CHECK(bad == 0, "n=%u: %ld centroids not exact", n, bad);
    /* across an edge: just inside each of the two triangles, the same value */
    bad = 0;
    for (uint64_t id = 0; id < lfio_part_count(n); id += 5 + lfio_part_count(n) / 50000) {
        double v[3][3];
        uint64_t nb[3];
        lfio_part_vertices(n, id, v);
        lfio_part_neighbours(n, id, nb);
        for (int k = 0; k < 3; k++) {
            const double *a = v[(k + 1) % 3], *b = v[(k + 2) % 3];
            double t = 0.1 + 0.8 * rng_unit(), p[3], inward[3], c[3];
            lfio_part_centroid(n, id, c);
            for (int q = 0; q < 3; q++) {
                p[q] = (1 - t) * a[q] + t * b[q];
                inward[q] = c[q] - p[q];
            }
            double vals[2];
            for (int side = 0; side < 2; side++) {
                double e = side ? -1e-9 : 1e-9, q3[3] = {p[0] + e * inward[0], p[1] + e * inward[1],
                                                         p[2] + e * inward[2]}, w[4];
                uint64_t ids[4];
                lfio_part_interp(n, q3, ids, w);
                /* a smooth test function of the centroid ids: its value at id */
                vals[side] = 0;
                for (int m = 0; m < 4; m++)
                    vals[side] += w[m] * (double)((ids[m] * 2654435761u) % 1000);
            }
            bad += fabs(vals[0] - vals[1]) > 1e-3;
        }
    }
    CHECK(bad == 0, "n=%u: %ld edges where the interpolant jumps", n, bad);
}

/* Ids beyond 2^31 round-trip through their centroids. */
static void check_large_ids(uint32_t n)
{
    long bad = 0;
    uint64_t count = lfio_part_count(n);
    for (int k = 0; k < 20000; k++) {
        uint64_t id = rng_next() % count, back;
        double c[3], v[3][3];
        lfio_part_centroid(n, id, c);
        lfio_part_vertices(n, id, v);
        if (!lfio_part_id(n, c, &back) || back != id || inside_margin(v, c) < 0)
            bad++;
    }
    CHECK(count > (1ull << 31), "n=%u has ids beyond 2^31", n);
    CHECK(bad == 0, "n=%u: %ld large ids fail to round-trip", n, bad);
}

/* Sum over one octant times eight: octants are exact mirror images. */
static void check_octant_sum(uint32_t n)
{
    ksum omega = {0, 0};
    uint64_t nn = (uint64_t)n * n;
    for (uint64_t id = 0; id < nn; id++)
        kadd(&omega, lfio_part_solid_angle(n, id));
    CHECK(fabs(8 * omega.sum - 4 * PI) < 1e-12 * 4 * PI, "n=%u: 8 x octant sum %.17g", n, 8 * omega.sum);
    double lo = INFINITY, hi = 0;
    for (uint64_t id = 0; id < nn; id += 1 + nn / 100000) {
        double w = lfio_part_solid_angle(n, id);
        lo = fmin(lo, w);
        hi = fmax(hi, w);
    }
    CHECK(hi / lo > 4.0 && hi / lo < 5.3, "n=%u: largest/smallest solid angle %.3f", n, hi / lo);
}

/* Strata: indices cover the triangle once, k = 1 passes barycentrics through
 * exactly, corners land where the scheme says, and the weights estimate the
 * solid angle on both planes (the unit corners and the octahedron face). */
static void check_strata(uint32_t n)
{
    lfio_part_strata st;
    double v[3][3], f[3][3];
    for (uint64_t id = 0; id < lfio_part_count(n); id += 1 + id / 3) {
        CHECK(lfio_part_vertices(n, id, v) && lfio_part_face_vertices(n, id, f), "n=%u id=%llu", n,
              (unsigned long long)id);
        for (int c = 0; c < 3; c++) {
            double l1 = fabs(f[c][0]) + fabs(f[c][1]) + fabs(f[c][2]);
            double cosang = (f[c][0] * v[c][0] + f[c][1] * v[c][1] + f[c][2] * v[c][2]) /
                            sqrt(f[c][0] * f[c][0] + f[c][1] * f[c][1] + f[c][2] * f[c][2]);
            CHECK(fabs(l1 - 1.0) < 1e-15 && fabs(cosang - 1.0) < 1e-15, "face corner %d off its ray", c);
        }
        double omega = lfio_part_solid_angle(n, id);
        for (int plane = 0; plane < 2; plane++) {
            for (uint32_t k = 1; k <= 5; k++) {
                CHECK(lfio_part_strata_init(&st, plane ? (const double(*)[3])f : (const double(*)[3])v, k), "init");
                /* many uniform points per stratum: the mean weight sums to the solid angle */
                double sum = 0.0;
                int per = 400;
                for (uint32_t s = 0; s < k * k; s++)
                    for (int j = 0; j < per; j++) {
                        double a = (j % 20 + 0.5) / 20, b = (j / 20 + 0.5) / 20, l[3], d[3], w, lam[3];
                        if (a + b > 1.0) {
                            a = 1.0 - a;
                            b = 1.0 - b;
                        }
                        l[0] = 1.0 - a - b, l[1] = a, l[2] = b;
                        CHECK(lfio_part_strata_sample(&st, s, l, d, &w, lam), "sample");
                        uint64_t got;
                        CHECK(lfio_part_id(n, d, &got) && (got == id || lam[0] < 1e-9 || lam[1] < 1e-9 ||
                                                           lam[2] < 1e-9),
                              "n=%u id=%llu k=%u s=%u: sample outside its solid angle", n, (unsigned long long)id, k, s);
                        if (k == 1)
                            CHECK(lam[0] == l[0] && lam[1] == l[1] && lam[2] == l[2], "k = 1 must pass l through");
                        sum += w / per;
                    }
                CHECK(fabs(sum - omega) < 2e-3 * omega, "n=%u id=%llu k=%u plane %d: %.9g vs %.9g", n,
                      (unsigned long long)id, k, plane, sum, omega);
                double l[3] = {1, 0, 0}, d[3], w;
                CHECK(!lfio_part_strata_sample(&st, k * k, l, d, &w, NULL), "stratum k*k refused");
                CHECK(!lfio_part_strata_centroid(&st, k * k, d, &w), "stratum k*k refused");
                /* the centroid rule: the sample at l = 1/3 to rounding, and its weights sum to about omega */
                double csum = 0.0;
                for (uint32_t s = 0; s < k * k; s++) {
                    const double third[3] = {1.0 / 3, 1.0 / 3, 1.0 / 3};
                    double dc[3], wc, ds[3], ws;
                    CHECK(lfio_part_strata_centroid(&st, s, dc, &wc) && lfio_part_strata_sample(&st, s, third, ds, &ws, NULL),
                          "centroid");
                    CHECK(fabs(dc[0] - ds[0]) + fabs(dc[1] - ds[1]) + fabs(dc[2] - ds[2]) < 1e-14 &&
                              fabs(wc - ws) < 1e-13 * ws,
                          "n=%u k=%u s=%u: centroid off the sample at l = 1/3", n, k, s);
                    csum += wc;
                }
                /* a midpoint rule: close once the strata are small (it overshoots a whole octant by 65%) */
                CHECK(n * k < 15 || fabs(csum - omega) < 0.05 * omega, "centroid weights %.9g vs %.9g", csum, omega);
            }
        }
    }
    /* the numbering: s = r(2k - r) + 2c + upper; corner 0 of an upper stratum is (c+1, r+1) */
    CHECK(lfio_part_vertices(n, 0, v), "vertices");
    lfio_part_strata_init(&st, (const double(*)[3])v, 4);
    for (uint32_t r = 0, s = 0; r < 4; r++)
        for (uint32_t c = 0; c + r < 4; c++)
            for (uint32_t up = 0; up < 2 && c + r + up < 4; up++, s++) {
                double l[3] = {1, 0, 0}, d[3], w, lam[3];
                lfio_part_strata_sample(&st, s, l, d, &w, lam);
                double a = up ? c + 1.0 : c, b = up ? r + 1.0 : r;
                CHECK(fabs(lam[1] - a / 4) < 1e-15 && fabs(lam[2] - b / 4) < 1e-15, "stratum %u at (%g, %g)", s,
                      lam[1] * 4, lam[2] * 4);
            }
    double bad[3][3] = {{NAN, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    CHECK(!lfio_part_strata_init(&st, (const double(*)[3])bad, 2), "non-finite corner refused");
    CHECK(!lfio_part_strata_init(&st, (const double(*)[3])v, 0), "k = 0 refused");
    CHECK(!lfio_part_strata_init(&st, (const double(*)[3])v, LFIO_PART_MAX_STRATA_K + 1), "k too large refused");
    CHECK(!lfio_part_face_vertices(n, lfio_part_count(n), f), "bad id refused");
}

int main(int argc, char **argv)
{
    int extremes = argc > 1 && strcmp(argv[1], "--extremes") == 0;
    if (!extremes) {
        check_invalid();
        check_erratum_is_caught();
        check_strata(1);
        check_strata(3);
        check_strata(8);
        for (uint32_t n = 1; n <= 64; n++) {
            check_level(n, 1);
            check_random(n, 2000);
            check_adversarial(n);
            check_interp(n);
        }
        for (uint32_t n = 128; n <= 512; n *= 2) {
            check_level(n, n <= 256);
            check_random(n, 20000);
            check_adversarial(n);
        }
    } else {
        check_level(1024, 0);
        for (uint32_t n = 2048; n <= 4096; n *= 2) {
            check_octant_sum(n);
            check_random(n, 200000);
            check_adversarial(n);
            check_interp(n);
        }
        check_random(1u << 20, 100000);
        check_large_ids(1u << 16);
        check_large_ids(1u << 20);
        check_large_ids(LFIO_PART_MAX_N);
    }
    return check_report();
}
