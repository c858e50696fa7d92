/*
 * emitter.h - the emitters one pass gathers from: a polygon of constant
 * emission, a receiving polygon re-emitting its last pass (a bounce), or a
 * light field slab. Each carries a frame whose pole is its front normal, so
 * that the partition's hemisphere 0 .. 4m^2-1 is exactly what it emits into.
 */
#ifndef RELIGHT_EMITTER_H
#define RELIGHT_EMITTER_H

#include "maps.h"

typedef enum em_kind {
    EM_CONST, /* polygon of constant emission */
    EM_MAP,   /* receiving polygon re-emitting albedo * E_prev / pi (a bounce) */
    EM_SLAB   /* light field slab */
} em_kind;

/* Where one light field emitter's slab is lit, derived from its radiance to cull by (rl__slab_tables_make()):
 * the engine's, built for each run (rl__slab_tables_new(), owned by the solution), never the scene's. */
typedef struct rl_slab_tables {
    /* Per stored direction of the slab, the box of positions [i0, i1] x [j0, j1] holding all its nonzero
     * radiance (i0 > i1: none). The engine shrinks each solid angle's emitter to it. */
    uint32_t (*support)[4];
    /* Per square of the slab's direction diamond, the box of positions its directions read with their
     * interpolation neighbours, and (lit_words > 0) their bits, lit_words a square. cone_support is in
     * support's allocation. */
    uint32_t (*cone_support)[4];
    uint64_t *cone_bits;
    uint32_t lit_words;
    int owned; /* emitters placing the same slab share one set of tables: the first owns it */
} rl_slab_tables;

/* An emitter: its polygon in world and frame coordinates and where its radiance comes from. */
typedef struct rl_emitter {
    em_kind kind;
    int32_t polygon;      /* scene polygon, -1 for a slab */
    rl_frame frame;       /* partition frame: pole = front normal */
    v3 verts[RL_MAX_POLY_VERTS];
    v2 poly2[RL_MAX_POLY_VERTS];
    rl_halfplane edge[RL_MAX_POLY_VERTS]; /* inside: a x + b y + c >= 0 for each edge of poly2 */
    uint32_t nverts;
    double area;
    float emission[3];         /* EM_CONST */
    const rl_map *map;         /* EM_MAP */
    const rl_lightfield *lf;   /* EM_SLAB */
    const rl_slab_tables *tab; /* EM_SLAB: where its slab is lit (the run's tables) */
    double len_u, len_v;       /* EM_SLAB: edge lengths in the scene */
} rl_emitter;

/* Sets up emitter e from scene polygon k (EM_CONST, or EM_MAP when map is given). */
void rl__emitter_from_polygon(const rl_scene *scene, uint32_t k, const rl_map *map, rl_emitter *e);

/* Sets up emitter e from light field lf, with tab the tables of its slab (borrowed; they outlive e), or NULL:
 * then e gives radiance (rl__emitter_radiance_at) but culls nothing. */
void rl__emitter_from_lightfield(const rl_lightfield *lf, const rl_slab_tables *tab, rl_emitter *e);

/* Radiance leaving emitter e at frame point q in propagation direction d (unit), W sr^-1 m^-2. */
void rl__emitter_radiance_at(const rl_emitter *e, v2 q, v3 d, double out[3]);

/* @return 1 if solid angle id at level lv of light field emitter e
 * certainly carries no radiance (its mask and its neighbours' are clear). */
int rl__emitter_node_dark(const rl_emitter *e, uint32_t lv, uint64_t id);

/* Widens box b = {i0, i1, j0, j1} of slab positions (start from
 * {UINT32_MAX, 0, UINT32_MAX, 0}) to hold box s too, unless s is empty (s[0] > s[1]). */
static inline void rl__box_union(uint32_t b[4], const uint32_t s[4])
{
    if (s[0] > s[1])
        return;
    b[0] = s[0] < b[0] ? s[0] : b[0];
    b[1] = s[1] > b[1] ? s[1] : b[1];
    b[2] = s[2] < b[2] ? s[2] : b[2];
    b[3] = s[3] > b[3] ? s[3] : b[3];
}

/* The most bytes each table of a slab's direction diamond's squares may take
 * (their boxes; their bits, and the bits' per-direction draft): a slab
 * whose table would be larger gets none (rl__slab_tables_make()). */
#define RL_CONE_MAX_BYTES ((uint64_t)16 << 20)

/* A cone of directions covering more squares than this gets no bound: the union would cost more
 * than the samples it spares (rl__emitter_lit_rect()). */
#define RL_CONE_MAX_SQUARES 4096u

/* Slabs of up to this many positions get, besides boxes, the bits of the lit positions (rl__emitter_dark_at()). */
#define RL_LIT_MAX_POSITIONS 4096u

/* Builds in *t the tables of where lf's slab is lit (rl_slab_tables): per stored direction the box of positions
 * holding its nonzero radiance; per square (ia, ib) of the slab's direction
 * diamond, a = l0 / |l|_1 in [(ia - n) / n, (ia - n + 1) / n) and b = l1 /
 * |l|_1 likewise (l the direction in the slab's frame, l2 > 0), the box and
 * the bits of every position that a direction there reads with its
 * interpolation neighbours. A table that would pass RL_CONE_MAX_BYTES is not
 * built: no boxes of squares (cone_support NULL, and then no bits either),
 * or no bits (lit_words 0).
 * @return 0, or -1 when memory runs out (nothing left allocated). */
int rl__slab_tables_make(const rl_lightfield *lf, rl_slab_tables *t);

/* Frees what rl__slab_tables_make() built into t (none built: a no-op). */
void rl__slab_tables_free(rl_slab_tables *t);

/* Builds the tables of every light field emitter of scene, in its order, emitters placing the same slab
 * sharing one set. @return the array (scene->nlightfields entries, rl__slab_tables_destroy()), or NULL when
 * memory runs out. */
rl_slab_tables *rl__slab_tables_new(const rl_scene *scene);

/* Frees the n entries of tables from rl__slab_tables_new(). NULL is a no-op. */
void rl__slab_tables_destroy(rl_slab_tables *tables, size_t n);

/* Gives in r = {s0, s1, t0, t1} (e's frame, m) the rectangle of light field
 * emitter e outside which it sends nothing toward any point of the convex
 * hull of the nx world points x from any point of its frame polygon y (ny
 * vertices): the slab's support over the directions of that cone. There is
 * no bound when a point of x is on or behind the slab's plane, when the slab
 * has no table of squares, or when the cone covers more than
 * RL_CONE_MAX_SQUARES of them.
 * @return 1 with r set, 0 without a bound, -1 when e is dark toward every such point. */
int rl__emitter_lit_rect(const rl_emitter *e, const v3 *x, uint32_t nx, const v2 *y, uint32_t ny, double r[4]);

/* Tells whether light field emitter e certainly reads zero at frame point q
 * along propagation direction l = (l0, l1, l2) in its frame (l2 > 0): no tap
 * that lfio's bilinear interpolation takes there is lit along any direction
 * mixed in l's square of the diamond (rl__slab_tables_make()). It
 * cannot tell when the slab has no bits (or e has no tables: a view's emitter,
 * which reads radiance without culling), or when l lies within rounding of a
 * square's side.
 * @return 1 if dark, 0 if it may be lit. */
static inline int rl__emitter_dark_at(const rl_emitter *e, v2 q, double l0, double l1, double l2)
{
    const rl_lightfield *lf = e->lf;
    const rl_slab_tables *tab = e->tab;
    if (tab == NULL || tab->lit_words == 0)
        return 0;
    double inv = (double)lf->n / (fabs(l0) + fabs(l1) + l2), ga = l0 * inv + lf->n, gb = l1 * inv + lf->n;
    if (!(ga >= 0.0 && gb >= 0.0 && ga < 2.0 * lf->n && gb < 2.0 * lf->n))
        return 0;
    uint32_t ia = (uint32_t)ga, ib = (uint32_t)gb;
    /* lfio finds the direction from the slab's own frame, equal to e's to rounding (the edges and the
     * transform's rotation are orthogonal to 1e-9): within 1e-6 of a side on the diamond (n times that in
     * squares) it may place it in the next square */
    const double margin = 1e-6 * lf->n;
    if (ga - ia < margin || ga - ia > 1.0 - margin || gb - ib < margin || gb - ib > 1.0 - margin)
        return 0;
    uint32_t nu = lf->nu, nv = lf->nv, i0, j0;
    /* the taps as lfio_slab_radiance_interp() finds them, from the same arithmetic */
    lfio_grid_split(q.x / e->len_u * nu - 0.5, nu - 1.0, &i0);
    lfio_grid_split(q.y / e->len_v * nv - 0.5, nv - 1.0, &j0);
    uint32_t i1 = i0 + 1 < nu ? i0 + 1 : i0, j1 = j0 + 1 < nv ? j0 + 1 : j0;
    uint32_t p[4] = {j0 * nu + i0, j0 * nu + i1, j1 * nu + i0, j1 * nu + i1};
    const uint64_t *bits = tab->cone_bits + ((size_t)ib * 2 * lf->n + ia) * tab->lit_words;
    uint64_t any = 0;
    for (int k = 0; k < 4; k++)
        any |= bits[p[k] / 64] >> (p[k] % 64);
    return !(any & 1);
}

/* Gives in r = {s0, s1, t0, t1} (e's frame, m) the rectangle of light field
 * emitter e outside which positions b = {i0, i1, j0, j1} read zero. */
void rl__emitter_support_rect(const rl_emitter *e, const uint32_t b[4], double r[4]);

/* @return 1 if frame point q lies in e's convex polygon. */
static inline int rl__emitter_contains(const rl_emitter *e, v2 q)
{
    int inside = 1;
    for (uint32_t i = 0; i < e->nverts; i++) /* no early exit: one branch per sample, not one per edge */
        inside &= e->edge[i].a * q.x + e->edge[i].b * q.y + e->edge[i].c >= 0;
    return inside;
}

#endif /* RELIGHT_EMITTER_H */
