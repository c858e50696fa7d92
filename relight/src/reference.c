/*
 * reference.c - the analytic irradiance from an unoccluded polygon.
 *
 * Lambert's formula integrates cos(theta) over the spherical polygon that
 * the emitter subtends; it holds for the part of the emitter above x's
 * tangent plane, so the polygon is clipped there first. Computed in long
 * double: references must be far more accurate than what they judge.
 */
#include "relight/reference.h"

#include <math.h>

#include "region.h"

double rl_reference_polygon_irradiance(const double *verts, size_t count, const double x[3], const double n[3],
                                       double radiance)
{
    if (count < 3 || count > RL_MAX_POLY_VERTS - 1)
        return 0.0;
    v3 p[RL_MAX_POLY_VERTS], c[RL_MAX_POLY_VERTS];
    for (size_t i = 0; i < count; i++)
        p[i] = v3_load(verts + 3 * i);
    v3 xp = v3_load(x), nn = v3_load(n);
    /* the emitter's front must face x */
    v3 ns = v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0]));
    if (!(v3_dot(v3_sub(xp, p[0]), ns) > 0))
        return 0.0;
    size_t m = rl__clip_poly3(p, count, xp, nn, c);
    if (m < 3)
        return 0.0;
    long double total = 0.0L;
    for (size_t i = 0; i < m; i++) {
        v3 a = v3_sub(c[i], xp), b = v3_sub(c[(i + 1) % m], xp);
        long double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
        long double la = sqrtl(ax * ax + ay * ay + az * az), lb = sqrtl(bx * bx + by * by + bz * bz);
        if (la == 0 || lb == 0)
            continue;
        ax /= la; ay /= la; az /= la; bx /= lb; by /= lb; bz /= lb;
        long double gx = ay * bz - az * by, gy = az * bx - ax * bz, gz = ax * by - ay * bx;
        long double s = sqrtl(gx * gx + gy * gy + gz * gz), cth = ax * bx + ay * by + az * bz;
        if (s == 0)
            continue;
        total += atan2l(s, cth) * (gx * n[0] + gy * n[1] + gz * n[2]) / s;
    }
    return (double)(0.5L * radiance * fabsl(total));
}
