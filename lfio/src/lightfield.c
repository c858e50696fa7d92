/*
 * lightfield.c - an ordered collection of slabs with unique names, their
 * optional coverage and covered share, and a creator string: the in-memory
 * content of one light field file.
 *
 * Invariants: every slab has a valid, unique name; the collection owns its
 * slabs and frees them with itself. coverage[k] is NULL or holds
 * dir_count*nu*nv bytes, each 0 or 1, for slab k. Coverage lives here rather
 * than in the slab because it belongs to a slab's place in a file (what the
 * data behind it covers), not to the radiance queries a slab answers.
 * fraction[k] is NaN (none) or the covered share of slab k's etendue, in [0, 1].
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"

struct lfio_lightfield {
    lfio_slab **slabs;
    uint8_t **coverage; /* [capacity], NULL where a slab has none */
    double *fraction;   /* [capacity], NaN where a slab has none */
    size_t count, capacity;
    char creator[256];
};

lfio_status lfio_lightfield_new(lfio_lightfield **out)
{
    if (!out)
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_new: out is NULL");
    *out = calloc(1, sizeof **out);
    if (!*out)
        return lfio__fail(LFIO_ERR_NOMEM, "lfio_lightfield_new: out of memory");
    snprintf((*out)->creator, sizeof (*out)->creator, "lfio %s", LFIO_VERSION_STRING);
    return LFIO_OK;
}

void lfio_lightfield_destroy(lfio_lightfield *lf)
{
    if (!lf)
        return;
    for (size_t k = 0; k < lf->count; k++) {
        lfio_slab_destroy(lf->slabs[k]);
        free(lf->coverage[k]);
    }
    free(lf->slabs);
    free(lf->coverage);
    free(lf->fraction);
    free(lf);
}

lfio_status lfio_lightfield_take_slab(lfio_lightfield *lf, lfio_slab *s)
{
    if (!lf || !s) {
        lfio_slab_destroy(s);
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_take_slab: NULL argument");
    }
    if (!lfio__valid_name(s->desc.name)) {
        lfio__fail(LFIO_ERR_ARG, "slab '%s': a slab in a light field needs a name of 1-63 letters, digits, "
                                 "'_', '-', '.'", s->desc.name);
        lfio_slab_destroy(s);
        return LFIO_ERR_ARG;
    }
    if (lfio_lightfield_find(lf, s->desc.name)) {
        lfio__fail(LFIO_ERR_ARG, "slab '%s': the name is already used", s->desc.name);
        lfio_slab_destroy(s);
        return LFIO_ERR_ARG;
    }
    if (lf->count == lf->capacity) {
        size_t cap = lf->capacity ? 2 * lf->capacity : 4;
        lfio_slab **grown = realloc(lf->slabs, cap * sizeof *grown);
        if (grown)
            lf->slabs = grown;
        uint8_t **cgrown = grown ? realloc(lf->coverage, cap * sizeof *cgrown) : NULL;
        if (cgrown)
            lf->coverage = cgrown;
        double *fgrown = cgrown ? realloc(lf->fraction, cap * sizeof *fgrown) : NULL;
        if (!fgrown) {
            lfio_slab_destroy(s);
            return lfio__fail(LFIO_ERR_NOMEM, "lfio_lightfield_take_slab: out of memory");
        }
        lf->fraction = fgrown;
        lf->capacity = cap;
    }
    lf->coverage[lf->count] = NULL;
    lf->fraction[lf->count] = NAN;
    lf->slabs[lf->count++] = s;
    return LFIO_OK;
}

size_t lfio_lightfield_slab_count(const lfio_lightfield *lf)
{
    return lf->count;
}

lfio_slab *lfio_lightfield_slab(const lfio_lightfield *lf, size_t k)
{
    return k < lf->count ? lf->slabs[k] : NULL;
}

lfio_slab *lfio_lightfield_find(const lfio_lightfield *lf, const char *name)
{
    for (size_t k = 0; name && k < lf->count; k++)
        if (strcmp(lf->slabs[k]->desc.name, name) == 0)
            return lf->slabs[k];
    return NULL;
}

lfio_status lfio_lightfield_set_creator(lfio_lightfield *lf, const char *creator)
{
    if (!creator || strlen(creator) >= sizeof lf->creator)
        return lfio__fail(LFIO_ERR_ARG, "creator string missing or longer than %zu bytes",
                          sizeof lf->creator - 1);
    strcpy(lf->creator, creator);
    return LFIO_OK;
}

const char *lfio_lightfield_creator(const lfio_lightfield *lf)
{
    return lf->creator;
}

lfio_status lfio_lightfield_set_coverage(lfio_lightfield *lf, size_t k, const uint8_t *coverage)
{
    if (!lf || k >= lf->count)
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_set_coverage: slab %zu out of range (%zu slabs)", k,
                          lf ? lf->count : 0);
    const lfio_slab *s = lf->slabs[k];
    uint8_t *copy = NULL;
    if (coverage) {
        /* The slab exists, so ndir*npos*12 bytes fit in memory: the product cannot overflow. */
        size_t total = (size_t)(s->ndir * s->npos);
        for (size_t e = 0; e < total; e++)
            if (coverage[e] > 1)
                return lfio__fail(LFIO_ERR_ARG, "slab '%s': coverage value %u at dir %llu, i %llu, j %llu "
                                  "(expected 0 or 1)", s->desc.name, coverage[e],
                                  (unsigned long long)(e / s->npos), (unsigned long long)(e % s->npos % s->desc.nu),
                                  (unsigned long long)(e % s->npos / s->desc.nu));
        copy = malloc(total ? total : 1);
        if (!copy)
            return lfio__fail(LFIO_ERR_NOMEM, "slab '%s': out of memory for its coverage", s->desc.name);
        memcpy(copy, coverage, total);
    }
    free(lf->coverage[k]);
    lf->coverage[k] = copy;
    return LFIO_OK;
}

const uint8_t *lfio_lightfield_coverage(const lfio_lightfield *lf, size_t k)
{
    return lf && k < lf->count ? lf->coverage[k] : NULL;
}

lfio_status lfio_lightfield_set_coverage_fraction(lfio_lightfield *lf, size_t k, double fraction)
{
    if (!lf || k >= lf->count)
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_set_coverage_fraction: slab %zu out of range (%zu slabs)", k,
                          lf ? lf->count : 0);
    if (!isnan(fraction) && !(fraction >= 0.0 && fraction <= 1.0))
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': coverage fraction %g is not in [0, 1]", lf->slabs[k]->desc.name,
                          fraction);
    lf->fraction[k] = fraction;
    return LFIO_OK;
}

double lfio_lightfield_coverage_fraction(const lfio_lightfield *lf, size_t k)
{
    return lf && k < lf->count ? lf->fraction[k] : NAN;
}

double lfio_coverage_share(const lfio_slab_desc *desc, const uint8_t *coverage, uint64_t *covered)
{
    const uint64_t npos = (uint64_t)desc->nu * desc->nv, ndir = 4ull * desc->n * desc->n;
    const double pole[3] = {0.0, 0.0, 1.0};
    double share = 0.0, total = 0.0;
    uint64_t all = 0;
    for (uint64_t dir = 0; dir < ndir; dir++) {
        uint64_t count = 0;
        for (uint64_t p = 0; p < npos; p++)
            count += coverage[dir * npos + p] != 0;
        double etendue = lfio_part_projected_solid_angle(desc->n, dir, pole);
        share += etendue * (double)count;
        total += etendue * (double)npos;
        all += count;
    }
    if (covered)
        *covered = all;
    return total > 0.0 ? share / total : 0.0;
}
