/*
 * tracer.h - ray queries against the scene's polygons. The only interface
 * to Embree; nothing else in the tree includes its headers.
 *
 * Coordinates are world metres in double; the tracer recentres the scene
 * on its bounding box before handing single-precision vertices to Embree,
 * so precision follows the scene's size rather than its distance from the
 * origin. Queries are thread-safe.
 */
#ifndef RELIGHT_TRACER_H
#define RELIGHT_TRACER_H

#include <stdint.h>

#include "scene_model.h"
#include "shadow.h"
#include "ilf/vec.h"

typedef struct rl_tracer rl_tracer;

/* Builds the acceleration structure of every polygon (robust mode) on at most `threads` threads (>= 1;
 * Embree's own workers, which it would otherwise start on every hardware thread, follow the run's count).
 * @return RL_OK and *out; RL_ERR_NOMEM or RL_ERR_INTERNAL. */
rl_status rl__tracer_new(const rl_scene *scene, unsigned threads, rl_tracer **out);

/* Releases the tracer. NULL is a no-op. */
void rl__tracer_destroy(rl_tracer *t);

/* @return 1 if any polygon meets the ray org + s*dir for s in [tnear, tfar] (dir unit). */
int rl__tracer_occluded(const rl_tracer *t, v3 org, v3 dir, double tnear, double tfar);

/* Most rays one rl__tracer_occluded_n() or rl__tracer_hit_n() call takes (hit_n traces 16 lanes). */
#define RL_RAY_PACKET 16

/* Tests n <= RL_RAY_PACKET rays at once (packets of 4, 8 or 16, as n
 * needs): occluded[i] = rl__tracer_occluded(t, org[i], dir[i], tnear[i], tfar[i]). */
void rl__tracer_occluded_n(const rl_tracer *t, size_t n, const v3 *org, const v3 *dir, const double *tnear,
                       const double *tfar, int *occluded);

/* Finds the first polygon hit by each of n <= RL_RAY_PACKET rays at once (one packet of 16):
 * polygon[i] and dist[i] as rl__tracer_hit() gives them, polygon[i] = UINT32_MAX where ray i hits none. */
void rl__tracer_hit_n(const rl_tracer *t, size_t n, const v3 *org, const v3 *dir, const double *tnear,
                      const double *tfar, uint32_t *polygon, double *dist);

/* Finds the first polygon in [tnear, tfar] whose front faces the ray (dot(dir, normal) < 0), passing
 * through backs: what a ray that met a back finds where two polygons coincide back to back.
 * @return 1 with *polygon and *dist, or 0. */
int rl__tracer_hit_front(const rl_tracer *t, v3 org, v3 dir, double tnear, double tfar, uint32_t *polygon,
                         double *dist);

/* Finds the first polygon hit in [tnear, tfar]. @return 1 with *polygon and *dist, or 0. */
int rl__tracer_hit(const rl_tracer *t, v3 org, v3 dir, double tnear, double tfar, uint32_t *polygon, double *dist);

/* @return the largest coordinate magnitude of the recentred scene, m: the
 * scale at which single-precision positions round. */
double rl__tracer_extent(const rl_tracer *t);

/* @return the point the tracer recentres the scene on. */
v3 rl__tracer_centre(const rl_tracer *t);

/* @return the exact occluder index of the same polygons (shadow.h), owned by the tracer. */
const rl_occluders *rl__tracer_occluders(const rl_tracer *t);

/* Sets flush-to-zero and denormals-are-zero for the calling thread, as Embree advises. */
void rl__tracer_thread_init(void);

#endif /* RELIGHT_TRACER_H */
