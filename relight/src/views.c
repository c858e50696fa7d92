/*
 * views.c - the estimator that replaces leaves where leaves are the wrong
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

#include "method.h"

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
    double leaf_sr = 2.0 * RL_PI / (4.0 * n * n);
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
        if (n == SIZE_MAX) {
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
 * wasted on directions that miss the emitter. */
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
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            rl_origin_domain dom;
            rl_visibility vis = (rl_visibility)s->vis[(size_t)(j - t->row0) * m->nu + i];
            if (cell < 0 || vis == VIS_BLOCKED)
                continue; /* in full shadow: rays would all be stopped, and the cell gets 0 */
            rl__cell_domain(m, (uint32_t)cell, &dom);
            lds_key key = rl__lds_make(ilf_hash_mix(rl__pair_key(ctx, ei, t->map_index), (uint64_t)cell));
            /* a light field lights the cell from part of its slab at most: the rest reads zero, unlooked */
            double lit[4];
            int bounded = e->kind == EM_SLAB ? cell_lit_rect(m, &dom, e, sp, (uint32_t)p->ns, lit) : 0;
            if (bounded < 0)
                continue; /* dark toward the whole cell: it gets 0 */
            /* the emitter this cell samples: the pair's, or its part the rectangle holds, which carries all
             * the light that can reach the cell (the estimator is the same on either) */
            const v3 *eq = p->sclip;
            size_t neq = p->ns;
            const rl_polygon_sampler *points = &emitter_points;
            v3 part[RL_MAX_POLY_VERTS + 6];
            v2 lp[RL_MAX_POLY_VERTS + 6]; /* part_points reads it */
            rl_polygon_sampler part_points;
            if (bounded) {
                v2 rect[4] = {{lit[0], lit[2]}, {lit[1], lit[2]}, {lit[1], lit[3]}, {lit[0], lit[3]}},
                   scratch[RL_MAX_POLY_VERTS + 6];
                neq = rl__clip_to_polygon(sp, p->ns, rect, 4, lp, scratch);
                if (neq < 3 || !(rl__polygon_area2(lp, (uint32_t)neq) > 0.0))
                    continue;
                for (size_t v = 0; v < neq; v++)
                    part[v] = frame_point(&e->frame, lp[v]);
                rl__polygon_sampler_init(&part_points, lp, (uint32_t)neq);
                eq = part, points = &part_points;
            }
            v3 centre = domain_centre(m, &dom);
            uint32_t nr = view_rays(ctx, eq, neq, centre);
            double all = 0.0, seen[3] = {0, 0, 0};
            if (vis == VIS_FREE && e->kind == EM_CONST) {
                /* wholly lit by a constant emitter: the rays would measure a visible fraction of exactly 1 */
                cnt->rays_free += nr;
                all = seen[0] = seen[1] = seen[2] = 1.0;
                nr = 0;
            }
            rl_ray_batch batch;
            batch.n = 0;
            cnt->samples += nr; /* counted once: a store per sample costs more than it says */
            for (uint32_t r = 0; r < nr; r++) {
                double u[4];
                rl__lds4(&key, r, u);
                v3 x = rl__domain_point(m, &dom, u[0], u[1]);
                v3 y = frame_point(&e->frame, rl__polygon_sampler_point(points, u[2], u[3]));
                v3 to = v3_sub(y, x);
                double dist = v3_len(to);
                if (!(dist > 0))
                    continue;
                to = v3_scale(to, 1.0 / dist);
                double cos_r = v3_dot(to, m->frame.n), cos_s = -v3_dot(to, e->frame.n);
                if (!(cos_r > 0) || !(cos_s > 0))
                    continue;
                double w = cos_r * cos_s / (dist * dist), l[3] = {w, w, w};
                all += w;
                if (e->kind != EM_CONST) {
                    /* a light field or a bounce: its radiance there, and no ray where it is dark */
                    double rad[3];
                    rl__emitter_radiance_at(e, frame_project(&e->frame, y), v3_scale(to, -1.0), rad);
                    if (!(rad[0] > 0 || rad[1] > 0 || rad[2] > 0))
                        continue;
                    for (int c = 0; c < 3; c++)
                        l[c] *= rad[c];
                }
                if (vis == VIS_FREE) {
                    /* every ray would arrive: add it as the batch would, in order */
                    for (int c = 0; c < 3; c++)
                        seen[c] += l[c];
                    cnt->rays_free++;
                    continue;
                }
                rl__batch_push(ctx, &batch, x, to, p->eps / fmax(cos_r, 1e-3), dist - p->eps / fmax(cos_s, 1e-3), l,
                               seen, cnt);
            }
            rl__batch_flush(ctx, &batch, cnt);
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
                    f += rl__polygon_lambert(x, m->frame.n, eq, neq);
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
