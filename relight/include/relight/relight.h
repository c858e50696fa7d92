/*
 * relight.h - the relighting engine: scenes of planar convex polygons lit by
 * diffuse polygon emitters and incident light field slabs (lfio), solved by
 * culled solid-angle transfer with projected Minkowski sums (Khanna et al.).
 *
 * Conventions, stated once:
 *   - World frame right-handed, metres. A polygon's front is the side from
 *     which its vertices run counter-clockwise; its normal points there.
 *     Emitters emit and receivers receive on the front side only.
 *   - Radiance in W sr^-1 m^-2, irradiance in W m^-2, linear Rec.709 RGB.
 *     Receivers are Lambertian: radiosity B = albedo * E, exitant radiance
 *     L = emission + albedo * E / pi.
 *   - A receiving polygon carries a grid of square cells of side cell_size
 *     in its own frame (e1 along its first edge, e2 = normal x e1, origin at
 *     its first vertex), clipped to the polygon; a cell's value is the mean
 *     over the clipped cell.
 *   - Fallible calls return rl_status; rl_errmsg() gives the calling
 *     thread's last message, naming the file and element. Destroy(NULL) is a no-op.
 *   - Results are deterministic: the same scene and seed give bit-identical
 *     output for any thread count.
 *
 * This header is valid C99 and C++.
 */
#ifndef RELIGHT_RELIGHT_H
#define RELIGHT_RELIGHT_H

#include <stddef.h>
#include <stdint.h>
#include "ilf/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The version of this API, raised by every change that breaks a caller (CHANGELOG.md): 2, where what to
 * compute and how is a job (rl_job, relight/job.h) passed with each call, apart from the scene. */
#define RL_API_VERSION 2

/** Result of a fallible call. */
typedef enum rl_status {
    RL_OK = 0,
    RL_ERR_ARG = 1,     /**< an argument is invalid */
    RL_ERR_NOMEM = 2,   /**< an allocation failed */
    RL_ERR_IO = 3,      /**< a file could not be read or written */
    RL_ERR_INPUT = 4,   /**< an input file (scene, mesh, light field, points) is invalid */
    RL_ERR_INTERNAL = 5 /**< the ray tracer failed */
} rl_status;

/** @return the calling thread's last failure message ("" if none), owned by the library. */
const char *rl_errmsg(void);

/** Transfer methods. */
typedef enum rl_method {
    RL_METHOD_CULLED = 0,    /**< solid angles culled by projected Minkowski sums and the mask */
    RL_METHOD_NAIVE = 1,     /**< every solid angle of the emitter's hemisphere, every cell */
    RL_METHOD_AREA = 2,      /**< uniform points on the emitter with shadow rays */
    RL_METHOD_SOLIDANGLE = 3, /**< uniform directions in the emitter's spherical polygon */
    RL_METHOD_ADAPTIVE = 4    /**< culled's leaves, each (cell, solid angle) refined into its four children
                                   where pilot samples find it uncertain, down to 4 x partition_n */
} rl_method;

/** @return the method's name ("culled", "naive", "area", "solidangle", "adaptive"). */
const char *rl_method_name(rl_method m);

/** Parses a method name. @return 1 and *m on success, 0 if name is unknown. */
int rl_method_parse(const char *name, rl_method *m);

/** Largest emission a material may have, W sr^-1 m^-2: irradiance sums of
 * such emitters stay far inside float32, the type of the radiance maps. */
#define RL_MAX_EMISSION ILF_MAX_EMISSION

/** Sampling settings (scene key "sampling"): what to compute, part of a job (rl_job in relight/job.h,
 * with the cell size). How a call runs (threads, progress, time budget) is not among them: rl_run_options. */
typedef struct rl_sampling {
    rl_method method;              /**< default culled */
    uint32_t partition_n;          /**< partition level, a power of two, default 32 (4096 solid angles per hemisphere) */
    uint32_t rays_per_solid_angle; /**< k rays per (cell, solid angle), default 4 */
    uint32_t samples_per_cell;     /**< shadow rays per (cell, emitter) for area and solidangle, default 128 */
    uint32_t bounces;              /**< further diffuse passes after the direct one, default 0 */
    uint32_t bounce_partition_n;   /**< with bounce_rays 0, the partition level of those passes (which never descend); 0 (default): partition_n / 4, at least 1.
                                        Indirect light is smooth, and a bounce pass gathers from every surface */
    uint32_t bounce_cell_factor;   /**< bounce passes gather on cells this many times larger (1 .. 64) and
                                        interpolate onto the cells bilinearly, as indirect light is smooth,
                                        except near occluders (with bounce_rays > 0: the cells of a larger
                                        cell whose rays meet a surface within half a larger cell above its
                                        polygon's inside, and of its eight neighbours, gather on their own);
                                        1: on every cell; 0 (default): 4, or 2 with bounce_rays 0 */
    uint32_t bounce_rays;          /**< bounce passes: rays per (bounce) cell, cosine-weighted over the cell's
                                        own hemisphere, each reading the radiance re-emitted where it first
                                        hits; default 256. 0: the method's own transfer from each lit polygon
                                        (bounce_partition_n), as the direct pass does */
    uint64_t seed;                 /**< default 1 */
    uint32_t descend;              /**< 1 (default, direct pass): constant emitters, and emitters that subtend
                                        less than a solid angle, use Lambert's formula times the sampled
                                        arriving light (radiance * visibility); 0: the plain
                                        estimator at partition_n everywhere, the paper's method */
    uint32_t zero_culling;         /**< 1 (default): culled and adaptive skip light field solid angles that the
                                        zero-radiance mask rules out, and cells that only the slab's dark
                                        positions could light; 0: no culling by radiance, only by geometry */
    uint32_t anchor_stride;        /**< Lambert's gather from a light field (descend): a polygon's cell that sees
                                        all of it gets the light interpolated bilinearly between anchor points
                                        this many cells apart, each sampled as a cell would be (that light varies
                                        smoothly: by one cell of the slab's partition n in direction over a
                                        move of about r / n, r the distance to the slab); 0 (default): chosen
                                        per receiver tile, at most a third of that apart (and r / 12), or 1
                                        when that is under 2 cells; 1: every cell sampled on its own. Cells
                                        that a shadow may cross, and point receivers, are always sampled */
    double target_error;           /**< adaptive: refine a (cell, solid angle) while its estimated standard
                                        error exceeds this fraction of its estimate; default 0.05 */
} rl_sampling;

/** Fills *s with the defaults above. */
void rl_sampling_default(rl_sampling *s);

/** The type of a sampling setting's value. */
typedef enum rl_setting_type {
    RL_SETTING_METHOD = 0, /**< an rl_method, written as its name (rl_method_name()) */
    RL_SETTING_UINT32 = 1, /**< a uint32_t integer */
    RL_SETTING_UINT64 = 2, /**< a uint64_t integer */
    RL_SETTING_REAL = 3    /**< a double */
} rl_setting_type;

/** Flags of a sampling setting's allowed values. */
enum {
    RL_SETTING_POW2 = 1,       /**< an integer that is also a power of two (or 0, where lo is 0) */
    RL_SETTING_LO_OPEN = 2,    /**< lo itself is not allowed (a real in (lo, hi]) */
    RL_SETTING_TEXT_BOUNDS = 4 /**< the bounds hold for values written as text (scene files, command
                                    lines), not for rl_job_check(): the integers a JSON
                                    number holds exactly */
};

/**
 * One sampling setting, as every reader of settings sees it: the scene
 * loader's "sampling" object, rl_job_check()'s checks, the
 * command line's options and their --help all come from this one table.
 */
typedef struct rl_setting_info {
    const char *key;       /**< key in the scene's "sampling" object and field name of rl_sampling */
    const char *option;    /**< command-line option without "--" */
    const char *meta;      /**< placeholder of the value in help ("N") */
    rl_setting_type type;
    size_t offset;         /**< offsetof(rl_sampling, the field) */
    double lo, hi;         /**< allowed values, inclusive unless RL_SETTING_LO_OPEN (METHOD: rl_method range) */
    unsigned flags;        /**< RL_SETTING_* */
    double default_value;  /**< as rl_sampling_default() sets it (METHOD: the rl_method) */
    const char *help;      /**< one line on what it does, without its bounds or default */
} rl_setting_info;

/** @return the number of sampling settings (the rows of the table, in the scene file's key order). */
size_t rl_sampling_setting_count(void);

/** @return setting k (static, read-only, never freed), or NULL if k >= rl_sampling_setting_count(). */
const rl_setting_info *rl_sampling_setting(size_t k);

/** @return the index of the setting with scene key `key`, or rl_sampling_setting_count() if there is none. */
size_t rl_sampling_setting_find(const char *key);

/** Writes setting k's allowed values in words ("a power of two in 1..4096", "in (0, 1]") into buf.
 * @return buf ("" for an unknown k); NULL buf or size 0 writes nothing and returns "". */
const char *rl_sampling_setting_rule(size_t k, char *buf, size_t size);

/** @return 1 if value is allowed for setting k (text bounds included when `text`), else 0. */
int rl_sampling_setting_allows(size_t k, double value, int text);

/** Reads setting k of s into *value (integers beyond 2^53 round). @return 1, or 0 for an unknown k or NULL. */
int rl_sampling_get(const rl_sampling *s, size_t k, double *value);

/** Sets setting k of s to value, converted to the field's type (no range check: rl_sampling_setting_allows()).
 * @return 1, or 0 for an unknown k, NULL s, or a value the type cannot hold. */
int rl_sampling_set(rl_sampling *s, size_t k, double value);

#ifdef __cplusplus
}
#endif

#endif /* RELIGHT_RELIGHT_H */
