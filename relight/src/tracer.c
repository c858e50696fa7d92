/*
 * tracer.c - Embree 3 behind the tracer interface.
 *
 * Every convex polygon is fanned into triangles of one triangle geometry;
 * prim_polygon maps Embree's primitive ids back to scene polygons. The scene
 * uses RTC_SCENE_FLAG_ROBUST: the engine's stratified rays often cross
 * shared triangle edges, which the fast mode may let slip through.
 * Single rays and packets of 4, 8 and 16 are used (rtcIntersect1M with the
 * default context aborts in Debian's Embree 3.13.5).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE__) || defined(__x86_64__)
#include <pmmintrin.h>
#include <xmmintrin.h>
#endif

#include <embree3/rtcore.h>

#include "tracer.h"

struct rl_tracer {
    RTCDevice device;
    RTCScene scene;
    uint32_t *prim_polygon;
    v3 *front;               /* [npolygons]: each polygon's front normal, for rl__tracer_hit_front() */
    rl_occluders *occluders; /* exact beam queries beside the rays (shadow.h) */
    v3 centre;
    double extent;
};

void rl__tracer_thread_init(void)
{
#if defined(__SSE__) || defined(__x86_64__)
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
}

/* Finds the bounding-box centre and the half-extent of the scene. */
static void scene_bounds(const rl_scene *s, v3 *centre, double *extent)
{
    v3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t k = 0; k < s->nvertices; k++) {
        v3 p = v3_load(s->vertices[k]);
        lo = v3_make(fmin(lo.x, p.x), fmin(lo.y, p.y), fmin(lo.z, p.z));
        hi = v3_make(fmax(hi.x, p.x), fmax(hi.y, p.y), fmax(hi.z, p.z));
    }
    if (s->nvertices == 0) {
        *centre = v3_make(0, 0, 0);
        *extent = 1.0;
        return;
    }
    *centre = v3_scale(v3_add(lo, hi), 0.5);
    *extent = fmax(v3_maxabs(v3_sub(hi, *centre)), 1e-30);
}

/* Counts the fan triangles of every polygon. */
static size_t triangle_count(const rl_scene *s)
{
    size_t n = 0;
    for (size_t k = 0; k < s->npolygons; k++)
        n += s->polygons[k].count - 2;
    return n;
}

rl_status rl__tracer_new(const rl_scene *s, unsigned threads, rl_tracer **out)
{
    /* Embree counts the calling thread among its threads; without a count it takes every hardware thread */
    char config[32];
    snprintf(config, sizeof config, "threads=%u", threads > 0 ? threads : 1u);
    *out = NULL;
    rl_tracer *t = calloc(1, sizeof *t);
    if (!t)
        return rl__fail(RL_ERR_NOMEM, "out of memory for the ray tracer");
    scene_bounds(s, &t->centre, &t->extent);
    t->device = rtcNewDevice(config);
    if (!t->device) {
        free(t);
        return rl__fail(RL_ERR_INTERNAL, "Embree could not start (rtcNewDevice failed)");
    }
    t->scene = rtcNewScene(t->device);
    /* the context filter lets rl__tracer_hit_front() skip back faces; other calls set none */
    rtcSetSceneFlags(t->scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    t->front = malloc((s->npolygons ? s->npolygons : 1) * sizeof *t->front);
    if (!t->front) {
        rl__tracer_destroy(t);
        return rl__fail(RL_ERR_NOMEM, "out of memory for the ray tracer");
    }
    for (size_t k = 0; k < s->npolygons; k++)
        t->front[k] = v3_load(s->polygons[k].normal);
    rtcSetSceneBuildQuality(t->scene, RTC_BUILD_QUALITY_HIGH);
    size_t ntri = triangle_count(s);
    if (ntri > 0) {
        RTCGeometry g = rtcNewGeometry(t->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                            s->nvertices);
        unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                               ntri);
        t->prim_polygon = malloc(ntri * sizeof *t->prim_polygon);
        if (!vb || !ib || !t->prim_polygon) {
            rtcReleaseGeometry(g);
            rl__tracer_destroy(t);
            return rl__fail(RL_ERR_NOMEM, "out of memory for %zu triangles", ntri);
        }
        for (size_t k = 0; k < s->nvertices; k++)
            for (int c = 0; c < 3; c++)
                vb[3 * k + c] = (float)(s->vertices[k][c] - (&t->centre.x)[c]);
        size_t tri = 0;
        for (size_t k = 0; k < s->npolygons; k++) {
            const rl_polygon *p = &s->polygons[k];
            for (uint32_t i = 1; i + 1 < p->count; i++, tri++) {
                ib[3 * tri] = p->first;
                ib[3 * tri + 1] = p->first + i;
                ib[3 * tri + 2] = p->first + i + 1;
                t->prim_polygon[tri] = (uint32_t)k;
            }
        }
        rtcCommitGeometry(g);
        rtcAttachGeometry(t->scene, g);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(t->scene);
    if (rtcGetDeviceError(t->device) != RTC_ERROR_NONE) {
        rl__tracer_destroy(t);
        return rl__fail(RL_ERR_INTERNAL, "Embree failed to build the scene");
    }
    rl_status st = rl__occluders_new(s, &t->occluders);
    if (st != RL_OK) {
        rl__tracer_destroy(t);
        return st;
    }
    *out = t;
    return RL_OK;
}

void rl__tracer_destroy(rl_tracer *t)
{
    if (!t)
        return;
    if (t->scene)
        rtcReleaseScene(t->scene);
    if (t->device)
        rtcReleaseDevice(t->device);
    free(t->prim_polygon);
    free(t->front);
    rl__occluders_destroy(t->occluders);
    free(t);
}

const rl_occluders *rl__tracer_occluders(const rl_tracer *t)
{
    return t->occluders;
}

double rl__tracer_extent(const rl_tracer *t)
{
    return t->extent;
}

v3 rl__tracer_centre(const rl_tracer *t)
{
    return t->centre;
}

/* Fills an Embree ray from a world ray. */
static void make_ray(const rl_tracer *t, v3 org, v3 dir, double tnear, double tfar, struct RTCRay *r)
{
    v3 o = v3_sub(org, t->centre);
    r->org_x = (float)o.x;
    r->org_y = (float)o.y;
    r->org_z = (float)o.z;
    r->dir_x = (float)dir.x;
    r->dir_y = (float)dir.y;
    r->dir_z = (float)dir.z;
    r->tnear = (float)tnear;
    r->tfar = (float)tfar;
    r->time = 0.0f;
    r->mask = 0xffffffffu;
    r->id = 0;
    r->flags = 0;
}

int rl__tracer_occluded(const rl_tracer *t, v3 org, v3 dir, double tnear, double tfar)
{
    if (!(tfar > tnear))
        return 0;
    struct RTCIntersectContext ctx;
    struct RTCRay r;
    rtcInitIntersectContext(&ctx);
    make_ray(t, org, dir, tnear, tfar, &r);
    rtcOccluded1(t->scene, &ctx, &r);
    return r.tfar < 0.0f;
}

/* Embree's packet structures RTCRay4, 8 and 16 share one layout: twelve
 * arrays of `width` 4-byte lanes, in this order. */
enum { F_ORG_X, F_ORG_Y, F_ORG_Z, F_TNEAR, F_DIR_X, F_DIR_Y, F_DIR_Z, F_TIME, F_TFAR, F_MASK, F_ID, F_FLAGS };

/* Sets float field f of lane i in a packet of the given width. */
static void lane_set(void *packet, size_t width, int f, size_t i, float v)
{
    ((float *)packet)[(size_t)f * width + i] = v;
}

void rl__tracer_occluded_n(const rl_tracer *t, size_t n, const v3 *org, const v3 *dir, const double *tnear,
                       const double *tfar, int *occluded)
{
    union {
        struct RTCRay4 r4;
        struct RTCRay8 r8;
        struct RTCRay16 r16;
    } packet;
    _Alignas(64) int valid[16];
    size_t width = n <= 4 ? 4 : n <= 8 ? 8 : 16;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    for (size_t i = 0; i < width; i++) {
        int on = i < n && tfar[i] > tnear[i];
        valid[i] = on ? -1 : 0;
        v3 o = on ? v3_sub(org[i], t->centre) : v3_make(0, 0, 0);
        v3 d = on ? dir[i] : v3_make(0, 0, 1);
        lane_set(&packet, width, F_ORG_X, i, (float)o.x);
        lane_set(&packet, width, F_ORG_Y, i, (float)o.y);
        lane_set(&packet, width, F_ORG_Z, i, (float)o.z);
        lane_set(&packet, width, F_DIR_X, i, (float)d.x);
        lane_set(&packet, width, F_DIR_Y, i, (float)d.y);
        lane_set(&packet, width, F_DIR_Z, i, (float)d.z);
        lane_set(&packet, width, F_TNEAR, i, on ? (float)tnear[i] : 0.0f);
        lane_set(&packet, width, F_TFAR, i, on ? (float)tfar[i] : 0.0f);
        lane_set(&packet, width, F_TIME, i, 0.0f);
        unsigned *u = (unsigned *)&packet;
        u[F_MASK * width + i] = 0xffffffffu;
        u[F_ID * width + i] = (unsigned)i;
        u[F_FLAGS * width + i] = 0;
    }
    if (width == 4)
        rtcOccluded4(valid, t->scene, &ctx, &packet.r4);
    else if (width == 8)
        rtcOccluded8(valid, t->scene, &ctx, &packet.r8);
    else
        rtcOccluded16(valid, t->scene, &ctx, &packet.r16);
    const float *tf = (const float *)&packet + (size_t)F_TFAR * width;
    for (size_t i = 0; i < n; i++)
        occluded[i] = valid[i] && tf[i] < 0.0f;
}

_Static_assert(RL_RAY_PACKET <= 16, "rl__tracer_hit_n() traces one packet of 16");

void rl__tracer_hit_n(const rl_tracer *t, size_t n, const v3 *org, const v3 *dir, const double *tnear,
                      const double *tfar, uint32_t *polygon, double *dist)
{
    _Alignas(64) struct RTCRayHit16 rh;
    _Alignas(64) int valid[16];
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (size_t i = 0; i < 16; i++) {
        int on = i < n && tfar[i] > tnear[i];
        valid[i] = on ? -1 : 0;
        v3 o = on ? v3_sub(org[i], t->centre) : v3_make(0, 0, 0);
        v3 d = on ? dir[i] : v3_make(0, 0, 1);
        rh.ray.org_x[i] = (float)o.x;
        rh.ray.org_y[i] = (float)o.y;
        rh.ray.org_z[i] = (float)o.z;
        rh.ray.dir_x[i] = (float)d.x;
        rh.ray.dir_y[i] = (float)d.y;
        rh.ray.dir_z[i] = (float)d.z;
        rh.ray.tnear[i] = on ? (float)tnear[i] : 0.0f;
        rh.ray.tfar[i] = on ? (float)tfar[i] : 0.0f;
        rh.ray.time[i] = 0.0f;
        rh.ray.mask[i] = 0xffffffffu;
        rh.ray.id[i] = (unsigned)i;
        rh.ray.flags[i] = 0;
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect16(valid, t->scene, &ctx, &rh);
    for (size_t i = 0; i < n; i++) {
        int hit = valid[i] && rh.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
        polygon[i] = hit ? t->prim_polygon[rh.hit.primID[i]] : UINT32_MAX;
        dist[i] = hit ? rh.ray.tfar[i] : 0.0;
    }
}

/* An intersection context that also carries the tracer, for front_faces_only(). */
typedef struct front_context {
    struct RTCIntersectContext base; /* first: Embree passes a pointer to it back to the filter */
    const rl_tracer *t;
} front_context;

/* Context filter of rl__tracer_hit_front(): rejects every hit on a polygon's back. RTCRayN and RTCHitN
 * are arrays of N lanes per field: the direction is fields 4 to 6 of the ray, primID field 5 of the hit. */
static void front_faces_only(const struct RTCFilterFunctionNArguments *args)
{
    const front_context *fc = (const front_context *)args->context;
    const float *ray = (const float *)args->ray;
    const unsigned *hit = (const unsigned *)args->hit;
    unsigned n = args->N;
    for (unsigned i = 0; i < n; i++) {
        if (args->valid[i] == 0)
            continue;
        v3 d = v3_make(ray[4 * n + i], ray[5 * n + i], ray[6 * n + i]);
        if (!(v3_dot(d, fc->t->front[fc->t->prim_polygon[hit[5 * n + i]]]) < 0))
            args->valid[i] = 0;
    }
}

/* Traces one ray through ctx (its filter, if any) for its first hit. @return 1 with *polygon and *dist, or 0. */
static int hit1(const rl_tracer *t, struct RTCIntersectContext *ctx, v3 org, v3 dir, double tnear, double tfar,
                uint32_t *polygon, double *dist)
{
    struct RTCRayHit rh;
    make_ray(t, org, dir, tnear, tfar, &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(t->scene, ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID)
        return 0;
    *polygon = t->prim_polygon[rh.hit.primID];
    *dist = rh.ray.tfar;
    return 1;
}

int rl__tracer_hit_front(const rl_tracer *t, v3 org, v3 dir, double tnear, double tfar, uint32_t *polygon,
                         double *dist)
{
    front_context fc;
    rtcInitIntersectContext(&fc.base);
    fc.base.filter = front_faces_only;
    fc.t = t;
    return hit1(t, &fc.base, org, dir, tnear, tfar, polygon, dist);
}

int rl__tracer_hit(const rl_tracer *t, v3 org, v3 dir, double tnear, double tfar, uint32_t *polygon, double *dist)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    return hit1(t, &ctx, org, dir, tnear, tfar, polygon, dist);
}
