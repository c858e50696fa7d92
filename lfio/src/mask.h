/*
 * mask.h - internal interface of the zero-radiance mask (mask.c) used by
 * slab.c; see internal.h for the invariants it keeps.
 */
#ifndef LFIO_MASK_H
#define LFIO_MASK_H

#include "internal.h"

/* @return 1 if max(r, g, b) of rgb exceeds thr. */
static inline int lfio__above(const float rgb[3], float thr)
{
    return rgb[0] > thr || rgb[1] > thr || rgb[2] > thr;
}

/* Sizes the levels for s->desc.n and allocates zeroed bits and counts. @return LFIO_OK or LFIO_ERR_NOMEM. */
lfio_status lfio__mask_alloc(lfio_slab *s);

/* Frees what lfio__mask_alloc() allocated (safe on a partial allocation). */
void lfio__mask_free(lfio_slab *s);

/* Records that one sample of direction dir went from was_above to now_above the threshold. */
void lfio__mask_update(lfio_slab *s, uint64_t dir, int was_above, int now_above);

#endif /* LFIO_MASK_H */
