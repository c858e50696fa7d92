/*
 * emitter_tree.c - a bounding-box tree over one pass's emitters, walked per
 * receiver region to list the emitters no polygon hides from it, alone or
 * at a corner with another (emitter_tree.h).
 *
 * Built once per pass over the emitters' boxes (box_tree.h); read-only afterwards, so
 * walks from any number of threads share it. A walk drops a whole subtree
 * when one polygon, or two meeting at a corner, crosses every segment from
 * the region to the subtree's box (rl__occluders_block_any()): the box holds
 * every point of its emitters, so each of their rays would be occluded. A
 * leaf's emitters are then tested one by one against their own polygons.
 * (Cutting a region in parts, each hidden by a blocker of its own, was
 * tried twice: a lamp of a room diagonally off is hidden from a room by its
 * corner's two walls, and the line through the corner crosses every part.
 * The corner as one blocker took a floor of 5 x 5 classrooms from 8,700 pairs
 * a room to 5,900, the classroom alone having 4,800.)
 * Before any search, a few traced segments from the region to the box, one
 * of which meets nothing, prove the box visible: most of a room's own
 * emitters cost a packet of rays, not a search. Work per region is so
 * in proportion to the emitters it may reach, plus the depth of the tree
 * for each subtree dropped, rather than to every emitter of the scene.
 */
#include <stdlib.h>

#include "box_tree.h"
#include "emitter_tree.h"

struct rl_emitter_tree {
    const rl_emitter *e;
    size_t n;
    rl_box_tree tree; /* over the emitters' boxes */
    const rl_tracer *tracer;
    v3 centre;
    double eps_floor;
};

static void emitter_box(const rl_emitter *e, v3 *lo, v3 *hi)
{
    *lo = *hi = e->verts[0];
    for (uint32_t i = 1; i < e->nverts; i++) {
        v3 v = e->verts[i];
        *lo = (v3){dmin(lo->x, v.x), dmin(lo->y, v.y), dmin(lo->z, v.z)};
        *hi = (v3){dmax(hi->x, v.x), dmax(hi->y, v.y), dmax(hi->z, v.z)};
    }
}

rl_status rl__emitter_tree_new(const rl_emitter *e, size_t n, const rl_tracer *tracer, v3 centre, double eps_floor,
                               rl_emitter_tree **out)
{
    *out = NULL;
    rl_emitter_tree *t = calloc(1, sizeof *t);
    v3 *lo = malloc((n ? n : 1) * sizeof *lo), *hi = malloc((n ? n : 1) * sizeof *hi);
    int built = -1;
    if (t && lo && hi && n > 0) {
        for (size_t k = 0; k < n; k++)
            emitter_box(&e[k], &lo[k], &hi[k]);
        built = rl__box_tree_build(&t->tree, lo, hi, n);
    }
    free(lo);
    free(hi);
    if (built != 0) {
        rl__emitter_tree_destroy(t);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the tree of %zu emitters", n);
    }
    t->e = e;
    t->n = n;
    t->tracer = tracer;
    t->centre = centre;
    t->eps_floor = eps_floor;
    *out = t;
    return RL_OK;
}

void rl__emitter_tree_destroy(rl_emitter_tree *t)
{
    if (!t)
        return;
    rl__box_tree_free(&t->tree);
    free(t);
}

/* @return 1 if one of a few segments from the hull of a (na; ca its vertex mean) to the hull of b (nb; cb
 * its vertex mean), but for tol at either end, meets no polygon as the tracer sees it: from ca to cb alone,
 * then at once from ca and from halfway to each vertex of a to cb and to the point of b's box nearest to
 * it, and from ca to halfway to each vertex of b. Then no polygon hides b
 * from a, nor anything holding b. (Only a shortcut, to spare the searches for blockers that would fail: a
 * segment the tracer finds clear that an exact test would find blocked only keeps an emitter, which is
 * always exact.) */
static int seen(const rl_emitter_tree *t, const v3 *a, size_t na, v3 ca, const v3 *b, size_t nb, v3 cb, double tol)
{
    /* the segment between the centres first, alone: it alone proves most seen boxes seen */
    v3 d0 = v3_sub(cb, ca);
    double len0 = v3_len(d0);
    if (len0 > 4.0 * tol && !rl__tracer_occluded(t->tracer, ca, v3_scale(d0, 1.0 / len0), tol, len0 - tol))
        return 1;
    v3 lo = b[0], hi = b[0];
    for (size_t j = 1; j < nb; j++) {
        lo = (v3){dmin(lo.x, b[j].x), dmin(lo.y, b[j].y), dmin(lo.z, b[j].z)};
        hi = (v3){dmax(hi.x, b[j].x), dmax(hi.y, b[j].y), dmax(hi.z, b[j].z)};
    }
    v3 from[RL_RAY_PACKET], to[RL_RAY_PACKET], org[RL_RAY_PACKET], dir[RL_RAY_PACKET];
    double tn[RL_RAY_PACKET], tf[RL_RAY_PACKET];
    int occluded[RL_RAY_PACKET];
    size_t n = 0;
    /* then, at once: from ca and halfway to each vertex of a, to the nearest point of b's box and to cb; and
     * from ca to halfway to each vertex of b */
    for (size_t i = 0; i <= na && n < RL_RAY_PACKET; i++) {
        v3 f = i == na ? ca : v3_scale(v3_add(ca, a[i]), 0.5);
        from[n] = f, to[n++] = (v3){dmin(dmax(f.x, lo.x), hi.x), dmin(dmax(f.y, lo.y), hi.y), dmin(dmax(f.z, lo.z), hi.z)};
        if (na == 1)
            break;
    }
    for (size_t i = 0; i < na && na > 1 && n < RL_RAY_PACKET; i++)
        from[n] = v3_scale(v3_add(ca, a[i]), 0.5), to[n++] = cb;
    for (size_t j = 0; j < nb && n < RL_RAY_PACKET; j++)
        from[n] = ca, to[n++] = v3_scale(v3_add(cb, b[j]), 0.5);
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        v3 d = v3_sub(to[k], from[k]);
        double len = v3_len(d);
        if (!(len > 4.0 * tol))
            continue;
        org[m] = from[k], dir[m] = v3_scale(d, 1.0 / len), tn[m] = tol, tf[m++] = len - tol;
    }
    if (m == 0)
        return 0;
    rl__tracer_occluded_n(t->tracer, m, org, dir, tn, tf, occluded);
    for (size_t k = 0; k < m; k++)
        if (!occluded[k])
            return 1;
    return 0;
}

/* The polygons that hid something from the region of one walk, most recent first: the next box is often
 * hidden by the same wall, which is then found without a search. */
#define RECENT RL_REACH_BLOCKERS
typedef struct walk {
    const rl_emitter_tree *t;
    const rl_occluders *o;
    uint32_t recent[RECENT];
    size_t nrecent;
} walk;

/* @return 1 if one polygon, alone or at a corner with another (rl__occluders_blocks()), hides the hull of b
 * (nb) from that of a (na) with margins tol and edge: one of w's recent blockers, or one found by a search
 * (rl__occluders_block_any(); then made the most recent). */
static int blocked(walk *w, const v3 *a, size_t na, const v3 *b, size_t nb, double tol, double edge)
{
    for (size_t i = 0; i < w->nrecent; i++)
        if (rl__occluders_blocks(w->o, w->recent[i], a, na, b, nb, tol, edge))
            return 1;
    uint32_t k = 0;
    if (!rl__occluders_block_any(w->o, a, na, b, nb, tol, edge, &k))
        return 0;
    size_t n = w->nrecent < RECENT ? w->nrecent + 1 : RECENT;
    for (size_t i = n - 1; i > 0; i--)
        w->recent[i] = w->recent[i - 1];
    w->recent[0] = k;
    w->nrecent = n;
    return 1;
}

/* @return 1 if every point of b (nb) is hidden from the hull of a (na): one polygon of o crosses every
 * segment between them, with the margins of RL_REACH_TOL_EPS and RL_REACH_EDGE_EPS times the eps of such
 * segments (as pair.c measures a pair's). */
static int hidden(walk *w, const v3 *a, size_t na, const v3 *b, size_t nb)
{
    const rl_emitter_tree *t = w->t;
    double r = 0.0;
    for (size_t i = 0; i < na; i++)
        r = dmax(r, v3_maxabs(v3_sub(a[i], t->centre)));
    for (size_t j = 0; j < nb; j++)
        r = dmax(r, v3_maxabs(v3_sub(b[j], t->centre)));
    double eps = dmax(1e-6 * r, t->eps_floor), tol = RL_REACH_TOL_EPS * eps;
    return !seen(t, a, na, v3_mean(a, na), b, nb, v3_mean(b, nb), tol) &&
           blocked(w, a, na, b, nb, tol, RL_REACH_EDGE_EPS * eps);
}

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

/* @return 1 if none of the n points v lies strictly in front of the plane through org with normal nrm. */
static int behind(const v3 *v, size_t n, v3 org, v3 nrm)
{
    for (size_t i = 0; i < n; i++)
        if (v3_dot(v3_sub(v[i], org), nrm) > 0)
            return 0;
    return 1;
}

/* @return 1 if emitter e and tile a cannot exchange light whatever lies between: the tile (in the plane of
 * frame rf; NULL: a point, for which nothing is told here) faces away from all of e, or lies behind e's
 * plane -- rl__pair_setup()'s tests (pair.c), in the same arithmetic, so that an emitter left out here is
 * one it would turn away. */
static int facing_away(const rl_emitter *e, const v3 *a, size_t na, const rl_frame *rf)
{
    return rf && (behind(e->verts, e->nverts, rf->origin, rf->n) || behind(a, na, e->frame.origin, e->frame.n));
}

size_t rl__emitter_tree_reach(const rl_emitter_tree *t, const rl_occluders *o, const v3 *a, size_t na,
                              const rl_frame *rf, uint32_t *out, uint32_t *blockers, size_t *nblockers)
{
    size_t n = 0;
    walk w = {t, o, {0}, 0};
    uint32_t stack[RL_BOX_TREE_STACK];
    size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const rl_box_node *nd = &t->tree.nodes[stack[--top]];
        v3 corner[8];
        for (int c = 0; c < 8; c++)
            corner[c] = (v3){c & 1 ? nd->hi.x : nd->lo.x, c & 2 ? nd->hi.y : nd->lo.y, c & 4 ? nd->hi.z : nd->lo.z};
        if ((rf && behind(corner, 8, rf->origin, rf->n)) || hidden(&w, a, na, corner, 8))
            continue;
        if (nd->count == 0 && top + 2 <= RL_BOX_TREE_STACK) {
            stack[top++] = nd->first + 1;
            stack[top++] = nd->first;
            continue;
        }
        if (nd->count == 0) { /* deeper than any tree of 2^64 emitters: cannot happen; keep them all */
            for (size_t k = 0; k < t->n; k++)
                out[k] = (uint32_t)k;
            *nblockers = 0;
            return t->n;
        }
        for (uint32_t i = nd->first; i < nd->first + nd->count; i++) {
            const rl_emitter *e = &t->e[t->tree.order[i]];
            if (!facing_away(e, a, na, rf) && (nd->count == 1 || !hidden(&w, a, na, e->verts, e->nverts)))
                out[n++] = t->tree.order[i];
        }
    }
    qsort(out, n, sizeof *out, cmp_u32);
    for (size_t i = 0; i < w.nrecent; i++)
        blockers[i] = w.recent[i];
    *nblockers = w.nrecent;
    return n;
}
