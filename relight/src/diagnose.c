/*
 * diagnose.c - findings about a scene or a solution that is legal but almost
 * surely not what its author meant (rl_scene_diagnose, rl_solution_diagnose):
 * no emitter, no receiver facing an emitter (or one emitter facing no
 * receiver), a light field whose coverage is below 100%, no camera, most
 * cells dark, a camera looking at back faces.
 *
 * Invariants: only reads the scene and the solution; each finding carries the
 * quantity it measured and a line naming it; findings come in the order of
 * rl_diagnostic_kind and are counted even past the caller's room.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>

#include "engine_internal.h"
#include "ilf/vec.h"

/* More than this share of dark cells, or of back faces among the camera's hits, is "most": a room lit
 * through one window may leave a good part dark, but not most of it, and a camera inside a room sees no
 * back face at all. */
#define MOSTLY 0.5
/* The grid of camera rays the back-face check casts: enough to measure a share to a few per cent, few
 * enough (3,072 rays) to cost nothing beside a run. */
#define FACES_NX 64u
#define FACES_NY 48u

/* Where findings go: out[0 .. max), counting all of them in n. */
typedef struct findings {
    rl_diagnostic *out;
    size_t max, n;
} findings;

/* Adds a finding of kind with quantity q and a formatted line. */
static void add(findings *f, rl_diagnostic_kind kind, double q, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static void add(findings *f, rl_diagnostic_kind kind, double q, const char *fmt, ...)
{
    if (f->n < f->max) {
        rl_diagnostic *d = &f->out[f->n];
        d->kind = kind;
        d->quantity = q;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(d->text, sizeof d->text, fmt, ap);
        va_end(ap);
    }
    f->n++;
}

static int positive(const float v[3])
{
    return v[0] > 0 || v[1] > 0 || v[2] > 0;
}

/* A flat emitter or receiver: a plane (point, unit normal of the side it emits to or receives from) and
 * the corners of its convex outline (a polygon's own vertices, or a slab's corners kept in own). */
typedef struct face {
    v3 point, normal;
    const double (*corners)[3];
    uint32_t count;
    double own[4][3];
} face;

static void polygon_face(const rl_scene *s, size_t k, face *f)
{
    const rl_polygon *p = &s->polygons[k];
    f->point = v3_load(s->vertices[p->first]);
    f->normal = v3_load(p->normal);
    f->corners = (const double(*)[3])s->vertices + p->first;
    f->count = p->count;
}

/* A light field slab emits towards its front, e3 = u x v. */
static void slab_face(const rl_lightfield *lf, face *f)
{
    v3 o = v3_load(lf->origin), u = v3_load(lf->u), v = v3_load(lf->v);
    const v3 c[4] = {o, v3_add(o, u), v3_add(v3_add(o, u), v), v3_add(o, v)};
    for (int k = 0; k < 4; k++)
        f->own[k][0] = c[k].x, f->own[k][1] = c[k].y, f->own[k][2] = c[k].z;
    f->point = o;
    f->normal = v3_norm(v3_cross(u, v));
    f->corners = (const double(*)[3])f->own;
    f->count = 4;
}

/* @return whether some corner of b lies in front of a's plane, by more than eps. */
static int in_front(const face *a, const face *b, double eps)
{
    for (uint32_t i = 0; i < b->count; i++)
        if (v3_dot(v3_sub(v3_load(b->corners[i]), a->point), a->normal) > eps)
            return 1;
    return 0;
}

/* @return whether receiver r and emitter e face each other: part of each in front of the other. */
static int facing(const face *r, const face *e, double eps)
{
    return in_front(e, r, eps) && in_front(r, e, eps);
}

/* @return a length below which a corner counts as on a plane: a millionth of the scene's extent. */
static double scene_eps(const rl_scene *s)
{
    double m = 0.0;
    for (size_t k = 0; k < s->nvertices; k++)
        for (int c = 0; c < 3; c++)
            m = fmax(m, fabs(s->vertices[k][c]));
    return 1e-6 * (m > 0 ? m : 1.0);
}

/* @return whether emitter e faces any receiver of the scene but polygon `self` (SIZE_MAX: none). */
static int reaches_a_receiver(const rl_scene *s, const face *e, size_t self, double eps)
{
    for (size_t k = 0; k < s->npolygons; k++) {
        if (k == self || !positive(s->materials[s->polygons[k].material].albedo))
            continue;
        face r;
        polygon_face(s, k, &r);
        if (facing(&r, e, eps))
            return 1;
    }
    return 0;
}

/* Checks that there are emitters and that they face receivers: none that does is one finding (the whole
 * scene is dark); otherwise each emitter that faces none is one (a lamp turned the wrong way). */
static void check_emitters(const rl_scene *s, findings *f)
{
    size_t emitters = s->nlightfields, receivers = 0, facing_none = 0;
    for (size_t k = 0; k < s->npolygons; k++) {
        emitters += positive(s->materials[s->polygons[k].material].emission);
        receivers += positive(s->materials[s->polygons[k].material].albedo);
    }
    if (emitters == 0) {
        add(f, RL_DIAG_NO_EMITTER, 0.0,
            "%s: no emitter (no material with emission > 0 and no light field): every result is black", s->path);
        return;
    }
    if (receivers == 0)
        return; /* nothing to light: a scene of lamps alone is odd, but its view is right */
    double eps = scene_eps(s);
    /* the labels of the first emitters that face nothing, reported once it is known that some do face */
    enum { KEEP = 4 };
    const char *none[KEEP];
    for (size_t k = 0; k < s->npolygons; k++) {
        if (!positive(s->materials[s->polygons[k].material].emission))
            continue;
        face e;
        polygon_face(s, k, &e);
        if (!reaches_a_receiver(s, &e, k, eps) && facing_none++ < KEEP)
            none[facing_none - 1] = s->polygons[k].label;
    }
    for (size_t k = 0; k < s->nlightfields; k++) {
        face e;
        slab_face(&s->lightfields[k], &e);
        if (!reaches_a_receiver(s, &e, SIZE_MAX, eps) && facing_none++ < KEEP)
            none[facing_none - 1] = s->lightfields[k].label;
    }
    if (facing_none == emitters) {
        add(f, RL_DIAG_NOT_FACING, 1.0,
            "%s: none of the %zu receiving polygons faces any of the %zu emitter%s from its front: no direct light "
            "arrives (normals pointing out of the room, or reversed walls or lamps?)",
            s->path, receivers, emitters, emitters == 1 ? "" : "s");
        return;
    }
    for (size_t k = 0; k < facing_none && k < KEEP; k++)
        add(f, RL_DIAG_EMITTER_UNSEEN, (double)facing_none / (double)emitters,
            "%s: emitter %s faces no receiving polygon from its front, so its light reaches nothing (placed "
            "without its flip, or its normal reversed?)%s",
            s->path, none[k], k + 1 == KEEP && facing_none > KEEP ? "; and more such emitters" : "");
}

/* Reports every light field placement whose slab has coverage below 100%. */
static void check_coverage(const rl_scene *s, findings *f)
{
    for (size_t k = 0; k < s->nlightfields; k++) {
        const rl_lightfield *lf = &s->lightfields[k];
        const uint8_t *cov = NULL;
        for (size_t j = 0; j < lfio_lightfield_slab_count(lf->lf) && !cov; j++)
            if (lfio_lightfield_slab(lf->lf, j) == lf->slab)
                cov = lfio_lightfield_coverage(lf->lf, j);
        if (!cov)
            continue;
        const lfio_slab_desc *d = lfio_slab_get_desc(lf->slab);
        double missing = 1.0 - lfio_coverage_share(d, cov, NULL);
        if (missing > 0)
            add(f, RL_DIAG_COVERAGE, missing,
                "%s: %s (%s, slab '%s'): coverage %.2f%%: %.2f%% of its etendue was not captured and emits nothing",
                s->path, lf->label, lf->file, d->name, 100.0 * (1.0 - missing), 100.0 * missing);
    }
}

size_t rl_scene_diagnose(const rl_scene *scene, rl_diagnostic *out, size_t max)
{
    findings f = {out, out ? max : 0, 0};
    if (!scene)
        return 0;
    check_emitters(scene, &f);
    check_coverage(scene, &f);
    if (!scene->has_camera)
        add(&f, RL_DIAG_NO_CAMERA, 0.0, "%s: the scene has no camera, so there is no view (no view.exr or view.png)", scene->path);
    return f.n;
}

size_t rl_solution_diagnose(const rl_solution *s, rl_diagnostic *out, size_t max)
{
    findings f = {out, out ? max : 0, 0};
    if (!s)
        return 0;
    uint64_t cells = 0, dark = 0;
    for (size_t m = 0; m < s->nmaps; m++)
        for (uint32_t c = 0; c < s->maps[m].ncells; c++) {
            const double *e = s->maps[m].e_total[c];
            cells++;
            dark += !(e[0] > 0 || e[1] > 0 || e[2] > 0);
        }
    if (cells > 0 && (double)dark > MOSTLY * (double)cells)
        add(&f, RL_DIAG_DARK_CELLS, (double)dark / (double)cells,
            "%s: %.1f%% of the cells (%llu of %llu) received no light", s->scene->path,
            100.0 * (double)dark / (double)cells, (unsigned long long)dark, (unsigned long long)cells);
    if (s->scene->has_camera) {
        uint64_t hits = 0, back = 0;
        rl__view_faces(s, FACES_NX, FACES_NY, &hits, &back);
        if (hits > 0 && (double)back > MOSTLY * (double)hits)
            add(&f, RL_DIAG_BACK_FACES, (double)back / (double)hits,
                "%s: the camera sees mostly back faces, drawn black: %.1f%% of the surface it sees faces away "
                "(a room whose normals point outwards?)",
                s->scene->path, 100.0 * (double)back / (double)hits);
    }
    return f.n;
}
