/*
 * probe.h - the per-position pipeline of a capture, shared by merge.c
 * (reading a position's images into one linear HDR image), resample.c
 * (box-filtering it onto the slab's hemisphere) and capture.c (running it
 * over every position). Not installed, not public.
 *
 * Invariants: a cap__hdr holds finite values >= 0 only (repairs happen as
 * images are read); every function here works on its arguments alone and
 * may run concurrently for different positions.
 */
#ifndef CAPTURE_PROBE_H
#define CAPTURE_PROBE_H

#include "capture/capture.h"
#include "image/image.h"
#include "manifest.h"

/* A position's merged image: linear radiance, RGB, [y][x][rgb]. */
typedef struct cap__hdr {
    int width, height;
    float *rgb;
} cap__hdr;

/*
 * Reads entry e's images (manifest m, for messages), repairs them (counts in
 * repairs[0 .. e->count-1], whose file, i and j are set too), decodes them
 * and merges a bracket; *unmerged counts bracket pixels with no usable exposure.
 * @return CAP_OK and *out (free out->rgb); CAP_ERR_INPUT or CAP_ERR_NOMEM.
 */
cap_status cap__load_position(const cap_manifest *m, const cap__entry *e, uint32_t i, uint32_t j, cap__hdr *out,
                              cap_repair *repairs, uint64_t *unmerged);

/* @return the capture status of the same meaning as the image library's s. */
cap_status cap__from_image(img_status s);

/*
 * Sums width * height * channels over every image m's capture will read, each
 * time it reads it, from the images' headers (budget.c), before any is decoded.
 * @return CAP_OK; CAP_ERR_INPUT past ILF_CAPTURE_MAX_SAMPLES or for an image
 * whose header cannot be read (the message names the manifest, and the element
 * and file, or the total and the limit); CAP_ERR_NOMEM.
 */
cap_status cap__check_samples(const cap_manifest *m);

/* What resampling one position found. */
typedef struct cap__resample_stats {
    double energy[3];      /* E_image: sum of L * cos * pixel solid angle over front pixels */
    uint64_t interpolated; /* solid angles filled by interpolation */
    uint32_t subdivision;  /* the sub-pixel factor S used */
} cap__resample_stats;

/*
 * Box-filters img (projection p, orientation R) onto the 4n^2 front
 * directions of a slab with frame rows e1, e2, e3 (frame[9]) at level n,
 * into rgb ([dir][rgb]).
 * @return CAP_OK; CAP_ERR_NOMEM.
 */
cap_status cap__resample(const cap__hdr *img, cap_projection p, const double R[9], const double frame[9],
                         uint32_t n, float *rgb, cap__resample_stats *stats);

/* Solid angle per unit image area (pixels^2) of a disc projection at (px, py); 0 outside the disc. */
double cap__disc_density(cap_projection p, int width, int height, double px, double py);

#endif /* CAPTURE_PROBE_H */
