/*
 * region.h - convex polygon clipping and the projected Minkowski sum
 * (S + w)_R of the paper, as the intersection of half-planes on R's plane.
 */
#ifndef RELIGHT_REGION_H
#define RELIGHT_REGION_H

#include <stddef.h>

#include <stdint.h>

#include "ilf/vec.h"

/* Largest vertex count of the polygons handled here: scene polygons have at
 * most RL_SCENE_MAX_POLY_VERTS (64), and clipping adds a few. */
#define RL_MAX_POLY_VERTS 72
#define RL_REGION_MAX_PLANES (RL_MAX_POLY_VERTS * 8)

/* A plane frame: points p = origin + u*e1 + v*e2 (+ h*n). */
typedef struct rl_frame {
    v3 origin, e1, e2, n;
} rl_frame;

/* @return the 2D coordinates of world point p in frame f. */
static inline v2 frame_project(const rl_frame *f, v3 p)
{
    v3 r = v3_sub(p, f->origin);
    return (v2){v3_dot(r, f->e1), v3_dot(r, f->e2)};
}

/* @return the world point of 2D coordinates q in frame f. */
static inline v3 frame_point(const rl_frame *f, v2 q)
{
    return v3_madd(v3_madd(f->origin, f->e1, q.x), f->e2, q.y);
}

/* @return the world vector of frame coordinates v (along e1, e2, n): how
 * partition directions, given in an emitter's frame, reach the world. */
static inline v3 frame_vector(const rl_frame *f, const double v[3])
{
    return v3_add(v3_add(v3_scale(f->e1, v[0]), v3_scale(f->e2, v[1])), v3_scale(f->n, v[2]));
}

/* A half-plane a*x + b*y + c >= 0. */
typedef struct rl_halfplane {
    double a, b, c;
} rl_halfplane;

/* @return the half-plane left of the directed edge p -> q, its line included:
 * the inside of a counter-clockwise convex polygon, one edge at a time. */
static inline rl_halfplane edge_halfplane(v2 p, v2 q)
{
    rl_halfplane h = {-(q.y - p.y), q.x - p.x, 0};
    h.c = -(h.a * p.x + h.b * p.y);
    return h;
}

/* The region of R's plane that may receive from S through a cone of
 * directions: the intersection of its half-planes. all = 1 means "the whole
 * plane" (a conservative answer when the geometry is degenerate); empty = 1
 * means nothing can transfer. */
typedef struct rl_region {
    int empty, all;
    size_t count;
    rl_halfplane h[RL_REGION_MAX_PLANES];
} rl_region;

/* Clips the convex 3D polygon p (count vertices) to the half-space
 * dot(x - o, n) >= 0, writing at most count+1 vertices to out.
 * @return the vertex count of the result (0 if nothing remains). */
size_t rl__clip_poly3(const v3 *p, size_t count, v3 o, v3 n, v3 *out);

/* @return the centroid of the convex 2D polygon p (count >= 1 vertices; its first vertex if degenerate). */
v2 rl__polygon_centroid(const v2 *p, uint32_t count);

/* Writes the convex hull of pts (n points, sorted in place) to hull (room
 * for 2n points). @return its vertex count, counter-clockwise. */
size_t rl__convex_hull2(v2 *pts, size_t n, v2 *hull);

/* Clips the convex 2D polygon p to half-plane h, writing at most count+1 vertices.
 * @return the vertex count of the result. */
size_t rl__clip_poly2(const v2 *p, size_t count, rl_halfplane h, v2 *out);

/* Clips the convex 2D polygon p (count vertices) to the counter-clockwise
 * convex polygon clip (nclip vertices), into out; scratch is working space.
 * out and scratch each need room for count + nclip vertices; p may be out.
 * @return the vertex count of the result (0 if they do not overlap). */
size_t rl__clip_to_polygon(const v2 *p, size_t count, const v2 *clip, size_t nclip, v2 *out, v2 *scratch);

/* Clips the convex 2D polygon p (count vertices, at most RL_MAX_POLY_VERTS) to every
 * half-plane of region r, into out (room for RL_MAX_POLY_VERTS + r->count vertices).
 * @return the vertex count (0 if the polygon misses the region). */
size_t rl__clip_to_region(const v2 *p, size_t count, const rl_region *r, v2 *out, size_t out_cap);

/* @return 1 if point q lies in region r. */
int rl__region_contains(const rl_region *r, v2 q);

/*
 * Computes (S + K)_R: the points x of R's plane (frame f, front side along
 * f->n) such that x = y + t*d for some y in S, d in the cone K, t > 0.
 * s: the emitter polygon already clipped to R's front half-space
 * (dot(y - f->origin, f->n) >= 0), ns vertices. k: the cone's generators
 * (unit vectors, propagation directions), nk of them (at most 8), already
 * clipped to dot(d, f->n) <= 0. margin: a distance by which every
 * half-plane is pushed outwards, so that rounding never makes the region
 * smaller than the truth. Directions parallel to R's plane project to
 * infinity; working with homogeneous coordinates keeps every number finite.
 */
void rl__region_compute(const rl_frame *f, const v3 *s, size_t ns, const v3 *k, size_t nk, double margin,
                    rl_region *out);

/* Clips the convex 3D polygon src (n vertices, at most RL_MAX_POLY_VERTS + 2)
 * to the points y seen from x along the cone of propagation directions g[0..3)
 * (x - y a nonnegative combination of g), into out (room for n + 3).
 * @return the vertex count (0 when fewer than 3 remain). */
size_t rl__clip_to_view(v3 x, const v3 g[3], const v3 *src, size_t n, v3 *out);

/* Clips the cone spanned by generators g (count, a convex spherical polygon,
 * at most 6) to dot(d, n) <= 0. @return the generator count of the result. */
size_t rl__clip_cone(const v3 *g, size_t count, v3 n, v3 *out);

#endif /* RELIGHT_REGION_H */
