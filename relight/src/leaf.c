/*
 * leaf.c - solid angles of an emitter's partition prepared for sampling.
 *
 * A leaf is one triangle of the partition (lfio/partition.h) in the
 * emitter's frame. Coarse leaves are sampled uniformly in solid angle by
 * Arvo's warp; from RL_PLANAR_MIN_LEVEL on, on their planar lattice
 * triangle through lfio's strata, each direction weighted by the Jacobian
 * to the sphere. A light field's leaf that nests in the slab's own
 * partition keeps the slab-level triangle and its three neighbours, so a
 * sample reads the slab by fixed interpolation weights instead of searching
 * for its direction. The weights always integrate to the leaf's exact solid
 * angle, which is what keeps every method built on leaves unbiased.
 */
#include <stdlib.h>
#include <string.h>

#include <lfio/partition.h>

#include "leaf.h"

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

void rl__leaf_make(const rl_transfer_ctx *ctx, const rl_emitter *e, uint32_t ei, uint32_t map_index, uint32_t lv,
                   uint64_t id, rl_leaf *L)
{
    double v[3][3];
    lattice_triangle(lv, id, v);
    L->lv = lv;
    L->id = id;
    L->omega = lfio_part_solid_angle(lv, id);
    L->key = ilf_hash_mix(ilf_hash_mix(rl__pair_key(ctx, ei, map_index), lv), id);
    for (int k = 0; k < 3; k++)
        L->p[k] = frame_vector(&e->frame, v[k]);
    /* in e's frame a corner is v[k] itself: it reaches the front when v[k].z > 0 */
    L->reach = v[0][2] > 0 && v[1][2] > 0 && v[2][2] > 0;
    for (int k = 0; k < 3 && L->reach; k++)
        L->land[k] = (v2){v[k][0] / v[k][2], v[k][1] / v[k][2]};
    L->planar = lv >= RL_PLANAR_MIN_LEVEL;
    L->mix = 0;
    L->nshared = 0;
    L->blend = NULL;
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

v3 rl__leaf_sample(const rl_leaf *L, double u1, double u2, double *w, double lam[3])
{
    if (!L->planar) {
        *w = L->omega;
        return rl__sph_tri_sample(&L->tri, u1, u2);
    }
    double su = sqrt(u1), l[3] = {1.0 - su, su * (1.0 - u2), su * u2}, d[3];
    lfio_part_strata_sample(&L->st, 0, l, d, w, lam);
    return v3_load(d);
}

/* Gives in b the slab positions outside which every direction L mixes is
 * zero. @return 0 when there are none. */
static int support_box(const rl_emitter *e, const rl_leaf *L, uint32_t b[4])
{
    uint64_t ndir = lfio_slab_dir_count(e->lf->slab);
    b[0] = UINT32_MAX, b[1] = 0, b[2] = UINT32_MAX, b[3] = 0;
    for (int k = 0; k < 4; k++)
        rl__box_union(b, e->tab->support[L->ids[k] < ndir ? L->ids[k] : L->ids[0]]);
    return b[0] != UINT32_MAX;
}

int rl__leaf_support(const rl_emitter *e, const rl_leaf *L, v3 out[4])
{
    if (!L->mix)
        return 0;
    uint32_t b[4];
    double r[4];
    if (!support_box(e, L, b))
        return -1;
    rl__emitter_support_rect(e, b, r);
    out[0] = frame_point(&e->frame, (v2){r[0], r[2]});
    out[1] = frame_point(&e->frame, (v2){r[1], r[2]});
    out[2] = frame_point(&e->frame, (v2){r[1], r[3]});
    out[3] = frame_point(&e->frame, (v2){r[0], r[3]});
    return 1;
}

/* Gives the slab interpolation weights (of L->ids) of the direction at barycentrics lam of mixing leaf L. */
static void mix_weights(const rl_leaf *L, const double lam[3], double w[4])
{
    double ls[3];
    for (int r = 0; r < 3; r++)
        ls[r] = L->to_slab[r][0] * lam[0] + L->to_slab[r][1] * lam[1] + L->to_slab[r][2] * lam[2];
    lfio_part_interp_weights(ls, w);
}

void rl__leaf_radiance_weighted(const rl_emitter *e, v2 q, const rl_leaf *L, const double wd[4], double out[3])
{
    float rgb[3] = {0, 0, 0};
    lfio_slab_radiance_mix(e->lf->slab, q.x / e->len_u, q.y / e->len_v, L->ids, wd, rgb);
    for (int c = 0; c < 3; c++)
        out[c] = rgb[c];
}

void rl__leaf_radiance_mix(const rl_emitter *e, v2 q, const rl_leaf *L, const double lam[3], double out[3])
{
    double w[4];
    mix_weights(L, lam, w);
    rl__leaf_radiance_weighted(e, q, L, w, out);
}

uint32_t rl__leaf_share(rl_leaf *L, uint32_t k)
{
    L->nshared = 0;
    if (!L->mix || k > RL_LEAF_SHARED)
        return 0;
    /* a sequence of the leaf's own, apart from the cells' (keyed by leaf and cell) */
    lds_key key = rl__lds_make(ilf_hash_mix(L->key, UINT64_MAX));
    for (uint32_t i = 0; i < k; i++) {
        double lam[3];
        L->sd[i] = rl__leaf_sample(L, rl__lds_coord(&key, i, 0), rl__lds_coord(&key, i, 1), &L->sw[i], lam);
        mix_weights(L, lam, L->swd[i]);
    }
    return L->nshared = k;
}

void rl__leaf_plan(rl_leaf *L, const rl_emitter *e, const rl_frame *rf, double eps)
{
    const rl_frame *ef = &e->frame;
    v3 o = v3_sub(rf->origin, ef->origin);
    for (uint32_t i = 0; i < L->nshared; i++) {
        rl_shared_plan *pl = &L->plan[i];
        v3 d = L->sd[i];
        double cos_r = -v3_dot(d, rf->n), dn = v3_dot(d, ef->n);
        pl->live = cos_r > 0 && dn > 0;
        if (!pl->live)
            continue;
        /* an origin x = rf.origin + u e1 + v e2 lies h(x) above the emitter's
         * plane, and its ray lands at x - d h(x) / dn: both affine in (u, v) */
        double h[3] = {v3_dot(o, ef->n), v3_dot(rf->e1, ef->n), v3_dot(rf->e2, ef->n)};
        double de1 = v3_dot(d, ef->e1), de2 = v3_dot(d, ef->e2);
        double px[3] = {v3_dot(o, ef->e1), v3_dot(rf->e1, ef->e1), v3_dot(rf->e2, ef->e1)};
        double py[3] = {v3_dot(o, ef->e2), v3_dot(rf->e1, ef->e2), v3_dot(rf->e2, ef->e2)};
        for (int c = 0; c < 3; c++) {
            pl->t[c] = h[c] / dn;
            pl->qx[c] = px[c] - de1 * pl->t[c];
            pl->qy[c] = py[c] - de2 * pl->t[c];
        }
        pl->back = v3_scale(d, -1.0);
        pl->tnear = eps / dmax(cos_r, 1e-3);
        pl->tshort = eps / dmax(dn, 1e-3);
        pl->scale = cos_r * L->sw[i];
    }
}

size_t rl__leaf_blend_size(const rl_emitter *e, rl_leaf *L, const double from[4])
{
    if (L->nshared == 0 || !support_box(e, L, L->box))
        return 0;
    const lfio_slab_desc *d = lfio_slab_get_desc(e->lf->slab);
    /* grid coordinates g = s * nu - 0.5, s = q / len: affine in the origin's as q is */
    double fu = d->nu / e->len_u, fv = d->nv / e->len_v;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    int finite = 1;
    for (uint32_t i = 0; i < L->nshared; i++) {
        rl_shared_plan *pl = &L->plan[i];
        for (int c = 0; c < 3; c++) {
            pl->gu[c] = pl->qx[c] * fu;
            pl->gv[c] = pl->qy[c] * fv;
        }
        pl->gu[0] -= 0.5;
        pl->gv[0] -= 0.5;
        for (int k = 0; k < 4 && pl->live; k++) {
            /* the landing is affine: its extremes over the rectangle are at its corners */
            double u = from[k % 2], v = from[2 + k / 2];
            double g[2] = {pl->gu[0] + pl->gu[1] * u + pl->gu[2] * v, pl->gv[0] + pl->gv[1] * u + pl->gv[2] * v};
            finite &= isfinite(g[0]) && isfinite(g[1]);
            for (int a = 0; a < 2; a++)
                lo[a] = dmin(lo[a], g[a]), hi[a] = dmax(hi[a], g[a]);
        }
    }
    /* the positions a landing's taps reach (the one at or below it and the
     * next), cut to the support: an origin within from reads nothing else */
    uint32_t b[4];
    double n[2] = {d->nu, d->nv};
    for (int a = 0; a < 2; a++) {
        double first = dmax(floor(lo[a]), 0.0), last = dmin(floor(hi[a]) + 1.0, n[a] - 1.0);
        b[2 * a] = first <= last ? (uint32_t)first : 1, b[2 * a + 1] = first <= last ? (uint32_t)last : 0;
    }
    /* a landing out of range (a direction grazing the emitter's plane) keeps the whole support */
    if (finite && b[0] <= b[1] && b[2] <= b[3] && b[0] <= L->box[1] && b[1] >= L->box[0] && b[2] <= L->box[3] &&
        b[3] >= L->box[2]) {
        L->box[0] = b[0] > L->box[0] ? b[0] : L->box[0], L->box[1] = b[1] < L->box[1] ? b[1] : L->box[1];
        L->box[2] = b[2] > L->box[2] ? b[2] : L->box[2], L->box[3] = b[3] < L->box[3] ? b[3] : L->box[3];
    }
    return L->nshared * rl__box_positions(L->box) * 3;
}

int rl__leaf_blend(const rl_emitter *e, rl_leaf *L, float *tables)
{
    size_t per = rl__box_positions(L->box) * 3;
    for (uint32_t i = 0; i < L->nshared; i++) {
        /* the direction's scale (cosine times weight) mixed in: a sample then only adds what it reads */
        double w[4], scale = L->plan[i].live ? L->plan[i].scale : 0.0;
        for (int k = 0; k < 4; k++)
            w[k] = L->swd[i][k] * scale;
        if (lfio_slab_blend(e->lf->slab, L->ids, w, L->box, tables + i * per) != LFIO_OK)
            return -1;
    }
    L->blend = tables;
    L->blend_stride = per;
    const lfio_slab_desc *d = lfio_slab_get_desc(e->lf->slab);
    lfio_slab_blend_grid(e->lf->slab, L->box, &L->grid);
    /* where the tables may be read, cut to the slab (the emitter) */
    L->grect[0] = dmax(L->grid.rect[0], -0.5);
    L->grect[1] = dmin(L->grid.rect[1], d->nu - 0.5);
    L->grect[2] = dmax(L->grid.rect[2], -0.5);
    L->grect[3] = dmin(L->grid.rect[3], d->nv - 0.5);
    return 0;
}
