/*
 * lightfield.c - an ordered collection of slabs with unique names and a
 * creator string: the in-memory content of one light field file.
 *
 * Invariants: every slab has a valid, unique name; the collection owns its
 * slabs and frees them with itself.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"

struct lfio_lightfield {
    lfio_slab **slabs;
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
    for (size_t k = 0; k < lf->count; k++)
        lfio_slab_destroy(lf->slabs[k]);
    free(lf->slabs);
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
        if (!grown) {
            lfio_slab_destroy(s);
            return lfio__fail(LFIO_ERR_NOMEM, "lfio_lightfield_take_slab: out of memory");
        }
        lf->slabs = grown;
        lf->capacity = cap;
    }
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
