/*
 * pair.c - what every method shares for one (emitter, receiver tile) pair:
 * the tile cut from a map's rows, the pair's clipped emitter, level and ray
 * offset, the Minkowski region of a solid angle on the tile, the domains
 * origins are drawn from, and the packets of shadow rays.
 *
 * Ray offsets are bounded once per pair from the corners (pair_eps()): a
 * bound over the corners bounds every point between them. A ray is traced
 * only when it can carry radiance, and the radiance of the rays of a packet
 * reaches their accumulators in the order they were queued.
 */
#include <stdlib.h>
#include <string.h>

#include <lfio/partition.h>

#include "pair.h"

/* @return the distance that single precision cannot resolve on segments
 * between the pair's tile and emitter: eight ulps of the largest recentred
 * coordinate among their corners, and at least the scene's own. Once per
 * pair rather than per ray: a bound over the corners bounds every point. */
static double pair_eps(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_map *m, const v2 *poly, size_t npoly)
{
    double r = 0.0;
    for (size_t i = 0; i < p->ns; i++)
        r = dmax(r, v3_maxabs(v3_sub(p->sclip[i], ctx->centre)));
    for (size_t j = 0; j < npoly; j++)
        r = dmax(r, v3_maxabs(v3_sub(frame_point(&m->frame, poly[j]), ctx->centre)));
    return dmax(1e-6 * r, ctx->eps);
}

void rl__batch_flush(const rl_transfer_ctx *ctx, rl_ray_batch *b, rl_counters *cnt)
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

/* The ray back from x along -d must meet e's front inside e's polygon with
 * nothing in between; a ray carrying no radiance is never traced, since it
 * could add nothing. */
void rl__shoot_back(const rl_transfer_ctx *ctx, const rl_pair *p, v3 x, v3 nr, v3 d, double w, const rl_leaf *L,
                    const double lam[3], const double *wd, double *acc, rl_ray_batch *b, rl_counters *cnt)
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
    if (!rl__emitter_contains(e, q))
        return;
    double l[3];
    if (wd)
        rl__leaf_radiance_weighted(e, q, L, wd, l);
    else
        rl__leaf_radiance(e, q, d, L, lam, l);
    if (!(l[0] > 0 || l[1] > 0 || l[2] > 0))
        return;
    for (int c = 0; c < 3; c++)
        l[c] *= cos_r * w;
    double eps = p->eps;
    rl__batch_push(ctx, b, x, v3_scale(d, -1.0), eps / dmax(cos_r, 1e-3), t - eps / dmax(dn, 1e-3), l, acc, cnt);
}

void rl__tile_make(rl_map *m, uint32_t map_index, uint32_t row0, uint32_t row1, rl_tile *t)
{
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
}

/* @return the solid angle (sr) of the pair's clipped emitter seen from r;
 * *width gets that over its angular extent (rad). */
static double subtended_from(const rl_pair *p, v3 r, double *width)
{
    v3 dir[RL_MAX_POLY_VERTS + 2];
    double om[RL_MAX_POLY_VERTS + 2];
    double omega = rl__sph_fan(p->sclip, p->ns, r, dir, om), ext = 0.0;
    for (size_t a = 0; a < p->ns; a++)
        for (size_t b = a + 1; b < p->ns; b++)
            ext = fmax(ext, acos(fmin(1.0, fmax(-1.0, v3_dot(dir[a], dir[b])))));
    *width = ext > 0 ? omega / ext : 0.0;
    return omega;
}

int rl__convex_contains(const v2 *poly, size_t n, v2 q)
{
    int left = 0, right = 0;
    for (size_t i = 0; i < n; i++) {
        v2 a = poly[i], b = poly[(i + 1) % n];
        double c = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
        left |= c > 0;
        right |= c < 0;
    }
    return !(left && right);
}

v3 rl__pair_centroid(const rl_pair *p)
{
    v3 c = {0, 0, 0};
    for (size_t i = 0; i < p->ns; i++)
        c = v3_add(c, v3_scale(p->sclip[i], 1.0 / (double)p->ns));
    return c;
}

/* Measures the pair's emitter from the tile. @return 1 if it subtends less
 * than one solid angle of partition_n (about 2*pi / (4 m^2) sr, about
 * 1.26 / m rad across) from every corner of the tile, in solid angle or in
 * angular width -- exact solid angles, so an emitter seen edge-on or a
 * sliver counts as small. Leaves aimed at such an emitter would mostly miss
 * it; such pairs are gathered by Lambert's formula times sampled radiance
 * and visibility instead (rl__gather_lambert()). *leaves gets the most
 * solid angles it subtends from a corner or from the foot of its centroid
 * on the tile (where a near emitter looks largest). */
static int pair_measure(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, double *leaves)
{
    double m = ctx->sampling->partition_n, subtended = 0.0, width = 0.0, w;
    for (size_t j = 0; j < t->npoly; j++) {
        subtended = fmax(subtended, subtended_from(p, frame_point(&t->m->frame, t->poly[j]), &w));
        width = fmax(width, w);
    }
    int small = 1.6 / (m * m) > subtended || 1.26 / m > width;
    v2 foot = frame_project(&t->m->frame, rl__pair_centroid(p));
    double peak = subtended;
    if (t->npoly >= 3 && rl__convex_contains(t->poly, t->npoly, foot))
        peak = fmax(peak, subtended_from(p, frame_point(&t->m->frame, foot), &w));
    *leaves = peak / (2.0 * ILF_PI / (4.0 * m * m));
    return small;
}

int rl__pair_setup(const rl_transfer_ctx *ctx, const rl_emitter *e, const rl_tile *t, rl_pair *p)
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
    int small = pair_measure(ctx, p, t, &p->leaves);
    p->descended = !plain && small;
    p->eps = pair_eps(ctx, p, t->m, t->poly, t->npoly);
    return 1;
}

/* Gives the cone of solid angle id at level lv, in world directions, clipped
 * to arrive at the receiver's front. @return the generator count (0: empty). */
static size_t node_cone(const rl_pair *p, const rl_frame *rf, uint32_t lv, uint64_t id, v3 *gens, v3 *clipped)
{
    double v[3][3];
    lfio_part_vertices(lv, id, v);
    for (int k = 0; k < 3; k++)
        gens[k] = frame_vector(&p->e->frame, v[k]);
    return rl__clip_cone(gens, 3, rf->n, clipped);
}

size_t rl__node_region(const rl_transfer_ctx *ctx, const rl_pair *p, const v3 *src, size_t ns, const rl_tile *t,
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

void rl__cell_domain(const rl_map *m, uint32_t cell, rl_origin_domain *d)
{
    d->n = rl__map_cell_polygon(m, cell, d->poly);
    d->square = !rl__map_cell(m, cell).clipped;
    if (!d->square)
        rl__polygon_sampler_init(&d->ps, d->poly, d->n);
}

/* Draws the direction of one sample of leaf L from origin x, informed by
 * the emitter: when the leaf's three corner directions all reach the
 * emitter from x, every direction of the leaf does (the view of a cone is
 * the convex hull of its corners' views), and d is drawn over the leaf as
 * rl__leaf_sample() does (*lp = L, lam its barycentrics); otherwise d is
 * uniform in the solid angle of the part of the emitter the leaf sees from
 * x (*lp = NULL, weight that solid angle), so that no sample misses. Either
 * way the mean of w * (radiance cos V) is the leaf's light at x.
 * @return 0 when the leaf sees nothing of the emitter from x. */
int rl__leaf_draw(const rl_pair *p, const rl_leaf *L, v3 x, double u1, double u2, v3 *d, double *w, double lam[3],
                  const rl_leaf **lp)
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
        inside = rl__emitter_contains(e, (v2){px.x - hx * L->land[k].x, px.y - hx * L->land[k].y});
    if (inside) {
        *d = rl__leaf_sample(L, u1, u2, w, lam);
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
