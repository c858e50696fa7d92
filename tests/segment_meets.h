/*
 * segment_meets.h - the brute-force answer the visibility tests check the
 * engine's exact tests against: does a segment cross a convex polygon,
 * intersected in double precision.
 */
#ifndef ILF_TEST_SEGMENT_MEETS_H
#define ILF_TEST_SEGMENT_MEETS_H

#include <stddef.h>

#include "ilf/vec.h"

/* @return 1 if segment x -> y meets the convex polygon v (count vertices,
 * counter-clockwise about unit normal n) at a parameter in (margin,
 * 1 - margin) and a point at least margin inside its edges (margin < 0
 * widens it: a lenient test). */
static inline int ts_segment_meets(const v3 *v, size_t count, v3 n, v3 x, v3 y, double margin)
{
    double hx = v3_dot(v3_sub(x, v[0]), n), hy = v3_dot(v3_sub(y, v[0]), n);
    if ((hx > 0) == (hy > 0) || hx == hy)
        return 0;
    double t = hx / (hx - hy);
    if (!(t > margin && t < 1 - margin))
        return 0;
    v3 h = v3_madd(x, v3_sub(y, x), t);
    for (size_t i = 0; i < count; i++) {
        v3 a = v[i], b = v[(i + 1) % count];
        v3 m = v3_cross(n, v3_sub(b, a));
        if (!(v3_dot(v3_sub(h, a), m) > margin * v3_len(m)))
            return 0;
    }
    return 1;
}

#endif /* ILF_TEST_SEGMENT_MEETS_H */
