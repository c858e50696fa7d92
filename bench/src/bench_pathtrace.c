/*
 * bench_pathtrace.c - an independent reference: plain Monte Carlo path
 * tracing of diffuse scenes lit by diffuse polygons and light field slabs.
 *
 * It shares nothing with the engine's estimators (no transfer, culling,
 * bounce maps, partition walks or emitter tables). What it takes from the
 * project are definitions, not methods: the scene as loaded (geometry,
 * albedo, emission, light field placement: relight/raycast.h), lfio's own
 * slab lookup (lfio_slab_radiance_interp(), the light field's radiance by
 * definition) and first hits from relight's public ray caster. Rays go
 * through rl_raycaster rather than an intersector of our own because the
 * data/ classroom has 3,035 polygons: brute force over every polygon would
 * make a converged reference of it take hours, and a first hit is a fact
 * about geometry, not an estimator (test_pathtrace checks it against
 * Lambert's closed form, which involves no ray at all).
 *
 * The estimator, per path from a receiver point x0 with normal n0:
 *   E = D(x0) + a1 (D(x1) + a2 (D(x2) + ...)), up to `bounces` reflections,
 * where x(k+1) is the first front hit along a cosine-weighted direction
 * about n(k), a(k) its albedo (the pi of the cosine pdf cancels the 1/pi
 * of the Lambertian BRDF), and D(x) is direct irradiance by two strategies
 * combined with the balance heuristic of multiple importance sampling:
 * light sampling (one point on every light field slab, uniform over its
 * rectangle, and one point on one emitting polygon, chosen with probability
 * proportional to area times luminance of emission, uniform over its area)
 * and one cosine-weighted ray (the slabs it crosses before its first hit,
 * and the emitting front it meets). Each sample adds L cos / (p_light +
 * p_cosine) in solid-angle densities, never more than pi L: the 1/r^2 of
 * light sampling next to an emitter cannot make a cell's estimate heavy-
 * tailed. The bounce ray is separate from D's ray, so emission it meets is
 * not added again. A ray meeting a polygon's back ends the path, as an
 * opaque black back face.
 *
 * Light arriving through a slab: radiance L(s, t, d) where the segment from
 * x toward the slab point crosses it, d the direction light travels
 * (pointing from the slab to x; zero behind the slab), read in the slab's
 * own frame (the placement's rotation, transposed). Slabs are not
 * occluders.
 *
 * Invariants: every random number comes from a splitmix64 stream seeded by
 * the caller; nothing is shared between calls, so calls may run in parallel.
 */
#include "bench_pathtrace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lfio/lightfield.h"
#include "ilf/vec.h"
#include "relight/raycast.h"

/* Offsets of ray origins off their surface, and of shadow rays short of their target, metres:
 * well above the single-precision rounding of scenes of a few metres, below any feature of one. */
#define PT_EPS 1e-4
/* Draws per path start before a cell is taken to be a sliver. */
#define PT_CELL_TRIES 64
/* Largest polygon the fan sampler handles (the scene loader's own bound is far below). */
#define PT_MAX_VERTS 64

typedef struct pt_emitter {
    uint32_t polygon;
    double cdf; /* running sum of area * luminance(emission), normalised to end at 1 */
    double power;
} pt_emitter;

/* A slab's plane: unit normal of its front and area. */
typedef struct pt_slab {
    double normal[3], area;
} pt_slab;

struct bench_pt {
    const rl_scene *scene;
    rl_raycaster *rc;
    size_t npolygons;
    rl_polygon_desc *polygons;
    size_t nemitters;
    pt_emitter *emitters;
    double total_power;
    double *emit_prob; /* [npolygons] probability that light sampling picks the polygon (0: never) */
    size_t nslabs;
    rl_lightfield_desc *slabs;
    pt_slab *geo;      /* [nslabs] */
};

/* ------------------------------------------------------------ small maths */

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double luminance(const double rgb[3]) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

/* splitmix64: a uniform double in [0, 1) from the stream *state. */
static double rnd(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

/* Writes into t1, t2 two unit vectors completing unit n to an orthonormal frame. */
static void frame(const double n[3], double t1[3], double t2[3])
{
    double a[3] = {fabs(n[0]) < 0.9 ? 1.0 : 0.0, fabs(n[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    cross3(n, a, t1);
    double l = sqrt(dot3(t1, t1));
    for (int k = 0; k < 3; k++)
        t1[k] /= l;
    cross3(n, t1, t2);
}

/* A direction about unit n with density cos(theta) / pi. */
static void cosine_direction(const double n[3], uint64_t *rng, double d[3])
{
    double t1[3], t2[3];
    frame(n, t1, t2);
    double r = sqrt(rnd(rng)), phi = 2.0 * ILF_PI * rnd(rng);
    double a = r * cos(phi), b = r * sin(phi), c = sqrt(fmax(0.0, 1.0 - r * r));
    for (int k = 0; k < 3; k++)
        d[k] = a * t1[k] + b * t2[k] + c * n[k];
}

/* A point uniformly over convex polygon p (a fan of triangles chosen by area, then a uniform point in one). */
static void polygon_point(const rl_polygon_desc *p, uint64_t *rng, double y[3])
{
    const double *v0 = p->vertices[0];
    double pick = rnd(rng) * p->area * 2.0, acc = 0.0;
    uint32_t k = 1;
    for (; k + 2 < p->count; k++) {
        double e1[3], e2[3], c[3];
        for (int q = 0; q < 3; q++) {
            e1[q] = p->vertices[k][q] - v0[q];
            e2[q] = p->vertices[k + 1][q] - v0[q];
        }
        cross3(e1, e2, c);
        acc += sqrt(dot3(c, c));
        if (pick < acc)
            break;
    }
    double a = rnd(rng), b = rnd(rng);
    if (a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
    }
    for (int q = 0; q < 3; q++)
        y[q] = v0[q] + a * (p->vertices[k][q] - v0[q]) + b * (p->vertices[k + 1][q] - v0[q]);
}

/* ------------------------------------------------------------ setting up */

bench_pt *bench_pt_new(const rl_scene *scene, char *why, size_t size)
{
    bench_pt *pt = calloc(1, sizeof *pt);
    if (pt == NULL) {
        snprintf(why, size, "out of memory");
        return NULL;
    }
    pt->scene = scene;
    pt->npolygons = rl_scene_polygon_count(scene);
    pt->nslabs = rl_scene_lightfield_count(scene);
    pt->polygons = calloc(pt->npolygons ? pt->npolygons : 1, sizeof *pt->polygons);
    pt->emitters = calloc(pt->npolygons ? pt->npolygons : 1, sizeof *pt->emitters);
    pt->slabs = calloc(pt->nslabs ? pt->nslabs : 1, sizeof *pt->slabs);
    pt->geo = calloc(pt->nslabs ? pt->nslabs : 1, sizeof *pt->geo);
    pt->emit_prob = calloc(pt->npolygons ? pt->npolygons : 1, sizeof *pt->emit_prob);
    if (pt->polygons == NULL || pt->emitters == NULL || pt->slabs == NULL || pt->geo == NULL || pt->emit_prob == NULL) {
        snprintf(why, size, "out of memory");
        bench_pt_destroy(pt);
        return NULL;
    }
    for (size_t k = 0; k < pt->npolygons; k++) {
        rl_polygon_desc *p = &pt->polygons[k];
        rl_scene_polygon_describe(scene, k, p);
        double e[3] = {p->emission[0], p->emission[1], p->emission[2]};
        double power = p->area * luminance(e);
        if (p->count > PT_MAX_VERTS || !(power > 0.0))
            continue;
        pt->total_power += power;
        pt->emitters[pt->nemitters++] = (pt_emitter){(uint32_t)k, pt->total_power, power};
    }
    for (size_t k = 0; k < pt->nemitters; k++) {
        pt->emitters[k].cdf /= pt->total_power;
        pt->emit_prob[pt->emitters[k].polygon] = pt->emitters[k].power / pt->total_power;
    }
    for (size_t k = 0; k < pt->nslabs; k++) {
        rl_lightfield_desc *d = &pt->slabs[k];
        rl_scene_lightfield_describe(scene, k, d);
        cross3(d->u, d->v, pt->geo[k].normal);
        pt->geo[k].area = sqrt(dot3(pt->geo[k].normal, pt->geo[k].normal));
        for (int c = 0; c < 3; c++)
            pt->geo[k].normal[c] /= pt->geo[k].area;
    }
    if (rl_raycaster_new(scene, &pt->rc) != RL_OK) {
        snprintf(why, size, "%s", rl_errmsg());
        bench_pt_destroy(pt);
        return NULL;
    }
    return pt;
}

void bench_pt_destroy(bench_pt *pt)
{
    if (pt == NULL)
        return;
    rl_raycaster_destroy(pt->rc);
    free(pt->polygons);
    free(pt->emitters);
    free(pt->slabs);
    free(pt->geo);
    free(pt->emit_prob);
    free(pt);
}

/* ------------------------------------------------------------ direct light */

/* @return the solid-angle density with which light sampling draws a point r^2 away, seen at cosine cos_e
 * off the normal of an emitter of the given area chosen with probability prob. */
static double light_pdf(double prob, double area, double r2, double cos_e)
{
    return prob * r2 / (area * cos_e);
}

/* Adds to e L cos_x / (p_light + cos_x / pi): one sample of either strategy, weighted by the balance heuristic. */
static void add_mis(double e[3], const double L[3], double cos_x, double p_light)
{
    double g = cos_x / (p_light + cos_x / ILF_PI);
    for (int k = 0; k < 3; k++)
        e[k] += g * L[k];
}

/* @return 1 when nothing lies between x and the point r away along unit w. */
static int visible(const bench_pt *pt, const double x[3], const double w[3], double r)
{
    rl_ray_hit h;
    return !rl_raycaster_hit(pt->rc, x, w, PT_EPS, r - PT_EPS, &h);
}

/* Writes into L the radiance of slab k at (a, b) that travels along -w (w points from the receiver to it). */
static void slab_radiance(const bench_pt *pt, size_t k, double a, double b, const double w[3], double L[3])
{
    const double(*R)[3] = pt->slabs[k].rot;
    double d[3] = {-(R[0][0] * w[0] + R[1][0] * w[1] + R[2][0] * w[2]),
                   -(R[0][1] * w[0] + R[1][1] * w[1] + R[2][1] * w[2]),
                   -(R[0][2] * w[0] + R[1][2] * w[1] + R[2][2] * w[2])};
    float rgb[3] = {0, 0, 0};
    if (lfio_slab_radiance_interp(pt->slabs[k].slab, a, b, d, rgb) != LFIO_OK)
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
    for (int c = 0; c < 3; c++)
        L[c] = rgb[c];
}

/* Light sampling of emitting polygon em (chosen with probability prob): a point drawn uniformly on it. */
static void light_polygon(const bench_pt *pt, const pt_emitter *em, double prob, const double x[3],
                          const double n[3], uint64_t *rng, double e[3])
{
    const rl_polygon_desc *p = &pt->polygons[em->polygon];
    double y[3], w[3];
    polygon_point(p, rng, y);
    for (int k = 0; k < 3; k++)
        w[k] = y[k] - x[k];
    double r2 = dot3(w, w), r = sqrt(r2);
    if (!(r > 2.0 * PT_EPS))
        return;
    for (int k = 0; k < 3; k++)
        w[k] /= r;
    double cos_x = dot3(w, n), cos_y = -dot3(w, p->normal);
    if (cos_x <= 0.0 || cos_y <= 0.0 || !visible(pt, x, w, r))
        return;
    double L[3] = {p->emission[0], p->emission[1], p->emission[2]};
    add_mis(e, L, cos_x, light_pdf(prob, p->area, r2, cos_y));
}

/* Light sampling of slab k: a point drawn uniformly on its rectangle. */
static void light_slab(const bench_pt *pt, size_t k, const double x[3], const double n[3], uint64_t *rng, double e[3])
{
    const pt_slab *s = &pt->geo[k];
    const rl_lightfield_desc *d = &pt->slabs[k];
    double a = rnd(rng), b = rnd(rng), w[3];
    for (int c = 0; c < 3; c++)
        w[c] = d->origin[c] + a * d->u[c] + b * d->v[c] - x[c];
    double r2 = dot3(w, w), r = sqrt(r2);
    if (!(r > 2.0 * PT_EPS))
        return;
    for (int c = 0; c < 3; c++)
        w[c] /= r;
    /* light travels along -w, from the slab toward x: it leaves the slab's front */
    double cos_x = dot3(w, n), cos_s = -dot3(w, s->normal);
    if (cos_x <= 0.0 || cos_s <= 0.0 || !visible(pt, x, w, r))
        return;
    double L[3];
    slab_radiance(pt, k, a, b, w, L);
    add_mis(e, L, cos_x, light_pdf(1.0, s->area, r2, cos_s));
}

/* Where the ray x + t w (t in (0, tmax)) crosses slab k from its front. @return 1 with *t, *a, *b. */
static int slab_crossing(const bench_pt *pt, size_t k, const double x[3], const double w[3], double tmax, double *t,
                         double *a, double *b)
{
    const pt_slab *s = &pt->geo[k];
    const rl_lightfield_desc *d = &pt->slabs[k];
    double wn = dot3(w, s->normal);
    if (wn >= 0.0) /* the ray must meet the front: light leaving it travels back along -w */
        return 0;
    double o[3] = {d->origin[0] - x[0], d->origin[1] - x[1], d->origin[2] - x[2]};
    *t = dot3(o, s->normal) / wn;
    if (!(*t > PT_EPS && *t < tmax))
        return 0;
    double q[3] = {x[0] + *t * w[0] - d->origin[0], x[1] + *t * w[1] - d->origin[1], x[2] + *t * w[2] - d->origin[2]};
    *a = dot3(q, d->u) / dot3(d->u, d->u);
    *b = dot3(q, d->v) / dot3(d->v, d->v);
    return *a >= 0.0 && *a <= 1.0 && *b >= 0.0 && *b <= 1.0;
}

/* BRDF (cosine) sampling of every emitter at once: one cosine-weighted ray, the slabs it crosses before its
 * first hit and the emitting front it meets. */
static void hemisphere_emitters(const bench_pt *pt, const double x[3], const double n[3], uint64_t *rng, double e[3])
{
    double w[3];
    cosine_direction(n, rng, w);
    double cos_x = dot3(w, n);
    if (cos_x <= 0.0)
        return;
    rl_ray_hit h;
    int hit = rl_raycaster_hit(pt->rc, x, w, PT_EPS, INFINITY, &h);
    for (size_t k = 0; k < pt->nslabs; k++) {
        double t, a, b, L[3];
        if (!slab_crossing(pt, k, x, w, hit ? h.distance : INFINITY, &t, &a, &b))
            continue;
        slab_radiance(pt, k, a, b, w, L);
        add_mis(e, L, cos_x, light_pdf(1.0, pt->geo[k].area, t * t, -dot3(w, pt->geo[k].normal)));
    }
    if (!hit || !h.front)
        return;
    const rl_polygon_desc *p = &pt->polygons[h.polygon];
    if (!(p->emission[0] > 0.0f || p->emission[1] > 0.0f || p->emission[2] > 0.0f))
        return;
    double L[3] = {p->emission[0], p->emission[1], p->emission[2]};
    double prob = pt->emit_prob[h.polygon];
    add_mis(e, L, cos_x,
            prob > 0.0 ? light_pdf(prob, p->area, h.distance * h.distance, -dot3(w, p->normal)) : 0.0);
}

/* Writes into e the estimate of direct irradiance at x (normal n): light sampling of every slab and of one
 * emitting polygon, and one cosine-weighted ray, combined by multiple importance sampling. */
static void direct(const bench_pt *pt, const double x[3], const double n[3], uint64_t *rng, double e[3])
{
    e[0] = e[1] = e[2] = 0.0;
    for (size_t k = 0; k < pt->nslabs; k++)
        light_slab(pt, k, x, n, rng, e);
    if (pt->nemitters > 0) {
        double u = rnd(rng);
        size_t lo = 0, hi = pt->nemitters - 1;
        while (lo < hi) { /* the first emitter whose cdf exceeds u */
            size_t mid = (lo + hi) / 2;
            if (pt->emitters[mid].cdf > u)
                hi = mid;
            else
                lo = mid + 1;
        }
        const pt_emitter *em = &pt->emitters[lo];
        light_polygon(pt, em, pt->emit_prob[em->polygon], x, n, rng, e);
    }
    hemisphere_emitters(pt, x, n, rng, e);
}

/* ------------------------------------------------------------ paths */

/* Writes into e one path's estimate of the irradiance at x0 (normal n0). */
static void path(const bench_pt *pt, const double x0[3], const double n0[3], uint32_t bounces, uint64_t *rng,
                 double e[3])
{
    double x[3], n[3], thr[3] = {1.0, 1.0, 1.0};
    memcpy(x, x0, sizeof x);
    memcpy(n, n0, sizeof n);
    e[0] = e[1] = e[2] = 0.0;
    for (uint32_t depth = 0;; depth++) {
        double d[3];
        direct(pt, x, n, rng, d);
        for (int k = 0; k < 3; k++)
            e[k] += thr[k] * d[k];
        if (depth == bounces)
            return;
        double w[3];
        cosine_direction(n, rng, w);
        rl_ray_hit h;
        if (!rl_raycaster_hit(pt->rc, x, w, PT_EPS, INFINITY, &h) || !h.front)
            return;
        const rl_polygon_desc *p = &pt->polygons[h.polygon];
        for (int k = 0; k < 3; k++) {
            n[k] = p->normal[k];
            x[k] += h.distance * w[k] + PT_EPS * n[k];
            thr[k] *= p->albedo[k];
        }
        if (thr[0] <= 0.0 && thr[1] <= 0.0 && thr[2] <= 0.0)
            return;
    }
}

/* Accumulates path estimates: sums of rgb, of Y and of Y^2. */
typedef struct pt_sums {
    double rgb[3], y, y2;
    uint32_t n;
} pt_sums;

static void sums_add(pt_sums *s, const double e[3])
{
    double y = luminance(e);
    for (int k = 0; k < 3; k++)
        s->rgb[k] += e[k];
    s->y += y;
    s->y2 += y * y;
    s->n++;
}

static void sums_finish(const pt_sums *s, bench_pt_estimate *out)
{
    double n = s->n > 0 ? (double)s->n : 1.0;
    for (int k = 0; k < 3; k++)
        out->rgb[k] = s->rgb[k] / n;
    out->y = s->y / n;
    double var = s->n > 1 ? (s->y2 - s->y * s->y / n) / (n - 1.0) : 0.0;
    out->y_se = sqrt(fmax(0.0, var) / n);
}

/* Moves x off its surface along n, so that no ray from it meets that surface again. */
static void lift(const double x[3], const double n[3], double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = x[k] + PT_EPS * n[k];
}

void bench_pt_point(const bench_pt *pt, const double x[3], const double n[3], uint32_t bounces, uint32_t paths,
                    uint64_t seed, bench_pt_estimate *out)
{
    uint64_t rng = seed;
    double x1[3];
    lift(x, n, x1);
    pt_sums s = {{0, 0, 0}, 0, 0, 0};
    for (uint32_t k = 0; k < paths; k++) {
        double e[3];
        path(pt, x1, n, bounces, &rng, e);
        sums_add(&s, e);
    }
    sums_finish(&s, out);
}

/* @return 1 when x (in polygon p's plane) lies inside convex polygon p. */
static int inside(const double *verts, uint32_t count, const double normal[3], const double x[3])
{
    for (uint32_t k = 0; k < count; k++) {
        const double *a = verts + 3 * k, *b = verts + 3 * ((k + 1) % count);
        double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, q[3] = {x[0] - a[0], x[1] - a[1], x[2] - a[2]}, c[3];
        cross3(e, q, c);
        if (dot3(c, normal) < 0.0)
            return 0;
    }
    return 1;
}

/* Draws a point of cell (i, j) of map m clipped to its polygon into x; the centre when PT_CELL_TRIES draws miss. */
static void cell_point(const rl_map_info *m, uint32_t i, uint32_t j, const double centre[3], uint64_t *rng, double x[3])
{
    for (int t = 0; t < PT_CELL_TRIES; t++) {
        double a = m->u0 + (i + rnd(rng)) * m->cell_size, b = m->v0 + (j + rnd(rng)) * m->cell_size;
        for (int k = 0; k < 3; k++)
            x[k] = m->origin[k] + a * m->e1[k] + b * m->e2[k];
        if (inside(m->vertices, m->nvertices, m->normal, x))
            return;
    }
    memcpy(x, centre, 3 * sizeof *x);
}

void bench_pt_cell(const bench_pt *pt, const rl_map_info *info, uint32_t i, uint32_t j, const double centre[3],
                   uint32_t bounces, uint32_t paths, uint64_t seed, bench_pt_estimate *out)
{
    uint64_t rng = seed;
    pt_sums s = {{0, 0, 0}, 0, 0, 0};
    for (uint32_t k = 0; k < paths; k++) {
        double x[3], x1[3], e[3];
        cell_point(info, i, j, centre, &rng, x);
        lift(x, info->normal, x1);
        path(pt, x1, info->normal, bounces, &rng, e);
        sums_add(&s, e);
    }
    sums_finish(&s, out);
}
