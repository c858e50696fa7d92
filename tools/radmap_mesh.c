/*
 * radmap_mesh.c - a radiance map's cells as convex polygons: Sutherland and
 * Hodgman's clipping of the patch's polygon by the four sides of a cell's
 * square, in the map's own (u, v) frame.
 *
 * Invariants: the polygon is projected once per patch; clipping a convex
 * polygon by half-planes keeps it convex and its order (counter-clockwise
 * from the front), so each pass adds at most one vertex. lfio's reader does
 * not check convexity: a pass that would pass the capacity (a non-convex
 * polygon in a hand-edited file) gives no cell rather than overrun.
 */
#include <stdlib.h>

#include "radmap_mesh.h"

int radmap_clipper_init(radmap_clipper *c, const lfio_radmap_patch *p)
{
    c->p = p;
    c->cap = p->nverts + 4;
    c->poly = malloc(sizeof(double) * 2 * p->nverts);
    c->a = malloc(sizeof(double) * 2 * c->cap);
    c->b = malloc(sizeof(double) * 2 * c->cap);
    if (c->poly == NULL || c->a == NULL || c->b == NULL) {
        radmap_clipper_free(c);
        return 0;
    }
    for (uint32_t k = 0; k < p->nverts; k++) {
        double d[3];
        for (int i = 0; i < 3; i++)
            d[i] = p->vertices[3 * k + i] - p->origin[i];
        c->poly[2 * k] = d[0] * p->e1[0] + d[1] * p->e1[1] + d[2] * p->e1[2];
        c->poly[2 * k + 1] = d[0] * p->e2[0] + d[1] * p->e2[1] + d[2] * p->e2[2];
    }
    return 1;
}

void radmap_clipper_free(radmap_clipper *c)
{
    free(c->poly);
    free(c->a);
    free(c->b);
    c->poly = c->a = c->b = NULL;
}

void radmap_point(const lfio_radmap_patch *p, double u, double v, double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = p->origin[i] + u * p->e1[i] + v * p->e2[i];
}

/* Keeps the part of polygon in[n] where sign * (coordinate axis - bound) >= 0, into out (room for cap
 * vertices). @return its count, 0 if it would not fit. */
static uint32_t clip_side(const double *in, uint32_t n, int axis, double bound, double sign, double *out,
                          uint32_t cap)
{
    uint32_t m = 0;
    for (uint32_t k = 0; k < n; k++) {
        const double *p = in + 2 * k, *q = in + 2 * ((k + 1) % n);
        double dp = sign * (p[axis] - bound), dq = sign * (q[axis] - bound);
        int keep = dp >= 0, cross = (dp >= 0) != (dq >= 0);
        if (m + (uint32_t)keep + (uint32_t)cross > cap)
            return 0;
        if (keep) {
            out[2 * m] = p[0];
            out[2 * m + 1] = p[1];
            m++;
        }
        if (cross) {
            double t = dp / (dp - dq);
            out[2 * m] = p[0] + t * (q[0] - p[0]);
            out[2 * m + 1] = p[1] + t * (q[1] - p[1]);
            m++;
        }
    }
    return m;
}

uint32_t radmap_clipper_cell(radmap_clipper *c, uint32_t k, double *world)
{
    const lfio_radmap_patch *p = c->p;
    double u0 = p->u0 + p->cell_ij[2 * k] * p->cell_size, v0 = p->v0 + p->cell_ij[2 * k + 1] * p->cell_size;
    uint32_t n = clip_side(c->poly, p->nverts, 0, u0, 1.0, c->a, c->cap);
    n = clip_side(c->a, n, 0, u0 + p->cell_size, -1.0, c->b, c->cap);
    n = clip_side(c->b, n, 1, v0, 1.0, c->a, c->cap);
    n = clip_side(c->a, n, 1, v0 + p->cell_size, -1.0, c->b, c->cap);
    if (n < 3)
        return 0;
    for (uint32_t i = 0; i < n; i++)
        radmap_point(p, c->b[2 * i], c->b[2 * i + 1], world + 3 * i);
    return n;
}
