/*
 * sampling.h - deterministic sample sequences and warps (keys hashed by
 * base's ilf_hash_mix): a scrambled 4-D Halton sequence, uniform directions in spherical
 * triangles (Arvo 1995), and exact spherical-triangle solid angles.
 */
#ifndef RELIGHT_SAMPLING_H
#define RELIGHT_SAMPLING_H

#include <stddef.h>
#include <stdint.h>

#include "ilf/hash.h"
#include "ilf/vec.h"

/* The Cranley-Patterson rotation of one key: four offsets in [0, 1). */
typedef struct lds_key {
    double shift[4];
} lds_key;

/* @return the rotation drawn from key. */
lds_key rl__lds_make(uint64_t key);

/* Sets the shifts of coordinates j and j + 1 of k from one hash h: its low
 * and high 32 bits, ample resolution for a rotation at half the hashing. */
static inline void rl__lds_shift_pair(lds_key *k, int j, uint64_t h)
{
    k->shift[j] = (double)(h & 0xffffffffu) * (1.0 / 4294967296.0);
    k->shift[j + 1] = (double)(h >> 32) * (1.0 / 4294967296.0);
}

/* @return rl__lds_make(key)'s shifts of coordinates 2 and 3, the others 0:
 * for a caller that reads only those (a cell's origins for shared
 * directions), at one hash instead of two. Needs an rl__lds_make() first
 * in the process (the table). */
static inline lds_key rl__lds_make_last2(uint64_t key)
{
    lds_key k = {{0.0, 0.0, 0.0, 0.0}};
    rl__lds_shift_pair(&k, 2, ilf_hash_mix(key, 2));
    return k;
}

/* Radical inverses in bases 2, 3, 5, 7 of the first RL_LDS_TABLE points,
 * filled once by the first rl__lds_make(): most (cell, solid angle) pairs
 * draw only a handful of samples, and the divisions of the radical inverse
 * would otherwise dominate the sequence's cost. */
#define RL_LDS_TABLE 1024
extern double rl__lds_table[4][RL_LDS_TABLE];

/* The sequence's bases, one per coordinate. */
static const uint32_t rl__lds_bases[4] = {2, 3, 5, 7};

/* @return the radical inverse of i in base b. */
double rl__radical_inverse(uint32_t i, uint32_t b);

/* @return coordinate j (0..3) of point i of the sequence of k (rl__lds4()). */
static inline double rl__lds_coord(const lds_key *k, uint32_t i, int j)
{
    double x = (i < RL_LDS_TABLE ? rl__lds_table[j][i] : rl__radical_inverse(i, rl__lds_bases[j])) + k->shift[j];
    x = x >= 1.0 ? x - 1.0 : x;
    return x < 1.0 ? x : 0x1.fffffffffffffp-1;
}

/* Point i of a 4-D Halton sequence (bases 2, 3, 5, 7), shifted modulo 1 by
 * k's offsets: low discrepancy within one key, independent between keys.
 * Each u[j] is in [0, 1). */
static inline void rl__lds4(const lds_key *k, uint32_t i, double u[4])
{
    for (int j = 0; j < 4; j++)
        u[j] = rl__lds_coord(k, i, j);
}


/* A spherical triangle prepared for repeated uniform sampling (Arvo 1995). */
typedef struct sph_tri {
    v3 a, b, c;        /* corners, unit vectors */
    v3 c_perp;         /* c's part orthogonal to a, normalised */
    double omega;      /* solid angle */
    double alpha;      /* interior angle at a */
    double cos_alpha, sin_alpha, cos_ab;
    int planar;        /* tiny or degenerate: sample the planar triangle instead */
} sph_tri;

/* Prepares the triangle a, b, c (unit vectors) of solid angle omega. Below
 * 1e-9 sr the planar triangle is sampled and normalised (density error < 1e-9). */
sph_tri rl__sph_tri_make(v3 a, v3 b, v3 c, double omega);

/* A direction uniformly distributed in t, from u1, u2 in [0, 1). */
v3 rl__sph_tri_sample(const sph_tri *t, double u1, double u2);

/* A direction uniformly distributed in the spherical triangle a, b, c (unit
 * vectors) of solid angle omega, from u1, u2 in [0, 1): rl__sph_tri_make then rl__sph_tri_sample. */
v3 rl__sample_spherical_triangle(v3 a, v3 b, v3 c, double omega, double u1, double u2);

/* @return the solid angle of the spherical triangle a, b, c (unit vectors). */
double rl__spherical_triangle_area(v3 a, v3 b, v3 c);

/* The fan of convex polygon p (n vertices, 3 <= n) as seen from x: unit
 * directions dir[0..n) and the solid angles omega[i] of triangles (0, i, i+1)
 * for i in [1, n-1). @return their total, the polygon's solid angle. */
double rl__sph_fan(const v3 *p, size_t n, v3 x, v3 *dir, double *omega);

/* A direction uniformly distributed in a fan of rl__sph_fan() (total > 0), from u1, u2 in [0, 1). */
v3 rl__sph_fan_sample(const v3 *dir, const double *omega, size_t n, double total, double u1, double u2);

#endif /* RELIGHT_SAMPLING_H */
