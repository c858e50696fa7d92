/*
 * emitter_tree.c - a bounding-box tree over one pass's emitters, walked per
 * receiver region to list the emitters no single polygon hides from it
 * (emitter_tree.h).
 *
 * Built once per pass by median splits on the longest axis of the
 * emitters' box centres, a few emitters a leaf; read-only afterwards, so
 * walks from any number of threads share it. A walk drops a whole subtree
 * when one polygon crosses every segment from the region to the subtree's
 * box (rl__occluders_block_any()): the box holds every point of its
 * emitters, so each of their rays would be occluded. A leaf's emitters are
 * then tested one by one against their own polygons. Work per region is so
 * in proportion to the emitters it may reach, plus the depth of the tree
 * for each subtree dropped, rather than to every emitter of the scene.
 */
#include <stdlib.h>

#include "emitter_tree.h"

#define LEAF_SIZE 4
#define TREE_STACK 128

typedef struct et_node {
    v3 lo, hi;
    uint32_t first, count; /* leaf: emitters order[first .. first+count); inner: count = 0, children first, first+1 */
} et_node;

struct rl_emitter_tree {
    const rl_emitter *e;
    size_t n;
    uint32_t *order;
    et_node *nodes;
    size_t nnodes;
    v3 centre;
    double eps_floor;
};

/* One emitter's place in the build: its box centre's coordinate on the axis being split, and its index. */
typedef struct et_key {
    double key;
    uint32_t index;
} et_key;

static int key_less(et_key a, et_key b) { return a.key < b.key || (a.key == b.key && a.index < b.index); }

/* Partially orders k[lo..hi) so that k[mid] holds the element it would in sorted order (quickselect). */
static void select_nth(et_key *k, size_t lo, size_t hi, size_t mid)
{
    while (hi - lo > 1) {
        /* Hoare's partition about the first element (after moving the middle one there, against sorted
         * input): it leaves lo <= j < hi - 1, so every round shrinks the range */
        et_key pivot = k[lo + (hi - lo) / 2];
        k[lo + (hi - lo) / 2] = k[lo];
        k[lo] = pivot;
        size_t i = lo, j = hi - 1;
        for (;;) {
            while (key_less(k[i], pivot))
                i++;
            while (key_less(pivot, k[j]))
                j--;
            if (i >= j)
                break;
            et_key t = k[i];
            k[i++] = k[j];
            k[j--] = t;
        }
        /* [lo, j] <= pivot <= [j + 1, hi) */
        if (mid <= j)
            hi = j + 1;
        else
            lo = j + 1;
    }
}

static void emitter_box(const rl_emitter *e, v3 *lo, v3 *hi)
{
    *lo = *hi = e->verts[0];
    for (uint32_t i = 1; i < e->nverts; i++) {
        v3 v = e->verts[i];
        *lo = (v3){dmin(lo->x, v.x), dmin(lo->y, v.y), dmin(lo->z, v.z)};
        *hi = (v3){dmax(hi->x, v.x), dmax(hi->y, v.y), dmax(hi->z, v.z)};
    }
}

static double axis_of(v3 a, int k) { return k == 0 ? a.x : k == 1 ? a.y : a.z; }

/* Builds the subtree of node over order[first, first+count), keys its scratch. */
static void build(rl_emitter_tree *t, et_key *keys, size_t node, uint32_t first, uint32_t count)
{
    v3 lo, hi, clo = {0, 0, 0}, chi = {0, 0, 0};
    for (uint32_t i = first; i < first + count; i++) {
        v3 l, h;
        emitter_box(&t->e[t->order[i]], &l, &h);
        v3 c = v3_scale(v3_add(l, h), 0.5);
        if (i == first) {
            lo = l, hi = h, clo = chi = c;
            continue;
        }
        lo = (v3){dmin(lo.x, l.x), dmin(lo.y, l.y), dmin(lo.z, l.z)};
        hi = (v3){dmax(hi.x, h.x), dmax(hi.y, h.y), dmax(hi.z, h.z)};
        clo = (v3){dmin(clo.x, c.x), dmin(clo.y, c.y), dmin(clo.z, c.z)};
        chi = (v3){dmax(chi.x, c.x), dmax(chi.y, c.y), dmax(chi.z, c.z)};
    }
    et_node *nd = &t->nodes[node];
    nd->lo = lo;
    nd->hi = hi;
    if (count <= LEAF_SIZE) {
        nd->first = first;
        nd->count = count;
        return;
    }
    v3 ext = v3_sub(chi, clo);
    int k = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    for (uint32_t i = first; i < first + count; i++) {
        v3 l, h;
        emitter_box(&t->e[t->order[i]], &l, &h);
        keys[i] = (et_key){axis_of(l, k) + axis_of(h, k), t->order[i]};
    }
    uint32_t half = count / 2;
    select_nth(keys, first, first + count, first + half);
    for (uint32_t i = first; i < first + count; i++)
        t->order[i] = keys[i].index;
    size_t left = t->nnodes;
    t->nnodes += 2;
    nd->first = (uint32_t)left;
    nd->count = 0;
    build(t, keys, left, first, half);
    build(t, keys, left + 1, first + half, count - half);
}

rl_status rl__emitter_tree_new(const rl_emitter *e, size_t n, v3 centre, double eps_floor, rl_emitter_tree **out)
{
    *out = NULL;
    rl_emitter_tree *t = calloc(1, sizeof *t);
    et_key *keys = malloc((n ? n : 1) * sizeof *keys);
    if (t) {
        t->order = malloc((n ? n : 1) * sizeof *t->order);
        t->nodes = malloc((2 * n + 1) * sizeof *t->nodes);
    }
    if (!t || !keys || !t->order || !t->nodes || n == 0 || n > UINT32_MAX) {
        free(keys);
        rl__emitter_tree_destroy(t);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the tree of %zu emitters", n);
    }
    t->e = e;
    t->n = n;
    t->centre = centre;
    t->eps_floor = eps_floor;
    for (size_t k = 0; k < n; k++)
        t->order[k] = (uint32_t)k;
    t->nnodes = 1;
    build(t, keys, 0, 0, (uint32_t)n);
    free(keys);
    *out = t;
    return RL_OK;
}

void rl__emitter_tree_destroy(rl_emitter_tree *t)
{
    if (!t)
        return;
    free(t->order);
    free(t->nodes);
    free(t);
}

/* @return 1 if one polygon of o hides every point of b (nb) from the hull of a (na), with the margin of
 * RL_REACH_TOL_EPS times the eps of segments between them (measured as pair.c measures a pair's). */
static int hidden(const rl_emitter_tree *t, const rl_occluders *o, const v3 *a, size_t na, const v3 *b, size_t nb)
{
    double r = 0.0;
    for (size_t i = 0; i < na; i++)
        r = dmax(r, v3_maxabs(v3_sub(a[i], t->centre)));
    for (size_t j = 0; j < nb; j++)
        r = dmax(r, v3_maxabs(v3_sub(b[j], t->centre)));
    double tol = RL_REACH_TOL_EPS * dmax(1e-6 * r, t->eps_floor);
    return rl__occluders_block_any(o, a, na, b, nb, tol);
}

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

size_t rl__emitter_tree_reach(const rl_emitter_tree *t, const rl_occluders *o, const v3 *a, size_t na,
                              uint32_t *out)
{
    size_t n = 0;
    uint32_t stack[TREE_STACK];
    size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const et_node *nd = &t->nodes[stack[--top]];
        v3 corner[8];
        for (int c = 0; c < 8; c++)
            corner[c] = (v3){c & 1 ? nd->hi.x : nd->lo.x, c & 2 ? nd->hi.y : nd->lo.y, c & 4 ? nd->hi.z : nd->lo.z};
        if (hidden(t, o, a, na, corner, 8))
            continue;
        if (nd->count == 0 && top + 2 <= TREE_STACK) {
            stack[top++] = nd->first + 1;
            stack[top++] = nd->first;
            continue;
        }
        if (nd->count == 0) { /* deeper than any tree of 2^64 emitters: cannot happen; keep them all */
            for (size_t k = 0; k < t->n; k++)
                out[k] = (uint32_t)k;
            return t->n;
        }
        for (uint32_t i = nd->first; i < nd->first + nd->count; i++) {
            const rl_emitter *e = &t->e[t->order[i]];
            if (nd->count == 1 || !hidden(t, o, a, na, e->verts, e->nverts))
                out[n++] = t->order[i];
        }
    }
    qsort(out, n, sizeof *out, cmp_u32);
    return n;
}
