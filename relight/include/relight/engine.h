/*
 * engine.h - running the relighting engine on a loaded scene: radiance maps
 * by passes (direct, then `bounces` diffuse passes), irradiance at points,
 * the camera's view and the ray tracer's benchmark. Conventions as in
 * relight/relight.h. A scene is what is (relight/scene.h); what to compute
 * (sampling settings, cell size) and how (threads, progress, time budget)
 * come with each solving call, as an rl_job (relight/job.h), whose defaults
 * the scene file suggests; the calls that only read a solution or trace rays
 * take the "how" alone, as rl_run_options. A solution and its scene are only
 * read by the calls here, except rl_solution_set_smooth().
 *
 * This header is valid C99 and C++.
 */
#ifndef RELIGHT_ENGINE_H
#define RELIGHT_ENGINE_H

#include "relight/camera.h"
#include "relight/job.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * The histogram of a pass's cells by the standard error of their estimates relative to their values
 * (rl_pass_stats.cell_error_histogram): RL_CELL_ERROR_BINS bins spaced evenly in log10, bin b holding
 * the errors in [10^(RL_CELL_ERROR_LOG0 + b / RL_CELL_ERROR_PER_DECADE), the next bin's start), about 2.3%
 * wide; bin 0 also holds everything below (the cells of no error) and the last bin everything above.
 * A histogram rather than a value per cell so that threads, ranks and a pass's two gathers merge by
 * summing, at no memory per cell.
 */
#define RL_CELL_ERROR_BINS 500
#define RL_CELL_ERROR_PER_DECADE 100
#define RL_CELL_ERROR_LOG0 (-4.0)

/** What one pass did. Times in seconds; counts summed over threads. */
typedef struct rl_pass_stats {
    double wall_seconds;          /**< elapsed time of the pass */
    double cpu_seconds;           /**< process CPU time of the pass, all threads */
    uint64_t samples;             /**< sample rays generated */
    uint64_t rays_cast;           /**< rays handed to the ray tracer */
    uint64_t rays_kept;           /**< rays that reached their emitter unoccluded (a first-hit bounce pass:
                                       rays whose first hit re-emits light; it has no pairs or solid angles,
                                       and its samples are its rays) */
    uint64_t rays_free;           /**< rays not traced, known to arrive: an exact test found nothing between
                                       their cell and the emitter, or, for a light field's shared directions,
                                       their origin in none of the direction's shadows (counted apart from
                                       rays_cast and rays_kept) */
    uint64_t solid_angles_considered; /**< (emitter, receiver, solid angle) leaves considered */
    uint64_t solid_angles_culled; /**< of those, culled without a ray */
    uint64_t pairs;               /**< (emitter, receiver tile) pairs that can exchange light */
    uint64_t pairs_descended;     /**< pairs whose emitter subtends less than a solid angle, gathered by Lambert's formula times sampled visibility */
    uint32_t emitters;            /**< emitters in this pass */
    uint64_t refinements;         /**< adaptive: (cell, solid angle) nodes split into their children */
    double estimated_rmse;        /**< adaptive: the estimator's own RMSE over cells, W m^-2 (0 otherwise) */
    int budget_reached;           /**< adaptive: 1 if the time budget stopped refinement */
    uint64_t cells_direct;        /**< a first-hit bounce pass on larger cells: cells gathered on their own
                                       (near an occluder, or on a narrow polygon) instead of interpolated */
    uint64_t cell_error_cells;    /**< cells whose estimate carries a standard error from its own samples (a
                                       first-hit bounce pass: every cell it gathers; 0 for other passes) */
    double cell_error_median;     /**< of those cells, the median of the standard error relative to the cell's
                                       value (luminance), to about 1% of itself (a bin's middle); 0 when none */
    double cell_error_p95;        /**< and its 95th percentile */
    double cell_error_max;        /**< and its largest value (a cell with samples and nothing met counts 0) */
    uint64_t cell_error_histogram[RL_CELL_ERROR_BINS]; /**< those cells by their relative standard error
                                                            (RL_CELL_ERROR_BINS), from which the three come */
} rl_pass_stats;

/**
 * The processes of one job (the ranks of an MPI job, docs/cluster.md), as the
 * engine sees them: it never calls MPI itself. Every rank loads the same
 * scene and makes the same calls with the same job (its run options aside); the work of each pass (tiles
 * of cells, or points) is dealt out to the ranks, up front by expected cost (the same deal on every rank) or,
 * with a `next` callback, as each rank becomes free, and after
 * the pass the callbacks make every rank's maps whole. The results are bit
 * for bit those of one process, whatever ranks and threads. The callbacks but
 * `next` are called from the calling thread, by every rank in the same order; when one
 * fails (returns nonzero) the run fails with RL_ERR_IO. A rank whose run
 * fails otherwise (out of memory) returns without entering the next
 * exchange: the caller must then end the whole job (MPI_Abort), since the
 * other ranks wait in it.
 */
typedef struct rl_cluster {
    uint32_t rank;  /**< this process, 0 .. ranks - 1 */
    uint32_t ranks; /**< processes in the job, >= 1 */
    /** On entry rank r has filled only block r of values (counts[r] doubles from offsets[r]);
     * on return every block holds its owner's values. @return 0, or nonzero on failure. */
    int (*allgather)(void *user, double *values, const uint64_t *counts, const uint64_t *offsets);
    /** Replaces each of the n values by its sum over the ranks. @return 0, or nonzero on failure. */
    int (*sum)(void *user, double *values, size_t n);
    /** NULL: the tiles of a pass are dealt up front, by expected cost. Else they are dealt as ranks become
     * free: next claims the next of the n tiles of the current pass for this rank and returns its place,
     * 0, 1, ... over the whole job, each place once, then n or more once all are claimed. The count starts
     * again at 0 for the next pass: every rank makes a call of sum or allgather (with the others) between
     * its last claim of one pass and its first of the next. Called from the engine's worker threads, one
     * at a time. */
    uint64_t (*next)(void *user, uint64_t n);
    void *user;     /**< passed to all three */
} rl_cluster;

/**
 * Relights a scene as job says (NULL: rl_job_default(scene)). The scene must
 * outlive the solution; the job need not outlive the call. Several calls may
 * run at once on the same scene, with the same or different jobs (the scene
 * is only read). The tables the engine derives from the scene (light field
 * supports, maps, ray tracer) belong to the solution.
 * @return RL_OK and *out, owned by the caller; RL_ERR_ARG (NULL scene or out, a job that fails
 * rl_job_check(), naming the field); RL_ERR_NOMEM, RL_ERR_INPUT, RL_ERR_INTERNAL.
 */
rl_status rl_relight(const rl_scene *scene, const rl_job *job, rl_solution **out);

/**
 * rl_relight() as rank cluster->rank of a job (NULL: one process, as
 * rl_relight()). Every rank ends with the whole solution; pass statistics
 * are summed over ranks, except wall_seconds (this rank's).
 * @return as rl_relight(); RL_ERR_ARG for a cluster with rank >= ranks; RL_ERR_IO when an exchange fails.
 */
rl_status rl_relight_cluster(const rl_scene *scene, const rl_cluster *cluster, const rl_job *job,
                             rl_solution **out);

/** Releases a solution. NULL is a no-op. */
void rl_solution_destroy(rl_solution *s);

/** @return the number of passes run (1 + bounces). */
uint32_t rl_solution_pass_count(const rl_solution *s);

/** Copies the statistics of pass k. @return RL_OK or RL_ERR_ARG. */
rl_status rl_solution_pass_stats(const rl_solution *s, uint32_t k, rl_pass_stats *out);

/** @return the bytes of irradiance accumulators the run held at their most: each map's pass, previous-pass
 * and total arrays (one array without bounces), and the coarser maps of bounce passes. */
uint64_t rl_solution_accumulator_bytes(const rl_solution *s);

/** @return the number of radiance maps (one per receiving polygon). */
size_t rl_solution_map_count(const rl_solution *s);

/** Geometry of one radiance map. Cell (i, j) covers
 * origin + [u0 + i*cell_size, u0 + (i+1)*cell_size] * e1 + [v0 + j*cell_size, ...] * e2, clipped to the polygon. */
typedef struct rl_map_info {
    uint32_t polygon;        /**< scene polygon index */
    const char *label;       /**< the polygon's element name in the scene file (borrowed) */
    double origin[3], e1[3], e2[3], normal[3]; /**< the map's frame, world */
    double cell_size, u0, v0; /**< metres */
    uint32_t nu, nv;         /**< grid size */
    uint32_t ncells;         /**< cells with area (at most nu*nv) */
    float albedo[3], emission[3];
    const double *vertices;  /**< the polygon's vertices, [nvertices][3] world, counter-clockwise seen from the front (borrowed) */
    uint32_t nvertices;
} rl_map_info;

/** Describes map k. @return RL_OK or RL_ERR_ARG. */
rl_status rl_solution_map_info(const rl_solution *s, size_t k, rl_map_info *out);

/**
 * Copies map k's cells; any output may be NULL. ij: [ncells][2] grid indices;
 * area: [ncells] m^2; centre: [ncells][3] world centroid of the clipped cell;
 * irradiance: [ncells][3] W m^-2 summed over passes; radiosity: [ncells][3]
 * W m^-2, pi * emission + albedo * irradiance; values beyond float range
 * (only from light fields near FLT_MAX) are clamped to FLT_MAX, never inf.
 * @return RL_OK or RL_ERR_ARG.
 */
rl_status rl_solution_map_cells(const rl_solution *s, size_t k, uint32_t *ij, double *area, double *centre,
                                float *irradiance, float *radiosity);

/**
 * Copies cells [first, first + count) of map k as rl_solution_map_cells()
 * copies them all, into arrays of count rows, so that a map is read a slice
 * at a time. @return RL_OK; RL_ERR_ARG for no map k or a range past its cells.
 */
rl_status rl_solution_map_rows(const rl_solution *s, size_t k, uint32_t first, uint32_t count, uint32_t *ij,
                               double *area, double *centre, float *irradiance, float *radiosity);

/**
 * Chooses how rl_solution_trace() and rl_solution_render() read a map:
 * smooth (nonzero, the default) interpolates irradiance bilinearly between
 * the centres of the cells around the point hit, over the cells of the same
 * polygon only (carried to its edges, never across them); 0 gives each
 * cell's own value, flat, for inspecting the cells. Not thread-safe with
 * renders of the same solution. @return RL_OK; RL_ERR_ARG if s is NULL.
 */
rl_status rl_solution_set_smooth(rl_solution *s, int smooth);

/**
 * Gives the radiance (W sr^-1 m^-2) arriving at org along the ray org + t*dir,
 * t > 0 (dir need not be unit), from the nearer of the first surface and the
 * first light field slab it crosses from the slab's emitting side. A surface
 * gives emission plus albedo * irradiance / pi at the point hit
 * (rl_solution_set_smooth()), 0 for a back face; a slab gives the light
 * field's radiance at the point crossed in the direction of the ray,
 * interpolated as the engine reads it (lfio_slab_radiance_interp()), and 0
 * where its mask or coverage holds nothing; neither: 0. Thread-safe.
 * @return RL_OK; RL_ERR_ARG if org or dir is not finite or dir is zero.
 */
rl_status rl_solution_trace(const rl_solution *s, const double org[3], const double dir[3], float rgb[3]);

/**
 * Finds the nearest light field slab of the scene that the ray org + t*dir
 * (dir need not be unit) crosses from its emitting side at 0 < t < t_max
 * (metres along the unit direction; INFINITY: any), and gives the radiance
 * it sends back along the ray, as rl_solution_trace() sees it: for a
 * caller with its own surfaces (`ilf view`). Thread-safe.
 * @return 1 and rgb; 0 (rgb untouched) when the ray crosses no slab so, or
 * an argument is NULL or not finite.
 */
int rl_scene_trace_lightfields(const rl_scene *s, const double org[3], const double dir[3], double t_max,
                               float rgb[3]);

/**
 * Renders a camera's view (the scene is not changed): cam->width * cam->height * 3
 * floats, rows top to bottom, the radiance rl_solution_trace() gives along each
 * pixel's centre ray: surfaces (back faces and the background 0) and light
 * field slabs seen from their emitting side. Runs on options->threads threads
 * (NULL: defaults); progress and time_budget are not used. The result does
 * not depend on the thread count.
 * @return RL_OK; RL_ERR_ARG if an argument is NULL, cam fails rl_camera_check(), or options are out of range.
 */
rl_status rl_solution_render_camera(const rl_solution *s, const rl_camera *cam, const rl_run_options *options,
                                    float *rgb);

/** rl_solution_render_camera() through the scene's camera. @return as that; RL_ERR_ARG if the scene has none. */
rl_status rl_solution_render(const rl_solution *s, const rl_run_options *options, float *rgb);

/**
 * Renders the irradiance (W m^-2, r g b, as rl_solution_render_camera() would read it: smooth or flat) on the
 * receiving surface each pixel of cam sees, into rgb ([height][width][3], row 0 at the top): what a
 * false-colour image of illuminance shows. Pixels that see no receiving front face get -1 in every channel;
 * light field slabs are not surfaces and are looked through.
 * @return as rl_solution_render_camera().
 */
rl_status rl_solution_render_irradiance_camera(const rl_solution *s, const rl_camera *cam,
                                               const rl_run_options *options, float *rgb);

/** rl_solution_render_irradiance_camera() through the scene's camera. @return as rl_solution_render(). */
rl_status rl_solution_render_irradiance(const rl_solution *s, const rl_run_options *options, float *rgb);

/**
 * Renders which cell each pixel of cam sees: map_ids and cell_ids get
 * width*height entries, rows top to bottom; -1 where the pixel sees no
 * map (background, back face, a surface that does not receive); light
 * field slabs are looked through. Options as in rl_solution_render_camera().
 * @return RL_OK; RL_ERR_ARG if an output is NULL, cam fails rl_camera_check(), or options are out of range.
 */
rl_status rl_solution_render_cells_camera(const rl_solution *s, const rl_camera *cam, const rl_run_options *options,
                                          int32_t *map_ids, int32_t *cell_ids);

/** rl_solution_render_cells_camera() through the scene's camera. @return as that; RL_ERR_ARG if the scene has none. */
rl_status rl_solution_render_cells(const rl_solution *s, const rl_run_options *options, int32_t *map_ids,
                                   int32_t *cell_ids);

/** Result of rl_bench_rays(). */
typedef struct rl_ray_bench {
    uint64_t rays;       /**< rays traced */
    uint64_t occluded;   /**< of those, blocked */
    double wall_seconds; /**< tracing only: the longest thread's */
    double cpu_seconds;  /**< tracing only: CPU time summed over threads */
} rl_ray_bench;

/**
 * Measures the ray tracer alone: the same packet occlusion queries the
 * engine makes (up to 16 rays, coherent flag), on about `rays` random shadow
 * rays (rounded up to a whole share per thread) from uniform points on the
 * scene's polygons in cosine-distributed directions, on options->threads
 * threads (NULL: defaults; progress and time_budget are not used). Each
 * thread draws its own fixed sequence of rays, in chunks before they are
 * traced, and only the tracing is timed, so no sampling work is counted. The
 * ceiling the engine's ray rate is measured against.
 * @return RL_OK and *out; RL_ERR_ARG (NULL scene or out, no polygons, options out of range);
 * RL_ERR_NOMEM or RL_ERR_INTERNAL.
 */
rl_status rl_bench_rays(const rl_scene *scene, const rl_run_options *options, uint64_t rays, rl_ray_bench *out);

/**
 * Irradiance at points, as Radiance's rtrace -I: points[6*i..] = x y z nx ny nz
 * (normal need not be unit, must be nonzero); out[3*i..] = r g b in W m^-2.
 * Each point is a receiver of zero area facing its normal; with bounces > 0
 * the light reflected by the solved radiance maps (at the job's cell size)
 * is included. Computed and run as job says (NULL: rl_job_default(scene));
 * progress covers the bounce passes and the points; job->run.maps_ready is
 * not used. stats (may be NULL) receives the points' pass. Thread-safe as
 * rl_relight().
 * @return RL_OK; RL_ERR_ARG (NULL scene, or NULL points or out with count > 0; a point or normal not
 * finite or zero, with its index; a job that fails rl_job_check()); RL_ERR_NOMEM; RL_ERR_INTERNAL.
 */
rl_status rl_irradiance(const rl_scene *scene, const rl_job *job, const double *points, size_t count,
                        double *out, rl_pass_stats *stats);

/**
 * rl_irradiance() as rank cluster->rank of a job (NULL: one process). Every
 * rank passes the same points and ends with every point's answer.
 * @return as rl_irradiance(); RL_ERR_ARG for a cluster with rank >= ranks; RL_ERR_IO when an exchange fails.
 */
rl_status rl_irradiance_cluster(const rl_scene *scene, const rl_cluster *cluster, const rl_job *job,
                                const double *points, size_t count, double *out, rl_pass_stats *stats);

/* ------------------------------------------------------------ diagnostics */

/** What a diagnostic is about: a scene or a result that is legal but almost surely not what was meant. */
typedef enum rl_diagnostic_kind {
    RL_DIAG_NO_EMITTER = 0,  /**< no emissive polygon and no light field: everything stays black */
    RL_DIAG_NOT_FACING = 1,  /**< emitters and receivers exist, but no receiver faces any emitter from its
                                  front (normals outward, reversed walls): no direct light can arrive;
                                  quantity 1 */
    RL_DIAG_COVERAGE = 2,    /**< a light field slab's coverage is below 100%: quantity is the share of its
                                  etendue that emits nothing because nothing was captured there */
    RL_DIAG_NO_CAMERA = 3,   /**< the scene has no camera: there is no view to render */
    RL_DIAG_DARK_CELLS = 4,  /**< most cells received nothing: quantity is their share of the cells */
    RL_DIAG_BACK_FACES = 5,  /**< most of what the camera sees is the back of a surface (drawn black):
                                  quantity is that share of the camera's rays that hit anything */
    RL_DIAG_EMITTER_UNSEEN = 6 /**< an emitter faces no receiver from its front while others do (a light
                                  field placed without its flip, a lamp's normal reversed): quantity is the
                                  share of the emitters that face none; one finding for each of the first four */
} rl_diagnostic_kind;

/** One finding of rl_scene_diagnose() or rl_solution_diagnose(). */
typedef struct rl_diagnostic {
    rl_diagnostic_kind kind;
    double quantity; /**< the share measured, in [0, 1]; 0 for kinds that measure nothing */
    char text[512];  /**< one line for people, naming what it is about and the quantity, no trailing newline */
} rl_diagnostic;

/**
 * Checks a loaded scene for what leaves a run dark or without output: no
 * emitter, no receiver facing an emitter or an emitter facing no receiver
 * (a receiver faces an emitter when part of each lies in front of the
 * other's plane), light field slabs whose coverage is below 100%, no
 * camera. Writes up to max findings to out (out may be NULL with max 0), in
 * that order.
 * @return the number of findings, which may exceed max.
 */
size_t rl_scene_diagnose(const rl_scene *scene, rl_diagnostic *out, size_t max);

/**
 * Checks a solution: most cells received nothing (more than half), or the
 * scene's camera sees mostly back faces (more than half of a 64 x 48 grid of
 * its rays that hit anything). As rl_scene_diagnose() for out, max and the result.
 */
size_t rl_solution_diagnose(const rl_solution *solution, rl_diagnostic *out, size_t max);

#ifdef __cplusplus
}
#endif

#endif /* RELIGHT_ENGINE_H */
