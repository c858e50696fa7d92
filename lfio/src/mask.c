/*
 * mask.c - the hierarchical zero-radiance mask of a slab.
 *
 * The finest level counts, per direction, the positions whose radiance
 * exceeds the threshold (leaf_count). A mask bit at level m is set iff some
 * finest direction below it has a nonzero count. Levels are n, n/2, n/4, ...
 * down to the first odd n, stored coarsest first, one bit per hemisphere id.
 *
 * A write changes at most one leaf count; only when that count moves between
 * zero and nonzero does a bit change, and then the change walks up the
 * hierarchy, checking the four siblings at each level before clearing. So
 * the mask is exact after every write, at O(levels) cost per flipped bit.
 */
#include <stdlib.h>
#include <string.h>

#include "mask.h"

/* @return bit id of level k. */
static int bit_get(const lfio_slab *s, uint32_t k, uint64_t id)
{
    return (int)((s->mask[k][id >> 6] >> (id & 63u)) & 1u);
}

/* Sets bit id of level k to on, keeping the level's count. */
static void bit_put(lfio_slab *s, uint32_t k, uint64_t id, int on)
{
    uint64_t m = (uint64_t)1 << (id & 63u);
    uint64_t *word = &s->mask[k][id >> 6];
    if (on && !(*word & m)) {
        *word |= m;
        s->mask_set[k]++;
    } else if (!on && (*word & m)) {
        *word &= ~m;
        s->mask_set[k]--;
    }
}

/* @return 1 if any of the four children (at level k+1) of id at level k is set. */
static int any_child(const lfio_slab *s, uint32_t k, uint64_t id)
{
    uint64_t child[4];
    lfio_part_children(s->level_n[k], id, child);
    for (int c = 0; c < 4; c++)
        if (bit_get(s, k + 1, child[c]))
            return 1;
    return 0;
}

lfio_status lfio__mask_alloc(lfio_slab *s)
{
    uint32_t n = s->desc.n, levels = 1;
    while (!(n & 1u) && levels < LFIO_MAX_MASK_LEVELS) {
        n /= 2;
        levels++;
    }
    s->nlevels = levels;
    for (uint32_t k = 0; k < levels; k++) {
        s->level_n[k] = s->desc.n >> (levels - 1 - k);
        uint64_t words = (lfio_part_hemi_count(s->level_n[k]) + 63u) / 64u;
        s->mask[k] = calloc(words, sizeof(uint64_t));
        if (!s->mask[k])
            return LFIO_ERR_NOMEM;
        s->mask_set[k] = 0;
    }
    s->leaf_count = calloc(s->ndir, sizeof(uint32_t));
    return s->leaf_count ? LFIO_OK : LFIO_ERR_NOMEM;
}

void lfio__mask_free(lfio_slab *s)
{
    for (uint32_t k = 0; k < s->nlevels; k++)
        free(s->mask[k]);
    free(s->leaf_count);
}

/* Propagates a change of leaf dir's bit (level nlevels-1) to the coarser levels. */
static void propagate(lfio_slab *s, uint64_t dir, int on)
{
    uint32_t k = s->nlevels - 1;
    uint64_t id = dir;
    bit_put(s, k, id, on);
    while (k > 0) {
        uint64_t parent;
        lfio_part_parent(s->level_n[k], id, &parent);
        k--;
        int parent_on = on ? 1 : any_child(s, k, parent);
        if (bit_get(s, k, parent) == parent_on)
            break; /* nothing above can change */
        bit_put(s, k, parent, parent_on);
        id = parent;
    }
}

void lfio__mask_update(lfio_slab *s, uint64_t dir, int was_above, int now_above)
{
    if (was_above == now_above)
        return;
    if (now_above) {
        if (s->leaf_count[dir]++ == 0)
            propagate(s, dir, 1);
    } else {
        if (--s->leaf_count[dir] == 0)
            propagate(s, dir, 0);
    }
}

void lfio__slab_rebuild_mask(lfio_slab *s)
{
    float thr = s->desc.mask_threshold;
    uint32_t fine = s->nlevels - 1;
    for (uint32_t k = 0; k < s->nlevels; k++) {
        memset(s->mask[k], 0, (lfio_part_hemi_count(s->level_n[k]) + 63u) / 64u * sizeof(uint64_t));
        s->mask_set[k] = 0;
    }
    for (uint64_t d = 0; d < s->ndir; d++) {
        const float *p = s->radiance + d * s->npos * 3;
        uint32_t count = 0;
        for (uint64_t q = 0; q < s->npos; q++)
            count += lfio__above(p + 3 * q, thr);
        s->leaf_count[d] = count;
        if (count)
            bit_put(s, fine, d, 1);
    }
    /* Coarser levels from finer ones: a parent is set iff a child is. */
    for (uint32_t k = fine; k > 0; k--) {
        uint64_t count = lfio_part_hemi_count(s->level_n[k]);
        for (uint64_t id = 0; id < count; id++) {
            uint64_t parent;
            if (bit_get(s, k, id) && lfio_part_parent(s->level_n[k], id, &parent))
                bit_put(s, k - 1, parent, 1);
        }
    }
}

uint32_t lfio_slab_mask_levels(const lfio_slab *s)
{
    return s->nlevels;
}

uint32_t lfio_slab_mask_n(const lfio_slab *s, uint32_t k)
{
    return k < s->nlevels ? s->level_n[k] : 0;
}

/* @return the mask level index of partition level m, or -1. */
static int level_index(const lfio_slab *s, uint32_t m)
{
    for (uint32_t k = 0; k < s->nlevels; k++)
        if (s->level_n[k] == m)
            return (int)k;
    return -1;
}

int lfio_slab_mask_test(const lfio_slab *s, uint32_t m, uint64_t id)
{
    /* Levels are powers of two apart, so the index follows from the ratio. */
    uint32_t n = s->desc.n;
    if (m == 0 || m > n || n % m)
        return 1;
    uint32_t ratio = n / m, shift = 0;
    while ((1u << shift) < ratio)
        shift++;
    if ((1u << shift) != ratio || shift >= s->nlevels)
        return 1;
    uint32_t k = s->nlevels - 1 - shift;
    if (id >= lfio_part_hemi_count(m))
        return 1;
    return bit_get(s, k, id);
}

uint64_t lfio_slab_mask_count(const lfio_slab *s, uint32_t m)
{
    int k = level_index(s, m);
    return k < 0 ? 0 : s->mask_set[k];
}
