/*
 * leaf_shadow.h - the shadows of a solid angle's shared directions on a
 * receiver tile (leaf_shadow.c): exact visibility of parallel rays without
 * tracing them.
 */
#ifndef RELIGHT_LEAF_SHADOW_H
#define RELIGHT_LEAF_SHADOW_H

#include "pair.h"

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

#endif /* RELIGHT_LEAF_SHADOW_H */
