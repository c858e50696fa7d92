/*
 * capture.h - turning light probe images taken on a grid of a plane into a
 * light field slab: the capture manifest (JSON, docs/capture.md) and the
 * capture itself.
 *
 * What a capture computes, stated once:
 *   - The manifest gives one or several capture planes (1 .. CAP_PLANES_MAX,
 *     each becoming one slab of the output, in order): for each, the plane
 *     origin + s*u + t*v, an nu x nv grid of positions at cell centres (as
 *     lfio/lightfield.h), and for each position one image or an exposure
 *     bracket, with its projection and orientation (capture/projection.h),
 *     colour space and scale. Each slab's mask threshold is the manifest's
 *     mask_threshold (default 0).
 *   - A probe pixel looking in world direction d records light travelling
 *     along w = -d. The slab stores the front hemisphere w.e3 >= 0, e3 =
 *     u x v / |u x v|: the light that comes from behind the plane (the
 *     half-space -e3) and crosses it towards its front. Point e3 at what
 *     the light field is to light.
 *   - Values: linear = colour_space decoded (sRGB curve undone for sRGB
 *     sources) after repair; radiance = scale * linear / exposure.
 *   - Repairs, counted per image in the report: a negative value becomes 0;
 *     NaN and infinite values become the mean of the finite, non-negative
 *     values among their eight neighbours in the same channel (0 if none).
 *   - Brackets: per pixel, the weighted mean of scale * linear / exposure
 *     over the images, with the hat weight of the pixel's largest stored
 *     (still encoded) channel value z: 0 for z <= 0.02 (noise) and for
 *     z >= 0.98 (clipped), rising linearly to 1 at z = 0.5. Where every
 *     image has weight 0, the image whose z is closest to 0.5 is used
 *     alone. Float images are assumed to clip at 1.0 like integer ones.
 *   - Resampling (a box filter): each pixel is cut into S x S sub-pixels
 *     with exact solid angles (midpoint rule for the angular map); the
 *     radiance of solid angle w is the solid-angle-weighted mean of the
 *     sub-pixels whose centre directions fall in w. S is chosen per image
 *     so that a solid angle receives hundreds of sub-pixels. A solid angle
 *     containing no pixel centre (the image is too coarse there) gets
 *     instead the mean of the image, interpolated bilinearly, at four
 *     directions inside it (cap_partition_samples() with k = 2).
 *   - Energy check, per position: E_image = sum over pixels whose centre
 *     direction has w.e3 > 0 of L times the integral of w.e3 over the pixel
 *     (exact for equirectangular pixels, whose direction integral has a
 *     closed form; the centre's w.e3 times the pixel's solid angle for the
 *     disc projections), against E_field = lfio_slab_irradiance() at the
 *     position. The report keeps the largest relative difference.
 *
 * Thread safety: a loaded manifest is immutable and may be shared; one
 * capture runs on its own worker threads. Memory: each worker holds one
 * position's images (one image and the bracket accumulators at a time),
 * plus the output slab, whatever the number of positions.
 *
 * This header is valid C99 and C++.
 */
#ifndef CAPTURE_CAPTURE_H
#define CAPTURE_CAPTURE_H

#include <stddef.h>
#include <stdint.h>

#include "capture/common.h"
#include "capture/projection.h"
#include "lfio/lightfield.h"
#include "ilf/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most images in one exposure bracket. */
#define CAP_BRACKET_MAX ILF_CAPTURE_MAX_BRACKET

/** Most capture planes (slabs) in one manifest. */
#define CAP_PLANES_MAX ILF_CAPTURE_MAX_PLANES

/** Most image samples (width * height * channels) one capture reads, over every image read, repeats counted. */
#define CAP_CAPTURE_MAX_SAMPLES ILF_CAPTURE_MAX_SAMPLES

/** Largest manifest file accepted, bytes. */
#define CAP_MANIFEST_MAX_BYTES ILF_MANIFEST_MAX_BYTES

/** How stored image values are decoded to linear light. */
typedef enum cap_colour_space {
    CAP_COLOUR_AUTO = 0,   /**< sRGB for integer (8/16-bit) files, linear for float files */
    CAP_COLOUR_LINEAR = 1, /**< values are linear already */
    CAP_COLOUR_SRGB = 2    /**< undo the sRGB transfer function (IEC 61966-2-1) */
} cap_colour_space;

/** @return "auto", "linear" or "srgb" ("" if invalid). */
const char *cap_colour_space_name(cap_colour_space c);

/** A loaded, validated manifest. Opaque, immutable. */
typedef struct cap_manifest cap_manifest;

/**
 * Reads and validates a manifest: JSON syntax (line and column given),
 * unknown or repeated keys, types, ranges, the plane (finite, nonzero,
 * orthogonal edges), every grid position given exactly once, rotations, and
 * that every image file exists and is a regular file (content is read by
 * the capture). Relative image paths are relative to the manifest's folder.
 * Messages name the manifest and the element: "m.json: positions[2].bracket[1].exposure: must be > 0".
 * @return CAP_OK and *out (destroy with cap_manifest_destroy()); CAP_ERR_INPUT;
 * CAP_ERR_NOMEM; CAP_ERR_ARG for NULL arguments. *out is NULL on failure.
 */
cap_status cap_manifest_load(const char *path, cap_manifest **out);

/** Releases a manifest. NULL is a no-op. */
void cap_manifest_destroy(cap_manifest *m);

/** @return the number of capture planes, each an output slab (1 .. CAP_PLANES_MAX); 0 for NULL. */
size_t cap_manifest_plane_count(const cap_manifest *m);

/**
 * @return the description of plane's output slab: name, plane, grid, n, units, mask threshold (borrowed,
 * valid for m's life); NULL for NULL or a plane out of range.
 */
const lfio_slab_desc *cap_manifest_get_desc(const cap_manifest *m, size_t plane);

/** @return the number of image files over all planes and positions (bracket images counted singly); 0 for NULL. */
uint64_t cap_manifest_image_count(const cap_manifest *m);

/** What one position of a manifest uses; every pointer is borrowed from the manifest. */
typedef struct cap_position_info {
    uint32_t i, j;                 /**< grid position, i along u, j along v */
    const char *element;           /**< where it comes from: "positions[3]", "pattern", "planes[1].pattern" */
    cap_projection projection;
    double orientation[9];         /**< camera frame to world, row-major */
    cap_colour_space colour_space;
    double scale;                  /**< > 0 */
    uint32_t image_count;          /**< 1 for a single image, 1 .. CAP_BRACKET_MAX for a bracket */
    int bracket;                   /**< 1 if given as a bracket (merged with hat weights), 0 for one image */
    const char *const *files;      /**< [image_count] resolved paths */
    const double *exposures;       /**< [image_count] relative exposures, > 0 */
} cap_position_info;

/**
 * Describes position (i, j) of a plane.
 * @return CAP_OK; CAP_ERR_ARG if m or out is NULL, or the plane or (i, j) is out of range.
 */
cap_status cap_manifest_get_position(const cap_manifest *m, size_t plane, uint32_t i, uint32_t j,
                                     cap_position_info *out);

/** One plane of the manifest cap_manifest_write() writes: one image a grid position, named by a pattern. */
typedef struct cap_manifest_plane {
    const lfio_slab_desc *desc; /**< its slab's name, plane (origin, u, v) and grid (nu, nv); the rest is not written */
    const char *pattern;        /**< image file names, relative to the manifest's folder: {i} and {j} replaced by
                                 *   the position (docs/capture.md) */
} cap_manifest_plane;

/** What cap_manifest_write() writes: the settings every plane shares, then the planes. */
typedef struct cap_manifest_spec {
    uint32_t n;                       /**< partition level of every slab, 1 .. LFIO_SLAB_MAX_N */
    lfio_units units;                 /**< "radiance" or "relative" */
    cap_projection projection;
    cap_colour_space colour_space;
    size_t nplanes;                   /**< 1 (the one-plane form: its keys at the top level) .. CAP_PLANES_MAX
                                       *   (under "planes") */
    const cap_manifest_plane *planes; /**< [nplanes] */
} cap_manifest_spec;

/**
 * Writes the manifest spec describes to path (docs/capture.md, the pattern
 * form: no orientation, scale or exposures, so identity, 1 and one image a
 * position) atomically: a temporary beside path renamed over it once
 * complete, so path holds the old file or the new one, never a part.
 * Formatted JSON, tab-indented, ending with a newline; numbers in their
 * shortest form of 15 or 17 significant digits that reads back equal, whole
 * numbers as integers. Only what spec holds is checked (not the images, nor
 * the plane's geometry): cap_manifest_load() checks the rest when it reads it.
 * @return CAP_OK; CAP_ERR_ARG for NULL pointers or a value out of range (the
 * message names it); CAP_ERR_OUTPUT with the message naming path and the
 * system's reason; CAP_ERR_NOMEM. On failure path is as it was.
 */
cap_status cap_manifest_write(const char *path, const cap_manifest_spec *spec);

/** Options of a capture; all zero means: one thread per processor, no progress. */
typedef struct cap_capture_options {
    unsigned threads;         /**< worker threads, 0 = one per processor; the result does not depend on it */
    cap_progress_fn progress; /**< counts finished positions; may be NULL */
    void *progress_user;
} cap_capture_options;

/** One image whose values needed repair. */
typedef struct cap_repair {
    const char *file;  /**< resolved path (a copy owned by the report) */
    uint32_t plane;    /**< its plane (slab index) */
    uint32_t i, j;     /**< its position */
    uint64_t negative; /**< channel values < 0, set to 0 */
    uint64_t nan;      /**< NaN channel values, replaced by their neighbours' mean */
    uint64_t infinite; /**< +-infinite channel values, replaced by their neighbours' mean */
    float lowest;      /**< the most negative value found (0 if none) */
} cap_repair;

/** What a capture did. Release with cap_report_free(). */
typedef struct cap_report {
    uint64_t positions;    /**< positions captured, over all planes */
    uint64_t images;       /**< image files read */
    uint64_t negative, nan, infinite; /**< repairs over all images */
    cap_repair *repairs;   /**< images that needed repair, by plane, position (k = j*nu + i), bracket order; owned */
    size_t repair_count;
    uint64_t interpolated; /**< solid angles, over all planes and positions, interpolated (image too coarse) */
    uint64_t unmerged;     /**< bracket pixels where every exposure was clipped or noisy */
    uint32_t subdivision_min, subdivision_max; /**< the sub-pixel factors S used */
    double energy_error;   /**< largest |E_field - E_image| / E_image over positions (brightest channel of E_image) */
    uint32_t energy_plane, energy_i, energy_j; /**< the plane and position where it occurs */
    double energy_image[3], energy_field[3]; /**< E_image and E_field there, W m^-2 (or relative) */
} cap_report;

/** Releases what report owns and zeroes it. NULL is a no-op. */
void cap_report_free(cap_report *report);

/**
 * Captures every position of m into a new light field holding one slab per
 * plane (cap_manifest_get_desc(m, k) for slab k), computed on worker
 * threads, plane after plane; the report covers them all and progress counts
 * positions over all planes. o may be NULL (all defaults).
 * @return CAP_OK with *out (owned by the caller) and *report filled (report
 * may be NULL); CAP_ERR_INPUT (the images ask for more than
 * CAP_CAPTURE_MAX_SAMPLES samples in all, an image counted each time a position
 * or bracket names it, found from their headers before any image is decoded;
 * an image is unreadable, has a size its
 * projection does not accept, or differs in size from the rest of its
 * bracket: the message names the manifest element and file); CAP_ERR_NOMEM
 * (including a slab over lfio's size limit); CAP_ERR_ARG for NULL. On
 * failure *out is NULL and *report is zeroed.
 */
cap_status cap_capture_run(const cap_manifest *m, const cap_capture_options *o, lfio_lightfield **out,
                           cap_report *report);

#ifdef __cplusplus
}
#endif

#endif /* CAPTURE_CAPTURE_H */
