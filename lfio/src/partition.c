/*
 * partition.c - the sphere partition of Khanna et al., Appendix A, with the
 * erratum of the design notes applied (the diagonal test is a sum).
 *
 * Every solid angle is a lattice triangle of one octant's face of the
 * octahedron |x|+|y|+|z| = n, projected onto the sphere. A triangle is
 * decoded into a `cell`: octant o, lattice column xi, row zi, and whether it
 * is the upper (inverted) triangle of the parallelogram (xi, zi). All
 * geometry is done on integer lattice points, which makes the solid angles
 * exact to rounding: every lattice triangle has the same triple product, n.
 *
 * Corner order: the canonical corners are C0 = the corner whose two edges
 * run along x and z ((xi,zi) for lower, (xi+1,zi+1) for upper), then C1 and
 * C2 such that (x, z) of C0, C1, C2 turn counter-clockwise. Seen from outside
 * the sphere, that order is clockwise in octants with an even number of
 * negative signs, so there C1 and C2 are swapped before anything is
 * returned; neighbours and weights are swapped with them.
 *
 * Strata (lfio_part_strata_*) cut a solid angle's planar triangle the same
 * way the partition cuts an octant's face, so a stratum's index is found
 * in constant time and every stratum has the same planar area.
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "lfio/partition.h"

typedef struct cell {
    uint32_t oct;    /* octant, bit 0: x<0, bit 1: y<0, bit 2: z<0 */
    uint32_t xi, zi; /* parallelogram cell, xi + zi <= n-1 */
    uint32_t upper;  /* 0: lower triangle, 1: upper (needs xi + zi <= n-2) */
} cell;

/* @return 1 if n is a supported level. */
static int valid_n(uint32_t n)
{
    return n >= 1 && n <= LFIO_PART_MAX_N;
}

/* @return the id of cell c at level n. */
static uint64_t encode(uint32_t n, cell c)
{
    uint64_t nn = (uint64_t)n * n;
    return c.oct * nn + (uint64_t)c.zi * (2u * (uint64_t)n - c.zi) + 2u * (uint64_t)c.xi + c.upper;
}

/* Decodes id at level n. @return 1, or 0 if n or id is invalid. */
static int decode(uint32_t n, uint64_t id, cell *c)
{
    if (!valid_n(n))
        return 0;
    uint64_t nn = (uint64_t)n * n;
    if (id >= 8u * nn)
        return 0;
    uint64_t local = id % nn;
    /* Row zi is the largest z with z*(2n - z) <= local; the square root
     * guesses it and the loops repair the last unit of rounding. */
    double guess = (double)n - sqrt((double)nn - (double)local);
    uint64_t z = guess <= 0.0 ? 0 : (uint64_t)guess;
    if (z > n - 1u)
        z = n - 1u;
    while (z > 0 && z * (2u * (uint64_t)n - z) > local)
        z--;
    while (z + 1 < n && (z + 1) * (2u * (uint64_t)n - z - 1) <= local)
        z++;
    uint64_t r = local - z * (2u * (uint64_t)n - z);
    c->oct = (uint32_t)(id / nn);
    c->zi = (uint32_t)z;
    c->xi = (uint32_t)(r / 2);
    c->upper = (uint32_t)(r & 1u);
    return 1;
}

/* @return 1 if the canonical corner order must swap C1 and C2 to turn
 * counter-clockwise seen from outside (an even number of mirrorings). */
static int needs_swap(cell c)
{
    uint32_t negatives = (c.oct & 1u) + ((c.oct >> 1) & 1u) + ((c.oct >> 2) & 1u);
    return (negatives & 1u) == 0;
}

/* Gives the canonical lattice corners (x, z) of c. */
static void lattice_corners(cell c, double xz[3][2])
{
    double x = c.xi, z = c.zi;
    if (!c.upper) {
        xz[0][0] = x;     xz[0][1] = z;
        xz[1][0] = x + 1; xz[1][1] = z;
        xz[2][0] = x;     xz[2][1] = z + 1;
    } else {
        xz[0][0] = x + 1; xz[0][1] = z + 1;
        xz[1][0] = x;     xz[1][1] = z + 1;
        xz[2][0] = x + 1; xz[2][1] = z;
    }
}

/* Gives the canonical corners of c as unsigned lattice points (x, n-x-z, z). */
static void lattice_points(uint32_t n, cell c, double p[3][3])
{
    double xz[3][2];
    lattice_corners(c, xz);
    for (int k = 0; k < 3; k++) {
        p[k][0] = xz[k][0];
        p[k][1] = (double)n - xz[k][0] - xz[k][1];
        p[k][2] = xz[k][1];
    }
}

/* Applies c's octant signs to vector p. */
static void apply_signs(cell c, double p[3])
{
    if (c.oct & 1u) p[0] = -p[0];
    if (c.oct & 2u) p[1] = -p[1];
    if (c.oct & 4u) p[2] = -p[2];
}

/* Scales p to unit length. */
static void normalise(double p[3])
{
    double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    p[0] /= len;
    p[1] /= len;
    p[2] /= len;
}

/* Swaps two doubles-triples, or ids, when the public corner order differs. */
static void swap3(double a[3], double b[3])
{
    for (int k = 0; k < 3; k++) {
        double t = a[k];
        a[k] = b[k];
        b[k] = t;
    }
}

/* Gives the neighbours of c across the edges opposite its canonical corners. */
static void canonical_neighbours(uint32_t n, cell c, cell nb[3])
{
    for (int k = 0; k < 3; k++) {
        nb[k] = c;
        nb[k].upper = !c.upper;
    }
    if (!c.upper) {
        /* opposite C0: the diagonal; beyond the octant's hypotenuse y = 0 */
        if (c.xi + c.zi + 2 > n) { nb[0].upper = 0; nb[0].oct ^= 2u; }
        /* opposite C1: the edge x = xi */
        if (c.xi > 0) nb[1].xi = c.xi - 1; else { nb[1].upper = 0; nb[1].oct ^= 1u; }
        /* opposite C2: the edge z = zi */
        if (c.zi > 0) nb[2].zi = c.zi - 1; else { nb[2].upper = 0; nb[2].oct ^= 4u; }
    } else {
        /* inverted triangles are always surrounded by lower ones of the octant */
        nb[1].xi = c.xi + 1;
        nb[2].zi = c.zi + 1;
    }
}

/* Finds the cell containing direction d and the planar lattice point (x, z).
 * @return 1, or 0 if n is invalid or d is zero or not finite. */
static int locate(uint32_t n, const double d[3], cell *c, double *px, double *pz)
{
    if (!valid_n(n) || !isfinite(d[0]) || !isfinite(d[1]) || !isfinite(d[2]))
        return 0;
    double ax = fabs(d[0]), ay = fabs(d[1]), az = fabs(d[2]);
    double m = fmax(ax, fmax(ay, az));
    if (m == 0.0)
        return 0;
    /* Dividing by the largest component first keeps huge components from
     * overflowing the sum and subnormal ones from losing all precision. */
    ax /= m;
    ay /= m;
    az /= m;
    double sum = ax + ay + az;
    double x = (double)n * (ax / sum), z = (double)n * (az / sum);
    uint32_t xi = x >= n ? n - 1 : (uint32_t)x;
    uint32_t zi = z >= n ? n - 1 : (uint32_t)z;
    c->oct = (d[0] < 0) | ((d[1] < 0) << 1) | ((d[2] < 0) << 2);
    if ((uint64_t)xi + zi > n - 1u) {
        /* on the hypotenuse x + z = n (or past it by rounding): the lower
         * triangle of the last cell in row zi touches it there */
        xi = n - 1u - zi;
        c->upper = 0;
    } else {
        double fx = x - xi, fz = z - zi;
        c->upper = (fx + fz > 1.0) && ((uint64_t)xi + zi + 2 <= n);
    }
    c->xi = xi;
    c->zi = zi;
    *px = x;
    *pz = z;
    return 1;
}

uint64_t lfio_part_count(uint32_t n)
{
    return valid_n(n) ? 8u * (uint64_t)n * n : 0;
}

uint64_t lfio_part_hemi_count(uint32_t n)
{
    return valid_n(n) ? 4u * (uint64_t)n * n : 0;
}

int lfio_part_id(uint32_t n, const double d[3], uint64_t *id)
{
    cell c;
    double x, z;
    if (!locate(n, d, &c, &x, &z))
        return 0;
    *id = encode(n, c);
    return 1;
}

int lfio_part_vertices(uint32_t n, uint64_t id, double v[3][3])
{
    cell c;
    if (!decode(n, id, &c))
        return 0;
    lattice_points(n, c, v);
    for (int k = 0; k < 3; k++) {
        apply_signs(c, v[k]);
        normalise(v[k]);
    }
    if (needs_swap(c))
        swap3(v[1], v[2]);
    return 1;
}

int lfio_part_centroid(uint32_t n, uint64_t id, double out[3])
{
    cell c;
    double p[3][3];
    if (!decode(n, id, &c))
        return 0;
    lattice_points(n, c, p);
    for (int k = 0; k < 3; k++)
        out[k] = p[0][k] + p[1][k] + p[2][k];
    apply_signs(c, out);
    normalise(out);
    return 1;
}

double lfio_part_solid_angle(uint32_t n, uint64_t id)
{
    cell c;
    double p[3][3];
    if (!decode(n, id, &c))
        return 0.0;
    /* Van Oosterom and Strackee on unnormalised lattice points: the triple
     * product of any lattice triangle on x+y+z = n is exactly n, and the dot
     * products are exact integers below 2^53, so only the three square roots
     * and the final arithmetic round. */
    lattice_points(n, c, p);
    double len[3], dot01 = 0, dot02 = 0, dot12 = 0;
    for (int k = 0; k < 3; k++)
        len[k] = sqrt(p[k][0] * p[k][0] + p[k][1] * p[k][1] + p[k][2] * p[k][2]);
    for (int a = 0; a < 3; a++) {
        dot01 += p[0][a] * p[1][a];
        dot02 += p[0][a] * p[2][a];
        dot12 += p[1][a] * p[2][a];
    }
    double den = len[0] * len[1] * len[2] + dot01 * len[2] + dot02 * len[1] + dot12 * len[0];
    return 2.0 * atan2((double)n, den);
}

double lfio_part_projected_solid_angle(uint32_t n, uint64_t id, const double axis[3])
{
    double v[3][3];
    if (!lfio_part_vertices(n, id, v))
        return 0.0;
    /* Lambert's edge formula: (1/2) sum over edges of the arc angle times
     * the axis component of the edge plane's unit normal. Long double
     * because small triangles far from the axis cancel terms of order h to
     * a result of order h^2. */
    long double total = 0.0L;
    for (int k = 0; k < 3; k++) {
        const double *a = v[k], *b = v[(k + 1) % 3];
        long double cx = (long double)a[1] * b[2] - (long double)a[2] * b[1];
        long double cy = (long double)a[2] * b[0] - (long double)a[0] * b[2];
        long double cz = (long double)a[0] * b[1] - (long double)a[1] * b[0];
        long double cross = sqrtl(cx * cx + cy * cy + cz * cz);
        long double dot = (long double)a[0] * b[0] + (long double)a[1] * b[1] + (long double)a[2] * b[2];
        if (cross == 0.0L)
            continue;
        long double angle = atan2l(cross, dot);
        total += angle * (cx * axis[0] + cy * axis[1] + cz * axis[2]) / cross;
    }
    return (double)(0.5L * total);
}

int lfio_part_parent(uint32_t n, uint64_t id, uint64_t *parent)
{
    cell c;
    if ((n & 1u) || !decode(n, id, &c))
        return 0;
    uint32_t bx = c.xi & 1u, bz = c.zi & 1u;
    cell p = {c.oct, c.xi >> 1, c.zi >> 1, 0};
    /* The centre child is inverted relative to its parent: an upper child
     * at odd offsets (0,0) sits in a lower parent, and a lower child at (1,1)
     * in an upper parent. */
    if (c.upper)
        p.upper = (bx | bz) ? 1u : 0u;
    else
        p.upper = (bx & bz) ? 1u : 0u;
    *parent = encode(n / 2, p);
    return 1;
}

int lfio_part_children(uint32_t n, uint64_t id, uint64_t child[4])
{
    cell c;
    if (!valid_n(n) || (uint64_t)n * 2 > LFIO_PART_MAX_N || !decode(n, id, &c))
        return 0;
    uint32_t x = 2 * c.xi, z = 2 * c.zi, o = c.oct, m = 2 * n;
    if (!c.upper) {
        child[0] = encode(m, (cell){o, x, z, 0});
        child[1] = encode(m, (cell){o, x + 1, z, 0});
        child[2] = encode(m, (cell){o, x, z + 1, 0});
        child[3] = encode(m, (cell){o, x, z, 1});
    } else {
        child[0] = encode(m, (cell){o, x + 1, z, 1});
        child[1] = encode(m, (cell){o, x, z + 1, 1});
        child[2] = encode(m, (cell){o, x + 1, z + 1, 1});
        child[3] = encode(m, (cell){o, x + 1, z + 1, 0});
    }
    return 1;
}

int lfio_part_neighbours(uint32_t n, uint64_t id, uint64_t nb[3])
{
    cell c, cn[3];
    if (!decode(n, id, &c))
        return 0;
    canonical_neighbours(n, c, cn);
    for (int k = 0; k < 3; k++)
        nb[k] = encode(n, cn[k]);
    if (needs_swap(c)) {
        uint64_t t = nb[1];
        nb[1] = nb[2];
        nb[2] = t;
    }
    return 1;
}

/* Gives the interpolation weights at barycentric coordinates lam of one
 * triangle: w[0] for the triangle, w[k+1] for its neighbour across the edge
 * opposite corner k. The formulas are symmetric in the corners, so any
 * corner order serves as long as lam and the neighbours share it. */
static void interp_weights(const double lam_in[3], double w[4])
{
    double lam[3], sum = 0.0;
    for (int k = 0; k < 3; k++) {
        /* clamped against rounding at edges (NaN becomes 0); comparisons
         * rather than fmin/fmax, which are calls in this hot path */
        double x = lam_in[k];
        lam[k] = x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0;
        sum += lam[k];
    }
    if (!(sum > 0.0)) {
        lam[0] = lam[1] = lam[2] = 1.0;
        sum = 3.0;
    }
    double inv = 1.0 / sum;
    for (int k = 0; k < 3; k++)
        lam[k] *= inv;
    /* Edge k's neighbour gets half weight on edge k (where lam[k] = 0) and
     * none on the other edges: g[k] = product of the other two coordinates.
     * The factor h vanishes at the centroid, so the centre value is exact. */
    double g[3] = {lam[1] * lam[2], lam[0] * lam[2], lam[0] * lam[1]};
    double gsum = g[0] + g[1] + g[2];
    double h = 1.0 - 27.0 * lam[0] * lam[1] * lam[2];
    double scale = gsum > 0.0 ? 0.5 * h / gsum : 0.0;
    for (int k = 0; k < 3; k++) {
        if (gsum > 0.0)
            w[k + 1] = scale * g[k];
        else /* at a corner: the two edges meeting there share the value */
            w[k + 1] = lam[k] > 0.5 ? 0.0 : 0.25;
    }
    /* rounding must not leave the centre a negative weight: interpolated
     * radiance has to stay >= 0 */
    double w0 = 1.0 - w[1] - w[2] - w[3];
    w[0] = w0 > 0.0 ? w0 : 0.0;
}

void lfio_part_interp_weights(const double lam[3], double w[4])
{
    interp_weights(lam, w);
}

int lfio_part_interp(uint32_t n, const double d[3], uint64_t ids[4], double w[4])
{
    cell c, cn[3];
    double x, z;
    if (!locate(n, d, &c, &x, &z))
        return 0;
    /* barycentric coordinates on the planar lattice triangle, canonical corner order */
    double fx = x - c.xi, fz = z - c.zi, lam[3];
    if (!c.upper) {
        lam[0] = 1.0 - fx - fz; lam[1] = fx; lam[2] = fz;
    } else {
        lam[0] = fx + fz - 1.0; lam[1] = 1.0 - fx; lam[2] = 1.0 - fz;
    }
    interp_weights(lam, w);
    canonical_neighbours(n, c, cn);
    ids[0] = encode(n, c);
    for (int k = 0; k < 3; k++)
        ids[k + 1] = encode(n, cn[k]);
    if (needs_swap(c)) {
        uint64_t ti = ids[2]; ids[2] = ids[3]; ids[3] = ti;
        double tw = w[2]; w[2] = w[3]; w[3] = tw;
    }
    return 1;
}

/* ---------------------------------------------------------------- strata */

int lfio_part_face_vertices(uint32_t n, uint64_t id, double v[3][3])
{
    if (!lfio_part_vertices(n, id, v))
        return 0;
    /* Scaled from the unit corners, not built from the lattice, so that the
     * corners are the ones relight has always sampled (bit for bit). */
    for (int k = 0; k < 3; k++) {
        double l1 = fabs(v[k][0]) + fabs(v[k][1]) + fabs(v[k][2]);
        for (int c = 0; c < 3; c++)
            v[k][c] /= l1;
    }
    return 1;
}

int lfio_part_strata_init(lfio_part_strata *st, const double p[3][3], uint32_t k)
{
    if (st == NULL || p == NULL || k < 1 || k > LFIO_PART_MAX_STRATA_K)
        return 0;
    for (int a = 0; a < 3; a++)
        for (int c = 0; c < 3; c++)
            if (!isfinite(p[a][c]))
                return 0;
    memcpy(st->p, p, sizeof st->p);
    /* det(p0, p1, p2) as p0 . (p1 x p2), the order relight has always used */
    double x = p[1][1] * p[2][2] - p[1][2] * p[2][1];
    double y = p[1][2] * p[2][0] - p[1][0] * p[2][2];
    double z = p[1][0] * p[2][1] - p[1][1] * p[2][0];
    double jac = 0.5 * fabs(p[0][0] * x + p[0][1] * y + p[0][2] * z);
    st->jac = jac / ((double)k * k);
    st->k = k;
    return 1;
}

/* Finds stratum s of k*k: lattice cell (c, r) and whether it is the upper triangle. @return 0 if s >= k*k. */
static int stratum_cell(uint32_t k, uint32_t s, uint32_t *c, uint32_t *r, uint32_t *upper)
{
    if ((uint64_t)s >= (uint64_t)k * k)
        return 0;
    /* row r holds 2(k - r) - 1 strata and starts at r(2k - r) = k*k - (k - r)^2 */
    uint64_t left = (uint64_t)k * k - s; /* in [1, k*k] */
    uint32_t q = (uint32_t)sqrt((double)left);
    while ((uint64_t)q * q > left)
        q--;
    while ((uint64_t)(q + 1) * (q + 1) <= left)
        q++;
    uint32_t width = (uint64_t)q * q == left ? q : q + 1; /* ceil(sqrt(left)) = k - r */
    *r = k - width;
    uint32_t t = s - (uint32_t)((uint64_t)*r * (2u * k - *r));
    *c = t / 2;
    *upper = t % 2;
    return 1;
}

/* Lattice point p0 + (p1 - p0) i/k + (p2 - p0) j/k of st's triangle (capture's arithmetic, kept bit for bit). */
static void lattice_point(const lfio_part_strata *st, uint32_t i, uint32_t j, double out[3])
{
    for (int a = 0; a < 3; a++)
        out[a] = st->p[0][a] + (st->p[1][a] - st->p[0][a]) * i / st->k + (st->p[2][a] - st->p[0][a]) * j / st->k;
}

int lfio_part_strata_centroid(const lfio_part_strata *st, uint32_t s, double dir[3], double *weight)
{
    uint32_t c, r, upper;
    if (!stratum_cell(st->k, s, &c, &r, &upper))
        return 0;
    double A[3], B[3], C[3];
    /* the corners in the order their sum has always been taken */
    lattice_point(st, c + 1, r, B);
    lattice_point(st, c, r + 1, C);
    if (!upper) {
        lattice_point(st, c, r, A);
        for (int a = 0; a < 3; a++)
            A[a] = (A[a] + B[a] + C[a]) / 3.0;
    } else {
        lattice_point(st, c + 1, r + 1, A);
        for (int a = 0; a < 3; a++)
            A[a] = (B[a] + C[a] + A[a]) / 3.0;
    }
    double len = sqrt(A[0] * A[0] + A[1] * A[1] + A[2] * A[2]);
    for (int a = 0; a < 3; a++)
        dir[a] = A[a] / len;
    *weight = st->jac / (len * len * len);
    return 1;
}

int lfio_part_strata_sample(const lfio_part_strata *st, uint32_t s, const double l[3], double dir[3], double *weight,
                            double lam[3])
{
    uint32_t k = st->k, c, r, upper;
    double g[3];
    if (k == 1) {
        /* one stratum, the whole triangle: every step of the general case is exact
         * (c = r = 0, divisions by 1), so g = l bit for bit; relight takes this path
         * once per sample, where the stratum search's square root and divisions show */
        if (s != 0)
            return 0;
        memcpy(g, l, sizeof g);
    } else if (!stratum_cell(k, s, &c, &r, &upper)) {
        return 0;
    } else if (!upper) {
        g[0] = ((double)(k - c - r - 1) + l[0]) / k;
        g[1] = (c + l[1]) / k;
        g[2] = (r + l[2]) / k;
    } else {
        g[0] = ((double)(k - c - r - 1) - l[0]) / k;
        g[1] = (c + 1.0 - l[1]) / k;
        g[2] = (r + 1.0 - l[2]) / k;
    }
    double P[3];
    for (int a = 0; a < 3; a++)
        P[a] = (st->p[0][a] * g[0] + st->p[1][a] * g[1]) + st->p[2][a] * g[2];
    double inv = 1.0 / sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2]);
    *weight = st->jac * inv * inv * inv;
    for (int a = 0; a < 3; a++)
        dir[a] = P[a] * inv;
    if (lam != NULL)
        memcpy(lam, g, sizeof g);
    return 1;
}
