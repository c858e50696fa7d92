/*
 * projection.h - light probe images: how their pixels map to directions
 * (equirectangular, mirror ball, angular map), exact pixel solid angles,
 * stratified directions inside a partition solid angle, and rendering the
 * equirectangular probe image a point of a scene would see.
 *
 * Conventions, stated once:
 *   - The probe's camera frame is right-handed: +x forward (the direction the
 *     probe camera looks), +y left, +z up. A probe's orientation is a
 *     rotation R, row-major 3x3, taking camera-frame directions to world
 *     directions: d_world = R * d_cam; its columns are the world directions
 *     of camera forward, left and up.
 *   - Image coordinates are continuous: pixel (x, y) covers [x, x+1] x
 *     [y, y+1] of (px, py), px rightwards, py downwards (row 0 is the top);
 *     its centre is (x + 0.5, y + 0.5). A W x H image spans [0, W] x [0, H].
 *   - A pixel's direction is where the light it records comes from (the
 *     direction one looks in), in the camera frame, unit length.
 *   - CAP_PROJECTION_EQUIRECTANGULAR (latitude-longitude), any W x H:
 *     polar angle theta = pi * py / H from +z (row 0 looks up), azimuth
 *     phi = pi * (1 - 2 px / W) about +z from +x towards +y, so the centre
 *     column looks forward and moving right in the image turns right, as
 *     seen from inside; d = (sin theta cos phi, sin theta sin phi, cos theta).
 *     Pixel (x, y) has solid angle exactly (2 pi / W) (cos theta0 - cos theta1),
 *     theta0 and theta1 its top and bottom edges.
 *   - CAP_PROJECTION_MIRROR_BALL, square images: a photograph of a mirror
 *     sphere filling the image, taken from far away (orthographic) by a
 *     camera looking along +x with up +z. With a = 2 px / W - 1 (right) and
 *     b = 1 - 2 py / H (up), r^2 = a^2 + b^2 <= 1 and c = sqrt(1 - r^2):
 *     d = (1 - 2c^2, -2ca, 2cb). The centre shows -x (behind the camera), the
 *     rim +x (the blind spot behind the ball). Solid angle per unit of (a, b)
 *     area is exactly 4, so a pixel inside the disc has 16 / (W H) sr.
 *   - CAP_PROJECTION_ANGULAR_MAP, square images (Debevec's light probe
 *     format): the angle from +x grows linearly with the distance from the
 *     centre: theta = pi r, d = (cos theta, -sin theta a / r, sin theta b / r)
 *     with a, b, r as above; the centre shows +x (forward), the rim -x.
 *     Solid angle per unit (a, b) area is pi sin(pi r) / r.
 *   - Image points outside the disc of a mirror ball or angular map carry
 *     no direction; a pixel on the rim counts with its part inside the disc.
 *   - Every function here is pure and thread-safe unless stated otherwise.
 *
 * This header is valid C99 and C++.
 */
#ifndef CAPTURE_PROJECTION_H
#define CAPTURE_PROJECTION_H

#include <stddef.h>
#include <stdint.h>

#include "capture/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Ways a probe image maps pixels to directions (see above). */
typedef enum cap_projection {
    CAP_PROJECTION_EQUIRECTANGULAR = 0,
    CAP_PROJECTION_MIRROR_BALL = 1,
    CAP_PROJECTION_ANGULAR_MAP = 2
} cap_projection;

/** @return the projection's name: "equirectangular", "mirror_ball" or "angular_map" ("" if invalid). */
const char *cap_projection_name(cap_projection p);

/** Parses a name as cap_projection_name() gives it. @return 1 and *out, or 0 if name is NULL or unknown. */
int cap_projection_parse(const char *name, cap_projection *out);

/**
 * @return NULL if a width x height image suits projection p, else a static
 * reason ("mirror ball and angular map images must be square").
 */
const char *cap_projection_check_size(cap_projection p, int width, int height);

/**
 * Gives the camera-frame direction d (unit) at image point (px, py).
 * @return 1; 0 (d untouched) outside the image or outside the disc, or for a bad size.
 */
int cap_projection_direction(cap_projection p, int width, int height, double px, double py, double d[3]);

/**
 * Gives the image point (px, py) whose direction is d (camera frame, any
 * nonzero length); the inverse of cap_projection_direction().
 * @return 1; 0 (outputs untouched) if d is zero or not finite, or for a bad size.
 */
int cap_projection_locate(cap_projection p, int width, int height, const double d[3], double *px, double *py);

/**
 * @return the solid angle (sr) of pixel (x, y): exact for equirectangular
 * images and for mirror-ball pixels wholly inside the disc; otherwise a
 * midpoint rule over the pixel, 4 x 4 points inside the disc and 16 x 16 on
 * its rim (relative error below 1e-4 for images of 64 pixels or more). 0
 * for a pixel outside the image or the disc. Over a whole image the sum is 4 pi.
 */
double cap_projection_solid_angle(cap_projection p, int width, int height, int x, int y);

/**
 * Fills k*k directions inside solid angle id of partition level n
 * (lfio/partition.h) with weights summing to 1: the planar triangle through
 * the solid angle's three unit corners is cut into k*k equal triangles, and
 * each contributes the direction through its centroid, weighted by the solid
 * angle it subtends per unit planar area (1/|p|^3), so that the weighted mean
 * of a function estimates its mean over the solid angle. dirs: [k*k][3] unit
 * vectors; weights: [k*k].
 * @return 1; 0 if n, id or k (1 .. 64) is invalid or an output is NULL.
 */
int cap_partition_samples(uint32_t n, uint64_t id, uint32_t k, double *dirs, double *weights);

/* ------------------------------------------------------------ rendering */

/**
 * Radiance (W sr^-1 m^-2 or relative) arriving at world point org from world
 * direction dir (unit: the direction one looks in), into rgb.
 * @return 1, or 0 on failure (rendering then stops with CAP_ERR_INPUT).
 * Called concurrently from several threads.
 */
typedef int (*cap_radiance_fn)(void *user, const double org[3], const double dir[3], float rgb[3]);

/** How cap_probe_render() samples. */
typedef struct cap_probe_settings {
    int width, height;        /**< image size, 1 .. 16384 each */
    uint32_t strata;          /**< s: s*s directions per pixel, 1 .. 64 */
    uint64_t seed;            /**< jitter seed: the image depends only on it and the inputs */
    unsigned threads;         /**< worker threads, 0 = one per processor; the image does not depend on it */
    cap_progress_fn progress; /**< counts finished rows; may be NULL */
    void *progress_user;
} cap_probe_settings;

/**
 * Renders the equirectangular probe image seen from org with orientation R
 * (NULL: identity): each pixel is the mean of fn over s*s directions, one
 * uniformly distributed (in solid angle) in each cell of an s x s grid in
 * (phi, cos theta) over the pixel, jittered by a hash of seed, pixel and
 * cell. The pixel is then the mean radiance over its solid angle, estimated.
 * rgb: width*height*3 floats, [y][x][rgb].
 * @return CAP_OK; CAP_ERR_ARG (bad settings, NULL, non-finite org, R not a
 * rotation within 1e-6); CAP_ERR_INPUT if fn failed (message names the pixel);
 * CAP_ERR_NOMEM.
 */
cap_status cap_probe_render(const cap_probe_settings *s, cap_radiance_fn fn, void *user, const double org[3],
                            const double R[9], float *rgb);

/** @return 1 if R (row-major 3x3) is a rotation: R^T R = I within 1e-6 and det R > 0; 0 otherwise or for NULL. */
int cap_rotation_check(const double R[9]);

#ifdef __cplusplus
}
#endif

#endif /* CAPTURE_PROJECTION_H */
