/*
 * pair.h - what every method shares for one (emitter, receiver tile) pair
 * (pair.c): the tile, the pair's clipped emitter and level, Minkowski
 * regions on the tile, the domains origins are drawn from, a leaf's
 * samples drawn from an origin, and the packets of shadow rays.
 */
#ifndef RELIGHT_PAIR_H
#define RELIGHT_PAIR_H

#include <string.h>

#include "leaf.h"

/* ------------------------------------------------- pairs, tiles and domains */

/* What one (emitter, receiver tile) pair needs, computed once. */
typedef struct rl_pair {
    const rl_emitter *e;
    v3 sclip[RL_MAX_POLY_VERTS + 2]; /* the emitter clipped to the tile's front half-space */
    size_t ns;
    uint32_t level;
    int descended;  /* the emitter subtends less than a solid angle of level from every corner of the tile */
    double leaves;  /* the most solid angles of level it subtends from a tile corner or its centroid's foot */
    double eps;     /* ray offset at both ends, m */
} rl_pair;

/* The tile: the part of map m in grid rows [row0, row1), as a 2D polygon. */
typedef struct rl_tile {
    rl_map *m;
    uint32_t map_index, row0, row1;
    v2 poly[RL_MAX_POLY_VERTS + 4];
    size_t npoly;
} rl_tile;

/* Cuts t from grid rows [row0, row1) of map m (map_index keys its samples). */
void rl__tile_make(rl_map *m, uint32_t map_index, uint32_t row0, uint32_t row1, rl_tile *t);

/* Sets up pair p for emitter e and tile t; naive and descend 0 keep every
 * pair at partition_n, others mark pairs whose emitter subtends less than a
 * solid angle as descended. @return 0 if they cannot exchange light. */
int rl__pair_setup(const rl_transfer_ctx *ctx, const rl_emitter *e, const rl_tile *t, rl_pair *p);

/* @return the vertex mean of pair p's emitter part in front of its receiver (p->sclip). */
v3 rl__pair_centroid(const rl_pair *p);

/* @return 1 if q lies in the convex polygon poly (n vertices, either turn). */
int rl__convex_contains(const v2 *poly, size_t n, v2 q);

/* Computes the region of node (lv, id) for the emitter polygon src (ns
 * vertices, in front of the tile's plane) and its intersection with the
 * tile into q (room for RL_MAX_POLY_VERTS + 4 + RL_REGION_MAX_PLANES).
 * @return the vertex count of that intersection (0: cull). */
size_t rl__node_region(const rl_transfer_ctx *ctx, const rl_pair *p, const v3 *src, size_t ns, const rl_tile *t,
                       uint32_t lv, uint64_t id, rl_region *reg, v2 *q);

/* Where the origins of a cell are drawn: the cell's polygon. */
typedef struct rl_origin_domain {
    v2 poly[RL_MAX_POLY_VERTS + 8];
    uint32_t n;
    int square;            /* a full square: sampled from its corner and side alone */
    rl_polygon_sampler ps; /* otherwise: poly prepared for sampling (points into this struct: never copy one) */
} rl_origin_domain;

/* Fills d for cell of map m. */
void rl__cell_domain(const rl_map *m, uint32_t cell, rl_origin_domain *d);

/* @return the map coordinates of an origin in domain d of map m from two numbers in [0, 1). */
static inline v2 rl__domain_uv(const rl_map *m, const rl_origin_domain *d, double a, double b)
{
    return d->square ? (v2){d->poly[0].x + a * m->cell, d->poly[0].y + b * m->cell}
                     : rl__polygon_sampler_point(&d->ps, a, b);
}

/* @return a world origin in domain d of map m from two numbers in [0, 1). */
static inline v3 rl__domain_point(const rl_map *m, const rl_origin_domain *d, double a, double b)
{
    return frame_point(&m->frame, rl__domain_uv(m, d, a, b));
}

/* ------------------------------------------------------------- shadow rays */

/* Shadow rays waiting to be traced as one packet, each with the radiance
 * it carries and the accumulator it adds to when unoccluded. Rays are added
 * to their accumulators in the order they were pushed, so results do not
 * depend on how rays are grouped into packets. Set n = 0 before use. */
typedef struct rl_ray_batch {
    size_t n;
    v3 org[RL_RAY_PACKET], dir[RL_RAY_PACKET];
    double tnear[RL_RAY_PACKET], tfar[RL_RAY_PACKET];
    double l[RL_RAY_PACKET][3];
    double *acc[RL_RAY_PACKET];
} rl_ray_batch;

/* Traces the pending rays of b and adds the unoccluded ones' radiance. */
void rl__batch_flush(const rl_transfer_ctx *ctx, rl_ray_batch *b, rl_counters *cnt);

/* Queues a shadow ray from org along unit dir over [tnear, tfar] carrying l into acc. */
static inline void rl__batch_push(const rl_transfer_ctx *ctx, rl_ray_batch *b, v3 org, v3 dir, double tnear,
                                  double tfar, const double l[3], double *acc, rl_counters *cnt)
{
    if (b->n == RL_RAY_PACKET)
        rl__batch_flush(ctx, b, cnt);
    size_t i = b->n++;
    b->org[i] = org;
    b->dir[i] = dir;
    b->tnear[i] = tnear;
    b->tfar[i] = tfar;
    memcpy(b->l[i], l, sizeof b->l[i]);
    b->acc[i] = acc;
}

/* Queues the ray back from receiver point x (normal nr) along -d to the
 * pair's emitter, carrying the radiance sampled in leaf L (may be NULL) at
 * barycentrics lam times weight w and the cosine at x, into acc; a ray that
 * misses the emitter's polygon or carries nothing is counted, never traced.
 * wd (NULL: from lam) gives a shared direction's slab interpolation weights. */
void rl__shoot_back(const rl_transfer_ctx *ctx, const rl_pair *p, v3 x, v3 nr, v3 d, double w, const rl_leaf *L,
                    const double lam[3], const double *wd, double *acc, rl_ray_batch *b, rl_counters *cnt);

/* Draws the direction of one sample of leaf L from origin x, informed by
 * the emitter for a constant one: d over the whole leaf when every direction
 * of it reaches the emitter (*lp = L), else uniform in the part of the
 * emitter the leaf sees (*lp = NULL, *w that solid angle). @return 0 when
 * the leaf sees nothing of the emitter from x. */
int rl__leaf_draw(const rl_pair *p, const rl_leaf *L, v3 x, double u1, double u2, v3 *d, double *w, double lam[3],
                  const rl_leaf **lp);

#endif /* RELIGHT_PAIR_H */
