/*
 * raycast.c - relight/raycast.h: single first-hit rays and the scene's
 * polygons and light fields described, for code outside the engine that
 * must not share its estimators (the path-traced reference of `ilf bench`).
 *
 * Invariants: it reaches Embree only through tracer.h (tracer.c stays the
 * one file that includes it); the tracer is built on one thread, so no
 * worker pool outlives rl_raycaster_new(); descriptions copy nothing but
 * the small fixed-size fields and borrow the rest from the scene.
 */
#include "relight/raycast.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "tracer.h"

struct rl_raycaster {
    const rl_scene *scene;
    rl_tracer *tracer;
};

rl_status rl_raycaster_new(const rl_scene *scene, rl_raycaster **out)
{
    if (!scene || !out)
        return rl__fail(RL_ERR_ARG, "rl_raycaster_new: NULL argument");
    *out = NULL;
    if (scene->npolygons == 0)
        return rl__fail(RL_ERR_ARG, "%s: the scene has no polygons to trace against", scene->path);
    rl_raycaster *rc = calloc(1, sizeof *rc);
    if (!rc)
        return rl__fail(RL_ERR_NOMEM, "out of memory");
    rc->scene = scene;
    rl_status st = rl__tracer_new(scene, 1, &rc->tracer);
    if (st != RL_OK) {
        free(rc);
        return st;
    }
    *out = rc;
    return RL_OK;
}

void rl_raycaster_destroy(rl_raycaster *rc)
{
    if (!rc)
        return;
    rl__tracer_destroy(rc->tracer);
    free(rc);
}

int rl_raycaster_hit(const rl_raycaster *rc, const double org[3], const double dir[3], double tnear, double tfar,
                     rl_ray_hit *hit)
{
    uint32_t polygon;
    double dist;
    v3 o = v3_load(org), d = v3_load(dir);
    if (!rl__tracer_hit(rc->tracer, o, d, tnear, tfar, &polygon, &dist) || polygon >= rc->scene->npolygons)
        return 0;
    const double *n = rc->scene->polygons[polygon].normal;
    hit->polygon = polygon;
    hit->distance = dist;
    hit->front = d.x * n[0] + d.y * n[1] + d.z * n[2] < 0.0;
    return 1;
}

rl_status rl_scene_polygon_describe(const rl_scene *s, size_t k, rl_polygon_desc *out)
{
    if (!s || !out || k >= s->npolygons)
        return rl__fail(RL_ERR_ARG, "rl_scene_polygon_describe: no polygon %zu", k);
    const rl_polygon *p = &s->polygons[k];
    const rl_material *m = &s->materials[p->material];
    out->vertices = (const double (*)[3])s->vertices + p->first;
    out->count = p->count;
    memcpy(out->normal, p->normal, sizeof out->normal);
    out->area = p->area;
    memcpy(out->albedo, m->albedo, sizeof out->albedo);
    memcpy(out->emission, m->emission, sizeof out->emission);
    return RL_OK;
}

rl_status rl_scene_lightfield_describe(const rl_scene *s, size_t k, rl_lightfield_desc *out)
{
    if (!s || !out || k >= s->nlightfields)
        return rl__fail(RL_ERR_ARG, "rl_scene_lightfield_describe: no light field %zu", k);
    const rl_lightfield *lf = &s->lightfields[k];
    out->slab = lf->slab;
    memcpy(out->origin, lf->origin, sizeof out->origin);
    memcpy(out->u, lf->u, sizeof out->u);
    memcpy(out->v, lf->v, sizeof out->v);
    memcpy(out->rot, lf->rot, sizeof out->rot);
    return RL_OK;
}
