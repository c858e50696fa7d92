/*
 * box_tree.h - a bounding-box tree over a set of boxes, the index that the
 * occluders (shadow.c) and the emitters (emitter_tree.c) are walked by.
 *
 * Boxes are axis-aligned, in world metres. The tree is built by median
 * splits on the longest axis of the boxes' centres, at most
 * RL_BOX_TREE_LEAF boxes a leaf; node 0 is the root, an inner node's
 * children are nodes first and first + 1, and a leaf holds the boxes
 * order[first .. first + count). Every node's box holds its boxes. The
 * tree is read-only once built, so walks from any number of threads share
 * it; the same boxes always make the same tree.
 */
#ifndef RL_BOX_TREE_H
#define RL_BOX_TREE_H

#include <stddef.h>
#include <stdint.h>

#include "ilf/vec.h"

#define RL_BOX_TREE_LEAF 4
/* a walk's stack: deeper than any tree of 2^64 boxes */
#define RL_BOX_TREE_STACK 128

typedef struct rl_box_node {
    v3 lo, hi;
    uint32_t first, count; /* leaf: boxes order[first .. first+count); inner: count = 0, children first, first+1 */
} rl_box_node;

typedef struct rl_box_tree {
    uint32_t *order; /* the boxes' indices, leaf by leaf */
    rl_box_node *nodes;
    size_t nnodes; /* 0 for a tree of no boxes */
} rl_box_tree;

/* Builds *t over boxes [lo[k], hi[k]], k < n (n <= UINT32_MAX; lo and hi are read only here).
 * @return 0, or -1 when memory runs out (t then holds nothing to free). */
int rl__box_tree_build(rl_box_tree *t, const v3 *lo, const v3 *hi, size_t n);

/* Frees what t holds; a zeroed tree is a no-op. */
void rl__box_tree_free(rl_box_tree *t);

#endif /* RL_BOX_TREE_H */
