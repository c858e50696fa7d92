/*
 * lambert.c - the estimator that replaces leaves where leaves are the wrong
 * tool, for culled and its relatives: Lambert's formula times what sampling
 * alone can tell (rl__gather_lambert()).
 *
 * A constant emitter leaves nothing unknown but visibility: its unoccluded
 * irradiance is Lambert's closed form, so rays are spent on the visible
 * fraction alone. An emitter only a few solid angles of the partition
 * across (far, small, a sliver; RL_LAMBERT_LEAVES) would be missed by most
 * of the leaves aimed at it; for it, a light field's cell mean is
 * Lambert's formula (as if its radiance were 1) times the mean of
 * radiance * visibility over uniform points of the emitter weighted by
 * cos cos / r^2. Seen from afar
 * those weights vary little, so the mean is well estimated; a constant
 * emitter is the case where the radiance term is the constant itself. A
 * light field is first cut, per cell, to the rectangle of its slab outside
 * which it sends nothing toward the cell (rl__emitter_lit_rect()): the same
 * estimator on the part that holds all the cell's light, and no sample at
 * all where the slab is dark toward the cell.
 * Origins come from one low-discrepancy sequence per (seed, pass, emitter,
 * map, cell), so results are deterministic; they are exact where a cell is
 * wholly lit by a constant emitter or wholly in shadow, and consistent (a
 * ratio of two estimates) in between, which the white-furnace test bounds.
 * A light field's cells that no shadow can cross take its light
 * bilinearly from anchors a few cells apart, each measured as a cell would
 * be, with a sequence per (seed, pass, emitter, map, grid corner): there
 * the light is smooth (see Anchors below). Its cells that a shadow may
 * cross take the same unoccluded light times the visible share that their
 * rays measure, so a cell whose rays all arrive matches its free
 * neighbours exactly.
 *
 * Before any ray, the tile is split into blocks of cells, halving the
 * longer side, and the beam of segments from each block to the emitter is
 * classified exactly (shadow.h) against the polygons its parent's beam met:
 * a block that no polygon meets is FREE, one that a single polygon crosses
 * wholly is BLOCKED, and only PARTIAL blocks split further (down to
 * BLOCK_MIN_SQUARES). A BLOCKED cell gets 0 with no sample; a FREE cell
 * adds each ray's radiance as if it were traced (a constant emitter's cell
 * skips its samples: its visible fraction is 1); only PARTIAL cells trace.
 * So the rays go where shadows are, and the result is the rays' own except
 * at the scale of a ray's end offsets: where single precision would have
 * stopped a ray grazing a plane, or where a ray would have started (or
 * stopped) past an occluder closer than its offset (up to 1000 eps at
 * grazing angles), which the exact test counts.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "emitter_tree.h"
#include "mesh.h"
#include "method.h"
#include "point_gather.h"

/* @return the world point at the vertex mean of domain dom of map m: where a
 * cell's view of an emitter is measured. */
static v3 domain_centre(const rl_map *m, const rl_origin_domain *dom)
{
    v2 c = {0, 0};
    for (uint32_t i = 0; i < dom->n; i++)
        c = (v2){c.x + dom->poly[i].x / dom->n, c.y + dom->poly[i].y / dom->n};
    return frame_point(&m->frame, c);
}

/* Bounds where light field emitter e (frame polygon y, ny vertices) can light
 * domain dom of map m from (rl__emitter_lit_rect()). @return as it does. */
static int cell_lit_rect(const rl_map *m, const rl_origin_domain *dom, const rl_emitter *e, const v2 *y, uint32_t ny,
                         double r[4])
{
    v3 x[RL_MAX_POLY_VERTS + 8];
    for (uint32_t i = 0; i < dom->n; i++)
        x[i] = frame_point(&m->frame, dom->poly[i]);
    return rl__emitter_lit_rect(e, x, dom->n, y, ny, r);
}

/* @return how many origins the mean of Lambert's formula over a cell takes
 * (rl__gather_lambert()). The formula is smooth except near the
 * emitter's plane, where it falls to 0 with the distance to that plane;
 * its quasi-random mean's error was measured to fall as (cell size /
 * distance to the emitter's plane) / origins: 0.45% of the peak at 16
 * origins for 0.25 m cells 1 m under a 1 m emitter, 0.12% at 64; 0.98%
 * at 29 and 0.16% at 256 for cells 1 mm to 0.5 m under an emitter seen
 * edge-on. So the count follows that ratio, from k to 64 k. */
static uint32_t lambert_origins(const rl_pair *p, const rl_map *m, v3 centre, uint32_t k)
{
    double h = fabs(v3_dot(v3_sub(centre, p->e->frame.origin), p->e->frame.n));
    double want = 72.0 * k * m->cell / dmax(h, 1e-300);
    return want >= 64.0 * k ? 64 * k : want <= k ? k : (uint32_t)ceil(want);
}

/* @return the shadow rays a cell takes for pair p: k per solid angle of
 * partition_n that the emitter subtends from the cell's centre (at least
 * k, at most 64 k), so that k and partition_n keep their meaning of "how
 * finely light is resolved". */
static uint32_t view_rays(const rl_transfer_ctx *ctx, const v3 *q, size_t nq, v3 centre)
{
    uint32_t k = ctx->sampling->rays_per_solid_angle, n = ctx->sampling->partition_n;
    double leaf_sr = 2.0 * ILF_PI / (4.0 * n * n);
    v3 dir[RL_MAX_POLY_VERTS + 2];
    double om[RL_MAX_POLY_VERTS + 2];
    double leaves = ceil(rl__sph_fan(q, nq, centre, dir, om) / leaf_sr);
    return leaves >= 64.0 ? 64 * k : leaves <= 1.0 ? k : k * (uint32_t)leaves;
}

/* Blocks of cells are classified down to this many grid squares; below it
 * a block's rays cost less than telling its beam apart. */
#define BLOCK_MIN_SQUARES 16u
/* Deepest split of a tile into blocks, and the occluders one level's list holds. */
#define BLOCK_LEVELS 40
#define BLOCK_OCC_CAP 256u

/* What classify_block() shares down its splits. */
typedef struct block_walk {
    const rl_transfer_ctx *ctx;
    const rl_pair *p;
    const rl_tile *t;
    rl_scratch *s;
    rl_beam *beam;
} block_walk;

/* Marks grid squares [i0, i1) x [j0, j1) of the tile as vis. */
static void block_mark(const block_walk *w, uint32_t i0, uint32_t i1, uint32_t j0, uint32_t j1, rl_visibility vis)
{
    uint32_t nu = w->t->m->nu;
    for (uint32_t j = j0; j < j1; j++)
        memset(w->s->vis + (size_t)(j - w->t->row0) * nu + i0, (int)vis, i1 - i0);
}

/* @return 1 if one of the polygons that hid emitters from the whole tile (rl_scratch.reach_blockers, the
 * cull's), alone or at a corner, crosses every segment from block a (na) to the pair's emitter, by the
 * cull's test and margins (emitter_tree.h), which hold for the rays as traced. An emitter the cull kept
 * because it is hidden from part of the tile only is often hidden from most of its blocks by those walls,
 * which this finds without collecting the polygons of a beam that may cross rooms. */
static int hidden_by_tile_blockers(const block_walk *w, const v3 *a, size_t na)
{
    const rl_pair *p = w->p;
    for (size_t k = 0; k < w->s->nreach_blockers; k++)
        if (rl__occluders_blocks(w->ctx->occluders, w->s->reach_blockers[k], a, na, p->sclip, p->ns,
                                 RL_REACH_TOL_EPS * p->eps, RL_REACH_EDGE_EPS * p->eps))
            return 1;
    return 0;
}

/* Classifies the segments from grid squares [i0, i1) x [j0, j1) of the tile
 * (clipped to its polygon) to the pair's emitter, given a superset of the
 * polygons meeting them (list, n; SIZE_MAX: unknown), and marks each square
 * FREE, BLOCKED or, where it stays undecided, PARTIAL. A PARTIAL block is
 * split in two across its longer side with the polygons found to meet it. */
static void classify_block(const block_walk *w, uint32_t i0, uint32_t i1, uint32_t j0, uint32_t j1,
                           const uint32_t *list, size_t n, int depth)
{
    const rl_map *m = w->t->m;
    v2 sq[4] = {{m->u0 + i0 * m->cell, m->v0 + j0 * m->cell},
                {m->u0 + i1 * m->cell, m->v0 + j0 * m->cell},
                {m->u0 + i1 * m->cell, m->v0 + j1 * m->cell},
                {m->u0 + i0 * m->cell, m->v0 + j1 * m->cell}};
    v2 clip[RL_MAX_POLY_VERTS + 8], tmp[RL_MAX_POLY_VERTS + 8];
    size_t nc = rl__clip_to_polygon(sq, 4, w->t->poly, w->t->npoly, clip, tmp);
    v3 a[RL_MAX_POLY_VERTS + 8];
    for (size_t k = 0; k < nc; k++)
        a[k] = frame_point(&m->frame, clip[k]);
    rl_visibility vis = VIS_PARTIAL;
    uint32_t *mine = w->s->block_occ + (size_t)depth * BLOCK_OCC_CAP;
    size_t nmine = SIZE_MAX;
    if (nc >= 3 && depth + 1 < BLOCK_LEVELS && rl__beam_make(a, nc, w->p->sclip, w->p->ns, w->p->eps, w->beam)) {
        const rl_occluders *occ = w->ctx->occluders;
        if (n == SIZE_MAX && hidden_by_tile_blockers(w, a, nc)) {
            vis = VIS_BLOCKED;
        } else if (n == SIZE_MAX) {
            uint32_t *found = w->s->block_occ + (size_t)(BLOCK_LEVELS - 1) * BLOCK_OCC_CAP;
            size_t nf = rl__occluders_collect(occ, w->beam, w->p->e->polygon, found, BLOCK_OCC_CAP);
            if (nf != SIZE_MAX)
                vis = rl__occluders_classify(occ, w->beam, found, nf, mine, &nmine);
        } else {
            vis = rl__occluders_classify(occ, w->beam, list, n, mine, &nmine);
        }
    }
    if (vis != VIS_PARTIAL || (size_t)(i1 - i0) * (j1 - j0) <= BLOCK_MIN_SQUARES || nc < 3 ||
        depth + 2 >= BLOCK_LEVELS) {
        block_mark(w, i0, i1, j0, j1, vis);
        return;
    }
    if (i1 - i0 >= j1 - j0) {
        uint32_t mid = i0 + (i1 - i0) / 2;
        classify_block(w, i0, mid, j0, j1, mine, nmine, depth + 1);
        classify_block(w, mid, i1, j0, j1, mine, nmine, depth + 1);
    } else {
        uint32_t mid = j0 + (j1 - j0) / 2;
        classify_block(w, i0, i1, j0, mid, mine, nmine, depth + 1);
        classify_block(w, i0, i1, mid, j1, mine, nmine, depth + 1);
    }
}

/* Fills s->vis with each grid square's view of the pair's emitter (squares
 * without a cell get whatever their block got). @return 0, or -1 without memory. */
static int classify_tile(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, rl_scratch *s)
{
    size_t squares = (size_t)t->m->nu * (t->row1 - t->row0);
    if (squares > s->vis_cap) {
        uint8_t *grown = realloc(s->vis, squares);
        if (!grown)
            return -1;
        s->vis = grown;
        s->vis_cap = squares;
    }
    if (!s->block_occ && !(s->block_occ = malloc((size_t)BLOCK_LEVELS * BLOCK_OCC_CAP * sizeof *s->block_occ)))
        return -1;
    if (!s->beam && !(s->beam = malloc(sizeof *s->beam)))
        return -1;
    block_walk w = {ctx, p, t, s, s->beam};
    classify_block(&w, 0, t->m->nu, t->row0, t->row1, NULL, SIZE_MAX, 0);
    return 0;
}

/* The part of a pair's emitter that a receiver samples: all of it, or where it can light the receiver from. */
typedef struct emitter_part {
    const v3 *q; /* world polygon, n vertices */
    size_t n;
    const rl_polygon_sampler *points; /* its sampler, in the emitter's frame */
    v3 part[RL_MAX_POLY_VERTS + 6];
    v2 lp[RL_MAX_POLY_VERTS + 6];
    rl_polygon_sampler part_points; /* points into lp: never copy a part */
} emitter_part;

/* Makes ep the pair's emitter (frame polygon sp, sampler whole), or with
 * bounded set its part within rectangle lit = {s0, s1, t0, t1} of its
 * frame, which carries all the light that can reach the receiver (the
 * estimator is the same on either). @return 1, or 0 if that part is empty. */
static int part_make(const rl_pair *p, const v2 *sp, const rl_polygon_sampler *whole, int bounded, const double lit[4],
                     emitter_part *ep)
{
    ep->q = p->sclip, ep->n = p->ns, ep->points = whole;
    if (!bounded)
        return 1;
    v2 rect[4] = {{lit[0], lit[2]}, {lit[1], lit[2]}, {lit[1], lit[3]}, {lit[0], lit[3]}}, scratch[RL_MAX_POLY_VERTS + 6];
    size_t n = rl__clip_to_polygon(sp, p->ns, rect, 4, ep->lp, scratch);
    if (n < 3 || !(rl__polygon_area2(ep->lp, (uint32_t)n) > 0.0))
        return 0;
    for (size_t v = 0; v < n; v++)
        ep->part[v] = frame_point(&p->e->frame, ep->lp[v]);
    rl__polygon_sampler_init(&ep->part_points, ep->lp, (uint32_t)n);
    ep->q = ep->part, ep->n = n, ep->points = &ep->part_points;
    return 1;
}

/* One emitter point as receiver point x on map m sees it. */
typedef struct view_sample {
    v3 to;               /* unit, from x to the point */
    double dist, cos_r, cos_s;
    double w;            /* cos_r cos_s / dist^2 */
    double l[3];         /* w times the radiance leaving the point toward x */
} view_sample;

/* Weighs world point y of emitter e seen from x on map m into vs. @return 0
 * if it does not count (x's own point, or either surface facing away), 1 if
 * it counts with no light (a light field or bounce dark there, read without
 * a ray), 2 with light. */
static inline int view_weigh(const rl_emitter *e, const rl_map *m, v3 x, v3 y, view_sample *vs)
{
    v3 to = v3_sub(y, x);
    double dist = v3_len(to);
    if (!(dist > 0))
        return 0;
    to = v3_scale(to, 1.0 / dist);
    double cos_r = v3_dot(to, m->frame.n), cos_s = -v3_dot(to, e->frame.n);
    if (!(cos_r > 0) || !(cos_s > 0))
        return 0;
    double w = cos_r * cos_s / (dist * dist);
    vs->to = to, vs->dist = dist, vs->cos_r = cos_r, vs->cos_s = cos_s, vs->w = w;
    vs->l[0] = vs->l[1] = vs->l[2] = w;
    if (e->kind != EM_CONST) {
        double rad[3];
        rl__emitter_radiance_at(e, frame_project(&e->frame, y), v3_scale(to, -1.0), rad);
        if (!(rad[0] > 0 || rad[1] > 0 || rad[2] > 0))
            return 1;
        for (int c = 0; c < 3; c++)
            vs->l[c] *= rad[c];
    }
    return 2;
}

/* Adds to *all the weights w, to seen the weighted radiance l * V and (unless
 * NULL) to unocc the weighted radiance l of samples r0 .. nr - 1 of emitter
 * part ep, point r of the sequence of key drawing its
 * emitter point from ep's sampler (coordinates 0 and 1, the sequence's
 * most even pair: at a few dozen points bases 5 and 7 still fall on lines,
 * and the light varies more over the emitter than over a cell) and its
 * origin from dom (coordinates 2 and 3; NULL: every origin is x0). Where vis is
 * VIS_FREE every ray arrives and none is traced; otherwise the rays go out
 * through batch, which adds them to seen as they arrive (the caller flushes). */
static void view_sums(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_map *m, const rl_origin_domain *dom,
                      v3 x0, const emitter_part *ep, const lds_key *key, uint32_t r0, uint32_t nr, rl_visibility vis,
                      rl_ray_batch *batch, double *all, double seen[3], double unocc[3], rl_counters *cnt)
{
    const rl_emitter *e = p->e;
    cnt->samples += nr - r0; /* counted once: a store per sample costs more than it says */
    for (uint32_t r = r0; r < nr; r++) {
        double u[4];
        rl__lds4(key, r, u);
        v3 x = dom ? rl__domain_point(m, dom, u[2], u[3]) : x0;
        v2 y = rl__polygon_sampler_point(ep->points, u[0], u[1]);
        view_sample vs;
        int got = view_weigh(e, m, x, frame_point(&e->frame, y), &vs);
        if (got == 0)
            continue;
        *all += vs.w;
        if (got == 1)
            continue;
        if (unocc)
            for (int c = 0; c < 3; c++)
                unocc[c] += vs.l[c];
        if (vis == VIS_FREE) {
            /* every ray would arrive: add it as the batch would, in order */
            for (int c = 0; c < 3; c++)
                seen[c] += vs.l[c];
            cnt->rays_free++;
            continue;
        }
        rl__batch_push(ctx, batch, x, vs.to, p->eps / fmax(vs.cos_r, 1e-3), vs.dist - p->eps / fmax(vs.cos_s, 1e-3),
                       vs.l, seen, cnt);
    }
}

/*
 * Anchors: a light field's light on cells that see all of it (VIS_FREE).
 * There the cell's light is the slab's unoccluded irradiance, a function
 * of the receiving point that varies no faster than the slab's radiance
 * varies with direction: moving a point by r / n (r its distance to the
 * slab, n the slab's partition) moves each of its directions to the slab
 * by about one cell of the partition, over which lfio interpolates
 * linearly. So it is measured at anchors, grid corners `stride` cells
 * apart, each with the samples a cell would take (Lambert's formula at the
 * point times the weighted mean radiance over its lit part of the slab),
 * and such cells get it bilinearly between the four anchors around their
 * centre. An anchor's sequence is keyed by its grid corner alone, so
 * lattices of different strides (neighbouring tiles may choose different
 * ones) agree where they meet, and nothing depends on the thread count.
 * Cells that a shadow may cross take the same blend times the visible share
 * that their own rays measure (rl__gather_lambert()).
 */

/* The fewest anchors per cell of a slab's partition that the directions from a receiver to the slab sweep
 * (anchor_stride()): lfio interpolates linearly across a cell, and bilinear anchors a third of one apart
 * follow that to about 1 / 18 of its bend. */
#define ANCHORS_PER_SQUARE 3.0
/* The widest stride anchor_stride() chooses: past it a tile has too few anchor rows to save much. */
#define ANCHOR_MAX_STRIDE 16u
/* Mixed into anchors' keys: their sequences are apart from the cells' (keyed by cell index alone). */
#define ANCHOR_KEY_TAG 0x616e63686f72ull

/* The anchors of one (pair, tile). */
typedef struct anchor_grid {
    uint32_t stride;    /* cells between anchors; < 2: none, every cell is sampled */
    uint32_t row0;      /* the tile's first anchor row on the map's lattice */
    uint32_t na, nb;    /* anchors per row, rows */
    uint64_t key;       /* the pair's anchor key: each anchor's sequence mixes in its grid corner */
    double (*value)[3]; /* NaN in [0]: not measured yet */
} anchor_grid;

/* @return the distance from world point c to tile t's polygon. */
static double tile_distance(const rl_tile *t, v3 c)
{
    const rl_map *m = t->m;
    v2 q = frame_project(&m->frame, c);
    double z = v3_dot(v3_sub(c, m->frame.origin), m->frame.n), d2 = INFINITY;
    if (rl__convex_contains(t->poly, t->npoly, q))
        return fabs(z);
    for (size_t k = 0; k < t->npoly; k++) {
        v2 a = t->poly[k], b = t->poly[(k + 1) % t->npoly], ab = {b.x - a.x, b.y - a.y}, aq = {q.x - a.x, q.y - a.y};
        double len2 = ab.x * ab.x + ab.y * ab.y, s = len2 > 0 ? (ab.x * aq.x + ab.y * aq.y) / len2 : 0.0;
        s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
        double dx = aq.x - s * ab.x, dy = aq.y - s * ab.y;
        d2 = dmin(d2, dx * dx + dy * dy);
    }
    return sqrt(d2 + z * z);
}

/* @return the cells between the anchors of pair p on tile t (anchor_stride; 0: chosen, 1: none). */
static uint32_t anchor_stride(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t)
{
    const rl_emitter *e = p->e;
    const rl_map *m = t->m;
    /* a light field seen from a polygon's cells; a point receiver is one cell of its own */
    if (e->kind != EM_SLAB || m->polygon < 0 || t->npoly < 3 || p->ns < 3)
        return 1;
    if (ctx->sampling->anchor_stride > 0)
        return ctx->sampling->anchor_stride;
    /* A lower bound on the distance from the tile to the emitter's part in front of it: the larger of
     * the distance to its plane and to the sphere around that part. Anchors lie up to sqrt 2 strides
     * beyond the tile, so a stride s needs s (ANCHORS_PER_SQUARE n + 1.5) cells within that distance.
     * Lambert's formula bends over the distance itself: n is taken as at least 4, which keeps bilinear
     * anchors within 0.4% of it. */
    double h = INFINITY;
    for (size_t k = 0; k < t->npoly; k++)
        h = dmin(h, v3_dot(v3_sub(frame_point(&m->frame, t->poly[k]), e->frame.origin), e->frame.n));
    v3 c = rl__pair_centroid(p);
    double radius = 0.0;
    for (size_t k = 0; k < p->ns; k++)
        radius = dmax(radius, v3_len(v3_sub(p->sclip[k], c)));
    double r = dmax(h, tile_distance(t, c) - radius);
    double n = e->lf->n > 4 ? (double)e->lf->n : 4.0;
    double cells = r / ((ANCHORS_PER_SQUARE * n + 1.5) * m->cell);
    return cells >= ANCHOR_MAX_STRIDE ? ANCHOR_MAX_STRIDE : cells >= 2.0 ? (uint32_t)cells : 1;
}

/* Sets up g for pair p (emitter ei) on tile t, with no anchor measured. @return 0, or -1 without memory. */
static int anchors_make(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, uint32_t ei, rl_scratch *s,
                        anchor_grid *g)
{
    g->stride = anchor_stride(ctx, p, t);
    if (g->stride < 2)
        return 0;
    const rl_map *m = t->m;
    uint32_t stride = g->stride;
    g->na = (m->nu + stride - 1) / stride + 1;
    g->row0 = t->row0 / stride;
    g->nb = (t->row1 + stride - 1) / stride + 1 - g->row0;
    size_t n = (size_t)g->na * g->nb;
    double(*grown)[3] = rl__grow(s->anchor, &s->anchor_cap, n, sizeof *grown);
    if (!grown)
        return -1;
    s->anchor = grown;
    g->value = grown;
    for (size_t k = 0; k < n; k++)
        g->value[k][0] = NAN;
    g->key = ilf_hash_mix(rl__pair_key(ctx, ei, t->map_index), ANCHOR_KEY_TAG);
    return 0;
}

/* Measures into out the anchor at grid corner (i, j) of map m: Lambert's
 * formula there times the mean of radiance weighted by cos cos / r^2 over
 * view_rays() uniform points of the part of the emitter (frame polygon sp,
 * sampler whole) that can light it, as a free cell's estimate with every
 * origin at the corner; 0 behind the slab or where it is dark toward the point. */
static void anchor_measure(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_map *m, const anchor_grid *g,
                           uint32_t i, uint32_t j, const v2 *sp, const rl_polygon_sampler *whole, double out[3],
                           rl_counters *cnt)
{
    const rl_emitter *e = p->e;
    out[0] = out[1] = out[2] = 0.0;
    v3 x = frame_point(&m->frame, (v2){m->u0 + (double)i * m->cell, m->v0 + (double)j * m->cell});
    if (!(v3_dot(v3_sub(x, e->frame.origin), e->frame.n) > 0))
        return;
    double lit[4];
    int bounded = rl__emitter_lit_rect(e, &x, 1, sp, (uint32_t)p->ns, lit);
    emitter_part ep;
    if (bounded < 0 || !part_make(p, sp, whole, bounded, lit, &ep))
        return;
    lds_key key = rl__lds_make(ilf_hash_mix(g->key, (uint64_t)j * (m->nu + 1) + i));
    double all = 0.0, seen[3] = {0, 0, 0};
    view_sums(ctx, p, m, NULL, x, &ep, &key, 0, view_rays(ctx, ep.q, ep.n, x), VIS_FREE, NULL, &all, seen, NULL, cnt);
    if (!(all > 0) || !(seen[0] > 0 || seen[1] > 0 || seen[2] > 0))
        return;
    double f = rl__polygon_lambert(x, m->frame.n, ep.q, ep.n);
    for (int c = 0; c < 3; c++)
        out[c] = f > 0 ? f * (seen[c] / all) : 0.0;
}

/* Sets out to the unoccluded light at cell of map m from g's anchors,
 * bilinearly at the cell's centroid (as bounces interpolate,
 * rl__map_interpolate()), measuring those not measured yet. */
static void anchors_blend(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_map *m, anchor_grid *g,
                          uint32_t cell, const v2 *sp, const rl_polygon_sampler *whole, double out[3],
                          rl_counters *cnt)
{
    const rl_cell c = rl__map_cell(m, cell);
    double gx = c.i + 0.5, gy = c.j + 0.5; /* in grid squares */
    if (c.clipped) {
        v2 centre = rl__map_cell_centroid(m, cell, NULL);
        gx = (centre.x - m->u0) / m->cell, gy = (centre.y - m->v0) / m->cell;
    }
    double fa = gx / g->stride, fb = gy / g->stride;
    double col = floor(fa), row = floor(fb);
    /* clamped to the lattice (a centre lies within its square, so only rounding can go past) */
    col = !(col >= 0.0) ? 0.0 : col > g->na - 2.0 ? g->na - 2.0 : col;
    row = !(row >= g->row0) ? g->row0 : row > g->row0 + g->nb - 2.0 ? g->row0 + g->nb - 2.0 : row;
    double wa = fa - col, wb = fb - row;
    wa = !(wa >= 0.0) ? 0.0 : wa > 1.0 ? 1.0 : wa;
    wb = !(wb >= 0.0) ? 0.0 : wb > 1.0 ? 1.0 : wb;
    out[0] = out[1] = out[2] = 0.0;
    for (int k = 0; k < 4; k++) {
        uint32_t a = (uint32_t)col + (k & 1), b = (uint32_t)row + (k >> 1);
        double w = (k & 1 ? wa : 1.0 - wa) * (k >> 1 ? wb : 1.0 - wb);
        double *v = g->value[(size_t)(b - g->row0) * g->na + a];
        if (isnan(v[0]))
            anchor_measure(ctx, p, m, g, a * g->stride, b * g->stride, sp, whole, v, cnt);
        for (int ch = 0; ch < 3; ch++)
            out[ch] += w * v[ch];
    }
}

/* With anchors, a cell that a shadow may cross traces this share of its rays
 * first (at least CELL_STAGE_MIN), and the rest only if those disagree:
 * where all arrive or all are stopped, the cell is taken to be wholly lit
 * or wholly in shadow. On the light-field classroom at 1.3 M cells, 57% of
 * such cells were one or the other; stopping them early costs about 0.03%
 * of the light in penumbrae that the first rays missed, and a third of the
 * rays. */
#define CELL_STAGE_DIVISOR 3u
#define CELL_STAGE_MIN 6u

/* Adds to *all, seen and (unless NULL) unocc the sums of view_sums() over
 * nr samples of part ep for a cell (domain dom, centre x0), tracing their
 * rays unless vis is VIS_FREE. With unocc (a control variate: only the
 * fraction of light that arrives is wanted) the samples come in two stages
 * (CELL_STAGE_DIVISOR), the second skipped where the first one's rays all
 * arrived or were all stopped. */
static void cell_rays(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_map *m, const rl_origin_domain *dom, v3 x0,
                      const emitter_part *ep, const lds_key *key, uint32_t nr, rl_visibility vis, double unocc[3],
                      double *all, double seen[3], rl_counters *cnt)
{
    rl_ray_batch batch;
    batch.n = 0;
    uint32_t n1 = nr;
    if (unocc && vis != VIS_FREE) {
        n1 = (nr + CELL_STAGE_DIVISOR - 1) / CELL_STAGE_DIVISOR;
        n1 = n1 < CELL_STAGE_MIN ? CELL_STAGE_MIN : n1;
        n1 = n1 > nr ? nr : n1; /* never more than the cell's own rays */
    }
    uint64_t cast0 = cnt->rays_cast, kept0 = cnt->rays_kept;
    view_sums(ctx, p, m, dom, x0, ep, key, 0, n1, vis, &batch, all, seen, unocc, cnt);
    rl__batch_flush(ctx, &batch, cnt);
    uint64_t cast = cnt->rays_cast - cast0, kept = cnt->rays_kept - kept0;
    /* no ray yet (the first samples all read dark) says nothing: go on */
    if (n1 < nr && (cast == 0 || (kept > 0 && kept < cast))) {
        view_sums(ctx, p, m, dom, x0, ep, key, n1, nr, vis, &batch, all, seen, unocc, cnt);
        rl__batch_flush(ctx, &batch, cnt);
    }
}

/* Transfer from emitter ei to every cell of the tile: Lambert's formula
 * averaged over lambert_origins() origins of the cell, times the mean of
 * radiance * visibility over shadow rays to uniform points of the emitter
 * (clipped to the receiver's front) weighted by cos cos / r^2, view_rays()
 * of them (for a constant emitter, its radiance times the fraction of light
 * that arrives). No ray is traced where a light field or a bounce map is
 * dark, and Lambert's mean (the costlier half) is taken only where some
 * light arrived: a cell in shadow or facing a dark light field gets its
 * exact 0 from the rays alone. For a constant emitter: unoccluded cells
 * get Lambert's field, cells in full shadow exactly 0: rays are spent on
 * visibility alone, which is all a constant emitter leaves unknown. A
 * ratio of two estimates is consistent rather than unbiased (by O(1 / rays)
 * in a penumbra; the white-furnace test bounds it); Lambert minus the sampled loss would be unbiased, but it
 * dips below zero in shadows. The solid angles play no part: no sample is
 * wasted on directions that miss the emitter. A light field's cells that
 * see all of it take their light from anchors instead, where it is smooth;
 * where anchors are, a cell that a shadow may cross takes their light times
 * the share of its samples' weighted radiance whose rays arrive (a control
 * variate: the radiance's variation over the slab cancels, leaving only
 * visibility to the rays), in two stages (cell_rays()). */
int rl__gather_lambert(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, uint32_t ei, rl_scratch *s,
                       rl_counters *cnt)
{
    rl_map *m = t->m;
    if (classify_tile(ctx, p, t, s) != 0)
        return -1;
    const rl_emitter *e = p->e;
    uint32_t k = ctx->sampling->rays_per_solid_angle;
    v2 sp[RL_MAX_POLY_VERTS + 2];
    for (size_t i = 0; i < p->ns; i++)
        sp[i] = frame_project(&e->frame, p->sclip[i]);
    rl_polygon_sampler emitter_points;
    rl__polygon_sampler_init(&emitter_points, sp, (uint32_t)p->ns);
    anchor_grid anchors = {0};
    if (anchors_make(ctx, p, t, ei, s, &anchors) != 0)
        return -1;
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = rl__map_grid_cell(m, i, j);
            rl_origin_domain dom;
            rl_visibility vis = (rl_visibility)s->vis[(size_t)(j - t->row0) * m->nu + i];
            if (cell < 0 || vis == VIS_BLOCKED)
                continue; /* in full shadow: rays would all be stopped, and the cell gets 0 */
            double blend[3] = {0, 0, 0};
            if (anchors.stride > 1) {
                anchors_blend(ctx, p, m, &anchors, (uint32_t)cell, sp, &emitter_points, blend, cnt);
                if (vis == VIS_FREE) {
                    for (int ch = 0; ch < 3; ch++)
                        m->e_pass[cell][ch] += blend[ch];
                    continue;
                }
                if (!(blend[0] > 0 || blend[1] > 0 || blend[2] > 0))
                    continue; /* the slab sends the cell nothing, occluded or not */
            }
            rl__cell_domain(m, (uint32_t)cell, &dom);
            lds_key key = rl__lds_make(ilf_hash_mix(rl__pair_key(ctx, ei, t->map_index), (uint64_t)cell));
            /* a light field lights the cell from part of its slab at most: the rest reads zero, unlooked */
            double lit[4];
            int bounded = e->kind == EM_SLAB ? cell_lit_rect(m, &dom, e, sp, (uint32_t)p->ns, lit) : 0;
            emitter_part ep;
            if (bounded < 0 || !part_make(p, sp, &emitter_points, bounded, lit, &ep))
                continue; /* dark toward the whole cell: it gets 0 */
            v3 centre = domain_centre(m, &dom);
            uint32_t nr = view_rays(ctx, ep.q, ep.n, centre);
            double all = 0.0, seen[3] = {0, 0, 0}, unocc[3] = {0, 0, 0};
            if (vis == VIS_FREE && e->kind == EM_CONST) {
                /* wholly lit by a constant emitter: the rays would measure a visible fraction of exactly 1 */
                cnt->rays_free += nr;
                all = seen[0] = seen[1] = seen[2] = 1.0;
                nr = 0;
            }
            cell_rays(ctx, p, m, &dom, centre, &ep, &key, nr, vis, anchors.stride > 1 ? unocc : NULL, &all, seen, cnt);
            if (anchors.stride > 1) {
                /* the anchors' unoccluded light times the share of it that the rays saw arrive */
                for (int ch = 0; ch < 3; ch++)
                    m->e_pass[cell][ch] += unocc[ch] > 0 ? blend[ch] * (seen[ch] / unocc[ch]) : 0.0;
                continue;
            }
            /* no light arrives (shadow, or a light field dark toward the cell): the cell gets exactly 0,
             * and Lambert's mean, the costlier half, is not needed */
            if (!(all > 0) || !(seen[0] > 0 || seen[1] > 0 || seen[2] > 0))
                continue;
            uint32_t no = lambert_origins(p, m, centre, k);
            double f = 0.0;
            for (uint32_t o = 0; o < no; o++) {
                double u[4];
                rl__lds4(&key, o, u);
                /* the emitter clipped to the tile's plane is the same for every origin on it */
                v3 x = rl__domain_point(m, &dom, u[0], u[1]);
                if (v3_dot(v3_sub(x, e->frame.origin), e->frame.n) > 0)
                    f += rl__polygon_lambert(x, m->frame.n, ep.q, ep.n);
            }
            if (!(f > 0))
                continue;
            /* a constant emitter: its radiance times Lambert's mean times the fraction that arrived;
             * otherwise Lambert's mean times the weighted mean of radiance * visibility */
            for (int ch = 0; ch < 3; ch++)
                m->e_pass[cell][ch] += e->kind == EM_CONST ? e->emission[ch] * (f / no * fmin(seen[0] / all, 1.0))
                                                           : f / no * (seen[ch] / all);
        }
    return 0;
}
