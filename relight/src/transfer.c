/*
 * transfer.c - culled solid-angle transfer and the three baselines.
 *
 * For one receiver tile R and one emitter S, `culled` walks the partition's
 * quad-tree in S's frame (pole = S's normal, so the hemisphere S emits into
 * is exactly ids 0 .. 4m^2-1) from level 1 down to the pair's level m. A
 * node is culled when its cone, clipped to directions arriving at R's
 * front, is empty; when the projected Minkowski sum (S + w)_R misses the
 * tile; or when a light field's zero-radiance mask rules out radiance in it
 * and in its three neighbours (whose values the interpolation reads). The
 * kept leaves are sorted by id and each is rasterised over the tile's cells;
 * every (cell, leaf) pair traces k rays whose origins and directions come
 * from a low-discrepancy sequence keyed by (seed, pass, emitter, receiver,
 * cell, level, leaf).
 *
 * `naive` takes every leaf and every cell and otherwise runs the same code:
 * a culled (cell, leaf) pair contributes exactly zero, and each cell adds
 * its leaves in id order either way, so the two are bit-identical as long
 * as no pair descends below partition_n (see pair_level()).
 *
 * A pair whose emitter subtends less than a leaf from the tile descends to
 * finer levels (pair_level()) and, under `culled`, draws origins from the
 * part of each cell inside the region, weighted by that part's area: that
 * is what makes small and distant emitters sampled rather than left to
 * luck. `naive` enumerates every leaf of the pair's level, so it is only
 * practical where pairs do not descend.
 */
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <lfio/partition.h>

#include "sampling.h"
#include "transfer.h"

#define PI 3.14159265358979323846
#define STACK_DEPTH 512

/* ----------------------------------------------------------------- emitters */

/* Fills the 2D polygon, its edge half-planes and area of e from its world vertices and frame. */
static void emitter_finish(rl_emitter *e)
{
    for (uint32_t i = 0; i < e->nverts; i++)
        e->poly2[i] = frame_project(&e->frame, e->verts[i]);
    for (uint32_t i = 0, j = e->nverts - 1; i < e->nverts; j = i++)
        e->edge[i] = edge_halfplane(e->poly2[j], e->poly2[i]);
    e->area = rl__polygon_area2(e->poly2, e->nverts);
}

void rl__emitter_from_polygon(const rl_scene *scene, uint32_t k, const rl_map *map, rl_emitter *e)
{
    const rl_polygon *pg = &scene->polygons[k];
    memset(e, 0, sizeof *e);
    e->kind = map ? EM_MAP : EM_CONST;
    e->polygon = (int32_t)k;
    e->map = map;
    e->nverts = pg->count;
    for (uint32_t i = 0; i < pg->count; i++)
        e->verts[i] = v3_load(scene->vertices[pg->first + i]);
    if (map) {
        e->frame = map->frame; /* so that frame coordinates index the map's cells */
    } else {
        e->frame.origin = e->verts[0];
        e->frame.n = v3_load(pg->normal);
        e->frame.e1 = v3_norm(v3_sub(e->verts[1], e->verts[0]));
        e->frame.e2 = v3_cross(e->frame.n, e->frame.e1);
    }
    memcpy(e->emission, scene->materials[pg->material].emission, sizeof e->emission);
    emitter_finish(e);
}

void rl__emitter_from_lightfield(const rl_lightfield *lf, rl_emitter *e)
{
    memset(e, 0, sizeof *e);
    e->kind = EM_SLAB;
    e->polygon = -1;
    e->lf = lf;
    v3 o = v3_load(lf->origin), u = v3_load(lf->u), v = v3_load(lf->v);
    e->len_u = v3_len(u);
    e->len_v = v3_len(v);
    e->frame.origin = o;
    e->frame.e1 = v3_scale(u, 1.0 / e->len_u);
    e->frame.e2 = v3_scale(v, 1.0 / e->len_v);
    e->frame.n = v3_cross(e->frame.e1, e->frame.e2);
    e->nverts = 4;
    e->verts[0] = o;
    e->verts[1] = v3_add(o, u);
    e->verts[2] = v3_add(v3_add(o, u), v);
    e->verts[3] = v3_add(o, v);
    emitter_finish(e);
}

/* @return 1 if frame point q lies in e's convex polygon. */
static int emitter_contains(const rl_emitter *e, v2 q)
{
    int inside = 1;
    for (uint32_t i = 0; i < e->nverts; i++) /* no early exit: one branch per sample, not one per edge */
        inside &= e->edge[i].a * q.x + e->edge[i].b * q.y + e->edge[i].c >= 0;
    return inside;
}

/* ------------------------------------------------------------------ leaves */

/* Leaves from this level on are sampled on their planar lattice triangle and
 * weighted by the Jacobian to the sphere, which varies by less than 1.5x
 * within one of them: far cheaper than Arvo's warp (no trigonometry) for
 * a negligible rise in variance. Coarser leaves (an octant's Jacobian
 * spans 5.2x) keep the uniform warp. */
#define PLANAR_MIN_LEVEL 4

/* A solid angle of emitter e's partition prepared for sampling: its
 * directions and their weights, its sample key, and for a light field the
 * slab-level interpolation its samples read. */
typedef struct leaf {
    uint32_t lv;
    uint64_t id;
    double omega;         /* exact solid angle, sr */
    uint64_t key;         /* hash of (seed, pass, emitter, receiver, level, id) */
    int planar;
    sph_tri tri;          /* !planar: Arvo's warp; every sample weighs omega */
    v3 p[3];              /* planar: the lattice triangle's corners (|x|+|y|+|z| = 1 in e's frame), world */
    lfio_part_strata st;  /* planar: the triangle's one stratum (lfio_part_strata_sample weighs each direction) */
    int reach;            /* every corner direction leaves the emitter's front (p[k] . n > 0) */
    v2 land[3];           /* then: corner k from origin x lands at project(x) - h(x) * land[k] on the emitter */
    int mix;              /* planar, light field, at or below the slab's level: lfio_slab_radiance_mix() */
    double to_slab[3][3]; /* mix: the slab-level triangle's barycentrics from the leaf's */
    uint64_t ids[4];      /* mix: the slab-level solid angle holding the leaf, then its neighbours */
} leaf;

/* Gives the barycentric coordinates of p in the triangle a (coplanar points). */
static void barycentric(const double a[3][3], const double p[3], double lam[3])
{
    v3 a0 = v3_load(a[0]), a1 = v3_load(a[1]), a2 = v3_load(a[2]), x = v3_load(p);
    v3 nrm = v3_cross(v3_sub(a1, a0), v3_sub(a2, a0));
    double nn = v3_dot(nrm, nrm);
    lam[0] = v3_dot(v3_cross(v3_sub(a1, x), v3_sub(a2, x)), nrm) / nn;
    lam[1] = v3_dot(v3_cross(v3_sub(a2, x), v3_sub(a0, x)), nrm) / nn;
    lam[2] = 1.0 - lam[0] - lam[1];
}

/* Gives the corners of solid angle id at level lv scaled onto |x|+|y|+|z| = 1. */
static void lattice_triangle(uint32_t lv, uint64_t id, double v[3][3])
{
    lfio_part_face_vertices(lv, id, v);
}

/* Prepares solid angle id at level lv of emitter e for the receiver map map_index, emitter ei. */
static void leaf_make(const rl_transfer_ctx *ctx, const rl_emitter *e, uint32_t ei, uint32_t map_index, uint32_t lv,
                      uint64_t id, leaf *L)
{
    double v[3][3];
    lattice_triangle(lv, id, v);
    L->lv = lv;
    L->id = id;
    L->omega = lfio_part_solid_angle(lv, id);
    L->key = hash_mix(hash_mix(hash_mix(hash_mix(hash_mix(ctx->sampling->seed, ctx->pass), ei), map_index), lv), id);
    for (int k = 0; k < 3; k++)
        L->p[k] = frame_vector(&e->frame, v[k]);
    /* in e's frame a corner is v[k] itself: it reaches the front when v[k].z > 0 */
    L->reach = v[0][2] > 0 && v[1][2] > 0 && v[2][2] > 0;
    for (int k = 0; k < 3 && L->reach; k++)
        L->land[k] = (v2){v[k][0] / v[k][2], v[k][1] / v[k][2]};
    L->planar = lv >= PLANAR_MIN_LEVEL;
    L->mix = 0;
    if (!L->planar) {
        L->tri = rl__sph_tri_make(v3_norm(L->p[0]), v3_norm(L->p[1]), v3_norm(L->p[2]), L->omega);
        return;
    }
    double pw[3][3];
    for (int k = 0; k < 3; k++)
        v3_store(L->p[k], pw[k]);
    lfio_part_strata_init(&L->st, (const double(*)[3])pw, 1);
    if (e->kind != EM_SLAB)
        return;
    /* the slab-level ancestor; levels that are not a power-of-two multiple of
     * the slab's n do not nest in it and take the general path */
    uint32_t n = lfio_slab_get_desc(e->lf->slab)->n, al = lv;
    uint64_t anc = id;
    while (al > n && al % 2 == 0 && lfio_part_parent(al, anc, &anc))
        al /= 2;
    if (al != n)
        return;
    double a[3][3], lam[3];
    lattice_triangle(n, anc, a);
    for (int k = 0; k < 3; k++) {
        barycentric(a, v[k], lam);
        for (int r = 0; r < 3; r++)
            L->to_slab[r][k] = lam[r];
    }
    L->ids[0] = anc;
    lfio_part_neighbours(n, anc, L->ids + 1);
    L->mix = 1;
}

/* @return a direction in leaf L from u1, u2 in [0, 1); *w its weight (the
 * inverse of its density, so that the mean of w is the solid angle) and,
 * for planar leaves, lam its barycentric coordinates on the triangle. */
static v3 leaf_sample(const leaf *L, double u1, double u2, double *w, double lam[3])
{
    if (!L->planar) {
        *w = L->omega;
        return rl__sph_tri_sample(&L->tri, u1, u2);
    }
    double su = sqrt(u1), l[3] = {1.0 - su, su * (1.0 - u2), su * u2}, d[3];
    lfio_part_strata_sample(&L->st, 0, l, d, w, lam);
    return v3_load(d);
}

/* For a mixing leaf of light field e: the rectangle of the slab outside which every
 * sample of L reads zero radiance, as 4 world corners (e's vertex order).
 * @return 1, 0 when L cannot say (use the whole emitter), -1 when L reads only zeros. */
static int leaf_support(const rl_emitter *e, const leaf *L, v3 out[4])
{
    if (!L->mix)
        return 0;
    const lfio_slab *slab = e->lf->slab;
    const lfio_slab_desc *d = lfio_slab_get_desc(slab);
    uint64_t ndir = lfio_slab_dir_count(slab);
    uint32_t b[4] = {UINT32_MAX, 0, UINT32_MAX, 0};
    for (int k = 0; k < 4; k++) {
        const uint32_t *s = e->lf->support[L->ids[k] < ndir ? L->ids[k] : L->ids[0]];
        if (s[0] > s[1])
            continue;
        b[0] = s[0] < b[0] ? s[0] : b[0];
        b[1] = s[1] > b[1] ? s[1] : b[1];
        b[2] = s[2] < b[2] ? s[2] : b[2];
        b[3] = s[3] > b[3] ? s[3] : b[3];
    }
    if (b[0] == UINT32_MAX)
        return -1;
    /* bilinear interpolation between position centres reaches half a
     * position past the last nonzero centre, and the border clamps */
    double s0 = b[0] == 0 ? 0.0 : (b[0] - 0.5) / d->nu, s1 = b[1] + 1 >= d->nu ? 1.0 : (b[1] + 1.5) / d->nu;
    double t0 = b[2] == 0 ? 0.0 : (b[2] - 0.5) / d->nv, t1 = b[3] + 1 >= d->nv ? 1.0 : (b[3] + 1.5) / d->nv;
    s0 *= e->len_u, s1 *= e->len_u, t0 *= e->len_v, t1 *= e->len_v;
    out[0] = frame_point(&e->frame, (v2){s0, t0});
    out[1] = frame_point(&e->frame, (v2){s1, t0});
    out[2] = frame_point(&e->frame, (v2){s1, t1});
    out[3] = frame_point(&e->frame, (v2){s0, t1});
    return 1;
}

/* Radiance leaving e at y (frame point q) in propagation direction d; L
 * and lam, when L mixes, give the direction's slab interpolation directly. */
static void emitter_radiance(const rl_emitter *e, v2 q, v3 d, const leaf *L, const double lam[3], double out[3])
{
    switch (e->kind) {
    case EM_CONST:
        for (int c = 0; c < 3; c++)
            out[c] = e->emission[c];
        return;
    case EM_MAP: {
        int64_t cell = rl__map_cell_at(e->map, q);
        for (int c = 0; c < 3; c++)
            out[c] = cell < 0 ? 0.0 : e->map->albedo[c] * e->map->e_prev[cell][c] / PI;
        return;
    }
    case EM_SLAB: {
        float rgb[3] = {0, 0, 0};
        if (L && L->mix) {
            double ls[3], w[4];
            for (int r = 0; r < 3; r++)
                ls[r] = L->to_slab[r][0] * lam[0] + L->to_slab[r][1] * lam[1] + L->to_slab[r][2] * lam[2];
            lfio_part_interp_weights(ls, w);
            lfio_slab_radiance_mix(e->lf->slab, q.x / e->len_u, q.y / e->len_v, L->ids, w, rgb);
            for (int c = 0; c < 3; c++)
                out[c] = rgb[c];
            return;
        }
        /* back to the slab's own frame: the transform's rotation, transposed */
        const double (*r)[3] = e->lf->rot;
        double ds[3] = {r[0][0] * d.x + r[1][0] * d.y + r[2][0] * d.z, r[0][1] * d.x + r[1][1] * d.y + r[2][1] * d.z,
                        r[0][2] * d.x + r[1][2] * d.y + r[2][2] * d.z};
        lfio_slab_radiance_interp(e->lf->slab, q.x / e->len_u, q.y / e->len_v, ds, rgb);
        for (int c = 0; c < 3; c++)
            out[c] = rgb[c];
        return;
    }
    }
}

void rl__emitter_radiance_at(const rl_emitter *e, v2 q, v3 d, double out[3])
{
    emitter_radiance(e, q, d, NULL, NULL, out);
}

int rl__emitter_node_dark(const rl_emitter *e, uint32_t lv, uint64_t id)
{
    const lfio_slab *s = e->lf->slab;
    uint32_t n = lfio_slab_get_desc(s)->n;
    while (lv > n) { /* finer than the slab: its ancestor at the slab's level */
        if (lv % 2 || !lfio_part_parent(lv, id, &id))
            return 0;
        lv /= 2;
    }
    if (lfio_slab_mask_test(s, lv, id))
        return 0;
    uint64_t nb[3];
    if (!lfio_part_neighbours(lv, id, nb))
        return 0;
    for (int k = 0; k < 3; k++)
        if (nb[k] < lfio_part_hemi_count(lv) && lfio_slab_mask_test(s, lv, nb[k]))
            return 0;
    return 1;
}

/* ------------------------------------------------------------------ one ray */

/* What one (emitter, receiver tile) pair needs, computed once. */
typedef struct pair {
    const rl_emitter *e;
    v3 sclip[RL_MAX_POLY_VERTS + 2]; /* the emitter clipped to the tile's front half-space */
    size_t ns;
    uint32_t level;
    int descended;
    double eps; /* ray offset at both ends, m (pair_eps()) */
} pair;

/* @return the distance that single precision cannot resolve on segments
 * between the pair's tile and emitter: eight ulps of the largest recentred
 * coordinate among their corners, and at least the scene's own. Once per
 * pair rather than per ray: a bound over the corners bounds every point. */
static double pair_eps(const rl_transfer_ctx *ctx, const pair *p, const rl_map *m, const v2 *poly, size_t npoly)
{
    double r = 0.0;
    for (size_t i = 0; i < p->ns; i++)
        r = dmax(r, v3_maxabs(v3_sub(p->sclip[i], ctx->centre)));
    for (size_t j = 0; j < npoly; j++)
        r = dmax(r, v3_maxabs(v3_sub(frame_point(&m->frame, poly[j]), ctx->centre)));
    return dmax(1e-6 * r, ctx->eps);
}

/* Shadow rays waiting to be traced as one packet, each with the radiance
 * it carries and the accumulator it adds to when unoccluded. Rays are added
 * to their accumulators in the order they were pushed, so results do not
 * depend on how rays are grouped into packets. */
typedef struct ray_batch {
    size_t n;
    v3 org[RL_RAY_PACKET], dir[RL_RAY_PACKET];
    double tnear[RL_RAY_PACKET], tfar[RL_RAY_PACKET];
    double l[RL_RAY_PACKET][3];
    double *acc[RL_RAY_PACKET];
} ray_batch;

/* Traces the pending rays and adds the unoccluded ones' radiance. */
static void batch_flush(const rl_transfer_ctx *ctx, ray_batch *b, rl_counters *cnt)
{
    int occluded[RL_RAY_PACKET];
    if (b->n == 0)
        return;
    cnt->rays_cast += b->n;
    rl__tracer_occluded_n(ctx->tracer, b->n, b->org, b->dir, b->tnear, b->tfar, occluded);
    for (size_t i = 0; i < b->n; i++) {
        if (occluded[i])
            continue;
        cnt->rays_kept++;
        for (int c = 0; c < 3; c++)
            b->acc[i][c] += b->l[i][c];
    }
    b->n = 0;
}

/* Queues a shadow ray from org along unit dir over [tnear, tfar] carrying l into acc. */
static void batch_push(const rl_transfer_ctx *ctx, ray_batch *b, v3 org, v3 dir, double tnear, double tfar,
                       const double l[3], double *acc, rl_counters *cnt)
{
    if (b->n == RL_RAY_PACKET)
        batch_flush(ctx, b, cnt);
    size_t i = b->n++;
    b->org[i] = org;
    b->dir[i] = dir;
    b->tnear[i] = tnear;
    b->tfar[i] = tfar;
    memcpy(b->l[i], l, sizeof b->l[i]);
    b->acc[i] = acc;
}

/* Shared by culled and naive: the radiance arriving at receiver point x
 * (normal nr) from emitter e along propagation direction d, sampled in leaf
 * L at barycentrics lam with weight w, times w and cos at x, queued for acc. The ray back from x along -d must meet e's front inside
 * e's polygon with nothing in between; a ray carrying no radiance is never
 * traced, since it could add nothing. */
static void shoot_back(const rl_transfer_ctx *ctx, const pair *p, v3 x, v3 nr, v3 d, double w, const leaf *L,
                       const double lam[3], double *acc, ray_batch *b, rl_counters *cnt)
{
    const rl_emitter *e = p->e;
    double cos_r = -v3_dot(d, nr), dn = v3_dot(d, e->frame.n);
    double hx = v3_dot(v3_sub(x, e->frame.origin), e->frame.n);
    cnt->samples++;
    if (!(cos_r > 0) || !(dn > 0) || !(hx > 0))
        return;
    double t = hx / dn;
    v3 y = v3_madd(x, d, -t);
    v2 q = frame_project(&e->frame, y);
    if (!emitter_contains(e, q))
        return;
    double l[3];
    emitter_radiance(e, q, d, L, lam, l);
    if (!(l[0] > 0 || l[1] > 0 || l[2] > 0))
        return;
    for (int c = 0; c < 3; c++)
        l[c] *= cos_r * w;
    double eps = p->eps;
    batch_push(ctx, b, x, v3_scale(d, -1.0), eps / dmax(cos_r, 1e-3), t - eps / dmax(dn, 1e-3), l, acc, cnt);
}

/* ----------------------------------------------------------- pair geometry */


/* The tile: the part of map m in grid rows [row0, row1), as a 2D polygon. */
typedef struct tile {
    rl_map *m;
    uint32_t map_index, row0, row1;
    v2 poly[RL_MAX_POLY_VERTS + 4];
    size_t npoly;
} tile;

/* @return 1 if the pair's emitter subtends less than one solid angle of
 * partition_n (about 2*pi / (4 m^2) sr, about 1.26 / m rad across) from every
 * corner of the tile, in solid angle or in angular width -- exact solid
 * angles, so an emitter seen edge-on or a sliver counts as small. Leaves
 * aimed at such an emitter would mostly miss it; such pairs are gathered
 * from each cell origin's exact view instead (gather_views()). */
static int pair_small(const rl_transfer_ctx *ctx, const pair *p, const tile *t)
{
    double m = ctx->sampling->partition_n, subtended = 0.0, width = 0.0;
    v3 dir[RL_MAX_POLY_VERTS + 2];
    double om[RL_MAX_POLY_VERTS + 2];
    for (size_t j = 0; j < t->npoly; j++) {
        v3 r = frame_point(&t->m->frame, t->poly[j]);
        double omega = rl__sph_fan(p->sclip, p->ns, r, dir, om), ext = 0.0;
        for (size_t a = 0; a < p->ns; a++)
            for (size_t b = a + 1; b < p->ns; b++)
                ext = fmax(ext, acos(fmin(1.0, fmax(-1.0, v3_dot(dir[a], dir[b])))));
        subtended = fmax(subtended, omega);
        width = fmax(width, ext > 0 ? omega / ext : 0.0);
    }
    return 1.6 / (m * m) > subtended || 1.26 / m > width;
}

/* Sets up pair p for emitter e and tile t. @return 0 if they cannot exchange light. */
static int pair_setup(const rl_transfer_ctx *ctx, const rl_emitter *e, const tile *t, pair *p)
{
    const rl_frame *rf = &t->m->frame;
    p->e = e;
    if (e->polygon >= 0 && e->polygon == t->m->polygon)
        return 0;
    /* the tile must be in front of the emitter somewhere */
    double front = -INFINITY, lift = 0.0;
    for (size_t j = 0; j < t->npoly; j++)
        front = fmax(front, v3_dot(v3_sub(frame_point(rf, t->poly[j]), e->frame.origin), e->frame.n));
    if (!(front > 0))
        return 0;
    p->ns = rl__clip_poly3(e->verts, e->nverts, rf->origin, rf->n, p->sclip);
    for (size_t i = 0; i < p->ns; i++)
        lift = fmax(lift, v3_dot(v3_sub(p->sclip[i], rf->origin), rf->n));
    if (p->ns < 3 || !(lift > 0))
        return 0; /* the emitter is behind, or in, the receiver's plane */
    /* naive never descends: it is the plain enumeration of partition_n */
    int plain = ctx->sampling->method == RL_METHOD_NAIVE || !ctx->sampling->descend;
    p->level = ctx->sampling->partition_n;
    p->descended = !plain && pair_small(ctx, p, t);
    p->eps = pair_eps(ctx, p, t->m, t->poly, t->npoly);
    return 1;
}

/* Gives the cone of solid angle id at level lv, in world directions, clipped
 * to arrive at the receiver's front. @return the generator count (0: empty). */
static size_t node_cone(const pair *p, const rl_frame *rf, uint32_t lv, uint64_t id, v3 *gens, v3 *clipped)
{
    double v[3][3];
    lfio_part_vertices(lv, id, v);
    for (int k = 0; k < 3; k++)
        gens[k] = frame_vector(&p->e->frame, v[k]);
    return rl__clip_cone(gens, 3, rf->n, clipped);
}

/* Computes the region of node (lv, id) for the emitter polygon src (ns
 * vertices, in front of the tile's plane) and its intersection with the tile.
 * @return the vertex count of that intersection (0: cull). */
static size_t node_region(const rl_transfer_ctx *ctx, const pair *p, const v3 *src, size_t ns, const tile *t,
                          uint32_t lv, uint64_t id, rl_region *reg, v2 *q)
{
    v3 gens[3], kc[6];
    size_t nk = node_cone(p, &t->m->frame, lv, id, gens, kc);
    if (nk == 0)
        return 0;
    rl__region_compute(&t->m->frame, src, ns, kc, nk, ctx->margin, reg);
    if (reg->empty)
        return 0;
    return rl__clip_to_region(t->poly, t->npoly, reg, q, RL_MAX_POLY_VERTS + 4 + RL_REGION_MAX_PLANES);
}

/* Appends a leaf. @return 0, or -1 when memory runs out. */
static int push_leaf(rl_scratch *s, uint64_t id)
{
    if (s->nleaves == s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 1024;
        uint64_t *grown = realloc(s->leaves, cap * sizeof *grown);
        if (!grown)
            return -1;
        s->leaves = grown;
        s->cap = cap;
    }
    s->leaves[s->nleaves++] = id;
    return 0;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Walks the hierarchy top-down, keeping the leaves at p->level that survive culling. */
static int walk(const rl_transfer_ctx *ctx, const pair *p, const tile *t, rl_scratch *s, rl_counters *cnt)
{
    struct node { uint32_t lv; uint64_t id; } stack[STACK_DEPTH];
    size_t top = 0;
    rl_region *reg = malloc(sizeof *reg);
    v2 *q = malloc((RL_MAX_POLY_VERTS + 4 + RL_REGION_MAX_PLANES) * sizeof *q);
    if (!reg || !q) {
        free(reg);
        free(q);
        return -1;
    }
    for (uint64_t id = 4; id-- > 0;)
        stack[top++] = (struct node){1, id};
    int rc = 0;
    while (top > 0 && rc == 0) {
        uint32_t lv = stack[top - 1].lv;
        uint64_t id = stack[--top].id;
        int dark = p->e->kind == EM_SLAB && ctx->sampling->zero_culling && rl__emitter_node_dark(p->e, lv, id);
        if (dark || node_region(ctx, p, p->sclip, p->ns, t, lv, id, reg, q) == 0)
            continue;
        if (lv >= p->level) {
            rc = push_leaf(s, id);
            continue;
        }
        uint64_t ch[4];
        lfio_part_children(lv, id, ch);
        for (int k = 3; k >= 0; k--)
            stack[top++] = (struct node){2 * lv, ch[k]};
    }
    free(reg);
    free(q);
    uint64_t total = lfio_part_hemi_count(p->level);
    cnt->leaves_considered += total;
    cnt->leaves_culled += total - s->nleaves;
    return rc;
}

/* Where the origins of one (cell, leaf) pair are drawn: the cell's polygon,
 * or for a descended pair its part inside the region, and that part's
 * share of the cell's area. */
typedef struct origin_domain {
    v2 poly[RL_MAX_POLY_VERTS + 8];
    uint32_t n;
    int square;    /* a full square: sampled from its corner and side alone */
    double weight; /* area of the part / area of the cell */
} origin_domain;

/* Fills d for cell of map m; clip (nclip vertices), when not NULL, is the
 * region to restrict origins to. @return 0 if the domain is empty. */
static int cell_domain(const rl_map *m, uint32_t cell, const v2 *clip, size_t nclip, origin_domain *d)
{
    d->n = rl__map_cell_polygon(m, &m->cells[cell], d->poly);
    d->square = m->cells[cell].poly_count == 0 && !clip;
    d->weight = 1.0;
    if (!clip || !(m->cells[cell].area > 0))
        return 1;
    /* cell intersect region: clip the cell by the clipped region's edges */
    v2 buf[2][RL_MAX_POLY_VERTS + RL_REGION_MAX_PLANES + 8];
    size_t n = rl__clip_to_polygon(d->poly, d->n, clip, nclip, buf[0], buf[1]);
    double part = n >= 3 ? rl__polygon_area2(buf[0], (uint32_t)n) : 0.0;
    if (!(part > 0))
        return 0;
    d->weight = part / m->cells[cell].area;
    d->n = (uint32_t)(n < RL_MAX_POLY_VERTS + 8 ? n : RL_MAX_POLY_VERTS + 8);
    memcpy(d->poly, buf[0], d->n * sizeof *d->poly);
    return 1;
}

/* @return a world origin in domain d of map m from two numbers in [0, 1). */
static v3 domain_point(const rl_map *m, const origin_domain *d, double a, double b)
{
    v2 q = d->square ? (v2){d->poly[0].x + a * m->cell, d->poly[0].y + b * m->cell}
                     : rl__sample_polygon(d->poly, d->n, a, b);
    return frame_point(&m->frame, q);
}

/* Draws the direction of one sample of leaf L from origin x, informed by
 * the emitter: when the leaf's three corner directions all reach the
 * emitter from x, every direction of the leaf does (the view of a cone is
 * the convex hull of its corners' views), and d is drawn over the leaf as
 * leaf_sample() does (*lp = L, lam its barycentrics); otherwise d is
 * uniform in the solid angle of the part of the emitter the leaf sees from
 * x (*lp = NULL, weight that solid angle), so that no sample misses. Either
 * way the mean of w * (radiance cos V) is the leaf's light at x.
 * @return 0 when the leaf sees nothing of the emitter from x. */
static int leaf_draw(const pair *p, const leaf *L, v3 x, double u1, double u2, v3 *d, double *w, double lam[3],
                     const leaf **lp)
{
    const rl_emitter *e = p->e;
    v3 rel = v3_sub(x, e->frame.origin);
    double hx = v3_dot(rel, e->frame.n);
    if (!(hx > 0))
        return 0;
    /* Only a constant emitter's leaves are informed. A light field's and a
     * bounce map's stay blind: their radiance varies inside a leaf anyway,
     * and on data/beams.json the clipping cost 1.8x the time of the direct
     * pass for 20% less error and 3.2x the time of the bounces for 21%
     * less, losses at equal time. */
    int blind = e->kind != EM_CONST, inside = L->reach || blind;
    v2 px = {v3_dot(rel, e->frame.e1), v3_dot(rel, e->frame.e2)};
    for (int k = 0; k < 3 && inside && !blind; k++)
        inside = emitter_contains(e, (v2){px.x - hx * L->land[k].x, px.y - hx * L->land[k].y});
    if (inside) {
        *d = leaf_sample(L, u1, u2, w, lam);
        *lp = L;
        return 1;
    }
    v3 q[RL_MAX_POLY_VERTS + 8], dir[RL_MAX_POLY_VERTS + 8];
    double om[RL_MAX_POLY_VERTS + 8];
    size_t nq = rl__clip_to_view(x, L->p, p->sclip, p->ns, q);
    double total = nq >= 3 ? rl__sph_fan(q, nq, x, dir, om) : 0.0;
    if (!(total > 0))
        return 0;
    *d = v3_scale(rl__sph_fan_sample(dir, om, nq, total, u1, u2), -1.0);
    *w = total;
    *lp = NULL;
    return 1;
}

/* Queues the k rays of (cell, leaf L) into acc.
 * @return the factor that turns acc into the cell's irradiance (0: no rays). */
static double gather_cell(const rl_transfer_ctx *ctx, const pair *p, const tile *t, uint32_t cell, const leaf *L,
                          const v2 *clip, size_t nclip, double *acc, ray_batch *batch, rl_counters *cnt)
{
    rl_map *m = t->m;
    origin_domain dom;
    if (!cell_domain(m, cell, clip, nclip, &dom))
        return 0.0;
    uint32_t k = ctx->sampling->rays_per_solid_angle;
    lds_key key = rl__lds_make(hash_mix(L->key, cell));
    /* draw a group of samples before shooting any: their square roots and
     * divisions are independent and overlap, where one sample at a time
     * would wait for each */
    enum { GROUP = 8 };
    for (uint32_t i0 = 0; i0 < k; i0 += GROUP) {
        uint32_t g = k - i0 < GROUP ? k - i0 : GROUP;
        double w[GROUP], lam[GROUP][3];
        v3 x[GROUP], d[GROUP];
        const leaf *lp[GROUP];
        int drawn[GROUP];
        for (uint32_t i = 0; i < g; i++) {
            double u[4];
            rl__lds4(&key, i0 + i, u);
            x[i] = domain_point(m, &dom, u[0], u[1]);
            drawn[i] = leaf_draw(p, L, x[i], u[2], u[3], &d[i], &w[i], lam[i], &lp[i]);
        }
        for (uint32_t i = 0; i < g; i++) {
            if (drawn[i])
                shoot_back(ctx, p, x[i], m->frame.n, d[i], w[i], lp[i], lam[i], acc, batch, cnt);
            else
                cnt->samples++;
        }
    }
    return dom.weight / k;
}

/* ---------------------------------------------------------------- adaptive */

/* Most samples one adaptive node draws. */
#define ADAPTIVE_MAX_SAMPLES 256

/* An adaptive estimate: irradiance, its variance (of the mean channel), and the samples behind it. */
typedef struct estimate {
    double e[3];
    double var;
    double samples;
} estimate;

/* @return 1 once the adaptive time budget has run out. */
static int budget_spent(const rl_transfer_ctx *ctx)
{
    if (!(ctx->deadline > 0))
        return 0;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9 > ctx->deadline;
}

/* Salts that keep adaptive's decisions apart from its estimates: samples
 * that decide whether a node is refined never enter the result, so the
 * decision cannot bias it (0: the estimate itself, culled's sequence). */
#define SALT_BUDGET UINT64_C(0x627564676574) /* "budget": stage 0's cell totals */
#define SALT_PILOT UINT64_C(0x70696c6f74)    /* "pilot": a node's refinement decision */

/* Estimates what solid angle id at level lv sends into one cell's domain
 * with count samples of the low-discrepancy sequence keyed by salt (salt 0:
 * the one culled uses, so an unrefined adaptive leaf equals culled's
 * estimate); the variance comes from the spread of the samples. */
static estimate node_estimate(const rl_transfer_ctx *ctx, const pair *p, const tile *t, const origin_domain *dom,
                              uint32_t cell, const leaf *L, uint32_t count, uint64_t salt, rl_counters *cnt)
{
    const rl_map *m = t->m;
    uint32_t k = count > ADAPTIVE_MAX_SAMPLES ? ADAPTIVE_MAX_SAMPLES : count;
    double acc[ADAPTIVE_MAX_SAMPLES][3];
    ray_batch batch;
    batch.n = 0;
    uint64_t h = hash_mix(L->key, cell);
    lds_key key = rl__lds_make(salt ? hash_mix(h, salt) : h);
    for (uint32_t i = 0; i < k; i++) {
        double u[4], w, lam[3];
        rl__lds4(&key, i, u);
        acc[i][0] = acc[i][1] = acc[i][2] = 0.0;
        v3 d, x = domain_point(m, dom, u[0], u[1]);
        const leaf *lp;
        if (leaf_draw(p, L, x, u[2], u[3], &d, &w, lam, &lp))
            shoot_back(ctx, p, x, m->frame.n, d, w, lp, lam, acc[i], &batch, cnt);
        else
            cnt->samples++;
    }
    batch_flush(ctx, &batch, cnt);
    estimate est = {{0, 0, 0}, 0, k};
    double lum = 0.0, sq = 0.0;
    for (uint32_t i = 0; i < k; i++) {
        double y = (acc[i][0] + acc[i][1] + acc[i][2]) / 3;
        for (int c = 0; c < 3; c++)
            est.e[c] += acc[i][c] / k;
        lum += y / k;
        sq += y * y / k;
    }
    est.var = k > 1 ? fmax(0.0, sq - lum * lum) / (k - 1) : 0.0;
    return est;
}

/* @return the equal-weight mean of two independent estimates of one quantity. */
static estimate estimate_mean(const estimate *a, const estimate *b)
{
    estimate m;
    for (int c = 0; c < 3; c++)
        m.e[c] = 0.5 * (a->e[c] + b->e[c]);
    m.var = 0.25 * (a->var + b->var);
    m.samples = a->samples + b->samples;
    return m;
}

/* Estimates solid angle id at level lv for one cell. k pilot samples
 * decide: while their standard error exceeds tol (W m^-2) the node is
 * replaced by its four children (recursively, each held to tol / 2);
 * otherwise k fresh samples estimate it. The result is the mean of the
 * pilot's estimate and the other one, with weights 1/2 whatever the
 * decision: the pilot is unbiased by itself and the fresh or refined
 * estimate is unbiased given the decision (its samples are independent of
 * the pilot's), so their fixed-weight mean is unbiased, and an unrefined
 * node gets the variance of 2k samples for the 2k it drew. (Using the
 * pilot alone when it decides against refining, as this method once did,
 * kept nodes whose few samples all missed at zero: 0.4% low in a white
 * furnace, 2.4% with two bounces.) */
static estimate adaptive_node(const rl_transfer_ctx *ctx, const pair *p, const tile *t, const origin_domain *dom,
                              uint32_t cell, uint32_t ei, const leaf *L, uint32_t max_level, double tol,
                              rl_counters *cnt)
{
    uint32_t k = ctx->sampling->rays_per_solid_angle;
    int pilot_drawn = 2 * L->lv <= max_level && k > 1, refine = pilot_drawn;
    estimate pilot = {{0, 0, 0}, 0, 0};
    if (pilot_drawn) {
        pilot = node_estimate(ctx, p, t, dom, cell, L, k, SALT_PILOT, cnt);
        refine = sqrt(pilot.var) > tol;
    }
    if (refine && budget_spent(ctx)) {
        cnt->budget_reached = 1;
        refine = 0;
    }
    if (!refine) {
        estimate fresh = node_estimate(ctx, p, t, dom, cell, L, k, 0, cnt);
        if (pilot_drawn)
            return estimate_mean(&pilot, &fresh);
        return fresh;
    }
    cnt->refinements++;
    uint64_t ch[4];
    lfio_part_children(L->lv, L->id, ch);
    estimate fine = {{0, 0, 0}, 0, 0};
    for (int c = 0; c < 4; c++) {
        leaf child;
        leaf_make(ctx, p->e, ei, t->map_index, 2 * L->lv, ch[c], &child);
        estimate r = adaptive_node(ctx, p, t, dom, cell, ei, &child, max_level, tol / 2, cnt);
        for (int j = 0; j < 3; j++)
            fine.e[j] += r.e[j];
        fine.var += r.var;
        fine.samples += r.samples;
    }
    return estimate_mean(&pilot, &fine);
}

/* Gives the u range [*ulo, *uhi] of convex polygon q within the band v in [va, vb]. @return 0 if none. */
static int band_range(const v2 *q, size_t nq, double va, double vb, double *ulo, double *uhi)
{
    v2 a[RL_MAX_POLY_VERTS + RL_REGION_MAX_PLANES + 8], b[RL_MAX_POLY_VERTS + RL_REGION_MAX_PLANES + 8];
    size_t n = rl__clip_poly2(q, nq, (rl_halfplane){0, 1, -va}, a);
    n = rl__clip_poly2(a, n, (rl_halfplane){0, -1, vb}, b);
    if (n == 0)
        return 0;
    *ulo = INFINITY;
    *uhi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        *ulo = fmin(*ulo, b[i].x);
        *uhi = fmax(*uhi, b[i].x);
    }
    return 1;
}

/* The adaptive method's work on one row of cells for one kept leaf. Stage
 * 0 only measures: each cell's total from this emitter and the number of
 * leaves that carry light into it (s->pair_total, s->pair_leaves, indexed
 * from the tile's first cell). Stage 1 estimates with refinement, holding
 * each (cell, leaf) node to an equal share of the cell's error budget:
 * target_error * total / sqrt(leaves). */
static void adaptive_row(const rl_transfer_ctx *ctx, const pair *p, const tile *t, const leaf *L, uint32_t ei,
                         const v2 *clip, size_t nq, uint32_t j, uint32_t i0, uint32_t i1, rl_scratch *s, int stage,
                         rl_counters *cnt)
{
    rl_map *m = t->m;
    uint32_t max_level = p->level >= (1u << 18) ? (1u << 20) : 4 * p->level;
    for (uint32_t i = i0; i <= i1; i++) {
        int32_t cell = m->grid[(size_t)j * m->nu + i];
        origin_domain dom;
        if (cell < 0 || !cell_domain(m, (uint32_t)cell, clip, nq, &dom))
            continue;
        size_t slot = (size_t)cell - s->first_cell;
        double tol = INFINITY;
        if (stage == 1 && s->pair_leaves[slot] > 0)
            tol = ctx->sampling->target_error * s->pair_total[slot] / sqrt(s->pair_leaves[slot]);
        /* stage 0 needs only each cell's total over all its leaves: one sample a leaf */
        estimate est = stage == 0 ? node_estimate(ctx, p, t, &dom, (uint32_t)cell, L, 1, SALT_BUDGET, cnt)
                                  : adaptive_node(ctx, p, t, &dom, (uint32_t)cell, ei, L, max_level, tol, cnt);
        double y = dom.weight * (est.e[0] + est.e[1] + est.e[2]) / 3;
        if (stage == 0) {
            s->pair_total[slot] += y;
            s->pair_leaves[slot] += y > 0;
            continue;
        }
        for (int c = 0; c < 3; c++)
            m->e_pass[cell][c] += dom.weight * est.e[c];
        cnt->variance += dom.weight * dom.weight * est.var;
    }
}

/* Makes room in s for a row of n cells' accumulators. @return 0 or -1. */
static int row_reserve(rl_scratch *s, size_t n)
{
    if (n <= s->row_cap)
        return 0;
    double (*acc)[3] = realloc(s->row_acc, n * sizeof *acc);
    if (acc)
        s->row_acc = acc;
    double *scale = acc ? realloc(s->row_scale, n * sizeof *scale) : NULL;
    if (scale)
        s->row_scale = scale;
    if (!acc || !scale)
        return -1;
    s->row_cap = n;
    return 0;
}

/* Processes one kept leaf over the tile's cells, a row at a time: the row's
 * rays go out in packets, then each cell adds its estimate. @return 0 or -1. */
static int gather_leaf(const rl_transfer_ctx *ctx, const pair *p, const tile *t, uint64_t id,
                       uint32_t emitter_index, int culled, rl_region *reg, v2 *q, rl_scratch *s, int stage,
                       rl_counters *cnt)
{
    rl_map *m = t->m;
    leaf L;
    leaf_make(ctx, p->e, emitter_index, t->map_index, p->level, id, &L);
    size_t nq = 0;
    if (culled) {
        /* a light field's solid angle is culled against the part of the
         * slab where its radiance is nonzero; cells outside that region
         * would only have drawn zeros */
        v3 box[4], src[RL_MAX_POLY_VERTS + 2];
        int sup = ctx->sampling->zero_culling ? leaf_support(p->e, &L, box) : 0;
        size_t ns = sup > 0 ? rl__clip_poly3(box, 4, m->frame.origin, m->frame.n, src) : 0;
        double lift = 0.0;
        for (size_t k = 0; k < ns; k++)
            lift = fmax(lift, v3_dot(v3_sub(src[k], m->frame.origin), m->frame.n));
        if (sup < 0 || (sup > 0 && (ns < 3 || !(lift > 0))))
            return 0;
        nq = sup > 0 ? node_region(ctx, p, src, ns, t, p->level, id, reg, q)
                     : node_region(ctx, p, p->sclip, p->ns, t, p->level, id, reg, q);
        if (nq == 0)
            return 0;
    }
    if (row_reserve(s, m->nu) != 0)
        return -1;
    const v2 *clip = culled && p->descended ? q : NULL;
    ray_batch batch;
    batch.n = 0;
    for (uint32_t j = t->row0; j < t->row1; j++) {
        uint32_t i0 = 0, i1 = m->nu - 1;
        if (culled && m->polygon >= 0) {
            double ulo, uhi, va = m->v0 + j * m->cell;
            if (!band_range(q, nq, va, va + m->cell, &ulo, &uhi))
                continue;
            double fi0 = floor((ulo - m->u0) / m->cell), fi1 = floor((uhi - m->u0) / m->cell);
            if (fi1 < 0 || fi0 > m->nu - 1)
                continue;
            i0 = fi0 < 0 ? 0 : (uint32_t)fi0;
            i1 = fi1 > m->nu - 1 ? m->nu - 1 : (uint32_t)fi1;
        }
        if (ctx->sampling->method == RL_METHOD_ADAPTIVE) {
            adaptive_row(ctx, p, t, &L, emitter_index, clip, nq, j, i0, i1, s, stage, cnt);
            continue;
        }
        for (uint32_t i = i0; i <= i1; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            double *acc = s->row_acc[i - i0];
            acc[0] = acc[1] = acc[2] = 0.0;
            s->row_scale[i - i0] = cell < 0 ? 0.0
                                   : gather_cell(ctx, p, t, (uint32_t)cell, &L, clip, nq, acc, &batch, cnt);
        }
        batch_flush(ctx, &batch, cnt);
        for (uint32_t i = i0; i <= i1; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            for (int c = 0; cell >= 0 && c < 3; c++)
                m->e_pass[cell][c] += s->row_acc[i - i0][c] * s->row_scale[i - i0];
        }
    }
    return 0;
}

/* Zeroes the adaptive per-cell measures for the tile's cells, growing them as needed. @return 0 or -1. */
static int adaptive_reserve(rl_scratch *s, const tile *t)
{
    const rl_map *m = t->m;
    uint32_t c0 = UINT32_MAX, c1 = 0; /* a tile's cells are numbered consecutively, row by row */
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t c = m->grid[(size_t)j * m->nu + i];
            if (c >= 0) {
                c0 = (uint32_t)c < c0 ? (uint32_t)c : c0;
                c1 = (uint32_t)c + 1 > c1 ? (uint32_t)c + 1 : c1;
            }
        }
    size_t n = c1 > c0 ? c1 - c0 : 1;
    if (n > s->pair_cap) {
        double *tot = realloc(s->pair_total, n * sizeof *tot);
        if (tot)
            s->pair_total = tot;
        uint32_t *lv = tot ? realloc(s->pair_leaves, n * sizeof *lv) : NULL;
        if (lv)
            s->pair_leaves = lv;
        if (!tot || !lv)
            return -1;
        s->pair_cap = n;
    }
    memset(s->pair_total, 0, n * sizeof *s->pair_total);
    memset(s->pair_leaves, 0, n * sizeof *s->pair_leaves);
    s->first_cell = c0 == UINT32_MAX ? 0 : c0;
    return 0;
}

/* @return how many origins the mean of Lambert's formula over a cell takes
 * (gather_lambert(), gather_views()). The formula is smooth except near the
 * emitter's plane, where it falls to 0 with the distance to that plane;
 * its quasi-random mean's error was measured to fall as (cell size /
 * distance to the emitter's plane) / origins: 0.45% of the peak at 16
 * origins for 0.25 m cells 1 m under a 1 m emitter, 0.12% at 64; 0.98%
 * at 29 and 0.16% at 256 for cells 1 mm to 0.5 m under an emitter seen
 * edge-on. So the count follows that ratio, from k to 64 k. */
static uint32_t lambert_origins(const pair *p, const rl_map *m, const origin_domain *dom, uint32_t k)
{
    v2 c = {0, 0};
    for (uint32_t i = 0; i < dom->n; i++)
        c = (v2){c.x + dom->poly[i].x / dom->n, c.y + dom->poly[i].y / dom->n};
    double h = fabs(v3_dot(v3_sub(frame_point(&m->frame, c), p->e->frame.origin), p->e->frame.n));
    double want = 72.0 * k * m->cell / dmax(h, 1e-300);
    return want >= 64.0 * k ? 64 * k : want <= k ? k : (uint32_t)ceil(want);
}

/* Transfer from emitter ei to every cell of the tile by the views of k
 * stratified origins per cell (rl__point_gather(), one ray per solid angle a
 * shadow boundary crosses, so k per cell and solid angle as elsewhere):
 * for pairs whose emitter subtends less than a solid angle, where leaves
 * aimed at it would mostly miss. A constant emitter's cell mean is then
 * the mean of Lambert's formula at lambert_origins() origins (at least k)
 * times the fraction of the
 * unoccluded light of the first k views that arrived: exact where the
 * views are unoccluded, exactly 0 where they are hidden, and consistent in
 * between (a difference of the two estimates would be unbiased, but it
 * dips below zero in shadows), with the cell's area integrated at more
 * origins than rays. @return 0 or -1. */
static int gather_views(const rl_transfer_ctx *ctx, const pair *p, const tile *t, uint32_t ei, rl_scratch *s,
                        rl_counters *cnt)
{
    rl_map *m = t->m;
    const rl_emitter *e = &ctx->emitters[ei];
    uint32_t k = ctx->sampling->rays_per_solid_angle;
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            origin_domain dom;
            if (cell < 0 || !cell_domain(m, (uint32_t)cell, NULL, 0, &dom))
                continue;
            uint32_t nl = e->kind == EM_CONST ? lambert_origins(p, m, &dom, k) : 0;
            uint64_t rk = hash_mix(hash_mix(t->map_index, (uint64_t)cell), UINT64_C(0x76696577)); /* "view" */
            lds_key key = rl__lds_make(hash_mix(hash_mix(hash_mix(ctx->sampling->seed, ctx->pass), ei), rk));
            double seen[3] = {0, 0, 0}, unocc = 0.0, full = 0.0;
            for (uint32_t o = 0; o < k || o < nl; o++) {
                double u[4];
                rl__lds4(&key, o, u);
                v3 x = domain_point(m, &dom, u[0], u[1]);
                double f = nl ? rl__point_lambert(e, x, m->frame.n) : 0.0;
                full += f;
                if (o >= k)
                    continue;
                unocc += f;
                if (rl__point_gather(ctx, ei, hash_mix(rk, o), x, m->frame.n, 1, seen, s, cnt) != 0)
                    return -1;
            }
            /* constant: Lambert's mean times the fraction of the views' unoccluded light that arrived */
            double frac[3];
            for (int c = 0; c < 3; c++)
                frac[c] = e->emission[c] * unocc > 0 ? fmin(seen[c] / (e->emission[c] * unocc), 1.0) : 0.0;
            for (int c = 0; c < 3; c++)
                m->e_pass[cell][c] += nl ? e->emission[c] * full / nl * frac[c] : seen[c] / k;
        }
    return 0;
}

/* Transfer from a constant emitter to every cell of the tile: the emitter's
 * radiance times Lambert's formula averaged over lambert_origins() origins
 * of the cell, times the fraction of light that arrives, estimated from
 * shadow rays to uniform points of the emitter (clipped to the receiver's
 * front) weighted by cos cos / r^2, k of them per solid angle of
 * partition_n the emitter subtends from the cell's centre (at least k, at
 * most 64 k). Unoccluded cells get Lambert's field, cells in full shadow
 * exactly 0: rays are spent on visibility alone, which is all a constant
 * emitter leaves unknown. A ratio of two estimates is consistent rather
 * than unbiased (by O(1 / rays) in a penumbra; the white-furnace test
 * bounds it); Lambert minus the sampled loss would be unbiased, but it
 * dips below zero in shadows. The solid angles play no part: no sample is
 * wasted on directions that miss the emitter. */
static void gather_lambert(const rl_transfer_ctx *ctx, const pair *p, const tile *t, uint32_t ei, rl_counters *cnt)
{
    rl_map *m = t->m;
    const rl_emitter *e = p->e;
    uint32_t k = ctx->sampling->rays_per_solid_angle, n = ctx->sampling->partition_n;
    double leaf_sr = 2.0 * PI / (4.0 * n * n);
    v2 sp[RL_MAX_POLY_VERTS + 2];
    for (size_t i = 0; i < p->ns; i++)
        sp[i] = frame_project(&e->frame, p->sclip[i]);
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            origin_domain dom;
            if (cell < 0 || !cell_domain(m, (uint32_t)cell, NULL, 0, &dom))
                continue;
            lds_key key = rl__lds_make(hash_mix(
                hash_mix(hash_mix(hash_mix(ctx->sampling->seed, ctx->pass), ei), t->map_index), (uint64_t)cell));
            uint32_t no = lambert_origins(p, m, &dom, k);
            double f = 0.0;
            for (uint32_t o = 0; o < no; o++) {
                double u[4];
                rl__lds4(&key, o, u);
                f += rl__point_lambert(e, domain_point(m, &dom, u[0], u[1]), m->frame.n);
            }
            if (!(f > 0))
                continue;
            /* rays in proportion to the solid angle the emitter subtends from the cell */
            v2 c = {0, 0};
            for (uint32_t v = 0; v < dom.n; v++)
                c = (v2){c.x + dom.poly[v].x / dom.n, c.y + dom.poly[v].y / dom.n};
            v3 dir[RL_MAX_POLY_VERTS + 2];
            double om[RL_MAX_POLY_VERTS + 2];
            double leaves = ceil(rl__sph_fan(p->sclip, p->ns, frame_point(&m->frame, c), dir, om) / leaf_sr);
            uint32_t nr = leaves >= 64.0 ? 64 * k : leaves <= 1.0 ? k : k * (uint32_t)leaves;
            double all = 0.0, seen[3] = {0, 0, 0};
            ray_batch batch;
            batch.n = 0;
            for (uint32_t r = 0; r < nr; r++) {
                double u[4];
                rl__lds4(&key, r, u);
                v3 x = domain_point(m, &dom, u[0], u[1]);
                v3 y = frame_point(&e->frame, rl__sample_polygon(sp, (uint32_t)p->ns, u[2], u[3]));
                v3 to = v3_sub(y, x);
                double dist = v3_len(to);
                cnt->samples++;
                if (!(dist > 0))
                    continue;
                to = v3_scale(to, 1.0 / dist);
                double cos_r = v3_dot(to, m->frame.n), cos_s = -v3_dot(to, e->frame.n);
                if (!(cos_r > 0) || !(cos_s > 0))
                    continue;
                double w = cos_r * cos_s / (dist * dist), l[3] = {w, 0, 0};
                all += w;
                batch_push(ctx, &batch, x, to, p->eps / fmax(cos_r, 1e-3), dist - p->eps / fmax(cos_s, 1e-3), l,
                           seen, cnt);
            }
            batch_flush(ctx, &batch, cnt);
            if (!(all > 0))
                continue;
            double scale = f / no * fmin(seen[0] / all, 1.0);
            for (int ch = 0; ch < 3; ch++)
                m->e_pass[cell][ch] += e->emission[ch] * scale;
        }
}

/* Culled or naive transfer from emitter e to the tile. */
static int gather_solid_angles(const rl_transfer_ctx *ctx, const tile *t, uint32_t ei, rl_scratch *s,
                               rl_counters *cnt)
{
    pair *p = malloc(sizeof *p);
    rl_region *reg = malloc(sizeof *reg);
    v2 *q = malloc((RL_MAX_POLY_VERTS + 4 + RL_REGION_MAX_PLANES) * sizeof *q);
    int rc = (!p || !reg || !q) ? -1 : 0;
    if (rc == 0 && pair_setup(ctx, &ctx->emitters[ei], t, p)) {
        int culled = ctx->sampling->method == RL_METHOD_CULLED || ctx->sampling->method == RL_METHOD_ADAPTIVE;
        cnt->pairs++;
        cnt->pairs_descended += p->descended;
        s->nleaves = 0;
        int method = ctx->sampling->method;
        if (ctx->sampling->descend && p->e->kind == EM_CONST &&
            (method == RL_METHOD_CULLED || method == RL_METHOD_NAIVE)) {
            /* a constant emitter: Lambert's formula, and rays for visibility alone */
            gather_lambert(ctx, p, t, ei, cnt);
        } else if (culled && p->descended) {
            /* an emitter smaller than a solid angle: each cell's origins see it exactly */
            rc = gather_views(ctx, p, t, ei, s, cnt);
        } else if (culled) {
            rc = walk(ctx, p, t, s, cnt);
            if (rc == 0 && s->nleaves > 1)
                qsort(s->leaves, s->nleaves, sizeof *s->leaves, cmp_u64);
        } else {
            uint64_t total = lfio_part_hemi_count(p->level);
            cnt->leaves_considered += total;
            for (uint64_t id = 0; id < total && rc == 0; id++)
                rc = push_leaf(s, id);
        }
        /* adaptive first measures every cell's total (stage 0), then estimates (stage 1) */
        int adaptive = ctx->sampling->method == RL_METHOD_ADAPTIVE;
        if (rc == 0 && adaptive)
            rc = adaptive_reserve(s, t);
        for (int stage = adaptive ? 0 : 1; stage <= 1 && rc == 0; stage++)
            for (size_t k = 0; k < s->nleaves && rc == 0; k++)
                rc = gather_leaf(ctx, p, t, s->leaves[k], ei, culled, reg, q, s, stage, cnt);
    }
    free(p);
    free(reg);
    free(q);
    return rc;
}

/* ------------------------------------------------------------- baselines */

/* One sample of `area` (uniform on the clipped emitter) or `solidangle`
 * (uniform in its spherical polygon) from cell point x; queues the weighted
 * radiance * cosines for acc. */
static void baseline_sample(const rl_transfer_ctx *ctx, const pair *p, const rl_frame *rf, v3 x,
                            const double u[4], double s_area, double *acc, ray_batch *b, rl_counters *cnt)
{
    const rl_emitter *e = p->e;
    v3 y, to_s; /* the emitter point and the unit direction from x to it */
    double weight, dist;
    cnt->samples++;
    if (ctx->sampling->method == RL_METHOD_AREA) {
        v2 sp[RL_MAX_POLY_VERTS + 2];
        for (size_t i = 0; i < p->ns; i++)
            sp[i] = frame_project(&e->frame, p->sclip[i]);
        y = frame_point(&e->frame, rl__sample_polygon(sp, (uint32_t)p->ns, u[2], u[3]));
        v3 r = v3_sub(y, x);
        dist = v3_len(r);
        if (!(dist > 0))
            return;
        to_s = v3_scale(r, 1.0 / dist);
        double cos_s = -v3_dot(to_s, e->frame.n);
        weight = cos_s > 0 ? s_area * cos_s / (dist * dist) : 0.0;
    } else {
        v3 dir[RL_MAX_POLY_VERTS + 2];
        double om[RL_MAX_POLY_VERTS + 2];
        double total = rl__sph_fan(p->sclip, p->ns, x, dir, om);
        if (!(total > 0))
            return;
        to_s = rl__sph_fan_sample(dir, om, p->ns, total, u[2], u[3]);
        double dn = -v3_dot(to_s, e->frame.n);
        if (!(dn > 0))
            return;
        dist = v3_dot(v3_sub(x, e->frame.origin), e->frame.n) / dn;
        y = v3_madd(x, to_s, dist);
        weight = total;
    }
    double cos_r = v3_dot(to_s, rf->n);
    if (!(cos_r > 0) || !(weight > 0))
        return;
    v2 q = frame_project(&e->frame, y);
    if (!emitter_contains(e, q))
        return;
    double l[3];
    emitter_radiance(e, q, v3_scale(to_s, -1.0), NULL, NULL, l);
    if (!(l[0] > 0 || l[1] > 0 || l[2] > 0))
        return; /* nothing to carry: no ray needed */
    for (int c = 0; c < 3; c++)
        l[c] *= cos_r * weight;
    double eps = p->eps, cos_s = -v3_dot(to_s, e->frame.n);
    batch_push(ctx, b, x, to_s, eps / fmax(cos_r, 1e-3), dist - eps / fmax(cos_s, 1e-3), l, acc, cnt);
}

/* Area or solid-angle sampling of emitter ei for every cell of the tile. */
static void gather_baseline(const rl_transfer_ctx *ctx, const tile *t, uint32_t ei, rl_counters *cnt)
{
    pair p;
    if (!pair_setup(ctx, &ctx->emitters[ei], t, &p))
        return;
    cnt->pairs++;
    rl_map *m = t->m;
    v2 sp[RL_MAX_POLY_VERTS + 2];
    for (size_t i = 0; i < p.ns; i++)
        sp[i] = frame_project(&p.e->frame, p.sclip[i]);
    double s_area = rl__polygon_area2(sp, (uint32_t)p.ns);
    uint32_t n = ctx->sampling->samples_per_cell;
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            if (cell < 0)
                continue;
            v2 cp[RL_MAX_POLY_VERTS + 8];
            uint32_t ncp = rl__map_cell_polygon(m, &m->cells[cell], cp);
            lds_key key = rl__lds_make(hash_mix(
                hash_mix(hash_mix(hash_mix(ctx->sampling->seed, ctx->pass), ei), t->map_index), (uint64_t)cell));
            double acc[3] = {0, 0, 0};
            ray_batch batch;
            batch.n = 0;
            for (uint32_t s = 0; s < n; s++) {
                double u[4];
                rl__lds4(&key, s, u);
                v3 x = frame_point(&m->frame, rl__sample_polygon(cp, ncp, u[0], u[1]));
                baseline_sample(ctx, &p, &m->frame, x, u, s_area, acc, &batch, cnt);
            }
            batch_flush(ctx, &batch, cnt);
            for (int c = 0; c < 3; c++)
                m->e_pass[cell][c] += acc[c] / n;
        }
}

/* ------------------------------------------------------------------ tiles */

int rl__transfer_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                  rl_scratch *scratch, rl_counters *cnt)
{
    tile *t = malloc(sizeof *t);
    if (!t)
        return -1;
    t->m = m;
    t->map_index = map_index;
    t->row0 = row0;
    t->row1 = row1;
    if (m->polygon < 0) {
        t->poly[0] = m->poly[0];
        t->npoly = 1;
    } else {
        v2 a[RL_MAX_POLY_VERTS + 4];
        double va = m->v0 + row0 * m->cell, vb = m->v0 + row1 * m->cell;
        size_t n = rl__clip_poly2(m->poly, m->npoly, (rl_halfplane){0, 1, -va}, a);
        t->npoly = rl__clip_poly2(a, n, (rl_halfplane){0, -1, vb}, t->poly);
    }
    int rc = 0;
    rl_method method = ctx->sampling->method;
    if (m->polygon < 0 && (method == RL_METHOD_CULLED || method == RL_METHOD_ADAPTIVE)) {
        /* a point receiver is culled from its own view of each emitter */
        for (size_t e = 0; e < ctx->nemitters && rc == 0; e++) {
            cnt->pairs++;
            rc = rl__point_gather(ctx, (uint32_t)e, map_index, m->frame.origin, m->frame.n,
                              ctx->sampling->rays_per_solid_angle, m->e_pass[0], scratch, cnt);
        }
        free(t);
        return rc;
    }
    for (size_t e = 0; e < ctx->nemitters && rc == 0 && t->npoly > 0; e++) {
        if (method != RL_METHOD_AREA && method != RL_METHOD_SOLIDANGLE)
            rc = gather_solid_angles(ctx, t, (uint32_t)e, scratch, cnt);
        else
            gather_baseline(ctx, t, (uint32_t)e, cnt);
    }
    free(t);
    return rc;
}

void rl__scratch_free(rl_scratch *s)
{
    free(s->occ);
    free(s->pair_total);
    free(s->pair_leaves);
    free(s->leaves);
    free(s->row_acc);
    free(s->row_scale);
}
