/*
 * shadow.h - which scene polygons can block the segments between two convex
 * polygons (or a point and a polygon), answered exactly in double precision
 * without rays.
 *
 * A "beam" is the set of segments from the points of a convex polygon A
 * (the near end; a single point makes it a pyramid with its apex there) to
 * the points of a convex polygon B (the far end): the only segments shadow
 * rays from A to B follow, so the beam is the convex hull of A and B.
 * Classifying it against the scene gives one of three answers: FREE (no
 * polygon meets it: every ray would arrive), BLOCKED (one polygon crosses
 * every segment: no ray would), PARTIAL (anything else). FREE and BLOCKED
 * are exact up to double rounding, so an estimator may replace the rays of
 * such a beam by their known outcome; PARTIAL only says rays are needed.
 * Polygons whose plane holds all of A, and polygons lying in B's plane, are
 * never counted: a shadow ray starts past its near end and stops short of
 * its far end, so it cannot meet them.
 *
 * Units are world metres. Queries are thread-safe (the index is read-only).
 */
#ifndef RELIGHT_SHADOW_H
#define RELIGHT_SHADOW_H

#include <stddef.h>
#include <stdint.h>

#include "region.h"
#include "scene_model.h"

typedef struct rl_occluders rl_occluders;

/* Most vertices either end of a beam may have. */
#define RL_BEAM_MAX_VERTS (RL_MAX_POLY_VERTS + 8)

/* Most faces a beam may have: one per edge of either end, and both ends' planes. */
#define RL_BEAM_MAX_PLANES (2 * RL_BEAM_MAX_VERTS + 2)

typedef enum rl_visibility { VIS_FREE = 0, VIS_PARTIAL = 1, VIS_BLOCKED = 2 } rl_visibility;

/* The segments from convex polygon a to convex polygon b, as half-spaces:
 * inside when dot(p - org[i], nrm[i]) >= 0 for every face i. */
typedef struct rl_beam {
    v3 a[RL_BEAM_MAX_VERTS], b[RL_BEAM_MAX_VERTS];
    size_t na, nb;
    v3 org[RL_BEAM_MAX_PLANES], nrm[RL_BEAM_MAX_PLANES];
    size_t nplanes;
    v3 b_n;     /* unit normal of b's plane, toward a */
    v3 lo, hi;  /* bounding box */
    double tol; /* distance below which a plane is taken to hold a point, m */
} rl_beam;

/* Builds the index of every polygon of scene. @return RL_OK and *out, or RL_ERR_NOMEM. */
rl_status rl__occluders_new(const rl_scene *scene, rl_occluders **out);

/* Releases the index. NULL is a no-op. */
void rl__occluders_destroy(rl_occluders *o);

/* Prepares beam out from the convex planar polygons a (na >= 1 vertices;
 * one: a point) and b (nb >= 3), each at most RL_BEAM_MAX_VERTS; tol as
 * above. @return 0 if b is degenerate or the two span no volume (then
 * nothing can be said). */
int rl__beam_make(const v3 *a, size_t na, const v3 *b, size_t nb, double tol, rl_beam *out);

/* Lists the polygons of o other than skip (-1: none) that meet beam p,
 * into list (room for cap). @return the count, or SIZE_MAX when more than
 * cap meet it (then treat the beam as PARTIAL and the list as unknown). */
size_t rl__occluders_collect(const rl_occluders *o, const rl_beam *p, int32_t skip, uint32_t *list, size_t cap);

/* Tells whether one polygon of o, alone or at a corner with another
 * (rl__occluders_blocks()), crosses every segment from the convex hull of
 * the points a (na) to that of the points b (nb; neither need be planar,
 * each at most RL_BEAM_MAX_VERTS): its plane parts them by more than tol
 * and every crossing lies more than edge (<= tol) inside its edges. It
 * visits only the boxes that the segment between the two hulls' vertex
 * means crosses (one of a corner's two polygons crosses it), and stops at
 * the first such polygon, which it gives in *blocker (unless NULL): the
 * same call on it with rl__occluders_blocks() finds its corner again.
 * @return 1 if one does, 0 if none does (or it cannot tell: nothing is
 * then known). */
int rl__occluders_block_any(const rl_occluders *o, const v3 *a, size_t na, const v3 *b, size_t nb, double tol,
                            double edge, uint32_t *blocker);

/* The same test for polygon k of o: alone, or where the segments cross
 * its plane outside one of its edges only, together with the polygon that
 * shares that edge (the same two vertices) at a corner that turns toward a
 * or toward b (each on that side of the other's plane), as a room's two
 * walls do: then every segment crosses one of the two, or their shared
 * edge, where the tracer may leave a crack no wider than its rounding,
 * which the exact shadows count blocked (leaf_shadow.c, lambert.c). A lamp
 * of a room diagonally off is hidden from most of a room by a corner's two
 * walls, by neither alone. @return 1 if it crosses every such segment. */
int rl__occluders_blocks(const rl_occluders *o, uint32_t k, const v3 *a, size_t na, const v3 *b, size_t nb,
                         double tol, double edge);

/* Gives in *verts polygon k's world vertices (counter-clockwise about its
 * normal). @return their count. */
size_t rl__occluders_polygon(const rl_occluders *o, uint32_t k, const v3 **verts);

/* Classifies beam p against the polygons in list (n of them, a superset
 * of those meeting p, as a parent beam's list is for its parts); writes
 * those that meet p to out (room for n; may not alias list) and their count
 * to *nout. @return FREE, BLOCKED or PARTIAL. */
rl_visibility rl__occluders_classify(const rl_occluders *o, const rl_beam *p, const uint32_t *list, size_t n,
                                 uint32_t *out, size_t *nout);

#endif /* RELIGHT_SHADOW_H */
