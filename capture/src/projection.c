/*
 * projection.c - pixel <-> direction maps of the three probe projections,
 * exact pixel solid angles, stratified directions inside a partition solid
 * angle, and the rotation check (capture/projection.h).
 *
 * Invariants: every direction returned is unit length and finite; every
 * solid angle is >= 0; the inverse maps give coordinates inside [0, W] x
 * [0, H] for any nonzero finite direction, so interpolation never reads
 * outside an image; nothing here allocates or keeps state.
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "capture/projection.h"
#include "internal.h"
#include "lfio/partition.h"
#include "probe.h"

/* Midpoint-rule resolution inside the disc and on its rim (cap_projection_solid_angle). */
#define INTERIOR_RULE 4
#define RIM_RULE 16

const char *cap_projection_name(cap_projection p)
{
    switch (p) {
    case CAP_PROJECTION_EQUIRECTANGULAR:
        return "equirectangular";
    case CAP_PROJECTION_MIRROR_BALL:
        return "mirror_ball";
    case CAP_PROJECTION_ANGULAR_MAP:
        return "angular_map";
    }
    return "";
}

int cap_projection_parse(const char *name, cap_projection *out)
{
    static const cap_projection all[] = {CAP_PROJECTION_EQUIRECTANGULAR, CAP_PROJECTION_MIRROR_BALL,
                                         CAP_PROJECTION_ANGULAR_MAP};
    if (name == NULL || out == NULL)
        return 0;
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
        if (strcmp(name, cap_projection_name(all[k])) == 0) {
            *out = all[k];
            return 1;
        }
    return 0;
}

const char *cap_projection_check_size(cap_projection p, int width, int height)
{
    if (width < 1 || height < 1)
        return "the image has no pixels";
    if (p != CAP_PROJECTION_EQUIRECTANGULAR && p != CAP_PROJECTION_MIRROR_BALL && p != CAP_PROJECTION_ANGULAR_MAP)
        return "unknown projection";
    if (p != CAP_PROJECTION_EQUIRECTANGULAR && width != height)
        return "mirror ball and angular map images must be square (the disc fills the image)";
    return NULL;
}

/* Disc coordinates (a right, b up, both in [-1, 1]) of image point (px, py). */
static void disc_coordinates(int width, int height, double px, double py, double *a, double *b)
{
    *a = 2.0 * px / width - 1.0;
    *b = 1.0 - 2.0 * py / height;
}

static void equirect_direction(int width, int height, double px, double py, double d[3])
{
    double theta = ILF_PI * py / height, phi = ILF_PI * (1.0 - 2.0 * px / width);
    double st = sin(theta);
    d[0] = st * cos(phi);
    d[1] = st * sin(phi);
    d[2] = cos(theta);
}

static int mirror_ball_direction(double a, double b, double d[3])
{
    double r2 = a * a + b * b;
    if (r2 > 1.0)
        return 0;
    double c = sqrt(1.0 - r2);
    d[0] = 1.0 - 2.0 * c * c;
    d[1] = -2.0 * c * a;
    d[2] = 2.0 * c * b;
    return 1;
}

static int angular_map_direction(double a, double b, double d[3])
{
    double r = sqrt(a * a + b * b);
    if (r > 1.0)
        return 0;
    double theta = ILF_PI * r, st = sin(theta);
    d[0] = cos(theta);
    d[1] = r > 0.0 ? -st * a / r : 0.0;
    d[2] = r > 0.0 ? st * b / r : 0.0;
    return 1;
}

int cap_projection_direction(cap_projection p, int width, int height, double px, double py, double d[3])
{
    if (d == NULL || cap_projection_check_size(p, width, height) != NULL || !(px >= 0.0 && px <= width) ||
        !(py >= 0.0 && py <= height))
        return 0;
    if (p == CAP_PROJECTION_EQUIRECTANGULAR) {
        equirect_direction(width, height, px, py, d);
        return 1;
    }
    double a, b;
    disc_coordinates(width, height, px, py, &a, &b);
    return p == CAP_PROJECTION_MIRROR_BALL ? mirror_ball_direction(a, b, d) : angular_map_direction(a, b, d);
}

/* Disc coordinates of unit direction u for a mirror ball (inverse of mirror_ball_direction). */
static void mirror_ball_locate(const double u[3], double *a, double *b)
{
    double c = sqrt(fmax(0.0, 0.5 * (1.0 - u[0])));
    double side = sqrt(u[1] * u[1] + u[2] * u[2]);
    if (c > 1e-12) {
        *a = -u[1] / (2.0 * c);
        *b = u[2] / (2.0 * c);
    } else {
        /* +x itself: the whole rim shows it; take the rim point along the residual. */
        *a = side > 0.0 ? -u[1] / side : 1.0;
        *b = side > 0.0 ? u[2] / side : 0.0;
    }
}

/* Disc coordinates of unit direction u for an angular map (inverse of angular_map_direction). */
static void angular_map_locate(const double u[3], double *a, double *b)
{
    double r = acos(fmax(-1.0, fmin(1.0, u[0]))) / ILF_PI;
    double side = sqrt(u[1] * u[1] + u[2] * u[2]);
    *a = side > 0.0 ? -r * u[1] / side : r;
    *b = side > 0.0 ? r * u[2] / side : 0.0;
}

/* Clamps v into [0, hi]. */
static double clamp_to(double v, double hi)
{
    return v < 0.0 ? 0.0 : v > hi ? hi : v;
}

int cap_projection_locate(cap_projection p, int width, int height, const double d[3], double *px, double *py)
{
    if (d == NULL || px == NULL || py == NULL || cap_projection_check_size(p, width, height) != NULL)
        return 0;
    double u[3] = {d[0], d[1], d[2]};
    if (!cap__normalise(u))
        return 0;
    double x, y;
    if (p == CAP_PROJECTION_EQUIRECTANGULAR) {
        double theta = acos(fmax(-1.0, fmin(1.0, u[2]))), phi = atan2(u[1], u[0]);
        x = 0.5 * width * (1.0 - phi / ILF_PI);
        y = height * theta / ILF_PI;
    } else {
        double a, b;
        if (p == CAP_PROJECTION_MIRROR_BALL)
            mirror_ball_locate(u, &a, &b);
        else
            angular_map_locate(u, &a, &b);
        x = 0.5 * width * (a + 1.0);
        y = 0.5 * height * (1.0 - b);
    }
    *px = clamp_to(x, width);
    *py = clamp_to(y, height);
    return 1;
}

/* Solid angle per unit of (a, b) disc area at radius r (0 outside the disc). */
static double disc_density(cap_projection p, double r)
{
    if (r > 1.0)
        return 0.0;
    if (p == CAP_PROJECTION_MIRROR_BALL)
        return 4.0;
    return r > 1e-12 ? ILF_PI * sin(ILF_PI * r) / r : ILF_PI * ILF_PI;
}

double cap__disc_density(cap_projection p, int width, int height, double px, double py)
{
    double a, b;
    disc_coordinates(width, height, px, py, &a, &b);
    /* one pixel covers (2/W)(2/H) of disc coordinates */
    return disc_density(p, sqrt(a * a + b * b)) * 4.0 / ((double)width * height);
}

/* Midpoint rule with m x m points over pixel (x, y) of a disc projection. */
static double disc_pixel_rule(cap_projection p, int width, int height, int x, int y, int m)
{
    double sum = 0.0;
    for (int sy = 0; sy < m; sy++)
        for (int sx = 0; sx < m; sx++)
            sum += cap__disc_density(p, width, height, x + (sx + 0.5) / m, y + (sy + 0.5) / m);
    return sum / ((double)m * m);
}

/* @return the smallest and largest disc radius over pixel (x, y), from its corners and the axes it spans. */
static void pixel_radius_range(int width, int height, int x, int y, double *rmin, double *rmax)
{
    double a0, b0, a1, b1;
    disc_coordinates(width, height, x, y, &a0, &b0);
    disc_coordinates(width, height, x + 1, y + 1, &a1, &b1);
    double alo = fmin(fabs(a0), fabs(a1)), ahi = fmax(fabs(a0), fabs(a1));
    double blo = fmin(fabs(b0), fabs(b1)), bhi = fmax(fabs(b0), fabs(b1));
    if (a0 <= 0.0 && a1 >= 0.0)
        alo = 0.0;
    if (b0 >= 0.0 && b1 <= 0.0)
        blo = 0.0;
    *rmin = sqrt(alo * alo + blo * blo);
    *rmax = sqrt(ahi * ahi + bhi * bhi);
}

double cap_projection_solid_angle(cap_projection p, int width, int height, int x, int y)
{
    if (cap_projection_check_size(p, width, height) != NULL || x < 0 || y < 0 || x >= width || y >= height)
        return 0.0;
    if (p == CAP_PROJECTION_EQUIRECTANGULAR)
        return 2.0 * ILF_PI / width * (cos(ILF_PI * y / height) - cos(ILF_PI * (y + 1) / height));
    double rmin, rmax;
    pixel_radius_range(width, height, x, y, &rmin, &rmax);
    if (rmin >= 1.0)
        return 0.0;
    if (rmax <= 1.0 && p == CAP_PROJECTION_MIRROR_BALL)
        return 16.0 / ((double)width * height);
    return disc_pixel_rule(p, width, height, x, y, rmax <= 1.0 ? INTERIOR_RULE : RIM_RULE);
}

/* ---------------------------------------------------------------- samples */

int cap_partition_samples(uint32_t n, uint64_t id, uint32_t k, double *dirs, double *weights)
{
    double v[3][3];
    lfio_part_strata st;
    if (dirs == NULL || weights == NULL || k < 1 || k > 64 || !lfio_part_vertices(n, id, v))
        return 0;
    for (int c = 0; c < 3; c++)
        cap__normalise(v[c]);
    lfio_part_strata_init(&st, (const double(*)[3])v, k);
    st.jac = 1.0; /* relative weights 1/|P|^3, normalised below: bit for bit the ones capture has always used */
    /* each stratum's centroid: a fixed, symmetric rule, the same on every run */
    double total = 0.0;
    for (uint32_t s = 0; s < k * k; s++) {
        lfio_part_strata_centroid(&st, s, &dirs[3 * s], &weights[s]);
        total += weights[s];
    }
    for (uint32_t s = 0; s < k * k; s++)
        weights[s] /= total;
    return 1;
}

int cap_rotation_check(const double R[9])
{
    if (R == NULL)
        return 0;
    for (int a = 0; a < 9; a++)
        if (!isfinite(R[a]))
            return 0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double dot = R[r] * R[c] + R[3 + r] * R[3 + c] + R[6 + r] * R[6 + c];
            if (fabs(dot - (r == c ? 1.0 : 0.0)) > 1e-6)
                return 0;
        }
    double det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                 R[2] * (R[3] * R[7] - R[4] * R[6]);
    return det > 0.0;
}
