/*
 * emitter.c - setting up emitters and reading the radiance they send.
 *
 * A constant polygon takes a frame on its first edge; a bounce emitter takes
 * the receiving map's own frame, so that frame coordinates index its cells;
 * a light field takes the slab's (u, v) edges, normalised, so that frame
 * coordinates divided by the edge lengths are the slab's positions. The
 * radiance read here is the general path: a light field interpolated in
 * direction through the slab's own rotation. Leaves that nest in the slab's
 * partition read it faster through rl__leaf_radiance_mix() (leaf.c).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <lfio/partition.h>

#include "emitter.h"

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

void rl__emitter_from_lightfield(const rl_lightfield *lf, const rl_slab_tables *tab, rl_emitter *e)
{
    memset(e, 0, sizeof *e);
    e->kind = EM_SLAB;
    e->polygon = -1;
    e->lf = lf;
    e->tab = tab;
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

void rl__emitter_radiance_at(const rl_emitter *e, v2 q, v3 d, double out[3])
{
    switch (e->kind) {
    case EM_CONST:
        for (int c = 0; c < 3; c++)
            out[c] = e->emission[c];
        return;
    case EM_MAP:
        rl__map_radiance(e->map, rl__map_cell_at(e->map, q), out);
        return;
    case EM_SLAB: {
        /* where no tap is lit along d's square of the diamond, lfio would mix zeros: 0 without the lookup */
        double l2 = v3_dot(d, e->frame.n);
        if (l2 > 0.0 && rl__emitter_dark_at(e, q, v3_dot(d, e->frame.e1), v3_dot(d, e->frame.e2), l2)) {
            out[0] = out[1] = out[2] = 0.0;
            return;
        }
        float rgb[3] = {0, 0, 0};
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

/* ------------------------------------------------ where a light field is lit
 *
 * Seen from a small receiver, a light field is often dark over most of its
 * slab: what reaches the receiver leaves along the few directions of the cone
 * from the slab to it, and each direction is lit over part of the positions
 * alone. rl__emitter_lit_rect() bounds that part. Directions are placed on
 * the slab's diamond, (a, b) = (l0, l1) / |l|_1 for l in the slab's frame
 * with l2 > 0, where the partition's lattice is a grid of unit squares of
 * side 1/n, each cut by its diagonal into two triangles. A table built once
 * per slab holds, for every square, the positions its two triangles and
 * their interpolation neighbours read (what lfio_slab_radiance_interp()
 * mixes anywhere in it); a cone's box of squares gives the union. */

/* Calls visit(ctx, id) for each stored direction that lfio mixes somewhere in square (ia, ib) of the
 * diamond of a slab of partition n with ndir stored directions: its triangles and their neighbours. */
static void square_directions(uint32_t n, uint64_t ndir, uint32_t ia, uint32_t ib,
                              void (*visit)(void *ctx, uint64_t id), void *ctx)
{
    /* the square's lattice corner (xi, yi) in its quadrant, and the quadrant's signs */
    uint32_t xi = ia >= n ? ia - n : n - 1 - ia, yi = ib >= n ? ib - n : n - 1 - ib;
    double sx = ia >= n ? 1.0 : -1.0, sy = ib >= n ? 1.0 : -1.0;
    for (int t = 0; t < 2; t++) {
        /* centroids: the lower-left triangle, then the upper-right (inside the diamond only) */
        double cx = xi + (t ? 2.0 : 1.0) / 3.0, cy = yi + (t ? 2.0 : 1.0) / 3.0;
        if (cx + cy >= (double)n)
            continue;
        double d[3] = {sx * cx, sy * cy, (double)n - cx - cy};
        uint64_t ids[4];
        if (!lfio_part_id(n, d, &ids[0]) || !lfio_part_neighbours(n, ids[0], ids + 1))
            continue;
        for (int k = 0; k < 4; k++)
            if (ids[k] < ndir) /* one behind the slab: lfio gives its share to the triangle itself */
                visit(ctx, ids[k]);
    }
}

/* What square_directions() visits for: one square's box and bits, from the per-direction ones. */
typedef struct square_union {
    const rl_slab_tables *t;
    const uint64_t *dir_bits;
    uint32_t *box;
    uint64_t *bits;
} square_union;

static void square_add(void *ctx, uint64_t id)
{
    square_union *u = ctx;
    rl__box_union(u->box, u->t->support[id]);
    for (uint32_t w = 0; w < u->t->lit_words; w++)
        u->bits[w] |= u->dir_bits[id * u->t->lit_words + w];
}

int rl__slab_tables_make(const rl_lightfield *lf, rl_slab_tables *t)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(lf->slab);
    uint64_t ndir = lfio_slab_dir_count(lf->slab), npos = (uint64_t)d->nu * d->nv, side = 2 * (uint64_t)d->n;
    /* the squares' tables only while they stay small (the finest partitions would take gigabytes): 16 bytes
     * of box a square, a word of bits a square and a direction (as many) per 64 positions */
    uint64_t words = (npos + 63) / 64, squares = side * side * 16 <= RL_CONE_MAX_BYTES ? side * side : 0;
    t->support = malloc((ndir + squares) * sizeof *t->support);
    if (t->support == NULL)
        return -1;
    lfio_slab_support(lf->slab, t->support);
    t->cone_support = squares ? t->support + ndir : NULL;
    t->cone_bits = NULL;
    /* lit positions per square, for slabs of up to RL_LIT_MAX_POSITIONS positions (a word per 64) */
    int bits = squares && npos <= RL_LIT_MAX_POSITIONS && squares * words * 8 <= RL_CONE_MAX_BYTES;
    t->lit_words = bits ? (uint32_t)words : 0;
    uint64_t *dir_bits = NULL;
    if (t->lit_words) {
        t->cone_bits = calloc(side * side * t->lit_words, sizeof *t->cone_bits);
        dir_bits = calloc(ndir * t->lit_words, sizeof *dir_bits);
        if (t->cone_bits == NULL || dir_bits == NULL) {
            free(dir_bits);
            rl__slab_tables_free(t);
            return -1;
        }
        const float *rad = lfio_slab_radiance(lf->slab);
        for (uint64_t k = 0; k < ndir; k++)
            for (uint64_t q = 0; q < npos; q++) {
                const float *v = rad + (k * npos + q) * 3;
                if (v[0] != 0.0f || v[1] != 0.0f || v[2] != 0.0f)
                    dir_bits[k * t->lit_words + q / 64] |= (uint64_t)1 << (q % 64);
            }
    }
    for (uint32_t ib = 0; ib < side && squares; ib++)
        for (uint32_t ia = 0; ia < side; ia++) {
            size_t sq = (size_t)ib * side + ia;
            uint32_t *box = t->cone_support[sq];
            box[0] = box[2] = UINT32_MAX;
            box[1] = box[3] = 0;
            square_union u = {t, dir_bits, box, t->lit_words ? t->cone_bits + sq * t->lit_words : NULL};
            square_directions(d->n, ndir, ia, ib, square_add, &u);
            if (box[0] == UINT32_MAX)
                box[0] = 1, box[1] = 0;
        }
    free(dir_bits);
    return 0;
}

void rl__slab_tables_free(rl_slab_tables *t)
{
    free(t->support);
    free(t->cone_bits);
    t->support = t->cone_support = NULL;
    t->cone_bits = NULL;
    t->lit_words = 0;
}

rl_slab_tables *rl__slab_tables_new(const rl_scene *scene)
{
    size_t n = scene->nlightfields;
    rl_slab_tables *tables = calloc(n ? n : 1, sizeof *tables);
    for (size_t k = 0; tables && k < n; k++) {
        size_t first = 0;
        while (scene->lightfields[first].slab != scene->lightfields[k].slab)
            first++;
        if (first < k) {
            tables[k] = tables[first]; /* borrowed: an earlier emitter places the same slab */
            tables[k].owned = 0;
        } else if (rl__slab_tables_make(&scene->lightfields[k], &tables[k]) == 0) {
            tables[k].owned = 1;
        } else {
            rl__slab_tables_destroy(tables, k);
            tables = NULL;
        }
    }
    return tables;
}

void rl__slab_tables_destroy(rl_slab_tables *tables, size_t n)
{
    for (size_t k = 0; tables && k < n; k++)
        if (tables[k].owned)
            rl__slab_tables_free(&tables[k]);
    free(tables);
}

void rl__emitter_support_rect(const rl_emitter *e, const uint32_t b[4], double r[4])
{
    /* bilinear interpolation between position centres reaches half a position past the last nonzero
     * centre, and the border clamps */
    uint32_t nu = e->lf->nu, nv = e->lf->nv;
    r[0] = (b[0] == 0 ? 0.0 : (b[0] - 0.5) / nu) * e->len_u;
    r[1] = (b[1] + 1 >= nu ? 1.0 : (b[1] + 1.5) / nu) * e->len_u;
    r[2] = (b[2] == 0 ? 0.0 : (b[2] - 0.5) / nv) * e->len_v;
    r[3] = (b[3] + 1 >= nv ? 1.0 : (b[3] + 1.5) / nv) * e->len_v;
}

/* @return t / (|t| + 1): a diamond coordinate where the other one is 0, t being the direction's slope. */
static double diamond_axis(double t)
{
    return t / (fabs(t) + 1.0);
}

/* @return the index of the diamond's square column holding coordinate a of n, clamped. */
static uint32_t diamond_square(double a, uint32_t n)
{
    double g = floor((a + 1.0) * n);
    return g <= 0.0 ? 0 : g >= 2.0 * n - 1 ? 2 * n - 1 : (uint32_t)g;
}

int rl__emitter_lit_rect(const rl_emitter *e, const v3 *x, uint32_t nx, const v2 *y, uint32_t ny, double r[4])
{
    const rl_slab_tables *tab = e->tab;
    uint32_t n = e->lf->n;
    if (tab->cone_support == NULL)
        return 0;
    /* the box of the cone's image on the diamond: its extreme rays' images, and where the cone crosses
     * l0 = 0 or l1 = 0 (the image bends there), the range of the other coordinate on that plane, which
     * its slope's range over the extreme rays bounds */
    double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
    double su0 = INFINITY, su1 = -INFINITY, sv0 = INFINITY, sv1 = -INFINITY;
    int upos = 0, uneg = 0, vpos = 0, vneg = 0;
    for (uint32_t i = 0; i < nx; i++) {
        v3 rel = v3_sub(x[i], e->frame.origin);
        double xu = v3_dot(rel, e->frame.e1), xv = v3_dot(rel, e->frame.e2), h = v3_dot(rel, e->frame.n);
        if (!(h > 0.0) || !isfinite(h))
            return 0;
        for (uint32_t j = 0; j < ny; j++) {
            double du = xu - y[j].x, dv = xv - y[j].y, l1 = fabs(du) + fabs(dv) + h;
            double a = du / l1, b = dv / l1, su = du / h, sv = dv / h;
            /* comparisons, not fmin/fmax (calls here): no value is NaN, h > 0 being finite */
            a0 = a < a0 ? a : a0, a1 = a > a1 ? a : a1, b0 = b < b0 ? b : b0, b1 = b > b1 ? b : b1;
            su0 = su < su0 ? su : su0, su1 = su > su1 ? su : su1, sv0 = sv < sv0 ? sv : sv0, sv1 = sv > sv1 ? sv : sv1;
            upos |= du >= 0.0, uneg |= du <= 0.0, vpos |= dv >= 0.0, vneg |= dv <= 0.0;
        }
    }
    if (upos && uneg) {
        a0 = fmin(a0, 0.0), a1 = fmax(a1, 0.0);
        b0 = fmin(b0, diamond_axis(sv0)), b1 = fmax(b1, diamond_axis(sv1));
    }
    if (vpos && vneg) {
        b0 = fmin(b0, 0.0), b1 = fmax(b1, 0.0);
        a0 = fmin(a0, diamond_axis(su0)), a1 = fmax(a1, diamond_axis(su1));
    }
    if (!(a0 <= a1) || !(b0 <= b1))
        return 0;
    /* a margin for the slab's own frame (orthogonal to 1e-9) and lfio's rounding of the same direction */
    const double margin = 1e-6;
    uint32_t ia0 = diamond_square(a0 - margin, n), ia1 = diamond_square(a1 + margin, n);
    uint32_t ib0 = diamond_square(b0 - margin, n), ib1 = diamond_square(b1 + margin, n);
    if ((uint64_t)(ia1 - ia0 + 1) * (ib1 - ib0 + 1) > RL_CONE_MAX_SQUARES)
        return 0;
    uint32_t box[4] = {UINT32_MAX, 0, UINT32_MAX, 0};
    for (uint32_t ib = ib0; ib <= ib1; ib++)
        for (uint32_t ia = ia0; ia <= ia1; ia++)
            rl__box_union(box, tab->cone_support[(size_t)ib * 2 * n + ia]);
    if (box[0] == UINT32_MAX)
        return -1;
    rl__emitter_support_rect(e, box, r);
    return 1;
}
