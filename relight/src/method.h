/*
 * method.h - the interface every transfer method implements, and the pieces
 * the methods share.
 *
 * A method adds to the cells of one receiver tile the irradiance arriving
 * from one emitter (rl_method_impl.gather). transfer.c cuts tiles, walks the
 * emitters and picks the method through rl__method_for(); each method lives
 * in a file of its own:
 *
 *   method_culled.c    culled and naive: the partition's solid angles of the
 *                      pair, culled by projected Minkowski regions (culled)
 *                      or all of them (naive), k rays per (cell, leaf)
 *   method_adaptive.c  culled's leaves, each refined while its estimate is
 *                      uncertain
 *   method_baseline.c  area and solidangle sampling of the emitter
 *
 * and they share: leaves (leaf.c: a solid angle prepared for sampling),
 * pairs, tiles, origin domains and shadow-ray packets (pair.c), and the
 * estimator that replaces leaves where leaves are the wrong tool (views.c:
 * Lambert's formula times visibility for a constant emitter, and times the
 * weighted mean of radiance * visibility for an emitter smaller than a
 * solid angle).
 *
 * Invariants: every estimate is a function of its arguments only (random
 * numbers come from low-discrepancy sequences keyed by seed, pass, emitter,
 * receiver, cell, level and leaf), so results do not depend on threads or on
 * how rays are grouped into packets; culled and naive run the same code per
 * (cell, leaf), so they agree bit for bit wherever no pair descends.
 */
#ifndef RELIGHT_METHOD_H
#define RELIGHT_METHOD_H

#include <string.h>

#include <lfio/partition.h>

#include "sampling.h"
#include "transfer.h"

/* ------------------------------------------------------------------ leaves */

/* Leaves from this level on are sampled on their planar lattice triangle and
 * weighted by the Jacobian to the sphere, which varies by less than 1.5x
 * within one of them: far cheaper than Arvo's warp (no trigonometry) for
 * a negligible rise in variance. Coarser leaves (an octant's Jacobian
 * spans 5.2x) keep the uniform warp. */
#define RL_PLANAR_MIN_LEVEL 4

/* Most directions a mixing leaf draws once for all its cells (rl__leaf_share()). */
#define RL_LEAF_SHARED 16

/* A leaf's shared direction seen from one receiver plane: what its samples
 * need that their origins do not change (rl__leaf_plan()). The affine maps
 * take an origin's map coordinates (u, v) as c[0] + c[1] u + c[2] v. */
typedef struct rl_shared_plan {
    int live;            /* the direction leaves the emitter's front and arrives at the receiver's */
    v3 back;             /* the ray's direction, toward the emitter */
    double tnear, tshort; /* the ray starts tnear past its origin and stops tshort short of the emitter */
    double scale;        /* the cosine at the receiver times the direction's weight */
    double t[3];         /* the distance to the emitter's plane along back */
    double qx[3], qy[3]; /* where the ray lands, in the emitter's frame */
    double gu[3], gv[3]; /* blend: where it lands in the slab's grid coordinates (lfio_blend_grid) */
} rl_shared_plan;

/* A solid angle of emitter e's partition prepared for sampling: its
 * directions and their weights, its sample key, and for a light field the
 * slab-level interpolation its samples read. */
typedef struct rl_leaf {
    uint32_t lv;
    uint64_t id;
    double omega;         /* exact solid angle, sr */
    uint64_t key;         /* hash of (seed, pass, emitter, receiver, level, id) */
    int planar;
    sph_tri tri;          /* !planar: Arvo's warp; every sample weighs omega */
    v3 p[3];              /* planar: the lattice triangle's corners (|x|+|y|+|z| = 1 in e's frame), world */
    lfio_part_strata st;  /* planar: the triangle's one stratum (lfio_part_strata_sample weighs each direction) */
    int reach;            /* every corner direction leaves the emitter's front (p[k] . n > 0) */
    v2 land[3];           /* then: corner k from origin x lands at project(x) - h(x) * land[k] on the emitter */
    int mix;              /* planar, light field, at or below the slab's level: lfio_slab_radiance_mix() */
    double to_slab[3][3]; /* mix: the slab-level triangle's barycentrics from the leaf's */
    uint64_t ids[4];      /* mix: the slab-level solid angle holding the leaf, then its neighbours */
    uint32_t nshared;     /* mix: directions drawn once for every cell (rl__leaf_share()), or 0 */
    v3 sd[RL_LEAF_SHARED];          /* their directions, */
    double sw[RL_LEAF_SHARED];      /* weights */
    double swd[RL_LEAF_SHARED][4];  /* and slab interpolation weights of ids */
    rl_shared_plan plan[RL_LEAF_SHARED]; /* each shared direction seen from the current receiver plane */
    uint32_t box[4];      /* blend: the slab positions outside which ids read zero, or which no origin reaches */
    const float *blend;   /* their mix for each shared direction, times its plan's scale (rl__leaf_blend()), or NULL */
    size_t blend_stride;  /* floats from one shared direction's table to the next */
    lfio_blend_grid grid; /* blend: the tables' grid */
    double grect[4];      /* blend: {gu0, gu1, gv0, gv1} in grid coordinates, within the slab, outside which it reads 0 */
} rl_leaf;

/* Prepares solid angle id at level lv of emitter e (index ei) for receiver map map_index. */
void rl__leaf_make(const rl_transfer_ctx *ctx, const rl_emitter *e, uint32_t ei, uint32_t map_index, uint32_t lv,
                   uint64_t id, rl_leaf *L);

/* @return a direction in leaf L from u1, u2 in [0, 1); *w its weight (the
 * inverse of its density, so that the mean of w is the solid angle) and,
 * for planar leaves, lam its barycentric coordinates on the triangle. */
v3 rl__leaf_sample(const rl_leaf *L, double u1, double u2, double *w, double lam[3]);

/* For a mixing leaf of light field e: the rectangle of the slab outside which every
 * sample of L reads zero radiance, as 4 world corners (e's vertex order).
 * @return 1, 0 when L cannot say (use the whole emitter), -1 when L reads only zeros. */
int rl__leaf_support(const rl_emitter *e, const rl_leaf *L, v3 out[4]);

/* Radiance leaving light field e at frame point q for a sample of mixing leaf
 * L at barycentrics lam, read through the slab-level interpolation. */
void rl__leaf_radiance_mix(const rl_emitter *e, v2 q, const rl_leaf *L, const double lam[3], double out[3]);

/* The same for a direction whose slab interpolation weights wd (of L->ids) are known. */
void rl__leaf_radiance_weighted(const rl_emitter *e, v2 q, const rl_leaf *L, const double wd[4], double out[3]);

/* Draws k directions of mixing leaf L once, from coordinates 0 and 1 of
 * L's own sequence, for every cell to share (each cell pairs them with
 * origins from coordinates 2 and 3 of its own): each sample taken alone has
 * the distribution it had, a cell's k pairs still form a shifted 4-D
 * sequence, and the direction's weight and slab interpolation are worked
 * out k times per leaf instead of k per cell. A leaf that does not mix, or
 * k above RL_LEAF_SHARED, keeps nshared 0. @return nshared. */
uint32_t rl__leaf_share(rl_leaf *L, uint32_t k);

/* Works out L->plan for the shared directions of L seen from the receiver
 * plane rf (origin offsets eps, m), for the shared samples of method_culled.c. */
void rl__leaf_plan(rl_leaf *L, const rl_emitter *e, const rl_frame *rf, double eps);

/* @return the slab positions in box = {i_min, i_max, j_min, j_max} (inclusive). */
static inline size_t rl__box_positions(const uint32_t box[4])
{
    return ((size_t)box[1] - box[0] + 1) * ((size_t)box[3] - box[2] + 1);
}

/* @return how many floats rl__leaf_blend() needs for the shared directions
 * of L (planned, rl__leaf_plan()) seen from origins in the map rectangle
 * from = {u0, u1, v0, v1}, 0 when L reads only zeros or does not share.
 * Sets L->box, the slab positions where L is nonzero that those origins'
 * samples reach, and L->plan's landings in the slab's grid coordinates. */
size_t rl__leaf_blend_size(const rl_emitter *e, rl_leaf *L, const double from[4]);

/* Mixes the slab's directions for each shared direction of L over L->box
 * (rl__leaf_blend_size(), before) into tables (that many floats), which L
 * then reads: radiance times the direction's plan scale.
 * @return 0, or -1 if lfio refused (L then reads the slab as before). */
int rl__leaf_blend(const rl_emitter *e, rl_leaf *L, float *tables);

/* Radiance leaving e at frame point q in propagation direction d; L (may be
 * NULL) and lam, when L mixes, give the direction's slab interpolation directly. */
static inline void rl__leaf_radiance(const rl_emitter *e, v2 q, v3 d, const rl_leaf *L, const double lam[3],
                                     double out[3])
{
    if (e->kind == EM_CONST) {
        for (int c = 0; c < 3; c++)
            out[c] = e->emission[c];
    } else if (L && L->mix) {
        rl__leaf_radiance_mix(e, q, L, lam, out);
    } else {
        rl__emitter_radiance_at(e, q, d, out);
    }
}

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

/* ------------------------------------ shadows of a leaf's shared directions */

/* One polygon's shadow along one shared direction, on the receiver's map:
 * convex, edges[first .. first+n) as half-planes (inside: >= 0). */
typedef struct rl_shadow_poly {
    double ulo, uhi, vlo, vhi;
    uint32_t first, n;
} rl_shadow_poly;

/* The shadows of the current (tile, leaf) (leaf_shadow.c), per thread. */
typedef struct rl_shadows {
    int known; /* 1: a sample's origin in no shadow of its direction arrives, in one is stopped */
    uint32_t nshared;
    rl_shadow_poly *polys; /* direction i's: polys[start[i] .. start[i+1]) */
    size_t npolys, cap_polys;
    rl_halfplane *edges;
    v2 *verts;       /* the shadows' corners, edges[e] running from verts[e] */
    double *du_dv;   /* edge e's change of u per unit of v (0 when level): rows cross it by a multiply */
    size_t nedges, cap_edges, cap_verts, cap_slopes;
    uint32_t start[RL_LEAF_SHARED + 1];
    struct rl_shadow_span {
        uint32_t poly;
        double ulo, uhi; /* its extent within the current row */
    } *active;       /* the current row's: direction i's active[row_first[i] ..] (row_count[i]), by ulo */
    size_t active_cap;
    uint32_t row_first[RL_LEAF_SHARED], row_count[RL_LEAF_SHARED];
    uint32_t *cand; /* the polygons collected for the pair's beam */
} rl_shadows;

/* Works out s->shadows for leaf L (its shared directions planned) from
 * tile t, or from the part of it within the map rectangle within = {u0, u1,
 * v0, v1} (NULL: all of it), which must hold every origin whose sample can
 * carry light; s->shadows->known = 0 when nothing can be said and rays
 * must tell. @return 0, or -1 without memory. */
int rl__shadows_build(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, const rl_leaf *L,
                      const double *within, rl_scratch *s);

/* Selects the shadows that meet the map rectangle [ulo, uhi] x [vlo, vhi]
 * (one row's cells), each with its extent in u within [vlo, vhi]. */
void rl__shadows_row(rl_shadows *sh, double ulo, double uhi, double vlo, double vhi);

/* @return 1 if map point uv lies in a selected shadow of shared direction i. */
static inline int rl__shadowed(const rl_shadows *sh, uint32_t i, v2 uv)
{
    for (uint32_t k = 0; k < sh->row_count[i]; k++) {
        const struct rl_shadow_span *sa = &sh->active[sh->row_first[i] + k];
        if (uv.x < sa->ulo)
            return 0; /* and so do the spans after it, in order of ulo */
        if (uv.x > sa->uhi)
            continue;
        const rl_shadow_poly *sp = &sh->polys[sa->poly];
        int inside = 1;
        for (uint32_t e = 0; e < sp->n; e++) {
            const rl_halfplane *h = &sh->edges[sp->first + e];
            inside &= h->a * uv.x + h->b * uv.y + h->c >= 0;
        }
        if (inside)
            return 1;
    }
    return 0;
}

/* Frees sh. NULL is a no-op. */
void rl__shadows_free(rl_shadows *sh);

/* ------------------------------------------------------- exact estimators */

/* An emitter that subtends fewer solid angles of partition_n than this
 * from a receiver tile (rl_pair.leaves) is gathered by Lambert's formula
 * under culled and naive when descend is on: leaves a few solid angles
 * across are mostly half empty, while the area-weighted mean is noisy only
 * for a near, large emitter (docs/methods.md has the measurements). */
#define RL_LAMBERT_LEAVES 64.0

/* Lambert's formula times the weighted mean of radiance * visibility, for
 * every cell of the tile: a constant emitter, or one a few solid angles
 * across (views.c). Blocks of cells that see all of the emitter or none of
 * it (shadow.h) take the rays' outcome without tracing them.
 * @return 0, or -1 if s ran out of memory. */
int rl__gather_lambert(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, uint32_t ei, rl_scratch *s,
                       rl_counters *cnt);

/* ------------------------------------------------------- the leaf family */

/* How a solid-angle method treats each kept leaf of a pair (method_culled.c
 * runs the family; culled, naive and adaptive differ in these). */
typedef struct rl_leaf_rows {
    int culls;       /* walk and cull the hierarchy (else every leaf of the pair's level) */
    int lambert;     /* a constant emitter under descend: Lambert times visibility instead of leaves */
    int shares;      /* a light field's leaf draws its directions once for all cells (rl__leaf_share()) */
    int shadows;     /* and their visibility comes from their shadows (leaf_shadow.c), not rays, where known */
    int stages;      /* 1, or 2: stage 0 measures every cell, stage 1 estimates */
    /* Before the stages: prepares s for tile t. @return 0 or -1. NULL: nothing. */
    int (*prepare)(rl_scratch *s, const rl_tile *t);
    /* Adds leaf L's light to cells i0..i1 of grid row j. @return 0 or -1 (memory). */
    int (*row)(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, const rl_leaf *L, uint32_t ei,
               uint32_t j, uint32_t i0, uint32_t i1, rl_scratch *s, int stage, rl_counters *cnt);
} rl_leaf_rows;

/* Gathers emitter ei into tile t by the leaves of their pair, each row of
 * cells handed to rows->row. @return 0, or -1 if memory ran out. */
int rl__leaves_gather(const rl_transfer_ctx *ctx, const rl_tile *t, uint32_t ei, rl_scratch *s, rl_counters *cnt,
                      const rl_leaf_rows *rows);

/* ------------------------------------------------------------- the methods */

/* One transfer method. */
typedef struct rl_method_impl {
    rl_method id;
    /* 1: a point receiver gathers from its own view of each emitter (rl__point_gather) */
    int point_view;
    /* Adds to the tile's cells the irradiance from emitter ei. @return 0, or -1 if memory ran out. */
    int (*gather)(const rl_transfer_ctx *ctx, const rl_tile *t, uint32_t ei, rl_scratch *s, rl_counters *cnt);
} rl_method_impl;

extern const rl_method_impl rl__method_culled, rl__method_naive, rl__method_adaptive, rl__method_area,
    rl__method_solidangle;

/* @return the implementation of method id, or NULL if there is none. */
const rl_method_impl *rl__method_for(rl_method id);

#endif /* RELIGHT_METHOD_H */
