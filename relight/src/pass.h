/*
 * pass.h - what the workers of one pass share: the pass's context (scene,
 * tracer, sampling, emitters), per-thread scratch space and work counters,
 * the key every random sequence of a (emitter, receiver) pair derives from,
 * and what a bounce pass by first hits reads of each polygon (rl_glow).
 * The types of the pass, below everything that runs one: the dispatcher
 * (transfer.h), the methods (method.h) and the gathers they share (leaf.h,
 * pair.h, point_gather.h, bounce.h) all stand on this header.
 */
#ifndef RELIGHT_PASS_H
#define RELIGHT_PASS_H

#include <math.h>

#include "emitter.h"
#include "emitter_tree.h"
#include "ilf/hash.h"
#include "relight/engine.h"
#include "shadow.h"
#include "tracer.h"

/* @return the bin of relative standard error r >= 0. */
static inline unsigned rl__cell_error_bin(double r)
{
    double x = r > 0 ? (log10(r) - RL_CELL_ERROR_LOG0) * RL_CELL_ERROR_PER_DECADE : 0.0;
    return x <= 0 ? 0u : x >= RL_CELL_ERROR_BINS - 1 ? RL_CELL_ERROR_BINS - 1 : (unsigned)x;
}

/* @return the relative standard error at the middle of bin b (in log10). */
static inline double rl__cell_error_of_bin(unsigned b)
{
    return pow(10.0, RL_CELL_ERROR_LOG0 + (b + 0.5) / RL_CELL_ERROR_PER_DECADE);
}

/* Work counters of one pass; summed over threads. */
typedef struct rl_counters {
    uint64_t samples;           /* sample rays generated */
    uint64_t rays_cast;         /* rays handed to Embree */
    uint64_t rays_kept;         /* rays that reached the emitter unoccluded (first hits: that met a re-emitter) */
    uint64_t rays_free;         /* rays not traced because an exact test found them unoccluded */
    uint64_t leaves_considered; /* (pair, solid angle) leaves of the hierarchy considered */
    uint64_t leaves_culled;     /* of those, culled before any ray */
    uint64_t pairs;             /* (emitter, receiver tile) pairs that can exchange light */
    uint64_t pairs_descended;   /* pairs sampled at a finer level than partition_n */
    uint64_t refinements;       /* adaptive: nodes split into their children */
    double variance;            /* adaptive: summed variance of the cells' estimates, (W m^-2)^2 */
    uint64_t cell_error[RL_CELL_ERROR_BINS]; /* cells by relative standard error (rl__cell_error_bin()) */
    int budget_reached;         /* adaptive: the time budget stopped a refinement */
} rl_counters;

/* What every worker shares during one pass. */
typedef struct rl_transfer_ctx {
    const rl_scene *scene;
    const rl_tracer *tracer;
    const rl_occluders *occluders; /* which polygons can block a point's view of an emitter */
    const rl_sampling *sampling;
    uint32_t pass;
    const rl_emitter *emitters;
    size_t nemitters;
    v3 centre;     /* where the tracer recentres the scene */
    double eps;    /* distance below which single precision cannot resolve the scene itself, m */
    double margin; /* outward margin of every Minkowski region, m */
    const struct rl_glow *glow; /* bounce passes with bounce_rays: what each scene polygon re-emits (bounce.c) */
    const struct rl_emitter_tree *reach; /* the emitters, to list those a tile may exchange light with (or NULL: all) */
    double deadline; /* adaptive: CLOCK_MONOTONIC seconds after which nothing is refined; 0 = none */
} rl_transfer_ctx;

/* Per-thread scratch space reused between tiles. */
typedef struct rl_scratch {
    uint64_t *leaves;
    size_t nleaves, cap;
    double (*row_acc)[3]; /* one grid row's accumulators */
    double *row_scale;    /* and the factors that turn them into irradiance */
    size_t row_cap;
    double *pair_total;   /* adaptive: each tile cell's total from the current emitter */
    uint32_t *pair_leaves; /* adaptive: and the leaves carrying it */
    size_t pair_cap;
    uint32_t first_cell;  /* the tile's first cell index */
    uint32_t *occ;        /* point receivers: one list of possible occluders per level of the walk */
    uint8_t *vis;         /* Lambert's gather: each grid square's rl_visibility of the current emitter */
    size_t vis_cap;
    uint32_t *block_occ;  /* and the possible occluders of each level of its blocks */
    struct rl_beam *beam; /* one beam's room (shadow.h), for Lambert's gather and point receivers */
    double (*anchor)[3];  /* Lambert's gather: a light field's unshadowed light at the tile's anchors (lambert.c) */
    size_t anchor_cap;
    float *blend;         /* a light field leaf's mixed radiance tables (rl__leaf_blend()) */
    struct rl_shadows *shadows; /* the current leaf's shadows (leaf_shadow.c) */
    size_t blend_cap;
    uint32_t *reach;      /* the emitters the current tile may exchange light with (emitter_tree.h) */
    size_t reach_cap;
    uint32_t reach_blockers[RL_REACH_BLOCKERS]; /* polygons that hid emitters from the current tile */
    size_t nreach_blockers;
} rl_scratch;

/* What a bounce pass by first hits reads of one scene polygon: the radiance its map re-emits from each
 * grid square (float; a square without a cell holds a neighbour's, rl__map_cell_near(), so that a hit
 * rounded just past the cells still reads light), W sr^-1 m^-2. map NULL: the polygon re-emits nothing. */
typedef struct rl_glow {
    const rl_map *map;
    float (*rad)[3]; /* [map->nu * map->nv] */
} rl_glow;

/* @return the key of what one pass samples between emitter ei and a receiver
 * (a map's index, or a point's key): every random sequence of the pair derives from it. */
static inline uint64_t rl__pair_key(const rl_transfer_ctx *ctx, uint32_t ei, uint64_t receiver)
{
    return ilf_hash_mix(ilf_hash_mix(ilf_hash_mix(ctx->sampling->seed, ctx->pass), ei), receiver);
}

#endif /* RELIGHT_PASS_H */
