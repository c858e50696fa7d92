/*
 * mesh.h - internal to the scene loader: polygons and meshes added to the
 * builder (build.h) while a scene file is read.
 *
 * scene.c owns the builder and reads the JSON; build.c keeps the material
 * table and formats messages; mesh.c turns vertex lists into polygons that satisfy
 * scene_model.h's invariants (planar, strictly convex, area > 0, finite,
 * right-hand normals) and turns imported mesh files (ilf/mesh.h) into them.
 */
#ifndef RELIGHT_MESH_H
#define RELIGHT_MESH_H

#include "build.h"

/*
 * Checks n vertices (finite, n <= RL_MAX_POLYGON_VERTICES) as one polygon
 * and appends it, or its ear-clipped parts under RL_POLY_SPLIT, labelled
 * label. v may be b->face but no other scratch array.
 * @return RL_OK; RL_ERR_INPUT naming label; RL_ERR_NOMEM.
 */
rl_status rl__build_polygon(rl_build *b, const double (*v)[3], size_t n, uint32_t material,
                            const char *label, rl_poly_policy policy);

/* Which axis of a mesh file is up (docs/scene.md, meshes). */
typedef enum rl_mesh_up {
    RL_MESH_UP_DECLARED, /* what the file declares (glTF +y, FBX its UpAxis), else z */
    RL_MESH_UP_Z,        /* +z: kept as stored */
    RL_MESH_UP_Y         /* +y: turned so that +y becomes +z, (x, y, z) -> (x, -z, y) */
} rl_mesh_up;

/* How one "meshes" entry is read. */
typedef struct rl_mesh_options {
    const uint32_t *fallback; /* the material of faces without their own, or NULL: such faces are an error */
    rl_mesh_up up;
    int flip;      /* every face turned over: its front becomes its back */
    int two_sided; /* every face added twice, once facing each way */
} rl_mesh_options;

/*
 * Reads the mesh file at path (already resolved) for scene element elem;
 * shown is the name the scene gave it. Faces are turned up, flipped and
 * doubled as opt says, and adjacent coplanar convex faces of one material
 * are merged into convex polygons (mesh.c says how).
 * @return RL_OK; RL_ERR_INPUT naming elem and the file; RL_ERR_NOMEM.
 */
rl_status rl__build_mesh(rl_build *b, const char *path, const char *elem, const char *shown,
                         const rl_mesh_options *opt);

#endif /* RELIGHT_MESH_H */
