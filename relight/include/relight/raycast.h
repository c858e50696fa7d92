/*
 * raycast.h - the scene as a plain ray caster sees it: first hits against
 * its polygons, and each polygon's and light field's description. It exists
 * for code that must not share the engine's estimators, such as the
 * independent path-traced reference of `ilf bench --reference pathtrace`
 * (bench/src/bench_pathtrace.c): Embree stays behind relight's wall, and
 * this is the one door through it that answers a single ray.
 *
 * Invariants: polygon ids are the scene's (0 .. rl_scene_polygon_count()-1);
 * descriptions borrow the scene's memory and live as long as the scene;
 * a ray caster answers from several threads at once.
 *
 * This header is valid C99 and C++.
 */
#ifndef RELIGHT_RAYCAST_H
#define RELIGHT_RAYCAST_H

#include <stddef.h>
#include <stdint.h>

#include "lfio/lightfield.h"
#include "relight/relight.h"
#include "relight/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/** First hits against a scene's polygons. Opaque. */
typedef struct rl_raycaster rl_raycaster;

/** Where a ray first meets a polygon. */
typedef struct rl_ray_hit {
    uint32_t polygon; /**< the scene's polygon id */
    double distance;  /**< along the unit direction, metres */
    int front;        /**< 1 when the ray meets the polygon's front (dir . normal < 0) */
} rl_ray_hit;

/** A polygon as loaded: geometry and material. */
typedef struct rl_polygon_desc {
    const double (*vertices)[3]; /**< count points, counter-clockwise seen from the front */
    uint32_t count;
    double normal[3];            /**< unit normal of the front */
    double area;                 /**< m^2 */
    float albedo[3];             /**< diffuse reflectance */
    float emission[3];           /**< exitant radiance of the front, W sr^-1 m^-2 */
} rl_polygon_desc;

/** A light field emitter as placed in the scene. */
typedef struct rl_lightfield_desc {
    const lfio_slab *slab;             /**< the slab; its radiance is read in its own frame */
    double origin[3], u[3], v[3];      /**< the slab's rectangle in the scene */
    double rot[3][3];                  /**< rotation from the slab's frame to the scene's */
} rl_lightfield_desc;

/** Builds a ray caster over the scene's polygons (one thread builds it).
 * @return RL_OK and *out; RL_ERR_ARG (no polygons), RL_ERR_NOMEM, RL_ERR_INTERNAL. */
rl_status rl_raycaster_new(const rl_scene *scene, rl_raycaster **out);

/** Releases a ray caster. NULL is a no-op. */
void rl_raycaster_destroy(rl_raycaster *rc);

/** Finds the first polygon met by org + s dir for s in [tnear, tfar] (dir of unit length).
 * @return 1 with *hit, or 0 when the ray meets none. */
int rl_raycaster_hit(const rl_raycaster *rc, const double org[3], const double dir[3], double tnear, double tfar,
                     rl_ray_hit *hit);

/** Describes polygon k. @return RL_OK, or RL_ERR_ARG when k is out of range. */
rl_status rl_scene_polygon_describe(const rl_scene *s, size_t k, rl_polygon_desc *out);

/** Describes light field emitter k. @return RL_OK, or RL_ERR_ARG when k is out of range. */
rl_status rl_scene_lightfield_describe(const rl_scene *s, size_t k, rl_lightfield_desc *out);

#ifdef __cplusplus
}
#endif

#endif /* RELIGHT_RAYCAST_H */
