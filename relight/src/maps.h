/*
 * maps.h - radiance maps: the grid of cells on each receiving polygon, and
 * receivers of zero area (query points).
 */
#ifndef RELIGHT_MAPS_H
#define RELIGHT_MAPS_H

#include <math.h>
#include <stdint.h>

#include "region.h"
#include "scene_model.h"

/* One cell (rl__map_cell()): its grid square, and whether the polygon's border cuts it. Its shape
 * (rl__map_cell_polygon()), centroid and area (rl__map_cell_centroid()) follow from these and the map, so a cell costs
 * 8 bytes, or one bit in a map whose every grid square is a cell. */
typedef struct rl_cell {
    uint32_t i;           /* grid column */
    uint32_t j : 31;      /* grid row */
    uint32_t clipped : 1; /* 1: the square clipped to the polygon (a point receiver's point), 0: the full square */
} rl_cell;

/* A receiver: a polygon's grid of cells, or a single point (npoly = 1, one cell). */
typedef struct rl_map {
    int32_t polygon;       /* scene polygon, or -1 for a point receiver */
    rl_frame frame;        /* origin at the first vertex, e1 along the first edge, n = front normal */
    v2 *poly;              /* npoly vertices (at most RL_MAX_POLY_VERTS), counter-clockwise about n; owned */
    uint32_t npoly;
    double cell;           /* cell side, m */
    double u0, v0;         /* grid origin in frame coordinates */
    uint32_t nu, nv;
    int32_t *grid;         /* nu*nv cell indices, -1 where the polygon has no area; NULL when every square is a
                              cell, cell j * nu + i (read through rl__map_grid_cell()) */
    rl_cell *cells;        /* ncells cells, row by row; NULL with grid (read through rl__map_cell()) */
    uint8_t *cut;          /* with grid NULL: bit c % 8 of cut[c / 8] set when cell c is cut */
    uint32_t ncells;
    double (*e_total)[3];  /* irradiance summed over passes; the same array as e_pass in a map without
                              e_prev (one pass: nothing to sum) */
    double (*e_pass)[3];   /* irradiance of the current pass */
    double (*e_prev)[3];   /* irradiance of the previous pass: what bounces re-emit; NULL without bounces.
                              After rl__map_settle(), e_pass and e_prev (unless NULL) both name e_total */
    float albedo[3];
    float emission[3];
    /* Borrowed, NULL unless rl__solve() (which owns the arrays) points them for a bounce pass by first
     * hits: rl__bounce_tile() sets near[cell] to 1 when one of the cell's rays meets a surface closer
     * than half a cell above the polygon's inside, or anywhere when the polygon is under three cells
     * across, where the light can change within the cell; and gathers only the cells with
     * subset[cell] != 0 when subset is set. */
    uint8_t *near;
    const uint8_t *subset;
} rl_map;

/* Builds the maps of every receiving polygon (albedo > 0 in some channel) with cells of side cell (m, the
 * job's cell size), clipping their cells on up to threads threads; re_emit: they re-emit in bounce passes
 * (room for e_prev and e_total apart from e_pass). @return RL_OK and *maps (count in *count); RL_ERR_NOMEM
 * or RL_ERR_INPUT (too many cells). */
rl_status rl__maps_build(const rl_scene *scene, double cell, int re_emit, unsigned threads, rl_map **maps,
                         size_t *count);

/* As rl__maps_build(), for receivers that never re-emit (no e_prev): the coarse grids of bounce passes. */
rl_status rl__maps_build_sized(const rl_scene *scene, double cell, unsigned threads, rl_map **maps, size_t *count);

/* Gives in out the value of a field known per cell of m (values[cell]) at
 * frame point q: bilinear between the centres of the grid squares around q,
 * over those whose cells exist, so values are carried to the polygon's
 * edges and never across them; the value of q's own cell when no centre
 * around it has one. */
void rl__map_sample(const rl_map *m, v2 q, const double (*values)[3], double out[3]);

/* Sets fine->e_pass from coarse->e_pass, the same polygon's map on a grid
 * of larger cells with the same origin, for the cells not in fine->subset:
 * bilinear between the coarse cells' centres at each fine cell's centroid,
 * over the coarse cells that exist and are not marked in gathered (NULL:
 * none), so values are carried to a polygon's edges and to the region
 * gathered on its own, never across them. */
void rl__map_interpolate(const rl_map *coarse, const uint8_t *gathered, rl_map *fine);

/* Marks the cells that bounce passes gather on their own instead of interpolating: in gathered
 * (coarse->ncells entries) every coarse cell that has coarse->near set or a neighbour (of eight) that
 * has, and in subset (fine->ncells entries) the fine cells whose centroid lies in one of those (or in
 * no coarse cell, by rounding, when coarse->near is set). The
 * cells of a coarse cell are thus either all gathered on their own, or all interpolated from coarse
 * cells of which none is flagged and whose own area no gathered cell takes (so none is counted twice).
 * @return how many fine cells it marked. */
uint32_t rl__map_mark_direct(const rl_map *coarse, const rl_map *fine, uint8_t *gathered, uint8_t *subset);

/* Builds one point receiver at p facing n (unit). @return RL_OK or RL_ERR_NOMEM. */
rl_status rl__map_point(v3 p, v3 n, rl_map *out);

/* After a solve's last pass: frees m's pass and previous-pass arrays, which then both name e_total (the light
 * the map re-emits, should a later pass ask), so that a finished solution holds 24 bytes a cell. */
void rl__map_settle(rl_map *m);

/* Frees every map's arrays and the array itself. */
void rl__maps_free(rl_map *maps, size_t count);

/* @return cell c (< m->ncells) of m. */
static inline rl_cell rl__map_cell(const rl_map *m, uint32_t c)
{
    if (m->cells != NULL)
        return m->cells[c];
    rl_cell r;
    r.i = c % m->nu;
    r.j = c / m->nu;
    r.clipped = (m->cut[c >> 3] >> (c & 7)) & 1u;
    return r;
}

/* @return the clipped polygon of cell c of m in frame coordinates, in out (room for
 * RL_MAX_POLY_VERTS + 4); the vertex count. A point receiver gives its point. A cut cell's polygon is
 * clipped anew on each call (its vertices are not stored). */
uint32_t rl__map_cell_polygon(const rl_map *m, uint32_t c, v2 *out);

/* @return the centroid of cell c of m in frame coordinates (a whole square's centre, computed without
 * clipping); *area (if not NULL): its area, m^2, 0 for a point receiver. */
v2 rl__map_cell_centroid(const rl_map *m, uint32_t c, double *area);

/* @return the cell on grid square (i, j) of m (i < nu, j < nv), or -1 where the polygon has no area. */
static inline int32_t rl__map_grid_cell(const rl_map *m, size_t i, size_t j)
{
    size_t square = j * m->nu + i;
    return m->grid ? m->grid[square] : (int32_t)square;
}

/* @return the index (j * nu + i) of the grid square of m holding frame point q, clamped to the grid
 * (rounding may put a point on the polygon just outside it); m has at least one square. */
static inline size_t rl__map_square_clamped(const rl_map *m, v2 q)
{
    double fi = floor((q.x - m->u0) / m->cell), fj = floor((q.y - m->v0) / m->cell);
    size_t i = fi < 0 ? 0 : fi > m->nu - 1 ? m->nu - 1 : (size_t)fi;
    size_t j = fj < 0 ? 0 : fj > m->nv - 1 ? m->nv - 1 : (size_t)fj;
    return j * m->nu + i;
}

/* @return the cell of m containing frame point q, or -1. */
int64_t rl__map_cell_at(const rl_map *m, v2 q);

/* @return the cell of m holding frame point q (clamped to the grid), or, when that square has no cell
 * (rounding at an edge), the first found of its side neighbours, then of its corner neighbours; -1 if none. */
int64_t rl__map_cell_near(const rl_map *m, v2 q);

/* Writes the radiance cell of m (-1: none) re-emits in a bounce, albedo * E_prev / pi, W sr^-1 m^-2. */
void rl__map_radiance(const rl_map *m, int64_t cell, double out[3]);

/* A convex polygon prepared for drawing many uniform points: its fan
 * triangles' areas, computed once. It points at the polygon, which must
 * outlive it. */
typedef struct rl_polygon_sampler {
    const v2 *p;
    uint32_t count;
    double total;                  /* the polygon's area */
    double w[RL_MAX_POLY_VERTS + 8]; /* w[t]: the area of fan triangle p[0], p[t], p[t + 1] */
} rl_polygon_sampler;

/* Prepares s for polygon p (count vertices, convex, at most RL_MAX_POLY_VERTS + 8). */
void rl__polygon_sampler_init(rl_polygon_sampler *s, const v2 *p, uint32_t count);

/* A point uniformly distributed over s's polygon, from two numbers in
 * [0, 1); a point receiver (count 1) gives its point. */
v2 rl__polygon_sampler_point(const rl_polygon_sampler *s, double a, double b);

/* The same for a polygon used once. */
v2 rl__sample_polygon(const v2 *p, uint32_t count, double a, double b);

/* @return the area of convex polygon p. */
double rl__polygon_area2(const v2 *p, uint32_t count);

/* @return 1 if q lies inside the convex counter-clockwise polygon p (count vertices) at least margin
 * (>= 0, in p's units) from each of its edges, else 0. */
int rl__polygon_holds(const v2 *p, uint32_t count, v2 q, double margin);

#endif /* RELIGHT_MAPS_H */
