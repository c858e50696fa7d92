/*
 * solution.c - the rl_solution accessors: pass statistics, the memory the
 * accumulators held, the maps' geometry and their cells' values (engine.c,
 * which makes solutions, also destroys them).
 *
 * A solution is immutable once rl_relight() returns it (engine.c), so
 * every accessor here only reads and may run on several threads at once.
 * Values leave as floats, clamped to FLT_MAX, never inf: the radiance maps
 * are float32 and a light field may hold radiance near FLT_MAX.
 */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "engine_internal.h"

uint32_t rl_solution_pass_count(const rl_solution *s)
{
    return s->npasses;
}

rl_status rl_solution_pass_stats(const rl_solution *s, uint32_t k, rl_pass_stats *out)
{
    if (k >= s->npasses)
        return rl__fail(RL_ERR_ARG, "pass %u of %u", k, s->npasses);
    *out = s->passes[k];
    return RL_OK;
}

uint64_t rl_solution_accumulator_bytes(const rl_solution *s)
{
    return s->accumulator_bytes;
}

size_t rl_solution_map_count(const rl_solution *s)
{
    return s->nmaps;
}

rl_status rl_solution_map_info(const rl_solution *s, size_t k, rl_map_info *out)
{
    if (k >= s->nmaps)
        return rl__fail(RL_ERR_ARG, "map %zu of %zu", k, s->nmaps);
    const rl_map *m = &s->maps[k];
    out->polygon = (uint32_t)m->polygon;
    out->label = s->scene->polygons[m->polygon].label;
    v3_store(m->frame.origin, out->origin);
    v3_store(m->frame.e1, out->e1);
    v3_store(m->frame.e2, out->e2);
    v3_store(m->frame.n, out->normal);
    out->cell_size = m->cell;
    out->u0 = m->u0;
    out->v0 = m->v0;
    out->nu = m->nu;
    out->nv = m->nv;
    out->ncells = m->ncells;
    memcpy(out->albedo, m->albedo, sizeof out->albedo);
    memcpy(out->emission, m->emission, sizeof out->emission);
    const rl_polygon *pg = &s->scene->polygons[m->polygon];
    out->vertices = &s->scene->vertices[pg->first][0];
    out->nvertices = pg->count;
    return RL_OK;
}

/* @return x as a float, FLT_MAX where it is beyond float's range: a light
 * field may hold radiance near FLT_MAX, whose irradiance is pi times more,
 * and a map must never hold inf. */
static float saturate_float(double x)
{
    return x > FLT_MAX ? FLT_MAX : (float)x;
}

rl_status rl_solution_map_cells(const rl_solution *s, size_t k, uint32_t *ij, double *area, double *centre,
                                float *irradiance, float *radiosity)
{
    uint32_t n = k < s->nmaps ? s->maps[k].ncells : 0;
    return rl_solution_map_rows(s, k, 0, n, ij, area, centre, irradiance, radiosity);
}

rl_status rl_solution_map_rows(const rl_solution *s, size_t k, uint32_t first, uint32_t count, uint32_t *ij,
                               double *area, double *centre, float *irradiance, float *radiosity)
{
    if (k >= s->nmaps)
        return rl__fail(RL_ERR_ARG, "map %zu of %zu", k, s->nmaps);
    const rl_map *m = &s->maps[k];
    if (first > m->ncells || count > m->ncells - first)
        return rl__fail(RL_ERR_ARG, "cells %u to %llu of map %zu, which has %u", first,
                        (unsigned long long)first + count, k, m->ncells);
    for (uint32_t r = 0; r < count; r++) {
        const uint32_t c = first + r;
        const rl_cell cell = rl__map_cell(m, c);
        if (ij) {
            ij[2 * r] = cell.i;
            ij[2 * r + 1] = cell.j;
        }
        if (area || centre) {
            double a;
            v2 q = rl__map_cell_centroid(m, c, &a);
            if (area)
                area[r] = a;
            if (centre)
                v3_store(frame_point(&m->frame, q), centre + 3 * r);
        }
        for (int ch = 0; ch < 3; ch++) {
            if (irradiance)
                irradiance[3 * r + ch] = saturate_float(m->e_total[c][ch]);
            if (radiosity)
                radiosity[3 * r + ch] = saturate_float(ILF_PI * m->emission[ch] + m->albedo[ch] * m->e_total[c][ch]);
        }
    }
    return RL_OK;
}
