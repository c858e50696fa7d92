/*
 * shadow.h - which scene polygons can block the segments between a point
 * and a convex polygon, answered exactly in double precision without rays.
 *
 * A "pyramid" is the set of segments from an apex x to the points of a
 * convex polygon Q (the base): the only segments a shadow ray from x to Q
 * follows. Classifying it against the scene gives one of three answers:
 * FREE (no polygon meets it: every ray would arrive), BLOCKED (one polygon
 * crosses every segment: no ray would), PARTIAL (anything else). FREE and
 * BLOCKED are exact up to double rounding, so an estimator may replace the
 * rays of such a pyramid by their known outcome; PARTIAL only says rays
 * are needed. Polygons whose plane holds the apex, and polygons lying in
 * the base's plane, are never counted: a shadow ray starts past its apex
 * and stops short of its base, so it cannot meet them.
 *
 * Units are world metres. Queries are thread-safe (the index is read-only).
 */
#ifndef RELIGHT_SHADOW_H
#define RELIGHT_SHADOW_H

#include <stddef.h>
#include <stdint.h>

#include "region.h"
#include "scene_internal.h"

typedef struct rl_occluders rl_occluders;

/* Most vertices a pyramid's base may have. */
#define RL_PYRAMID_MAX_BASE (RL_MAX_POLY_VERTS + 8)

typedef enum rl_visibility { VIS_FREE = 0, VIS_PARTIAL = 1, VIS_BLOCKED = 2 } rl_visibility;

/* The segments from apex to the convex polygon base (counter-clockwise or
 * clockwise, planar), as half-spaces: inside when dot(p - apex, side[i]) >= 0
 * for every side and dot(p - base[0], base_n) >= 0 (apex side of the base). */
typedef struct rl_pyramid {
    v3 apex;
    v3 base[RL_PYRAMID_MAX_BASE];
    size_t nbase;
    v3 side[RL_PYRAMID_MAX_BASE];
    v3 base_n;
    v3 lo, hi;  /* bounding box */
    double tol; /* distance below which a plane is taken to hold a point, m */
} rl_pyramid;

/* Builds the index of every polygon of scene. @return RL_OK and *out, or RL_ERR_NOMEM. */
rl_status rl__occluders_new(const rl_scene *scene, rl_occluders **out);

/* Releases the index. NULL is a no-op. */
void rl__occluders_destroy(rl_occluders *o);

/* Prepares pyramid p from apex and base (nbase >= 3 vertices, at most
 * RL_PYRAMID_MAX_BASE); tol as above. @return 0 if the base is degenerate
 * or holds the apex in its plane (then nothing can be said). */
int rl__pyramid_make(v3 apex, const v3 *base, size_t nbase, double tol, rl_pyramid *p);

/* Lists the polygons of o other than skip (-1: none) that meet pyramid p,
 * into list (room for cap). @return the count, or SIZE_MAX when more than
 * cap meet it (then treat the pyramid as PARTIAL and the list as unknown). */
size_t rl__occluders_collect(const rl_occluders *o, const rl_pyramid *p, int32_t skip, uint32_t *list, size_t cap);

/* Classifies pyramid p against the polygons in list (n of them, a superset
 * of those meeting p, as a parent pyramid's list is for its parts); writes
 * those that meet p to out (room for n; may not alias list) and their count
 * to *nout. @return FREE, BLOCKED or PARTIAL. */
rl_visibility rl__occluders_classify(const rl_occluders *o, const rl_pyramid *p, const uint32_t *list, size_t n,
                                 uint32_t *out, size_t *nout);

#endif /* RELIGHT_SHADOW_H */
