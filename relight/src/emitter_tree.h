/*
 * emitter_tree.h - a bounding-box tree over one pass's emitters, and the
 * exact cull it serves: which emitters a receiver tile may exchange light
 * with at all (emitter_tree.c).
 *
 * An emitter is dropped for a region only when one scene polygon, or two
 * meeting at a corner (shadow.h), crosses every segment from the region to
 * it, with margins that hold for the shadow rays as traced (their ends offset by up to half RL_REACH_TOL_EPS
 * times the pair's eps, along their own lines): every ray of such a pair would be occluded (but for one
 * through a corner's shared edge, where the tracer may leave a crack no wider than its rounding, and the
 * exact shadows count it blocked), so the pair adds nothing to any cell and leaving it out changes no sum. Nothing is
 * dropped for distance or for being faint. Emitters are listed in
 * increasing index, the order the pass would have visited them in, so the
 * sums that remain keep their order.
 */
#ifndef RELIGHT_EMITTER_TREE_H
#define RELIGHT_EMITTER_TREE_H

#include "emitter.h"
#include "shadow.h"
#include "tracer.h"

typedef struct rl_emitter_tree rl_emitter_tree;

/* A shadow ray's ends are offset by up to eps / 1e-3 (pair.c, point_gather.c: eps / max(cos, 1e-3)); the
 * cull's margin from a blocker's plane is twice that, so that the ray's end points stay well clear of it
 * at the tracer's single precision (eps is eight of its ulps). */
#define RL_REACH_TOL_EPS 2000.0

/* Offsets shorten a ray along its own line, so where it crosses a blocker's plane does not move: inside the
 * blocker's edges the margin need only outlast the tracer's rounding (eps is eight of its ulps). A margin that
 * grew with the offsets (which grow with the scene's extent) would, on a floor of 10 x 10 rooms, exceed the
 * few centimetres by which a segment from a floor to the next room's lamp clears that room's wall's foot. */
#define RL_REACH_EDGE_EPS 16.0

/* Most polygons a walk gives back as having hidden something from its region (rl__emitter_tree_reach()). */
#define RL_REACH_BLOCKERS 4

/* Builds the tree of emitters e[0 .. n) (n >= 1; e and tracer must outlive it; the tracer's segments only
 * spare searches). centre and eps_floor are the pass's (rl_transfer_ctx): the cull's margin is measured as
 * the pairs' eps is. @return RL_OK and *out, or RL_ERR_NOMEM. */
rl_status rl__emitter_tree_new(const rl_emitter *e, size_t n, const rl_tracer *tracer, v3 centre, double eps_floor,
                               rl_emitter_tree **out);

/* Releases the tree. NULL is a no-op. */
void rl__emitter_tree_destroy(rl_emitter_tree *t);

/* Lists into out (room for every emitter of t), in increasing index, the
 * emitters of t that some segment from the convex hull of the world points
 * a (na, 1 .. RL_BEAM_MAX_VERTS) may reach unblocked by the polygons of o:
 * all but those one polygon wholly hides from it. Also left out, as rl__pair_setup()
 * would leave them: emitters wholly behind the plane of frame rf, a's
 * receiver, and emitters the whole of a lies behind (both only when rf is
 * given: a is a tile, not a point). Gives in blockers (room for
 * RL_REACH_BLOCKERS; *nblockers of them) the polygons that hid something
 * from a, the latest first: a tile's own room's walls, which often hide the
 * narrower beams of an emitter they do not hide whole. @return the count of out. */
size_t rl__emitter_tree_reach(const rl_emitter_tree *t, const rl_occluders *o, const v3 *a, size_t na,
                              const rl_frame *rf, uint32_t *out, uint32_t *blockers, size_t *nblockers);

#endif /* RELIGHT_EMITTER_TREE_H */
