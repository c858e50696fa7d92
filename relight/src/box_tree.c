/*
 * box_tree.c - the bounding-box tree of box_tree.h.
 *
 * Invariants: the tree depends on nothing but the boxes and their order
 * (the median selection is deterministic), and has at most 2n - 1 nodes.
 */
#include <stdlib.h>

#include "box_tree.h"

typedef struct build_ctx {
    const v3 *lo, *hi;
    rl_box_tree *t;
} build_ctx;

static double v3_axis(v3 a, int k) { return k == 0 ? a.x : k == 1 ? a.y : a.z; }

/* Twice box k's centre on axis a (the halving changes no comparison). */
static double centre2(const build_ctx *c, uint32_t k, int a) { return v3_axis(c->lo[k], a) + v3_axis(c->hi[k], a); }

/* Partially orders order[lo..hi) so that the box at mid has the median centre on axis a (quickselect). */
static void select_median(const build_ctx *c, uint32_t *order, size_t lo, size_t hi, size_t mid, int a)
{
    while (hi - lo > 1) {
        double pivot = centre2(c, order[(lo + hi) / 2], a);
        size_t i = lo, j = hi - 1;
        while (i <= j) {
            while (centre2(c, order[i], a) < pivot)
                i++;
            while (centre2(c, order[j], a) > pivot)
                j--;
            if (i <= j) {
                uint32_t t = order[i];
                order[i] = order[j];
                order[j] = t;
                i++;
                if (j == 0)
                    break;
                j--;
            }
        }
        if (mid <= j)
            hi = j + 1;
        else if (mid >= i)
            lo = i;
        else
            return;
    }
}

/* Builds the subtree of node over order[first, first+count), count >= 1. */
static void build(const build_ctx *c, size_t node, uint32_t first, uint32_t count)
{
    rl_box_tree *t = c->t;
    uint32_t k0 = t->order[first];
    v3 lo = c->lo[k0], hi = c->hi[k0];
    v3 clo = v3_scale(v3_add(lo, hi), 0.5), chi = clo;
    for (uint32_t i = first; i < first + count; i++) {
        uint32_t k = t->order[i];
        lo = (v3){dmin(lo.x, c->lo[k].x), dmin(lo.y, c->lo[k].y), dmin(lo.z, c->lo[k].z)};
        hi = (v3){dmax(hi.x, c->hi[k].x), dmax(hi.y, c->hi[k].y), dmax(hi.z, c->hi[k].z)};
        v3 m = v3_scale(v3_add(c->lo[k], c->hi[k]), 0.5);
        clo = (v3){dmin(clo.x, m.x), dmin(clo.y, m.y), dmin(clo.z, m.z)};
        chi = (v3){dmax(chi.x, m.x), dmax(chi.y, m.y), dmax(chi.z, m.z)};
    }
    rl_box_node *nd = &t->nodes[node];
    nd->lo = lo;
    nd->hi = hi;
    if (count <= RL_BOX_TREE_LEAF) {
        nd->first = first;
        nd->count = count;
        return;
    }
    v3 ext = v3_sub(chi, clo);
    int a = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    uint32_t half = count / 2;
    select_median(c, t->order, first, first + count, first + half, a);
    size_t left = t->nnodes;
    t->nnodes += 2;
    nd->first = (uint32_t)left;
    nd->count = 0;
    build(c, left, first, half);
    build(c, left + 1, first + half, count - half);
}

int rl__box_tree_build(rl_box_tree *t, const v3 *lo, const v3 *hi, size_t n)
{
    *t = (rl_box_tree){NULL, NULL, 0};
    if (n > UINT32_MAX)
        return -1;
    t->order = malloc((n ? n : 1) * sizeof *t->order);
    t->nodes = malloc((2 * n + 1) * sizeof *t->nodes);
    if (!t->order || !t->nodes) {
        rl__box_tree_free(t);
        return -1;
    }
    for (size_t k = 0; k < n; k++)
        t->order[k] = (uint32_t)k;
    if (n > 0) {
        t->nnodes = 1;
        build(&(build_ctx){lo, hi, t}, 0, 0, (uint32_t)n);
    }
    return 0;
}

void rl__box_tree_free(rl_box_tree *t)
{
    free(t->order);
    free(t->nodes);
    *t = (rl_box_tree){NULL, NULL, 0};
}
