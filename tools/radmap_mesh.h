/*
 * radmap_mesh.h - the surfaces of a radiance map as geometry: each stored
 * cell's square clipped to its (convex) polygon, for `ilf export` and `ilf
 * view`.
 *
 * Invariants: a cell's polygon is the intersection of its grid square with
 * the patch's polygon (docs/format.md, "Radiance-map files"), convex since
 * both are, counter-clockwise seen from the patch's front, at most nverts + 4
 * vertices. Nothing is read but the patch as lfio_radmap_get() gives it.
 */
#ifndef ILF_RADMAP_MESH_H
#define ILF_RADMAP_MESH_H

#include <stdint.h>

#include "lfio/radmap.h"

/** Clips cells of one patch; holds the polygon in the map's (u, v) frame and scratch space. */
typedef struct radmap_clipper {
    const lfio_radmap_patch *p;
    uint32_t cap;      /* vertices a clipped polygon may have: nverts + 4 */
    double *poly;      /* [nverts][2] the polygon in (u, v), metres */
    double *a, *b;     /* [cap][2] scratch for the clipping passes */
} radmap_clipper;

/** Prepares c for patch p (kept by pointer). @return 1, or 0 when memory runs out. */
int radmap_clipper_init(radmap_clipper *c, const lfio_radmap_patch *p);

/** Frees c's arrays. */
void radmap_clipper_free(radmap_clipper *c);

/**
 * Writes the world vertices ([count][3], room for c->cap) of cell k's
 * clipped polygon to world. @return count, 0 when nothing is left (a cell the
 * writer kept for an area below rounding).
 */
uint32_t radmap_clipper_cell(radmap_clipper *c, uint32_t k, double *world);

/** @return the world point origin + u e1 + v e2 of patch p in *out. */
void radmap_point(const lfio_radmap_patch *p, double u, double v, double out[3]);

#endif /* ILF_RADMAP_MESH_H */
