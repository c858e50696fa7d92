/*
 * transfer.h - one tile of one pass, the entry point the scheduler calls:
 * it picks the pass's method (method.h), or the point receivers' own-view
 * gather (point_gather.h), or the bounce gather by first hits (bounce.h), and
 * gathers every emitter into the tile. The shared types of the pass are
 * in pass.h, below this dispatcher.
 */
#ifndef RELIGHT_TRANSFER_H
#define RELIGHT_TRANSFER_H

#include "pass.h"

/* Frees what a scratch space holds (not the struct). */
void rl__scratch_free(rl_scratch *s);

/* Adds to m->e_pass, for the cells in grid rows [row0, row1) of map m, the
 * irradiance from every emitter of ctx, by ctx->sampling->method; when
 * ctx->glow is set (a bounce pass by first hits), by rl__bounce_tile()
 * instead, for every map of a polygon. map_index
 * only keys the random sequences. Deterministic: the result depends on
 * nothing but the arguments. @return 0, or -1 if scratch memory ran out. */
int rl__transfer_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                  rl_scratch *scratch, rl_counters *cnt);

#endif /* RELIGHT_TRANSFER_H */
