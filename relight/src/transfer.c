/*
 * transfer.c - one tile of one pass: the part of a receiver map in a band of
 * grid rows, gathered from every emitter by the pass's method.
 *
 * A tile's result depends on nothing but its arguments (the methods key
 * every random number by seed, pass, emitter, receiver and cell), so the
 * scheduler may hand tiles to threads in any order. A tile gathers only
 * from the emitters that no single polygon wholly hides from it
 * (emitter_tree.h), in increasing index as it would visit them all, so
 * its sums are those of the whole loop. Point receivers (maps
 * with no polygon) of methods that cull from a point's own view are
 * gathered by rl__point_gather() rather than by leaves of a tile.
 */
#include <assert.h>
#include <stdlib.h>

#include "bounce.h"
#include "emitter_tree.h"
#include "method.h"
#include "point_gather.h"
#include "transfer.h"

const rl_method_impl *rl__method_for(rl_method id)
{
    static const rl_method_impl *const all[] = {&rl__method_culled, &rl__method_naive, &rl__method_area,
                                                &rl__method_solidangle, &rl__method_adaptive};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
        if (all[k]->id == id)
            return all[k];
    return NULL;
}

/* Lists in s->reach the emitters that region a (na world points, their
 * hull; a tile's with its map's frame rf, a point's with NULL) may
 * exchange light with, in increasing index: every emitter when the
 * pass has no tree, else those no single polygon hides from the region
 * and that face it (rl__emitter_tree_reach()). @return their count, or SIZE_MAX without memory. */
static size_t reachable(const rl_transfer_ctx *ctx, const v3 *a, size_t na, const rl_frame *rf, rl_scratch *s)
{
    if (ctx->nemitters > s->reach_cap) {
        uint32_t *grown = realloc(s->reach, ctx->nemitters * sizeof *grown);
        if (!grown)
            return SIZE_MAX;
        s->reach = grown;
        s->reach_cap = ctx->nemitters;
    }
    s->nreach_blockers = 0;
    if (!ctx->reach || !ctx->occluders || na < 1 || na > RL_BEAM_MAX_VERTS) {
        for (size_t e = 0; e < ctx->nemitters; e++)
            s->reach[e] = (uint32_t)e;
        return ctx->nemitters;
    }
    return rl__emitter_tree_reach(ctx->reach, ctx->occluders, a, na, rf, s->reach, s->reach_blockers,
                                  &s->nreach_blockers);
}

int rl__transfer_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                      rl_scratch *scratch, rl_counters *cnt)
{
    const rl_method_impl *method = rl__method_for(ctx->sampling->method);
    assert(method); /* the scene's settings are validated against the same list */
    if (m->polygon < 0 && method->point_view) {
        /* a point receiver is culled from its own view of each emitter it may reach */
        size_t n = reachable(ctx, &m->frame.origin, 1, NULL, scratch);
        if (n == SIZE_MAX)
            return -1;
        int rc = 0;
        for (size_t k = 0; k < n && rc == 0; k++) {
            cnt->pairs++;
            rc = rl__point_gather(ctx, scratch->reach[k], map_index, m->frame.origin, m->frame.n,
                                  ctx->sampling->rays_per_solid_angle, m->e_pass[0], scratch, cnt);
        }
        return rc;
    }
    if (ctx->glow && m->polygon >= 0) {
        rl__bounce_tile(ctx, map_index, m, row0, row1, cnt);
        return 0;
    }
    rl_tile *t = malloc(sizeof *t);
    if (!t)
        return -1;
    rl__tile_make(m, map_index, row0, row1, t);
    int rc = 0;
    if (t->npoly > 0) {
        /* the emitters every one of whose rays to the tile a single polygon stops add nothing: left out */
        v3 a[RL_MAX_POLY_VERTS + 4];
        for (size_t j = 0; j < t->npoly; j++)
            a[j] = frame_point(&m->frame, t->poly[j]);
        size_t n = reachable(ctx, a, t->npoly, &m->frame, scratch);
        rc = n == SIZE_MAX ? -1 : 0;
        for (size_t k = 0; k < n && rc == 0; k++)
            rc = method->gather(ctx, t, scratch->reach[k], scratch, cnt);
    }
    free(t);
    return rc;
}

void rl__scratch_free(rl_scratch *s)
{
    free(s->occ);
    free(s->vis);
    free(s->block_occ);
    free(s->anchor);
    free(s->beam);
    free(s->blend);
    rl__shadows_free(s->shadows);
    free(s->pair_total);
    free(s->pair_leaves);
    free(s->leaves);
    free(s->row_acc);
    free(s->row_scale);
    free(s->reach);
}
