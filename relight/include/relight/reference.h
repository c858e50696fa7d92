/*
 * reference.h - closed-form answers the engine is measured against.
 *
 * This header is valid C99 and C++.
 */
#ifndef RELIGHT_REFERENCE_H
#define RELIGHT_REFERENCE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Irradiance (W m^-2) at point x on a surface with unit normal n, from a
 * one-sided Lambertian convex polygon of radiance L with nothing in
 * between: (L/2) * sum over edges of theta_i * (n . g_i) (Lambert), after
 * clipping the polygon to the half-space in front of x. verts: count
 * points (x, y, z), counter-clockwise seen from the emitting side.
 * @return the irradiance; 0 when x is behind the emitter or the emitter
 * is behind x's surface.
 */
double rl_reference_polygon_irradiance(const double *verts, size_t count, const double x[3], const double n[3],
                                       double radiance);

#ifdef __cplusplus
}
#endif

#endif /* RELIGHT_REFERENCE_H */
