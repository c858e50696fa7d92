/*
 * internal.h - what the capture library's sources share and do not export:
 * setting the calling thread's error message, small 3-vector helpers, and
 * the position-parallel runner that fills a slab (runner.c).
 *
 * Invariants: internal names start with cap__ and never appear in a public
 * header; this header is included by C and by the one C++ source.
 */
#ifndef CAPTURE_INTERNAL_H
#define CAPTURE_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Sets the calling thread's message from a printf format. @return status. */
cap_status cap__fail(cap_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** Puts "<formatted prefix>: " before the calling thread's current message. @return status. */
cap_status cap__fail_prefix(cap_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/** Sets the calling thread's message to text (copied, truncated to one line). @return status. */
cap_status cap__fail_text(cap_status status, const char *text);

#ifdef __cplusplus
}

#else /* the helpers below are C only */

#include "ilf/vec.h"
#include "lfio/lightfield.h"

/* Scales a to unit length. @return 1, or 0 (a untouched) if a is zero or not finite. */
static inline int cap__normalise(double a[3])
{
    double len = a3_len(a);
    if (!(len > 0.0) || !isfinite(len))
        return 0;
    a[0] /= len;
    a[1] /= len;
    a[2] /= len;
    return 1;
}

/* out = m * a for a row-major 3x3 matrix m. */
static inline void cap__mat_apply(const double m[9], const double a[3], double out[3])
{
    double x = m[0] * a[0] + m[1] * a[1] + m[2] * a[2];
    double y = m[3] * a[0] + m[4] * a[1] + m[5] * a[2];
    double z = m[6] * a[0] + m[7] * a[1] + m[8] * a[2];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

/* out = m^T * a for a row-major 3x3 matrix m. */
static inline void cap__mat_apply_transposed(const double m[9], const double a[3], double out[3])
{
    double x = m[0] * a[0] + m[3] * a[1] + m[6] * a[2];
    double y = m[1] * a[0] + m[4] * a[1] + m[7] * a[2];
    double z = m[2] * a[0] + m[5] * a[1] + m[8] * a[2];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

/* ---------------------------------------------------------------- runner */

/*
 * Computes one position's radiance into rgb ([dir][rgb], 4n^2 directions of
 * the slab being filled). Runs on worker threads, concurrently for different
 * positions; on failure it sets the thread's message and returns its status.
 */
typedef cap_status (*cap__position_fn)(void *ctx, uint32_t i, uint32_t j, float *rgb);

/*
 * Fills every position of slab with fn on `threads` threads (0: one per
 * processor), each into its own buffer, written with
 * lfio_slab_write_position() one at a time. Positions are claimed in order
 * k = j*nu + i; after a failure no new position is started, and the failure
 * of the lowest position is returned with its message, so the outcome does
 * not depend on the thread count. progress (may be NULL) counts positions.
 */
cap_status cap__run_positions(lfio_slab *slab, unsigned threads, cap__position_fn fn, void *ctx,
                              cap_progress_fn progress, void *user);


#endif /* __cplusplus */

#endif /* CAPTURE_INTERNAL_H */
