/*
 * bounce.h - a bounce pass gathered by first-hit rays from each receiver
 * cell's hemisphere (bounce.c), and the glow of every scene polygon that
 * those rays read (rl_glow, pass.h).
 */
#ifndef RELIGHT_BOUNCE_H
#define RELIGHT_BOUNCE_H

#include "pass.h"

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

#endif /* RELIGHT_BOUNCE_H */
