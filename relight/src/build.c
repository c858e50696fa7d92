/*
 * build.c - the scene builder's shared pieces (build.h): its messages and
 * its material table, looked up by name through open addressing.
 * Invariant: names indexes every material of the scene under construction
 * by name, in a table at most half full.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "build.h"

rl_status rl__build_fail(const rl_build *b, const char *elem, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (elem[0] == '\0')
        return rl__fail(RL_ERR_INPUT, "%s: %s", b->file, msg);
    return rl__fail(RL_ERR_INPUT, "%s: %s: %s", b->file, elem, msg);
}

/* @return the FNV-1a hash of s. */
static uint64_t name_hash(const char *s)
{
    uint64_t h = 14695981039346656037u;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 1099511628211u;
    return h;
}

/* Puts material index i into the name table, which has room. */
static void names_put(rl_build *b, uint32_t i)
{
    size_t mask = b->names_cap - 1, h = (size_t)name_hash(b->scene->materials[i].name) & mask;
    while (b->names[h])
        h = (h + 1) & mask;
    b->names[h] = i + 1;
}

/* Makes room in the name table for one more material, rehashing into double the size. @return 0 on failure. */
static int names_reserve(rl_build *b)
{
    size_t n = b->scene->nmaterials;
    if (2 * (n + 1) < b->names_cap)
        return 1;
    size_t cap = b->names_cap ? 2 * b->names_cap : 64;
    uint32_t *t = calloc(cap, sizeof *t);
    if (!t)
        return 0;
    free(b->names);
    b->names = t;
    b->names_cap = cap;
    for (size_t i = 0; i < n; i++)
        names_put(b, (uint32_t)i);
    return 1;
}

int rl__build_find_material(const rl_build *b, const char *name, uint32_t *index)
{
    if (b->names_cap == 0)
        return 0;
    size_t mask = b->names_cap - 1;
    for (size_t h = (size_t)name_hash(name) & mask; b->names[h]; h = (h + 1) & mask)
        if (strcmp(b->scene->materials[b->names[h] - 1].name, name) == 0) {
            *index = b->names[h] - 1;
            return 1;
        }
    return 0;
}

rl_status rl__build_material(rl_build *b, const char *elem, const char *name, const double albedo[3],
                             const double emission[3], uint32_t *index)
{
    rl_scene *s = b->scene;
    size_t len = strlen(name);
    if (len == 0 || len >= sizeof s->materials->name)
        return rl__build_fail(b, elem, "material name '%.100s' must be 1 to %zu bytes long", name,
                              sizeof s->materials->name - 1);
    rl_material m;
    memset(&m, 0, sizeof m);
    memcpy(m.name, name, len);
    for (int k = 0; k < 3; k++) {
        if (!(albedo[k] >= 0 && albedo[k] <= 1))
            return rl__build_fail(b, elem, "albedo[%d] is %.6g, outside [0, 1]", k, albedo[k]);
        /* at most RL_MAX_EMISSION, so that irradiance and radiosity (pi L
         * per emitter, summed over emitters and bounces) fit in the float32 maps */
        if (!(emission[k] >= 0 && emission[k] <= RL_MAX_EMISSION))
            return rl__build_fail(b, elem, "emission[%d] is %.6g; it must be >= 0 and at most %.0e W sr^-1 m^-2", k,
                                  emission[k], RL_MAX_EMISSION);
        m.albedo[k] = (float)albedo[k];
        m.emission[k] = (float)emission[k];
    }
    uint32_t old;
    if (rl__build_find_material(b, name, &old)) {
        const rl_material *o = &s->materials[old];
        if (memcmp(o->albedo, m.albedo, sizeof m.albedo) != 0 || memcmp(o->emission, m.emission, sizeof m.emission) != 0)
            return rl__build_fail(b, elem, "material '%s' is already defined with other values", name);
        *index = old;
        return RL_OK;
    }
    if (s->nmaterials >= RL_MAX_ELEMENTS)
        return rl__build_fail(b, elem, "more than %zu materials, the limit", RL_MAX_ELEMENTS);
    void *p = rl__grow(s->materials, &b->material_cap, s->nmaterials + 1, sizeof *s->materials);
    if (!p || !names_reserve(b)) {
        if (p)
            s->materials = p;
        return rl__fail(RL_ERR_NOMEM, "%s: out of memory", b->file);
    }
    s->materials = p;
    s->materials[s->nmaterials] = m;
    names_put(b, (uint32_t)s->nmaterials);
    *index = (uint32_t)s->nmaterials++;
    return RL_OK;
}
