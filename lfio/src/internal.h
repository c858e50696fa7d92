/*
 * internal.h - what lfio's source files share and users never see: the
 * slab's layout, error reporting, and checked arithmetic.
 *
 * Invariants of struct lfio_slab, kept by every function that writes it:
 *   - radiance holds ndir*npos*3 finite floats >= 0, laid out [dir][j][i][rgb];
 *   - leaf_count[d] is the number of positions where direction d has
 *     max(r,g,b) > desc.mask_threshold;
 *   - bit id of mask[k] is set iff some level-n direction below id at level
 *     level_n[k] has leaf_count > 0; mask_set[k] counts the set bits.
 */
#ifndef LFIO_INTERNAL_H
#define LFIO_INTERNAL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "lfio/lightfield.h"
#include "lfio/partition.h"

#define LFIO_MAX_MASK_LEVELS 32

struct lfio_slab {
    lfio_slab_desc desc;
    uint64_t ndir;              /* 4*n*n */
    uint64_t npos;              /* nu*nv */
    float *radiance;            /* ndir*npos*3, then one padding float (mix_directions) */
    double e1[3], e2[3], e3[3]; /* slab frame, world coordinates */
    double len_u, len_v;        /* |u|, |v| in metres */
    double *solid_angle;        /* ndir, steradians */
    double *proj_solid_angle;   /* ndir, projected about e3 */
    uint32_t *leaf_count;       /* ndir */
    uint32_t nlevels;           /* mask levels, coarsest first */
    uint32_t level_n[LFIO_MAX_MASK_LEVELS];
    uint64_t *mask[LFIO_MAX_MASK_LEVELS]; /* bit per hemisphere id */
    uint64_t mask_set[LFIO_MAX_MASK_LEVELS];
};

/* Records a formatted message for lfio_errmsg(). @return status, for `return lfio__fail(...)`. */
lfio_status lfio__fail(lfio_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Clears the calling thread's message. */
void lfio__clear_error(void);

/* Checks desc; on failure writes the reason to why. @return LFIO_OK or LFIO_ERR_ARG. */
lfio_status lfio__check_desc(const lfio_slab_desc *desc, char *why, size_t why_size);

/* @return 1 if name is a valid slab name (1..LFIO_NAME_MAX of [A-Za-z0-9_.-]), else 0. */
int lfio__valid_name(const char *name);

/* Recomputes leaf counts and every mask level from the radiance array. */
void lfio__slab_rebuild_mask(lfio_slab *s);

/* @return 1 and *r = a*b if the product fits in uint64_t, else 0. */
static inline int lfio__mul_u64(uint64_t a, uint64_t b, uint64_t *r)
{
    if (a != 0 && b > UINT64_MAX / a)
        return 0;
    *r = a * b;
    return 1;
}

#endif /* LFIO_INTERNAL_H */
