/*
 * ilf/vec.h - small 3-vector and 2-vector helpers for every floor.
 * Values by copy, doubles throughout: geometry is computed in double and only
 * ray tracing is handed to Embree's single precision. Header-only static
 * inline functions, so they never become symbols; they keep short names
 * (v3_add, not ilf_v3_add) because they are the vocabulary of every formula.
 */
#ifndef ILF_VEC_H
#define ILF_VEC_H

#include <math.h>
#include <stddef.h>

/* pi, the project's one definition (strict C17 does not provide M_PI). */
#define ILF_PI 3.14159265358979323846

typedef struct v3 { double x, y, z; } v3;
typedef struct v2 { double x, y; } v2;

static inline v3 v3_make(double x, double y, double z) { return (v3){x, y, z}; }
static inline v3 v3_load(const double a[3]) { return (v3){a[0], a[1], a[2]}; }
static inline void v3_store(v3 a, double out[3]) { out[0] = a.x; out[1] = a.y; out[2] = a.z; }
static inline v3 v3_add(v3 a, v3 b) { return (v3){a.x + b.x, a.y + b.y, a.z + b.z}; }
static inline v3 v3_sub(v3 a, v3 b) { return (v3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline v3 v3_scale(v3 a, double s) { return (v3){a.x * s, a.y * s, a.z * s}; }
/* @return a + s*b */
static inline v3 v3_madd(v3 a, v3 b, double s) { return (v3){a.x + s * b.x, a.y + s * b.y, a.z + s * b.z}; }
static inline double v3_dot(v3 a, v3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline v3 v3_cross(v3 a, v3 b)
{
    return (v3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline double v3_len(v3 a) { return sqrt(v3_dot(a, a)); }
/* @return a scaled to unit length (a must be nonzero). */
static inline v3 v3_norm(v3 a) { return v3_scale(a, 1.0 / v3_len(a)); }
/* @return the mean of the n >= 1 points v. */
static inline v3 v3_mean(const v3 *v, size_t n)
{
    v3 c = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        c = v3_add(c, v3_scale(v[i], 1.0 / (double)n));
    return c;
}
/* max and min for hot paths: compiled inline (fmax is a library call
 * unless NaN semantics are waived); a NaN argument yields b. */
static inline double dmax(double a, double b) { return a > b ? a : b; }
static inline double dmin(double a, double b) { return a < b ? a : b; }
static inline double v3_maxabs(v3 a) { return dmax(fabs(a.x), dmax(fabs(a.y), fabs(a.z))); }

/* The same vocabulary for vectors kept as double[3] arrays (file formats,
 * public APIs); a3_cross reads both inputs before writing, so out may alias one. */
static inline double a3_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline double a3_len(const double a[3]) { return sqrt(a3_dot(a, a)); }
static inline void a3_cross(const double a[3], const double b[3], double out[3])
{
    double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2], z = a[0] * b[1] - a[1] * b[0];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

static inline v2 v2_sub(v2 a, v2 b) { return (v2){a.x - b.x, a.y - b.y}; }
/* @return the z component of the cross product (twice the signed area of 0, a, b). */
static inline double v2_cross(v2 a, v2 b) { return a.x * b.y - a.y * b.x; }

#endif /* ILF_VEC_H */
