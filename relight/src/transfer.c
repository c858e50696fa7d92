/*
 * transfer.c - one tile of one pass: the part of a receiver map in a band of
 * grid rows, gathered from every emitter by the pass's method.
 *
 * A tile's result depends on nothing but its arguments (the methods key
 * every random number by seed, pass, emitter, receiver and cell), so the
 * scheduler may hand tiles to threads in any order. Point receivers (maps
 * with no polygon) of methods that cull from a point's own view are
 * gathered by rl__point_gather() rather than by leaves of a tile.
 */
#include <assert.h>
#include <stdlib.h>

#include "bounce.h"
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

int rl__transfer_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                      rl_scratch *scratch, rl_counters *cnt)
{
    const rl_method_impl *method = rl__method_for(ctx->sampling->method);
    assert(method); /* the scene's settings are validated against the same list */
    if (m->polygon < 0 && method->point_view) {
        /* a point receiver is culled from its own view of each emitter */
        int rc = 0;
        for (size_t e = 0; e < ctx->nemitters && rc == 0; e++) {
            cnt->pairs++;
            rc = rl__point_gather(ctx, (uint32_t)e, map_index, m->frame.origin, m->frame.n,
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
    for (size_t e = 0; e < ctx->nemitters && rc == 0 && t->npoly > 0; e++)
        rc = method->gather(ctx, t, (uint32_t)e, scratch, cnt);
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
}
