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
 * estimator that replaces leaves where leaves are the wrong tool (lambert.c:
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

#include "leaf_shadow.h"

/* ------------------------------------------------------- exact estimators */

/* An emitter that subtends fewer solid angles of partition_n than this
 * from a receiver tile (rl_pair.leaves) is gathered by Lambert's formula
 * under culled and naive when descend is on: leaves a few solid angles
 * across are mostly half empty, while the area-weighted mean is noisy only
 * for a near, large emitter (docs/methods.md has the measurements). */
#define RL_LAMBERT_LEAVES 64.0

/* Lambert's formula times the weighted mean of radiance * visibility, for
 * every cell of the tile: a constant emitter, or one a few solid angles
 * across (lambert.c). Blocks of cells that see all of the emitter or none of
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
