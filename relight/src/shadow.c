/*
 * shadow.c - an index of the scene's polygons (a bounding-box tree) and
 * exact tests of a polygon against a beam of segments (shadow.h).
 *
 * A beam is kept as the faces of the convex hull of its two ends: a side
 * through each edge of either end and a vertex of the other, and the ends'
 * planes (a pyramid's sides all pass through its apex), each checked to
 * hold both ends on its inner side. A polygon P meets
 * the beam when P clipped by those faces keeps a positive area. P blocks
 * the beam when every vertex of one end lies strictly on one side of P's
 * plane and every vertex of the other strictly on the other, and the
 * segment between every such pair of vertices crosses P inside its edges:
 * the beam and P are convex, so then every segment crosses P. Points
 * within `tol` of a plane count as on it, and "inside P" needs a margin of
 * tol, so FREE and BLOCKED err towards PARTIAL, which only costs rays.
 *
 * The tree (box_tree.h) is built once over the polygons' boxes; it is
 * read-only afterwards.
 */
#include <stdlib.h>
#include <string.h>

#include "box_tree.h"
#include "shadow.h"

typedef struct occ_poly {
    uint32_t first, count; /* into rl_occluders.verts */
    v3 n;                  /* unit normal, vertices counter-clockwise about it */
    v3 lo, hi;
} occ_poly;

struct rl_occluders {
    v3 *verts;
    occ_poly *polys;
    size_t npolys;
    rl_box_tree tree; /* over the polygons' boxes */
};

static v3 v3_min(v3 a, v3 b) { return (v3){dmin(a.x, b.x), dmin(a.y, b.y), dmin(a.z, b.z)}; }
static v3 v3_max(v3 a, v3 b) { return (v3){dmax(a.x, b.x), dmax(a.y, b.y), dmax(a.z, b.z)}; }
static double v3_axis(v3 a, int k) { return k == 0 ? a.x : k == 1 ? a.y : a.z; }

static int boxes_overlap(v3 alo, v3 ahi, v3 blo, v3 bhi)
{
    return alo.x <= bhi.x && blo.x <= ahi.x && alo.y <= bhi.y && blo.y <= ahi.y && alo.z <= bhi.z &&
           blo.z <= ahi.z;
}

/* Builds o's tree over its polygons' boxes. @return 0, or -1 when memory runs out. */
static int index_polygons(rl_occluders *o)
{
    size_t n = o->npolys;
    v3 *lo = malloc((n ? n : 1) * sizeof *lo), *hi = malloc((n ? n : 1) * sizeof *hi);
    int rc = -1;
    if (lo && hi) {
        for (size_t k = 0; k < n; k++) {
            lo[k] = o->polys[k].lo;
            hi[k] = o->polys[k].hi;
        }
        rc = rl__box_tree_build(&o->tree, lo, hi, n);
    }
    free(lo);
    free(hi);
    return rc;
}

rl_status rl__occluders_new(const rl_scene *scene, rl_occluders **out)
{
    *out = NULL;
    rl_occluders *o = calloc(1, sizeof *o);
    size_t n = scene->npolygons, nv = 0;
    for (size_t k = 0; k < n; k++)
        nv += scene->polygons[k].count;
    if (o) {
        o->verts = malloc((nv ? nv : 1) * sizeof *o->verts);
        o->polys = malloc((n ? n : 1) * sizeof *o->polys);
    }
    if (!o || !o->verts || !o->polys) {
        rl__occluders_destroy(o);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the occluder index of %zu polygons", n);
    }
    size_t at = 0;
    for (size_t k = 0; k < n; k++) {
        const rl_polygon *pg = &scene->polygons[k];
        occ_poly *p = &o->polys[k];
        p->first = (uint32_t)at;
        p->count = pg->count;
        p->n = v3_load(pg->normal);
        for (uint32_t i = 0; i < pg->count; i++) {
            v3 v = v3_load(scene->vertices[pg->first + i]);
            o->verts[at++] = v;
            p->lo = i ? v3_min(p->lo, v) : v;
            p->hi = i ? v3_max(p->hi, v) : v;
        }
    }
    o->npolys = n;
    if (index_polygons(o) != 0) {
        rl__occluders_destroy(o);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the occluder index of %zu polygons", n);
    }
    *out = o;
    return RL_OK;
}

void rl__occluders_destroy(rl_occluders *o)
{
    if (!o)
        return;
    free(o->verts);
    free(o->polys);
    rl__box_tree_free(&o->tree);
    free(o);
}

/* @return point i of p's ends: the near end's vertices, then the far end's. */
static inline v3 end_point(const rl_beam *p, size_t i)
{
    return i < p->na ? p->a[i] : p->b[i - p->na];
}

/* Adds the face through org with normal n (either way round) when every
 * point of both ends lies on one side of it, within the rounding of its
 * products (scale: the beam's extent). @return 1 if added. */
static int add_face(rl_beam *p, v3 org, v3 n, double scale)
{
    double len = v3_len(n);
    if (!(len > 0))
        return 0;
    double lo = 0.0, hi = 0.0, slack = 1e-9 * len * scale;
    for (size_t i = 0; i < p->na + p->nb; i++) {
        double s = v3_dot(v3_sub(end_point(p, i), org), n);
        lo = dmin(lo, s);
        hi = dmax(hi, s);
    }
    if (lo >= -slack && hi > slack)
        p->nrm[p->nplanes] = n;
    else if (hi <= slack && lo < -slack)
        p->nrm[p->nplanes] = v3_scale(n, -1.0);
    else
        return 0;
    p->org[p->nplanes++] = org;
    return 1;
}

/* @return the Newell normal of polygon v (n vertices), not normalised. */
static v3 newell_normal(const v3 *v, size_t n)
{
    v3 s = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        s = v3_add(s, v3_cross(v[i], v[(i + 1) % n]));
    return s;
}

/* Adds the faces of the hull of p's ends that hold an edge of `from` (n
 * vertices) and a vertex of `to` (m): at most one per edge. */
static void add_edge_faces(rl_beam *p, const v3 *from, size_t n, const v3 *to, size_t m, double scale)
{
    for (size_t i = 0; i < n; i++) {
        v3 e = v3_sub(from[(i + 1) % n], from[i]);
        for (size_t j = 0; j < m; j++)
            if (add_face(p, from[i], v3_cross(e, v3_sub(to[j], from[i])), scale))
                break;
    }
}

int rl__beam_make(const v3 *a, size_t na, const v3 *b, size_t nb, double tol, rl_beam *p)
{
    if (na < 1 || nb < 3 || na > RL_BEAM_MAX_VERTS || nb > RL_BEAM_MAX_VERTS)
        return 0;
    v3 newell = newell_normal(b, nb);
    double len = v3_len(newell);
    if (!(len > 0))
        return 0;
    p->b_n = v3_scale(newell, 1.0 / len);
    /* b's normal faces the point of a farthest from its plane; a within tol of that plane spans no volume */
    double h = 0.0;
    for (size_t i = 0; i < na; i++) {
        double hi = v3_dot(v3_sub(a[i], b[0]), p->b_n);
        if (fabs(hi) > fabs(h))
            h = hi;
    }
    if (!(fabs(h) > tol))
        return 0;
    if (h < 0)
        p->b_n = v3_scale(p->b_n, -1.0);
    memcpy(p->a, a, na * sizeof *a);
    memcpy(p->b, b, nb * sizeof *b);
    p->na = na;
    p->nb = nb;
    p->tol = tol;
    p->lo = p->hi = a[0];
    for (size_t i = 0; i < na + nb; i++) {
        p->lo = v3_min(p->lo, end_point(p, i));
        p->hi = v3_max(p->hi, end_point(p, i));
    }
    p->nplanes = 0;
    /* the convex hull of two planar polygons (a point: a pyramid): every face
     * holds an edge of one and a vertex of the other, or lies in either one's
     * plane; each is kept only once every point of both ends is checked to lie
     * on its inner side, so that a vertex a rounding away from its neighbours'
     * line cannot turn a face into one that cuts the beam */
    double scale = v3_maxabs(v3_sub(p->hi, p->lo));
    if (na == 1) {
        /* a pyramid's sides, through its apex (where point queries have always measured them from) */
        for (size_t i = 0; i < nb; i++)
            add_face(p, a[0], v3_cross(v3_sub(b[i], a[0]), v3_sub(b[(i + 1) % nb], a[0])), scale);
    } else {
        add_edge_faces(p, a, na, b, nb, scale);
        add_edge_faces(p, b, nb, a, na, scale);
    }
    if (na >= 3)
        add_face(p, a[0], newell_normal(a, na), scale);
    add_face(p, b[0], p->b_n, scale);
    return p->nplanes >= 4;
}

/* @return 1 if shadow rays of p can never meet polygon q: its plane holds
 * all of p's near end, or it lies in the far end's plane. */
static int unreachable(const rl_occluders *o, const occ_poly *q, const rl_beam *p)
{
    const v3 *v = o->verts + q->first;
    size_t i = 0;
    while (i < p->na && fabs(v3_dot(v3_sub(p->a[i], v[0]), q->n)) <= p->tol)
        i++;
    if (i == p->na)
        return 1;
    for (uint32_t k = 0; k < q->count; k++)
        if (fabs(v3_dot(v3_sub(v[k], p->b[0]), p->b_n)) > p->tol)
            return 0;
    return 1;
}

/* @return the side of q's plane (1, -1; 0: on it or on both sides) on which every point of p's ends lies. */
static int ends_side(const occ_poly *q, const v3 *v0, const rl_beam *p)
{
    int side = 2;
    for (size_t i = 0; i < p->na + p->nb; i++) {
        double s = v3_dot(v3_sub(end_point(p, i), *v0), q->n);
        int si = s > 0 ? 1 : s < 0 ? -1 : 0;
        if (si == 0 || (side != 2 && si != side))
            return 0;
        side = si;
    }
    return side;
}

/* @return 1 if polygon q meets beam p in a positive area. */
static int meets(const rl_occluders *o, const occ_poly *q, const rl_beam *p)
{
    /* cheap separations first: q wholly outside one face of p, or p wholly
     * on one side of q's plane; only what survives both is clipped */
    const v3 *v = o->verts + q->first;
    for (size_t i = 0; i < p->nplanes; i++) {
        uint32_t k = 0;
        while (k < q->count && v3_dot(v3_sub(v[k], p->org[i]), p->nrm[i]) < 0)
            k++;
        if (k == q->count)
            return 0;
    }
    if (ends_side(q, &v[0], p) != 0)
        return 0;
    v3 buf[2][RL_SCENE_MAX_POLY_VERTS + RL_BEAM_MAX_PLANES + 2];
    v3 *cur = buf[0], *next = buf[1];
    size_t n = q->count;
    memcpy(cur, o->verts + q->first, n * sizeof *cur);
    for (size_t i = 0; i < p->nplanes && n >= 3; i++) {
        n = rl__clip_poly3(cur, n, p->org[i], p->nrm[i], next);
        v3 *t = cur;
        cur = next;
        next = t;
    }
    if (n < 3)
        return 0;
    v3 newell = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        newell = v3_add(newell, v3_cross(v3_sub(cur[i], cur[0]), v3_sub(cur[(i + 1) % n], cur[0])));
    return v3_len(newell) > 1e-6 * p->tol * p->tol;
}

/* What polygon q does to the segments between the convex hulls of points pa (na) and pb (nb) (stands()). */
typedef enum stand { STAND_MISSES, STAND_ONE_EDGE, STAND_BLOCKS } stand;

/* STAND_BLOCKS if q crosses every segment between the convex hulls of
 * points pa (na) and pb (nb): its plane parts the two sets by more than tol,
 * and the segment between every pair of their points crosses it more than
 * edge inside its edges (the section of a convex hull by a plane that parts
 * its ends is the hull of those crossings; the ends need not be planar).
 * With one_edge, STAND_ONE_EDGE if its plane parts them and the crossings
 * lie so inside all its edges but one, whose number goes to *open
 * (corner_blocks()); else STAND_MISSES, at the first crossing outside. */
static stand stands(const rl_occluders *o, const occ_poly *q, const v3 *pa, size_t na, const v3 *pb, size_t nb,
                    double tol, double edge, int one_edge, uint32_t *open)
{
    const v3 *v = o->verts + q->first;
    int near_above = v3_dot(v3_sub(pa[0], v[0]), q->n) > 0; /* the side every near vertex must share */
    uint32_t out = q->count;                                 /* the one edge some crossing lies outside */
    for (size_t ia = 0; ia < na; ia++) {
        double sa = v3_dot(v3_sub(pa[ia], v[0]), q->n);
        if (!(fabs(sa) > tol) || (sa > 0) != near_above)
            return STAND_MISSES;
        for (size_t b = 0; b < nb; b++) {
            double sb = v3_dot(v3_sub(pb[b], v[0]), q->n);
            if (!(sa > 0 ? sb < -tol : sb > tol))
                return STAND_MISSES;
            v3 h = v3_madd(pa[ia], v3_sub(pb[b], pa[ia]), sa / (sa - sb));
            for (uint32_t i = 0; i < q->count; i++) {
                v3 a = v[i], c = v[(i + 1) % q->count];
                v3 m = v3_cross(q->n, v3_sub(c, a));
                if (v3_dot(v3_sub(h, a), m) > edge * v3_len(m) || i == out)
                    continue;
                if (!one_edge || out < q->count)
                    return STAND_MISSES;
                out = i;
            }
        }
    }
    if (out == q->count)
        return STAND_BLOCKS;
    *open = out;
    return STAND_ONE_EDGE;
}

/* @return 1 if polygon q crosses every segment between the hulls of pa (na) and pb (nb) (stands()). */
static int blocks_ends(const rl_occluders *o, const occ_poly *q, const v3 *pa, size_t na, const v3 *pb, size_t nb,
                       double tol, double edge)
{
    return stands(o, q, pa, na, pb, nb, tol, edge, 0, NULL) == STAND_BLOCKS;
}

/* blocks_ends() for beam p's two ends and tolerance. */
static int blocks(const rl_occluders *o, const occ_poly *q, const rl_beam *p)
{
    return blocks_ends(o, q, p->a, p->na, p->b, p->nb, p->tol, p->tol);
}

/* @return 1 if box [lo, hi] lies wholly outside some face of p. */
static int box_outside(v3 lo, v3 hi, const rl_beam *p)
{
    for (size_t i = 0; i < p->nplanes; i++) {
        v3 n = p->nrm[i];
        v3 far = {n.x > 0 ? hi.x : lo.x, n.y > 0 ? hi.y : lo.y, n.z > 0 ? hi.z : lo.z};
        if (v3_dot(v3_sub(far, p->org[i]), n) < 0)
            return 1;
    }
    return 0;
}

size_t rl__occluders_collect(const rl_occluders *o, const rl_beam *p, int32_t skip, uint32_t *list, size_t cap)
{
    if (o->npolys == 0)
        return 0;
    uint32_t stack[RL_BOX_TREE_STACK];
    size_t top = 0, n = 0;
    stack[top++] = 0;
    while (top > 0) {
        const rl_box_node *nd = &o->tree.nodes[stack[--top]];
        if (!boxes_overlap(nd->lo, nd->hi, p->lo, p->hi) || box_outside(nd->lo, nd->hi, p))
            continue;
        if (nd->count == 0) {
            if (top + 2 > RL_BOX_TREE_STACK)
                return SIZE_MAX; /* deeper than any tree of 2^64 polygons: cannot happen */
            stack[top++] = nd->first + 1;
            stack[top++] = nd->first;
            continue;
        }
        for (uint32_t i = nd->first; i < nd->first + nd->count; i++) {
            uint32_t k = o->tree.order[i];
            const occ_poly *q = &o->polys[k];
            if ((int64_t)k == skip || !boxes_overlap(q->lo, q->hi, p->lo, p->hi) || unreachable(o, q, p) ||
                !meets(o, q, p))
                continue;
            if (n == cap)
                return SIZE_MAX;
            list[n++] = k;
        }
    }
    return n;
}

/* @return 1 if the segment from p0 to p1 meets box [lo, hi] widened by pad on every side. */
static int segment_meets_box(v3 p0, v3 p1, v3 lo, v3 hi, double pad)
{
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; k++) {
        double a = v3_axis(p0, k), d = v3_axis(p1, k) - a, l = v3_axis(lo, k) - pad, h = v3_axis(hi, k) + pad;
        if (d == 0.0) {
            if (a < l || a > h)
                return 0;
            continue;
        }
        double ta = (l - a) / d, tb = (h - a) / d;
        t0 = dmax(t0, dmin(ta, tb));
        t1 = dmin(t1, dmax(ta, tb));
        if (t0 > t1)
            return 0;
    }
    return 1;
}

/* @return 1 if points u and w are the same, coordinate for coordinate. */
static int same_point(v3 u, v3 w)
{
    return u.x == w.x && u.y == w.y && u.z == w.z;
}

/* Visits, in the tree's order, the polygons of o whose boxes meet the segment from p0 to p1 widened by pad
 * (a point when p0 is p1), until test(user, k) holds for one. @return 1 with it in *found, or 0. */
static int first_along(const rl_occluders *o, v3 p0, v3 p1, double pad, int (*test)(void *, uint32_t), void *user,
                       uint32_t *found)
{
    if (o->npolys == 0)
        return 0;
    uint32_t stack[RL_BOX_TREE_STACK];
    size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const rl_box_node *nd = &o->tree.nodes[stack[--top]];
        if (!segment_meets_box(p0, p1, nd->lo, nd->hi, pad))
            continue;
        if (nd->count == 0) {
            if (top + 2 > RL_BOX_TREE_STACK)
                return 0; /* deeper than any tree of 2^64 polygons: cannot happen; finding none is safe */
            stack[top++] = nd->first + 1;
            stack[top++] = nd->first;
            continue;
        }
        for (uint32_t i = nd->first; i < nd->first + nd->count; i++) {
            uint32_t k = o->tree.order[i];
            const occ_poly *q = &o->polys[k];
            if (segment_meets_box(p0, p1, q->lo, q->hi, pad) && test(user, k)) {
                *found = k;
                return 1;
            }
        }
    }
    return 0;
}

/* A polygon's edge, from q0 to q1, looked for in other polygons (across_edge()). */
typedef struct edge_search {
    const rl_occluders *o;
    uint32_t kq;
    v3 q0, q1;
    uint32_t er; /* found: the edge's number in the polygon holding it */
} edge_search;

/* first_along()'s test: polygon k, other than es->kq, has es's edge (the same two vertices, in either order). */
static int holds_edge(void *user, uint32_t k)
{
    edge_search *es = user;
    const occ_poly *r = &es->o->polys[k];
    const v3 *vr = es->o->verts + r->first;
    for (uint32_t j = 0; k != es->kq && j < r->count; j++) {
        v3 r0 = vr[j], r1 = vr[(j + 1) % r->count];
        if ((same_point(es->q0, r1) && same_point(es->q1, r0)) || (same_point(es->q0, r0) && same_point(es->q1, r1))) {
            es->er = j;
            return 1;
        }
    }
    return 0;
}

/* Finds the polygon other than kq that holds edge e of polygon kq, the same two vertices in either order:
 * among those whose boxes hold the edge's middle. @return 1 with it in *kr and the edge's number in it in
 * *er, or 0. */
static int across_edge(const rl_occluders *o, uint32_t kq, uint32_t e, uint32_t *kr, uint32_t *er)
{
    const occ_poly *q = &o->polys[kq];
    edge_search es = {o, kq, o->verts[q->first + e], o->verts[q->first + (e + 1) % q->count], 0};
    v3 mid = v3_scale(v3_add(es.q0, es.q1), 0.5);
    if (!first_along(o, mid, mid, 0.0, holds_edge, &es, kr))
        return 0;
    *er = es.er;
    return 1;
}

/* @return 1 if polygon r lies on point x's side of q's plane: no vertex on the other side (rounding apart),
 * and one clear of the plane (r is not in q's plane). */
static int on_side_of(const rl_occluders *o, const occ_poly *q, const occ_poly *r, v3 x)
{
    const v3 *vq = o->verts + q->first, *vr = o->verts + r->first;
    double sx = v3_dot(v3_sub(x, vq[0]), q->n);
    int off = 0;
    for (uint32_t i = 0; i < r->count; i++) {
        double s = v3_dot(v3_sub(vr[i], vq[0]), q->n), round = 1e-9 * (1.0 + v3_maxabs(vr[i]));
        if ((s > 0) != (sx > 0) && fabs(s) > round)
            return 0;
        off |= fabs(s) > 1e3 * round;
    }
    return off;
}

/* The corner of polygon kq, which parts the hulls of a (na) and b (nb) and crosses their segments inside all
 * its edges but edge e (stands()), with the polygon across that edge, if any. Each on x's side of the other's
 * plane, for x a point of a or of b: the region on that side of both planes is bounded there by the two
 * half-planes that the line of the shared edge cuts them to, which hold the polygons. Every segment from a to
 * b (beyond both planes) leaves the region about a, or enters the region about b, through a point of the
 * plane it crosses first, or last, on its half-plane: one the polygon there crosses inside its other edges, so
 * a point of that polygon. @return 1 if the corner so crosses every segment. */
static int corner_blocks(const rl_occluders *o, uint32_t kq, uint32_t e, const v3 *a, size_t na, const v3 *b,
                         size_t nb, double tol, double edge)
{
    uint32_t kr = 0, er = 0, open = 0;
    if (!across_edge(o, kq, e, &kr, &er))
        return 0;
    const occ_poly *q = &o->polys[kq], *r = &o->polys[kr];
    if (!((on_side_of(o, q, r, a[0]) && on_side_of(o, r, q, a[0])) ||
          (on_side_of(o, q, r, b[0]) && on_side_of(o, r, q, b[0]))))
        return 0;
    stand s = stands(o, r, a, na, b, nb, tol, edge, 1, &open);
    return s == STAND_BLOCKS || (s == STAND_ONE_EDGE && open == er);
}

/* @return 1 if polygon k crosses every segment between the hulls of a (na) and b (nb) on its own or, where
 * they cross it inside all its edges but one, with the polygon across that edge (corner_blocks()). */
static int blocks_or_corner(const rl_occluders *o, uint32_t k, const v3 *a, size_t na, const v3 *b, size_t nb,
                            double tol, double edge)
{
    uint32_t open = 0;
    stand s = stands(o, &o->polys[k], a, na, b, nb, tol, edge, 1, &open);
    return s == STAND_BLOCKS || (s == STAND_ONE_EDGE && corner_blocks(o, k, open, a, na, b, nb, tol, edge));
}

int rl__occluders_blocks(const rl_occluders *o, uint32_t k, const v3 *a, size_t na, const v3 *b, size_t nb,
                         double tol, double edge)
{
    return k < o->npolys && na >= 1 && nb >= 1 && blocks_or_corner(o, k, a, na, b, nb, tol, edge);
}

/* What rl__occluders_block_any() looks for, as first_along()'s test (blocks_or_corner()). */
typedef struct blocker_search {
    const rl_occluders *o;
    const v3 *a, *b;
    size_t na, nb;
    double tol, edge;
} blocker_search;

/* first_along()'s test: polygon k blocks alone or at a corner. */
static int blocks_all(void *user, uint32_t k)
{
    const blocker_search *bs = user;
    return blocks_or_corner(bs->o, k, bs->a, bs->na, bs->b, bs->nb, bs->tol, bs->edge);
}

int rl__occluders_block_any(const rl_occluders *o, const v3 *a, size_t na, const v3 *b, size_t nb, double tol,
                            double edge, uint32_t *blocker)
{
    if (na < 1 || nb < 1 || na > RL_BEAM_MAX_VERTS || nb > RL_BEAM_MAX_VERTS)
        return 0;
    /* every blocker, and one of a corner's two polygons, crosses the segment between the hulls' vertex means */
    v3 ca = v3_mean(a, na), cb = v3_mean(b, nb);
    double pad = edge + 1e-12 * (v3_maxabs(ca) + v3_maxabs(cb));
    blocker_search bs = {o, a, b, na, nb, tol, edge};
    uint32_t k = 0;
    if (!first_along(o, ca, cb, pad, blocks_all, &bs, &k))
        return 0;
    if (blocker)
        *blocker = k;
    return 1;
}

size_t rl__occluders_polygon(const rl_occluders *o, uint32_t k, const v3 **verts)
{
    *verts = o->verts + o->polys[k].first;
    return o->polys[k].count;
}

rl_visibility rl__occluders_classify(const rl_occluders *o, const rl_beam *p, const uint32_t *list, size_t n,
                                 uint32_t *out, size_t *nout)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        const occ_poly *q = &o->polys[list[i]];
        if (!boxes_overlap(q->lo, q->hi, p->lo, p->hi) || !meets(o, q, p))
            continue;
        if (blocks(o, q, p)) {
            *nout = 0;
            return VIS_BLOCKED;
        }
        out[m++] = list[i];
    }
    *nout = m;
    return m ? VIS_PARTIAL : VIS_FREE;
}
