/*
 * reproject.h - depth correction: moving a captured light field onto proxy
 * geometry standing where the light really comes from (Unger et al. 2003,
 * the "pre-process stage of depth-correction" of Khanna et al., section 6).
 *
 * Conventions, stated once:
 *   - A proxy is a list of rectangles, each becoming one slab (lfio frames:
 *     origin + s*u + t*v, front e3 = u x v / |u x v|, positions at cell
 *     centres, 4n^2 front directions). The light stored on a proxy slab is
 *     the light leaving its front.
 *   - For a proxy position y and direction w (front hemisphere of the proxy
 *     slab), the line y + t*w meets a captured slab's plane at p (line-plane
 *     intersection; no occlusion is considered: light travels in free space
 *     between the proxy and the capture plane). The ray is covered by that
 *     slab when w.e3_captured > 0 (the captured slab stores that direction)
 *     and p lies on the captured rectangle (s, t in [0, 1]). A capture of
 *     several slabs (planes) covers a ray when one of them does: the ray's
 *     radiance is the mean of the covering slabs' answers weighted by how
 *     finely each resolves it, (w.e3_captured) / (|t| * a)^2 with a =
 *     sqrt(2 pi / 4n^2) the side of the slab's mean solid angle: |t| * a is
 *     the size of the patch of the proxy that one of its solid angles spans
 *     along the ray, so the nearest, least grazing capture dominates and
 *     captures of similar resolution are blended. An uncovered ray carries
 *     zero radiance.
 *   - CAP_REPROJECT_DEPTH (the default): the captured probes around p (the
 *     bilinear cell of position centres, clamped at the border) are each
 *     asked for the radiance they saw in the direction from y to
 *     themselves, w_k = unit(w + (x_k - p) / t), interpolated over
 *     directions by lfio_slab_radiance_interp() at their own centre, and the
 *     answers are blended with the bilinear weights of p. When the proxy is
 *     at the true depth of the light, every probe looks at the same point y,
 *     so the blend does not smear the source across the probe spacing.
 *     CAP_REPROJECT_PLAIN: lfio_slab_radiance_interp() at p in direction w
 *     (the same direction for every probe), for comparison. The two agree
 *     as the proxy recedes to infinity (|t| -> infinity).
 *   - Each stored value is the mean over strata*strata rays: ray k leaves
 *     the centre of sub-cell k of a strata x strata split of the position's
 *     cell along direction k of cap_partition_samples() for its solid angle,
 *     so the value estimates the mean over the cell and the solid angle
 *     together (a box filter in position and direction), which keeps the
 *     slab's power where a sample at the cell centre alone would not.
 *   - Coverage of a proxy slab: the share of its etendue whose rays are
 *     covered (by any captured slab), weighting each sampled ray by its share of the projected
 *     solid angle (about e3) of its solid angle, and positions equally.
 *     Coverage of a sample (one solid angle at one position): 1 when at
 *     least one of its rays is covered, 0 when none is (its radiance is then
 *     exactly 0); the layout of lfio_lightfield_set_coverage().
 *
 * Thread safety: a proxy is immutable once loaded; reprojection only reads
 * the captured slab (which must not be written meanwhile).
 *
 * This header is valid C99 and C++.
 */
#ifndef CAPTURE_REPROJECT_H
#define CAPTURE_REPROJECT_H

#include <stddef.h>
#include <stdint.h>

#include "capture/common.h"
#include "lfio/lightfield.h"
#include "ilf/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most captured slabs one reprojection may merge. */
#define CAP_CAPTURED_MAX ILF_CAPTURE_MAX_PLANES

/** Most proxy rectangles one proxy may hold. */
#define CAP_PROXY_MAX ILF_PROXY_MAX_RECTANGLES

/** A loaded proxy: named rectangles with their sampling. Opaque, immutable. */
typedef struct cap_proxy cap_proxy;

/** Sampling for rectangles whose proxy file does not give it. */
typedef struct cap_proxy_defaults {
    uint32_t nu, nv; /**< positions along u and v, 1 .. 65536 */
    uint32_t n;      /**< partition level, 1 .. LFIO_SLAB_MAX_N */
} cap_proxy_defaults;

/**
 * Reads a proxy. A file ending in .json (any case) is a JSON array of
 * rectangles {"name", "origin", "u", "v", "grid": {"nu", "nv"}, "n"}, of
 * which origin, u and v are required (u and v orthogonal) and grid and n
 * default to *defaults; names default to "proxy<k>". Any other file is a
 * mesh in a format scenes accept (OBJ, PLY, glTF, GLB, STL, FBX or 3DS, by
 * its extension), imported with the same pre-checks as scene meshes (PLY
 * counts against the file's size, glTF headers and accessor types; other
 * formats are refused because their readers trust a header's counts), node
 * transforms applied, whose faces are rectangles: a quad v0..v3, counter-clockwise seen from its front,
 * becomes origin v0, u = v1 - v0, v = v3 - v0; a triangle is merged with
 * the later triangle that shares its longest edge (run the other way) into
 * the rectangle c0 c1 c2 c3, where c0 c1 c2 is the first triangle rotated
 * so that c1 is its corner opposite that edge and c3 is the partner's third
 * vertex (a quad v0 v1 v2 v3 split into v0 v1 v2 and v0 v2 v3 gives the
 * quad's own rectangle). Each is named "face<k>" after its first face (k
 * counting faces over the file's meshes); a triangle without a partner,
 * a pair or quad that is not a rectangle (relative tolerance 1e-5), and
 * any other polygon are refused. Rectangles get the defaults' grid and n. Names are unique; the units of the slabs are set
 * when reprojecting.
 * @return CAP_OK and *out; CAP_ERR_INPUT (the message names the file and the
 * rectangle or face); CAP_ERR_NOMEM; CAP_ERR_ARG for NULL or invalid defaults.
 */
cap_status cap_proxy_load(const char *path, const cap_proxy_defaults *defaults, cap_proxy **out);

/** Releases a proxy. NULL is a no-op. */
void cap_proxy_destroy(cap_proxy *p);

/** @return the number of rectangles (0 for NULL). */
size_t cap_proxy_count(const cap_proxy *p);

/** @return rectangle k's slab description (borrowed, valid for p's life); NULL if p is NULL or k is out of range. */
const lfio_slab_desc *cap_proxy_get_desc(const cap_proxy *p, size_t k);

/** How rays are looked up in the captured field (see above). */
typedef enum cap_reproject_mode {
    CAP_REPROJECT_DEPTH = 0, /**< each probe looks at the proxy point: depth-corrected */
    CAP_REPROJECT_PLAIN = 1  /**< every probe looks along the ray's direction */
} cap_reproject_mode;

/** Options of a reprojection; all zero means depth-corrected, 2x2 strata, one thread per processor. */
typedef struct cap_reproject_options {
    cap_reproject_mode mode;
    uint32_t strata;          /**< s: s*s directions per solid angle, 1 .. 16; 0 means 2 */
    unsigned threads;         /**< worker threads, 0 = one per processor; the result does not depend on it */
    cap_progress_fn progress; /**< counts finished positions; may be NULL */
    void *progress_user;
    uint8_t *covered;         /**< NULL, or an output of 4n^2*nu*nv bytes ([dir][j][i] of the target): each sample's coverage */
} cap_reproject_options;

/** How much of a proxy slab the capture covers. */
typedef struct cap_coverage {
    double fraction;  /**< covered share of the etendue, 0 .. 1 */
    uint64_t rays;    /**< rays sampled: positions x directions x strata^2 */
    uint64_t covered; /**< of those, covered */
} cap_coverage;

/**
 * Makes the slab target (its units replaced by the captured slabs', which
 * must agree, and its mask threshold by the smallest of theirs) from the
 * count captured slabs merged as above (1 .. CAP_CAPTURED_MAX), on worker
 * threads, and each sample's coverage into o->covered when that is not
 * NULL. o may be NULL (all defaults). The result does not depend on the
 * thread count.
 * @return CAP_OK, *out (owned by the caller) and *coverage (may be NULL);
 * CAP_ERR_ARG (NULL, a count out of range, units that differ, invalid
 * target or options); CAP_ERR_NOMEM. *out is NULL on failure.
 */
cap_status cap_reproject_field(const lfio_slab *const *captured, size_t count, const lfio_slab_desc *target,
                               const cap_reproject_options *o, lfio_slab **out, cap_coverage *coverage);

/** cap_reproject_field() with one captured slab. */
cap_status cap_reproject_slab(const lfio_slab *captured, const lfio_slab_desc *target,
                              const cap_reproject_options *o, lfio_slab **out, cap_coverage *coverage);

#ifdef __cplusplus
}
#endif

#endif /* CAPTURE_REPROJECT_H */
