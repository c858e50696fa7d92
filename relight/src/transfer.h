/*
 * transfer.h - one pass's transfer of light from emitters to receivers: what
 * the workers share (context, per-thread scratch, counters), the tile entry
 * point the scheduler calls, and the point receivers' own-view gather. The
 * methods themselves sit behind method.h, each in a file of its own.
 */
#ifndef RELIGHT_TRANSFER_H
#define RELIGHT_TRANSFER_H

#include "emitter.h"
#include "ilf/hash.h"
#include "shadow.h"
#include "tracer.h"

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
    double (*anchor)[3];  /* Lambert's gather: a light field's unshadowed light at the tile's anchors (views.c) */
    size_t anchor_cap;
    float *blend;         /* a light field leaf's mixed radiance tables (rl__leaf_blend()) */
    struct rl_shadows *shadows; /* the current leaf's shadows (leaf_shadow.c) */
    size_t blend_cap;
} rl_scratch;

/* @return the key of what one pass samples between emitter ei and a receiver
 * (a map's index, or a point's key): every random sequence of the pair derives from it. */
static inline uint64_t rl__pair_key(const rl_transfer_ctx *ctx, uint32_t ei, uint64_t receiver)
{
    return ilf_hash_mix(ilf_hash_mix(ilf_hash_mix(ctx->sampling->seed, ctx->pass), ei), receiver);
}

/* Frees what a scratch space holds (not the struct). */
void rl__scratch_free(rl_scratch *s);

/* Adds to out the irradiance at point x (unit normal nx) from emitter ei,
 * by culled transfer from the point's own view (points.c): exact where a
 * part of the emitter is wholly seen or wholly hidden, `rays` samples in
 * each solid angle a shadow boundary crosses. receiver keys the samples.
 * @return 0, or -1 if scratch memory ran out. */
int rl__point_gather(const rl_transfer_ctx *ctx, uint32_t ei, uint64_t receiver, v3 x, v3 nx, uint32_t rays,
                 double out[3], rl_scratch *s, rl_counters *cnt);

/* @return (1/2) sum over edges of theta_i (n . g_i): the irradiance at x (unit normal n) from the
 * convex polygon q (nq vertices, all in front of x's plane) of unit radiance, unoccluded. */
double rl__polygon_lambert(v3 x, v3 n, const v3 *q, size_t nq);

/* Adds to m->e_pass, for the cells in grid rows [row0, row1) of map m, the
 * irradiance from every emitter of ctx, by ctx->sampling->method; when
 * ctx->glow is set (a bounce pass by first hits), by rl__bounce_tile()
 * instead, for every map of a polygon. map_index
 * only keys the random sequences. Deterministic: the result depends on
 * nothing but the arguments. @return 0, or -1 if scratch memory ran out. */
int rl__transfer_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                  rl_scratch *scratch, rl_counters *cnt);

/* What a bounce pass by first hits reads of one scene polygon: the radiance its map re-emits from each
 * grid square (float; a square without a cell holds a neighbour's, rl__map_cell_near(), so that a hit
 * rounded just past the cells still reads light), W sr^-1 m^-2. map NULL: the polygon re-emits nothing. */
typedef struct rl_glow {
    const rl_map *map;
    float (*rad)[3]; /* [map->nu * map->nv] */
} rl_glow;

/* Builds the glow of every scene polygon from the bounce emitters e[0 .. ne) (EM_MAP), one per
 * polygon, in *out ([scene->npolygons]), on up to threads threads. @return RL_OK, or RL_ERR_NOMEM
 * (nothing to free). */
rl_status rl__glow_new(const rl_scene *scene, const rl_emitter *e, size_t ne, unsigned threads, rl_glow **out);

/* Frees glow (npolygons entries, as built). NULL is a no-op. */
void rl__glow_free(rl_glow *glow, size_t npolygons);

/* A bounce pass by first-hit rays from each cell's hemisphere (bounce.c): adds to m->e_pass, for
 * the cells in grid rows [row0, row1) of map m, the irradiance re-emitted by the surfaces its
 * sampling->bounce_rays cosine-weighted rays per cell first meet (ctx->glow). */
void rl__bounce_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                     rl_counters *cnt);

#endif /* RELIGHT_TRANSFER_H */
