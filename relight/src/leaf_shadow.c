/*
 * leaf_shadow.c - exact visibility for the shared directions of a solid
 * angle seen from a receiver tile, without rays.
 *
 * All cells of a tile pair a leaf's shared direction d with their own
 * origins (rl__leaf_share()), so the rays of one direction are parallel:
 * each goes from an origin x on the receiver's plane along b = -d, over
 * [tnear, t(x) - tshort]. A scene polygon P stops the ray from x exactly
 * when P, cut to the points at least tnear * cos_r above the receiver's
 * plane and at least tshort * dn below the emitter's (the ray's interval
 * in those terms), meets the line through x along b: when x lies in the
 * projection of the cut P along b onto the receiver's plane. So for each
 * direction the polygons cast convex shadows on the tile's map, and a
 * sample is blocked exactly when its origin lies in one; nothing is traced.
 *
 * The polygons that can matter are collected once per (tile, leaf) by the
 * beam from the tile to where the leaf's directions from it land on the
 * emitter (shadow.h): a superset of every polygon any of its rays can meet.
 * Culled and naive give the rectangle around the leaf's region on the tile
 * when they know it (an origin outside the region sees only where the leaf
 * reads zero), the same for both, so that they decide alike. When nothing
 * can be said (a leaf
 * grazing the emitter's plane, more polygons than the list holds), the
 * shadows are unknown and the caller traces rays.
 *
 * Exact up to double rounding, where Embree's single precision decides a
 * ray grazing an edge; a point on a shadow's edge counts as blocked.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "leaf_shadow.h"

/* Most polygons one (tile, leaf) may collect before its shadows count as unknown. */
#define SHADOW_CANDIDATES 256u

/* Makes *arr hold need items of size bytes (rl__grow()). @return 0, or -1 with *arr as it was. */
static int reserve(void **arr, size_t *cap, size_t need, size_t size)
{
    void *g = rl__grow(*arr, cap, need, size);
    if (!g)
        return -1;
    *arr = g;
    return 0;
}

void rl__shadows_free(rl_shadows *sh)
{
    if (!sh)
        return;
    free(sh->polys);
    free(sh->edges);
    free(sh->verts);
    free(sh->du_dv);
    free(sh->active);
    free(sh->cand);
    free(sh);
}

/* Writes to out (room for RL_BEAM_MAX_VERTS) where leaf L's directions
 * from the tile polygon a (na world vertices) land on the pair's clipped
 * emitter: the hull of where its corner directions from a's vertices land
 * (landing is affine in the origin and projective in the direction, so
 * every landing point is inside it), clipped to the emitter.
 * @return the vertex count, 0 if nothing can be said. */
static size_t footprint(const rl_pair *p, const rl_leaf *L, const v3 *a, size_t na, v3 *out)
{
    const rl_emitter *e = p->e;
    v2 pts[3 * RL_BEAM_MAX_VERTS], hull[6 * RL_BEAM_MAX_VERTS], src[RL_MAX_POLY_VERTS + 2];
    if (na > RL_BEAM_MAX_VERTS)
        return 0;
    for (size_t i = 0; i < na; i++) {
        v3 rel = v3_sub(a[i], e->frame.origin);
        double h = dmax(v3_dot(rel, e->frame.n), 0.0); /* a is cut to the emitter's front: only rounding is below */
        v2 px = {v3_dot(rel, e->frame.e1), v3_dot(rel, e->frame.e2)};
        for (int k = 0; k < 3; k++)
            pts[3 * i + k] = (v2){px.x - h * L->land[k].x, px.y - h * L->land[k].y};
    }
    size_t nh = rl__convex_hull2(pts, 3 * na, hull);
    if (nh < 3 || nh + p->ns > RL_BEAM_MAX_VERTS)
        return 0;
    for (size_t k = 0; k < p->ns; k++)
        src[k] = frame_project(&e->frame, p->sclip[k]);
    v2 clip[RL_BEAM_MAX_VERTS], tmp[RL_BEAM_MAX_VERTS];
    size_t nc = rl__clip_to_polygon(src, p->ns, hull, nh, clip, tmp);
    for (size_t i = 0; i < nc; i++)
        out[i] = frame_point(&e->frame, clip[i]);
    return nc >= 3 ? nc : 0;
}

/* Adds the shadow of polygon v (n world vertices) along shared direction
 * plan pl onto map frame f. @return 0, or -1 without memory. */
static int add_shadow(rl_shadows *sh, const rl_frame *f, const rl_emitter *e, const rl_shared_plan *pl, const v3 *v,
                      size_t n)
{
    v3 a[RL_SCENE_MAX_POLY_VERTS + 4], b[RL_SCENE_MAX_POLY_VERTS + 4];
    double cos_r = v3_dot(pl->back, f->n), dn = -v3_dot(pl->back, e->frame.n);
    /* the ray's interval: at least tnear * cos_r above the receiver, tshort * dn below the emitter */
    size_t m = rl__clip_poly3(v, n, v3_madd(f->origin, f->n, pl->tnear * cos_r), f->n, a);
    m = m >= 3 ? rl__clip_poly3(a, m, v3_madd(e->frame.origin, e->frame.n, pl->tshort * dn), e->frame.n, b) : 0;
    if (m < 3)
        return 0;
    v2 q[RL_SCENE_MAX_POLY_VERTS + 4];
    double area = 0.0;
    for (size_t k = 0; k < m; k++) {
        double h = v3_dot(v3_sub(b[k], f->origin), f->n);
        q[k] = frame_project(f, v3_madd(b[k], pl->back, -h / cos_r));
    }
    for (size_t k = 0; k < m; k++)
        area += q[k].x * q[(k + 1) % m].y - q[(k + 1) % m].x * q[k].y;
    if (!(area != 0.0))
        return 0; /* seen edge-on: a shadow of no area stops no sample */
    if (reserve((void **)&sh->polys, &sh->cap_polys, sh->npolys + 1, sizeof *sh->polys) != 0 ||
        reserve((void **)&sh->edges, &sh->cap_edges, sh->nedges + m, sizeof *sh->edges) != 0 ||
        reserve((void **)&sh->verts, &sh->cap_verts, sh->nedges + m, sizeof *sh->verts) != 0 ||
        reserve((void **)&sh->du_dv, &sh->cap_slopes, sh->nedges + m, sizeof *sh->du_dv) != 0)
        return -1;
    rl_shadow_poly *sp = &sh->polys[sh->npolys++];
    sp->first = (uint32_t)sh->nedges;
    sp->n = (uint32_t)m;
    sp->ulo = sp->vlo = INFINITY;
    sp->uhi = sp->vhi = -INFINITY;
    for (size_t k = 0; k < m; k++) {
        /* counter-clockwise edges keep the inside on their left */
        v2 p0 = q[area > 0 ? k : m - 1 - k], p1 = q[area > 0 ? (k + 1) % m : (2 * m - 2 - k) % m];
        sh->verts[sh->nedges] = p0;
        sh->du_dv[sh->nedges] = p1.y != p0.y ? (p1.x - p0.x) / (p1.y - p0.y) : 0.0;
        sh->edges[sh->nedges++] = edge_halfplane(p0, p1);
        sp->ulo = fmin(sp->ulo, q[k].x), sp->uhi = fmax(sp->uhi, q[k].x);
        sp->vlo = fmin(sp->vlo, q[k].y), sp->vhi = fmax(sp->vhi, q[k].y);
    }
    return 0;
}

int rl__shadows_build(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, const rl_leaf *L,
                      const double *within, rl_scratch *s)
{
    if (!s->shadows && !(s->shadows = calloc(1, sizeof *s->shadows)))
        return -1;
    rl_shadows *sh = s->shadows;
    sh->known = 0;
    sh->npolys = sh->nedges = 0;
    if (!L->reach || L->nshared == 0 || t->npoly < 3 || !ctx->occluders)
        return 0;
    if (!s->beam && !(s->beam = malloc(sizeof *s->beam)))
        return -1;
    if (!sh->cand && !(sh->cand = malloc(SHADOW_CANDIDATES * sizeof *sh->cand)))
        return -1;
    const rl_map *m = t->m;
    v3 tile[RL_BEAM_MAX_VERTS], a[RL_BEAM_MAX_VERTS + 1], far[RL_BEAM_MAX_VERTS];
    v2 cut[RL_BEAM_MAX_VERTS + 4], scratch[RL_BEAM_MAX_VERTS + 4];
    if (t->npoly > RL_BEAM_MAX_VERTS - 5)
        return 0;
    /* the tile, cut to the rectangle where origins can carry light (counter-clockwise) */
    size_t nt = 0;
    if (within) {
        const v2 rect[4] = {{within[0], within[2]}, {within[1], within[2]}, {within[1], within[3]},
                            {within[0], within[3]}};
        nt = rl__clip_to_polygon(t->poly, t->npoly, rect, 4, cut, scratch);
    }
    if (nt < 3) { /* no rectangle, or a sliver: the whole tile */
        nt = t->npoly;
        memcpy(cut, t->poly, nt * sizeof *t->poly);
    }
    for (size_t k = 0; k < nt; k++)
        tile[k] = frame_point(&m->frame, cut[k]);
    /* origins behind the emitter's plane shoot nothing: the beam starts from the rest */
    size_t na = rl__clip_poly3(tile, nt, p->e->frame.origin, p->e->frame.n, a);
    size_t nf = na >= 3 ? footprint(p, L, a, na, far) : 0;
    if (nf == 0 || !rl__beam_make(a, na, far, nf, p->eps, s->beam))
        return 0;
    size_t nc = rl__occluders_collect(ctx->occluders, s->beam, p->e->polygon, sh->cand, SHADOW_CANDIDATES);
    if (nc == SIZE_MAX)
        return 0;
    for (uint32_t i = 0; i < L->nshared; i++) {
        sh->start[i] = (uint32_t)sh->npolys;
        for (size_t c = 0; c < nc && L->plan[i].live; c++) {
            const v3 *v;
            size_t n = rl__occluders_polygon(ctx->occluders, sh->cand[c], &v);
            if (add_shadow(sh, &m->frame, p->e, &L->plan[i], v, n) != 0)
                return -1;
        }
    }
    sh->start[L->nshared] = (uint32_t)sh->npolys;
    sh->nshared = L->nshared;
    if (reserve((void **)&sh->active, &sh->active_cap, sh->npolys + 1, sizeof *sh->active) != 0)
        return -1;
    sh->known = 1;
    return 0;
}

/* Gives in [*lo, *hi] the extent in u of shadow sp within the band v in [va, vb]. @return 0 if they miss. */
static int band_extent(const rl_shadows *sh, const rl_shadow_poly *sp, double va, double vb, double *lo, double *hi)
{
    double l = INFINITY, h = -INFINITY; /* compared, not fmin/fmax: libm calls on a hot path */
    for (uint32_t e = 0; e < sp->n; e++) {
        v2 a = sh->verts[sp->first + e], b = sh->verts[sp->first + (e + 1 < sp->n ? e + 1 : 0)];
        double slope = sh->du_dv[sp->first + e];
        if (a.y >= va && a.y <= vb) {
            l = a.x < l ? a.x : l;
            h = a.x > h ? a.x : h;
        }
        /* where the edge crosses either side of the band */
        for (int k = 0; k < 2; k++) {
            double v = k ? vb : va;
            if ((a.y < v) != (b.y < v)) {
                double u = a.x + (v - a.y) * slope;
                l = u < l ? u : l;
                h = u > h ? u : h;
            }
        }
    }
    *lo = l, *hi = h;
    return l <= h;
}

void rl__shadows_row(rl_shadows *sh, double ulo, double uhi, double vlo, double vhi)
{
    uint32_t at = 0;
    for (uint32_t i = 0; i < sh->nshared; i++) {
        sh->row_first[i] = at;
        for (uint32_t k = sh->start[i]; k < sh->start[i + 1]; k++) {
            const rl_shadow_poly *sp = &sh->polys[k];
            double lo, hi;
            if (sp->uhi < ulo || sp->ulo > uhi || sp->vhi < vlo || sp->vlo > vhi ||
                !band_extent(sh, sp, vlo, vhi, &lo, &hi) || hi < ulo || lo > uhi)
                continue;
            /* kept in order of ulo (insertion: a row holds a few), so that a
             * point's test stops at the first span starting past it */
            uint32_t pos = at++;
            while (pos > sh->row_first[i] && sh->active[pos - 1].ulo > lo) {
                sh->active[pos] = sh->active[pos - 1];
                pos--;
            }
            sh->active[pos] = (struct rl_shadow_span){k, lo, hi};
        }
        sh->row_count[i] = at - sh->row_first[i];
    }
}
