/*
 * build.h - internal to the scene loader: the builder that scene.c and
 * mesh.c fill together while a scene file is read, its messages and its
 * material table (build.c).
 *
 * Invariants of a builder between calls: the scene's vertices, polygons,
 * materials and light fields arrays hold their counts of valid entries
 * inside capacities vertex_cap, polygon_cap, material_cap and
 * lightfield_cap; vertex, polygon and material counts never exceed
 * RL_MAX_ELEMENTS; names indexes every material by name; the scratch arrays
 * are allocated before any reading starts.
 */
#ifndef RELIGHT_BUILD_H
#define RELIGHT_BUILD_H

#include "ilf/limits.h"
#include "scene_model.h"

/* Most polygons, and most vertices, one scene may hold (ilf/limits.h says why). */
#define RL_MAX_ELEMENTS ILF_MESH_MAX_ELEMENTS

/* Most vertices one polygon or mesh face may have (ilf/limits.h says why). */
#define RL_MAX_POLYGON_VERTICES ILF_MESH_MAX_FACE_VERTICES

/* What to do with a polygon that is not planar and convex. */
typedef enum rl_poly_policy {
    RL_POLY_STRICT, /* scene polygons: any problem is an error */
    RL_POLY_SPLIT   /* mesh faces: split by ear clipping; drop degenerate faces */
} rl_poly_policy;

typedef struct rl_build {
    rl_scene *scene;       /* under construction, owned by the caller */
    const char *file;      /* the scene file as the caller named it, for messages */
    char dir[1024];        /* its folder with a trailing '/', or "" */
    unsigned read_threads; /* threads its light fields' radiance inflates on (rl_scene_load_options.threads) */
    size_t vertex_cap, polygon_cap, material_cap, lightfield_cap;
    uint32_t *names;       /* open addressing: material index + 1, 0 = empty slot */
    size_t names_cap;      /* 0, or a power of two > 2 * nmaterials */
    /* scratch space, each RL_MAX_POLYGON_VERTICES long */
    double (*face)[3];     /* one polygon's vertices as read */
    size_t *keep;          /* the vertices of a polygon that survive cleaning */
    double (*flat)[2];     /* ear clipping: vertices in the face's plane */
    int *link;             /* ear clipping: next and previous links (twice as long) */
    size_t (*tris)[3];     /* ear clipping: the triangles found */
} rl_build;

/* Records "<scene file>: <elem>: <message>" and @return RL_ERR_INPUT. */
rl_status rl__build_fail(const rl_build *b, const char *elem, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Looks a material up by name. @return 1 and *index if it exists, else 0. */
int rl__build_find_material(const rl_build *b, const char *name, uint32_t *index);

/*
 * Checks a material (name 1..63 bytes, albedo in [0, 1], emission >= 0 and
 * finite as a float) and adds it, or reuses one of the same name with the
 * same values. @return RL_OK; RL_ERR_INPUT naming elem if a value is out of
 * range or the name is taken by different values; RL_ERR_NOMEM.
 */
rl_status rl__build_material(rl_build *b, const char *elem, const char *name,
                             const double albedo[3], const double emission[3], uint32_t *index);

#endif /* RELIGHT_BUILD_H */
