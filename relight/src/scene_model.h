/*
 * scene_model.h - the layout of a loaded scene, shared by the loader
 * (scene.c, mesh.c) and the engine. Invariants established by rl_scene_load():
 *   - every polygon has 3 .. RL_SCENE_MAX_POLY_VERTS vertices, is planar (every vertex within
 *     1e-6 * its diameter of the plane), strictly convex (collinear vertices
 *     removed), has area > 0 and finite coordinates; normal is the unit
 *     right-hand-rule normal; material indexes materials;
 *   - albedo in [0, 1], emission finite and >= 0;
 *   - every light field emitter holds its loaded file and a borrowed slab,
 *     and its transform is a similarity (rotation times uniform scale > 0,
 *     plus translation), so directions map by the rotation alone;
 *   - cell_size > 0 and finite; sampling passes rl_job_check()'s checks.
 * cell_size, sampling and time_budget are the job the file suggests: only rl_job_default() reads them,
 * never the engine, which takes its job with each call.
 */
#ifndef RELIGHT_SCENE_INTERNAL_H
#define RELIGHT_SCENE_INTERNAL_H

#include <lfio/lightfield.h>

#include "common.h"
#include "relight/camera.h"
#include "relight/scene.h"
#include "ilf/limits.h"
#include "ilf/vec.h"

/* Most vertices one polygon may have (the engine's clipping buffers are sized by it). */
#define RL_SCENE_MAX_POLY_VERTS ILF_POLYGON_MAX_VERTICES

typedef struct rl_material {
    char name[64];
    float albedo[3];   /* reflectance, 0..1 */
    float emission[3]; /* exitant radiance of the front face, W sr^-1 m^-2 */
} rl_material;

typedef struct rl_polygon {
    uint32_t first;    /* first vertex in rl_scene.vertices */
    uint32_t count;    /* number of vertices, >= 3 */
    uint32_t material; /* index into rl_scene.materials */
    double normal[3];  /* unit normal of the front face */
    double area;       /* m^2 */
    char label[96];    /* element for messages, e.g. "polygons[3]" or "meshes[1] (room.obj) face 12" */
} rl_polygon;

typedef struct rl_lightfield {
    char file[1024];        /* as resolved against the scene's folder */
    lfio_lightfield *lf;    /* owned when owns_lf, else borrowed from an earlier entry naming the same file */
    const lfio_slab *slab;  /* borrowed from lf */
    int owns_lf;            /* entries naming the same file share one copy: the first owns it */
    double rot[3][3];       /* rotation part of the transform (orthonormal, det +1) */
    double scale;           /* uniform scale of the transform, > 0 */
    double translate[3];
    double origin[3], u[3], v[3]; /* the slab rectangle placed in the scene */
    char label[96];         /* e.g. "lightfields[0]" */
    uint32_t nu, nv, n; /* the slab's positions and partition level (where it is lit: the engine's
                         * rl_slab_tables, built for each run) */
} rl_lightfield;

/* The scene's camera is a public value (relight/camera.h). Checks it (camera.c): @return 0, or 1 with the problem
 * in why (size bytes). */
int rl__camera_problem(const rl_camera *c, char *why, size_t size);

struct rl_scene {
    char path[1024];
    rl_material *materials;
    size_t nmaterials;
    double (*vertices)[3];
    size_t nvertices;
    rl_polygon *polygons;
    size_t npolygons;
    rl_lightfield *lightfields;
    size_t nlightfields;
    double cell_size;     /* the file's radiance_maps.cell_size, metres (suggested) */
    rl_sampling sampling; /* the file's sampling settings (suggested) */
    double time_budget;   /* the file's sampling.time_budget: a suggested run option, seconds, >= 0 */
    int has_camera;
    rl_camera camera;
};

#endif /* RELIGHT_SCENE_INTERNAL_H */
