/*
 * scene.h - scenes for the relighting engine, read from JSON (docs/scene.md).
 *
 * A scene is what is: materials, planar convex polygons (from the file's
 * "polygons" and from mesh files read with assimp), light field slabs that
 * act as emitters and an optional camera. What to compute and how is a job
 * (relight/job.h's rl_job); the file's "sampling" and "radiance_maps"
 * sections are only the job it suggests, handed out by rl_job_default().
 * Loading validates everything and reports the first problem with the file
 * and the element ("beams.json: polygons[3]: not planar"). A loaded scene
 * never changes and may be read from several threads, by several runs at once.
 *
 * This header is valid C99 and C++.
 */
#ifndef RELIGHT_SCENE_H
#define RELIGHT_SCENE_H

#include "relight/relight.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The radiance-map cell size, metres, that a scene file without radiance_maps.cell_size suggests. */
#define RL_DEFAULT_CELL_SIZE 0.05

/** A loaded scene. Opaque. */
typedef struct rl_scene rl_scene;

/**
 * Reads and validates a scene file; relative paths inside it are relative to its folder.
 * @return RL_OK and *out, owned by the caller; RL_ERR_IO (unreadable), RL_ERR_INPUT
 * (invalid scene, mesh or light field; the message names the file and element), RL_ERR_NOMEM.
 */
rl_status rl_scene_load(const char *path, rl_scene **out);

/**
 * How a scene is loaded (not what it holds: the scene is the same whatever
 * these say). Set size to sizeof(rl_scene_load_options)
 * (rl_scene_load_options_default() does), so that a later library with more
 * fields still takes it; fields past size take their defaults.
 */
typedef struct rl_scene_load_options {
    size_t size;       /**< sizeof(rl_scene_load_options) as the caller was compiled */
    unsigned threads;  /**< threads inflating its light fields' radiance (lfio_read_options.threads): 0 every
                        *   online core (the default), at most 1024 */
} rl_scene_load_options;

/** Fills *opt with the defaults: threads 0 (every online core). */
void rl_scene_load_options_default(rl_scene_load_options *opt);

/**
 * Reads and validates a scene file as rl_scene_load() does, as opt says (NULL: the defaults).
 * @return as rl_scene_load(); RL_ERR_ARG for options out of range or of a size this library does not know.
 */
rl_status rl_scene_load_with(const char *path, const rl_scene_load_options *opt, rl_scene **out);

/** Releases a scene and the light fields it loaded. NULL is a no-op. */
void rl_scene_destroy(rl_scene *s);

/** @return the number of polygons (after meshes are expanded). */
size_t rl_scene_polygon_count(const rl_scene *s);

/** @return the number of light field emitters. */
size_t rl_scene_lightfield_count(const rl_scene *s);

/** @return the bytes of radiance the light fields hold in memory, every slab of each file counted once
 * (lfio_slab_desc_bytes()); 0 without light fields. */
uint64_t rl_scene_lightfield_bytes(const rl_scene *s);

/** @return 1 if the scene has a camera. */
int rl_scene_has_camera(const rl_scene *s);

/** Gives the camera's image size in pixels. @return 1, or 0 (outputs untouched) if the scene has no camera. */
int rl_scene_camera_size(const rl_scene *s, uint32_t *width, uint32_t *height);

#ifdef __cplusplus
}
#endif

#endif /* RELIGHT_SCENE_H */
