/*
 * ilf/hash.h - the project's one integer hash: splitmix64's finaliser, and a
 * combiner built on it. Deterministic on every platform; not cryptographic.
 */
#ifndef ILF_HASH_H
#define ILF_HASH_H

#include <stdint.h>

/* @return splitmix64's output for state z (the finaliser of z + golden ratio). */
static inline uint64_t ilf_splitmix64(uint64_t z)
{
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* @return a well-mixed 64-bit hash of h and x (order matters). */
static inline uint64_t ilf_hash_mix(uint64_t h, uint64_t x)
{
    uint64_t z = h ^ (x + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2));
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* @return a uniform double in [0, 1) from the top 53 bits of h. */
static inline double ilf_unit_from_bits(uint64_t h) { return (double)(h >> 11) * 0x1p-53; }

#endif /* ILF_HASH_H */
