/*
 * partition.h - the sphere partition of Khanna et al., Appendix A.
 *
 * Conventions, stated once for every function below:
 *   - A direction is any finite, nonzero 3-vector (x, y, z); it need not be
 *     unit length. Results are unit vectors. Angles in steradians.
 *   - Octants are numbered o = (x<0) + 2*(y<0) + 4*(z<0). A component that is
 *     zero, including -0.0, counts as positive.
 *   - Level n >= 1 cuts each octant's face of the octahedron |x|+|y|+|z| = 1
 *     into n*n triangles and projects them onto the unit sphere from the
 *     origin: 8*n*n solid angles in all. Ids run 0 .. 8*n*n-1:
 *         id = o*n*n + zi*(2n - zi) + 2*xi + upper
 *     where (xi, zi) is the lattice cell of the planar point n*|d|/|d|_1 in
 *     the octant (x along |dx|, z along |dz|), upper = 0 for the triangle
 *     (xi,zi),(xi+1,zi),(xi,zi+1) and 1 for (xi+1,zi),(xi,zi+1),(xi+1,zi+1).
 *   - The octants with z >= 0 (o = 0..3) come first, so the ids of the
 *     hemisphere around +z are exactly 0 .. 4*n*n-1.
 *   - Solid angles differ (largest/smallest up to about 5.2); use the exact
 *     values from lfio_part_solid_angle(), never 4*pi/(8*n*n).
 *   - Hierarchy: for even n, solid angle id at level n is the union of the
 *     four ids lfio_part_children() gives at level 2n, and lfio_part_parent()
 *     at level n/2 contains it. Powers of two give the full quad-tree.
 *   - All functions are pure and thread-safe. Functions returning int return
 *     1 on success and 0 when an argument is invalid (outputs then untouched).
 *
 * This header is valid C99 and C++.
 */
#ifndef LFIO_PARTITION_H
#define LFIO_PARTITION_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Largest supported level; 8*n*n then stays below 2^51. */
#define LFIO_PART_MAX_N 16777216u

/** @return the number of solid angles over the sphere at level n: 8*n*n (0 if n is invalid). */
uint64_t lfio_part_count(uint32_t n);

/** @return the number of solid angles over the +z hemisphere at level n: 4*n*n (0 if n is invalid). */
uint64_t lfio_part_hemi_count(uint32_t n);

/**
 * Finds the solid angle containing direction d, in constant time.
 * @return 1 and *id on success; 0 if n is invalid or d is zero or not finite.
 */
int lfio_part_id(uint32_t n, const double d[3], uint64_t *id);

/**
 * Gives the three corner directions of solid angle id, counter-clockwise seen
 * from outside the sphere (so det(v[0], v[1], v[2]) > 0).
 * @return 1 on success; 0 if n or id is invalid.
 */
int lfio_part_vertices(uint32_t n, uint64_t id, double v[3][3]);

/**
 * Gives the representative direction of id: the direction through the
 * centroid of its planar triangle on the octahedron face (the point where
 * the barycentric weights of lfio_part_interp() are equal).
 * @return 1 on success; 0 if n or id is invalid.
 */
int lfio_part_centroid(uint32_t n, uint64_t id, double c[3]);

/** @return the exact solid angle of id in steradians (about 1e-16 relative error); 0 if invalid. */
double lfio_part_solid_angle(uint32_t n, uint64_t id);

/**
 * @return the projected solid angle of id about axis a (a unit vector):
 * the integral of max(0, w.a) over the directions w of id, exact to rounding
 * for ids entirely in a's hemisphere. 0 if invalid.
 */
double lfio_part_projected_solid_angle(uint32_t n, uint64_t id, const double a[3]);

/**
 * Gives the solid angle at level n/2 that contains id.
 * @return 1 on success; 0 if n is odd or 1, or id is invalid.
 */
int lfio_part_parent(uint32_t n, uint64_t id, uint64_t *parent);

/**
 * Gives the four solid angles at level 2n whose union is id; the centre
 * (inverted) child comes last.
 * @return 1 on success; 0 if 2n exceeds LFIO_PART_MAX_N or id is invalid.
 */
int lfio_part_children(uint32_t n, uint64_t id, uint64_t child[4]);

/**
 * Gives the three solid angles sharing an edge with id; nb[k] lies across
 * the edge opposite corner k of lfio_part_vertices(). Edges on octant
 * borders lead to the mirror-image triangle in the adjacent octant.
 * @return 1 on success; 0 if n or id is invalid.
 */
int lfio_part_neighbours(uint32_t n, uint64_t id, uint64_t nb[3]);

/**
 * Weights for interpolating a function sampled at the centroids, at
 * direction d: ids[0] is the solid angle containing d and ids[1..3] its
 * neighbours (as lfio_part_neighbours()). The weights are >= 0 and sum to 1;
 * w[0] = 1 at the centroid of ids[0]; on an edge shared with neighbour k the
 * weights are 1/2 for ids[0] and ids[k] and 0 otherwise, so the interpolant
 * is continuous across edges; corners, a set of measure zero, take the mean
 * of the two edges' values.
 * @return 1 on success; 0 if n is invalid or d is zero or not finite.
 */
int lfio_part_interp(uint32_t n, const double d[3], uint64_t ids[4], double w[4]);

/**
 * The weights of lfio_part_interp() at the point of a solid angle's planar
 * lattice triangle with barycentric coordinates lam (corners in the order of
 * lfio_part_vertices(); clamped to >= 0 and normalised): w[0] for the solid
 * angle, w[k] for neighbour k-1 of lfio_part_neighbours(). For callers that
 * sample a triangle and so know where they are without locating.
 */
void lfio_part_interp_weights(const double lam[3], double w[4]);

/**
 * Gives the corners of solid angle id scaled onto the octahedron face
 * |x|+|y|+|z| = 1: the planar triangle the partition cuts, whose lattice
 * the ids are defined on (corner order as lfio_part_vertices()).
 * @return 1 on success; 0 if n or id is invalid.
 */
int lfio_part_face_vertices(uint32_t n, uint64_t id, double v[3][3]);

/** Largest k of lfio_part_strata_init(): k*k strata per solid angle. */
#define LFIO_PART_MAX_STRATA_K 4096u

/**
 * A solid angle prepared for stratified sampling through a planar triangle:
 * corners p[0..2] on the solid angle's corner rays, in any frame the caller
 * rotates them into (lfio_part_vertices() gives them on the unit sphere,
 * lfio_part_face_vertices() on the octahedron face). The triangle is cut into
 * k*k strata of equal planar area: lattice cell (c, r) of the corners
 * p[0] + a (p[1]-p[0]) + b (p[2]-p[0]), a = c/k.., b = r/k.., c + r < k,
 * gives its lower triangle (c,r),(c+1,r),(c,r+1) and, when c + r + 1 < k,
 * that triangle turned half a turn about the cell's centre. Strata are
 * numbered row by row (r), then by c, lower before upper:
 *     s = r*(2k - r) + 2c + upper
 * the same scheme as the partition's own ids within an octant.
 */
typedef struct lfio_part_strata {
    double p[3][3]; /**< the planar triangle's corners */
    double jac;     /**< |det(p0, p1, p2)| / (2 k*k): a stratum's area times the plane's distance from 0
                         (a caller that normalises the weights itself may set it to 1) */
    uint32_t k;     /**< strata per edge */
} lfio_part_strata;

/**
 * Prepares corners p (copied) for k*k strata.
 * @return 1 on success; 0 if k is 0 or above LFIO_PART_MAX_STRATA_K, or a corner is not finite.
 */
int lfio_part_strata_init(lfio_part_strata *st, const double p[3][3], uint32_t k);

/**
 * Gives the direction through the point of stratum s with barycentric
 * coordinates l inside the stratum (l >= 0, summing to 1; l[0] weighs the
 * stratum corner on the side of p[0] .. as listed above), and its weight
 * jac / |P|^3 for the point P: its share of solid angle, so that with l
 * uniform on the stratum the weight's mean is the stratum's solid angle and
 * one sample per stratum sums to an unbiased estimate of the whole. lam, if
 * not NULL, receives P's barycentric coordinates in the whole triangle. For
 * k = 1 lam equals l exactly, so a caller's own warp passes straight through.
 * P = (p0 lam0 + p1 lam1) + p2 lam2; dir = P * (1/|P|); weight = jac*i*i*i, i = 1/|P|.
 * @return 1 on success; 0 if s >= k*k (outputs untouched).
 */
int lfio_part_strata_sample(const lfio_part_strata *st, uint32_t s, const double l[3], double dir[3], double *weight,
                            double lam[3]);

/**
 * Gives the direction through the centroid of stratum s (the mean of its three
 * lattice corners, each p0 + (p1-p0) i/k + (p2-p0) j/k) and its weight
 * jac / |P|^3: a fixed quadrature rule, one point per stratum, for callers
 * that want the same directions on every run. dir = P / |P|.
 * @return 1 on success; 0 if s >= k*k (outputs untouched).
 */
int lfio_part_strata_centroid(const lfio_part_strata *st, uint32_t s, double dir[3], double *weight);

#ifdef __cplusplus
}
#endif

#endif /* LFIO_PARTITION_H */
