/*
 * leaf.h - solid angles of an emitter's partition prepared for sampling
 * (leaf.c): their directions and weights, their sample keys, a light
 * field's slab-level interpolation, and the directions a mixing leaf draws
 * once for all the cells of a tile.
 */
#ifndef RELIGHT_LEAF_H
#define RELIGHT_LEAF_H

#include <lfio/partition.h>

#include "pass.h"
#include "sampling.h"

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

#endif /* RELIGHT_LEAF_H */
