/*
 * method_culled.c - culled solid-angle transfer, the paper's method, and
 * naive, its plain enumeration; and the leaf loop adaptive shares.
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
 * cell, level, leaf), except that a light field's leaf nested in its slab
 * draws its k directions once from its own key (rl__leaf_share()) and each
 * cell only its origins, at the same places in every cell (the leaf's key
 * again): neighbouring cells then read the slab at points one cell apart,
 * and their errors change smoothly from cell to cell instead of mottling. Those shared directions' rays are parallel, so
 * their visibility comes from the occluders' shadows along each direction
 * on the tile (leaf_shadow.c) rather than from Embree, wherever the shadows
 * can be worked out; both methods build them from the whole tile, so they
 * see the same ones.
 *
 * `naive` takes every leaf and every cell and otherwise runs the same code:
 * a culled (cell, leaf) pair contributes exactly zero, and each cell adds
 * its leaves in id order either way, so the two are bit-identical as long
 * as no pair descends below partition_n.
 *
 * Where leaves are the wrong tool, both hand the pair to lambert.c under
 * `descend`: a constant emitter gets Lambert's formula times visibility,
 * and so does an emitter fewer than RL_LAMBERT_LEAVES solid angles across
 * (times its weighted mean radiance); culled also hands over a pair that
 * descends (thinner than a solid angle), which naive keeps.
 */
#include <math.h>
#include <stdlib.h>

#include <lfio/lightfield.h>

#include "mesh.h"
#include "method.h"

#define STACK_DEPTH 512

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
static int walk(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, rl_scratch *s, rl_counters *cnt)
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
        if (dark || rl__node_region(ctx, p, p->sclip, p->ns, t, lv, id, reg, q) == 0)
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

/* rl__shoot_back() for shared direction i of L (planned, rl__leaf_plan())
 * from the origin at map coordinates uv of m, with what the origin does
 * not change worked out once; sh (NULL: unknown, trace a ray) gives the
 * direction's shadows on m. */
static inline void shoot_shared(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_map *m, const rl_leaf *L,
                                const rl_shadows *sh, uint32_t i, v2 uv, double *acc, rl_ray_batch *b,
                                rl_counters *cnt)
{
    const rl_shared_plan *pl = &L->plan[i];
    if (!pl->live)
        return;
    double t = pl->t[0] + pl->t[1] * uv.x + pl->t[2] * uv.y;
    if (!(t > 0))
        return;
    double l[3];
    if (L->blend) {
        double gu = pl->gu[0] + pl->gu[1] * uv.x + pl->gu[2] * uv.y, gv = pl->gv[0] + pl->gv[1] * uv.x + pl->gv[2] * uv.y;
        /* outside the blend's rectangle (which the slab holds) every tap reads 0 */
        if (!(gu >= L->grect[0] && gu <= L->grect[1] && gv >= L->grect[2] && gv <= L->grect[3]))
            return;
        if (sh && rl__shadowed(sh, i, uv))
            return;
        float rgb[3]; /* the scale is in the table */
        lfio_blend_at(&L->grid, L->blend + i * L->blend_stride, gu, gv, rgb);
        if (!(rgb[0] > 0 || rgb[1] > 0 || rgb[2] > 0))
            return;
        l[0] = rgb[0], l[1] = rgb[1], l[2] = rgb[2];
    } else {
        v2 q = {pl->qx[0] + pl->qx[1] * uv.x + pl->qx[2] * uv.y, pl->qy[0] + pl->qy[1] * uv.x + pl->qy[2] * uv.y};
        if (!rl__emitter_contains(p->e, q))
            return;
        if (sh && rl__shadowed(sh, i, uv))
            return;
        rl__leaf_radiance_weighted(p->e, q, L, L->swd[i], l);
        if (!(l[0] > 0 || l[1] > 0 || l[2] > 0))
            return;
        for (int c = 0; c < 3; c++)
            l[c] *= pl->scale;
    }
    if (sh) {
        /* the shadows are known: no ray */
        for (int c = 0; c < 3; c++)
            acc[c] += l[c];
        cnt->rays_free++;
        return;
    }
    rl__batch_push(ctx, b, frame_point(&m->frame, uv), pl->back, pl->tnear, t - pl->tshort, l, acc, cnt);
}

/* Queues the k rays of (cell, leaf L) into acc; sh (NULL: unknown) gives
 * the shadows of L's shared directions.
 * @return the factor that turns acc into the cell's irradiance (0: no rays). */
static double gather_cell(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, uint32_t cell,
                          const rl_leaf *L, const rl_shadows *sh, double *acc, rl_ray_batch *batch, rl_counters *cnt)
{
    rl_map *m = t->m;
    rl_origin_domain dom;
    uint32_t k = ctx->sampling->rays_per_solid_angle;
    if (L->nshared > 0 && L->nshared == k) {
        /* The leaf's shared directions (coordinates 0 and 1 of its own
         * sequence) with origins from coordinates 2 and 3 of the same
         * sequence, so that each cell's k pairs are the points of a shifted
         * 4-D sequence: the same two coordinates for both would tie each
         * direction to its origin, and a cell's error would stop falling
         * with k. Every cell takes the same origins within itself (one key
         * per leaf, not per cell): the demo's walls, lit directly, mottled
         * half as much again with a key per cell (docs/accuracy.md). A light field's leaf is blind (rl__leaf_draw() draws over
         * all of it whatever the origin), which is what lets cells share
         * its directions; shoot_shared() counts and drops what lands
         * behind or beside the emitter, as the draw would have. A whole
         * square cell needs no domain: its corner comes from its indices. */
        const rl_cell c = rl__map_cell(m, cell);
        int square = !c.clipped;
        v2 corner = {m->u0 + c.i * m->cell, m->v0 + c.j * m->cell};
        if (!square)
            rl__cell_domain(m, cell, &dom);
        lds_key key = rl__lds_make_last2(L->key); /* the same origins in every cell (above) */
        cnt->samples += k;
        for (uint32_t i = 0; i < k; i++) {
            double a = rl__lds_coord(&key, i, 2), b = rl__lds_coord(&key, i, 3);
            v2 uv = square ? (v2){corner.x + a * m->cell, corner.y + b * m->cell} : rl__domain_uv(m, &dom, a, b);
            shoot_shared(ctx, p, m, L, sh, i, uv, acc, batch, cnt);
        }
        return 1.0 / k;
    }
    rl__cell_domain(m, cell, &dom);
    lds_key key = rl__lds_make(ilf_hash_mix(L->key, cell));
    /* draw a group of samples before shooting any: their square roots and
     * divisions are independent and overlap, where one sample at a time
     * would wait for each */
    enum { GROUP = 8 };
    for (uint32_t i0 = 0; i0 < k; i0 += GROUP) {
        uint32_t g = k - i0 < GROUP ? k - i0 : GROUP;
        double w[GROUP], lam[GROUP][3];
        v3 x[GROUP], d[GROUP];
        const rl_leaf *lp[GROUP];
        int drawn[GROUP];
        for (uint32_t i = 0; i < g; i++) {
            double u[4];
            rl__lds4(&key, i0 + i, u);
            x[i] = rl__domain_point(m, &dom, u[0], u[1]);
            drawn[i] = rl__leaf_draw(p, L, x[i], u[2], u[3], &d[i], &w[i], lam[i], &lp[i]);
        }
        for (uint32_t i = 0; i < g; i++) {
            if (drawn[i])
                rl__shoot_back(ctx, p, x[i], m->frame.n, d[i], w[i], lp[i], lam[i], NULL, acc, batch, cnt);
            else
                cnt->samples++;
        }
    }
    return 1.0 / k;
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

/* Makes room in s for n floats of blend tables (rl__grow()). @return 0 or -1. */
static int blend_reserve(rl_scratch *s, size_t n)
{
    float *grown = rl__grow(s->blend, &s->blend_cap, n, sizeof *grown);
    if (!grown)
        return -1;
    s->blend = grown;
    return 0;
}

/* @return the current leaf's shadows when they are known (its shared directions need no rays), else NULL. */
static rl_shadows *rows_shadows(rl_scratch *s, const rl_leaf *L)
{
    return L->nshared > 0 && s->shadows && s->shadows->known ? s->shadows : NULL;
}

/* Culled's and naive's work on one row of cells for one leaf: every cell's
 * k rays go out in packets (or, where the leaf's shadows are known, its
 * samples are settled without rays), then each cell adds its estimate. */
static int culled_row(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, const rl_leaf *L, uint32_t ei,
                      uint32_t j, uint32_t i0, uint32_t i1, rl_scratch *s, int stage, rl_counters *cnt)
{
    (void)ei;
    (void)stage;
    rl_map *m = t->m;
    rl_ray_batch batch;
    batch.n = 0;
    rl_shadows *sh = rows_shadows(s, L);
    if (sh) {
        double va = m->v0 + j * m->cell;
        /* a hair wider than the row: a cell's clipped corner may round past its square, and culled
         * (which visits part of a row) must select every shadow naive does for the cells both visit */
        double pad = 1e-9 * m->cell;
        rl__shadows_row(sh, m->u0 + i0 * m->cell - pad, m->u0 + (i1 + 1.0) * m->cell + pad, va - pad,
                        va + m->cell + pad);
    }
    for (uint32_t i = i0; i <= i1; i++) {
        int32_t cell = rl__map_grid_cell(m, i, j);
        double *acc = s->row_acc[i - i0];
        acc[0] = acc[1] = acc[2] = 0.0;
        s->row_scale[i - i0] = cell < 0 ? 0.0 : gather_cell(ctx, p, t, (uint32_t)cell, L, sh, acc, &batch, cnt);
    }
    rl__batch_flush(ctx, &batch, cnt);
    for (uint32_t i = i0; i <= i1; i++) {
        int32_t cell = rl__map_grid_cell(m, i, j);
        for (int c = 0; cell >= 0 && c < 3; c++)
            m->e_pass[cell][c] += s->row_acc[i - i0][c] * s->row_scale[i - i0];
    }
    return 0;
}

/* Processes one kept leaf over the tile's cells, a row at a time, handing
 * each row's cells that the leaf's region covers (every cell when the method
 * does not cull) to rows->row. @return 0 or -1. */
static int gather_leaf(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, uint64_t id,
                       uint32_t emitter_index, const rl_leaf_rows *rows, rl_region *reg, v2 *q, rl_scratch *s,
                       int stage, rl_counters *cnt)
{
    rl_map *m = t->m;
    int culled = rows->culls;
    rl_leaf L;
    rl__leaf_make(ctx, p->e, emitter_index, t->map_index, p->level, id, &L);
    size_t nq = 0;
    /* The leaf's region on the tile: where its directions can see the part of
     * the emitter (for a light field, of the slab where its radiance is
     * nonzero) they can reach. Culled visits only the cells it meets; both
     * methods build a sharing leaf's tables and shadows for the rectangle
     * around it alone (an origin outside sees only where the leaf reads
     * zero), so that they decide and read alike. */
    if (culled || (rows->shares && L.mix)) {
        v3 box[4], src[RL_MAX_POLY_VERTS + 2];
        int sup = ctx->sampling->zero_culling ? rl__leaf_support(p->e, &L, box) : 0;
        size_t ns = sup > 0 ? rl__clip_poly3(box, 4, m->frame.origin, m->frame.n, src) : 0;
        double lift = 0.0;
        for (size_t k = 0; k < ns; k++)
            lift = fmax(lift, v3_dot(v3_sub(src[k], m->frame.origin), m->frame.n));
        int dark = sup < 0 || (sup > 0 && (ns < 3 || !(lift > 0)));
        if (!dark)
            nq = sup > 0 ? rl__node_region(ctx, p, src, ns, t, p->level, id, reg, q)
                         : rl__node_region(ctx, p, p->sclip, p->ns, t, p->level, id, reg, q);
        if (culled && nq == 0)
            return 0;
    }
    if (row_reserve(s, m->nu) != 0)
        return -1;
    /* the rectangle around the region (the tile's rows without one, where every sample reads zero) */
    double pad = 1e-6 * m->cell;
    double within[4] = {m->u0 - pad, m->u0 + (double)m->nu * m->cell + pad, m->v0 + (double)t->row0 * m->cell - pad,
                        m->v0 + (double)t->row1 * m->cell + pad};
    if (nq > 0) {
        within[0] = within[2] = INFINITY, within[1] = within[3] = -INFINITY;
        for (size_t k = 0; k < nq; k++) {
            within[0] = dmin(within[0], q[k].x - pad), within[1] = dmax(within[1], q[k].x + pad);
            within[2] = dmin(within[2], q[k].y - pad), within[3] = dmax(within[3], q[k].y + pad);
        }
    }
    if (rows->shares && rl__leaf_share(&L, ctx->sampling->rays_per_solid_angle) > 0) {
        rl__leaf_plan(&L, p->e, &m->frame, p->eps);
        /* one mix of the slab's directions per shared direction, read 4 taps
         * a sample (inline) instead of 16 (a call): a position of a table
         * costs about what a sample saves, and a tile's cells each draw one
         * sample per direction, so it is built when it has at most 4 times as
         * many positions as the tile has cells (1, 4 and 16 times: 'beams' at
         * 47k cells 8.67, 8.49 and 8.50 G instructions). Its box holds only
         * the positions that origins within the rectangle reach. */
        size_t floats = rl__leaf_blend_size(p->e, &L, within);
        if (floats > 0 && rl__box_positions(L.box) <= 4 * (size_t)m->nu * (t->row1 - t->row0)) {
            if (blend_reserve(s, floats) != 0)
                return -1;
            (void)rl__leaf_blend(p->e, &L, s->blend); /* refused: L reads the slab itself */
        }
    }
    if (s->shadows)
        s->shadows->known = 0;
    /* the shadows from the rectangle alone too: a narrower beam collects fewer polygons */
    if (rows->shadows && L.nshared > 0 && rl__shadows_build(ctx, p, t, &L, nq > 0 ? within : NULL, s) != 0)
        return -1;
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
        if (rows->row(ctx, p, t, &L, emitter_index, j, i0, i1, s, stage, cnt) != 0)
            return -1;
    }
    return 0;
}

int rl__leaves_gather(const rl_transfer_ctx *ctx, const rl_tile *t, uint32_t ei, rl_scratch *s, rl_counters *cnt,
                      const rl_leaf_rows *rows)
{
    rl_pair *p = malloc(sizeof *p);
    rl_region *reg = malloc(sizeof *reg);
    v2 *q = malloc((RL_MAX_POLY_VERTS + 4 + RL_REGION_MAX_PLANES) * sizeof *q);
    int rc = (!p || !reg || !q) ? -1 : 0;
    if (rc == 0 && rl__pair_setup(ctx, &ctx->emitters[ei], t, p)) {
        cnt->pairs++;
        cnt->pairs_descended += p->descended;
        s->nleaves = 0;
        int lambert = ctx->sampling->descend &&
                      ((rows->lambert && (p->e->kind == EM_CONST || p->leaves < RL_LAMBERT_LEAVES)) ||
                       (rows->culls && p->descended));
        if (lambert) {
            /* Lambert's formula, and rays for visibility (and the radiance of light fields) alone */
            rc = rl__gather_lambert(ctx, p, t, ei, s, cnt);
        } else if (rows->culls) {
            rc = walk(ctx, p, t, s, cnt);
            if (rc == 0 && s->nleaves > 1)
                qsort(s->leaves, s->nleaves, sizeof *s->leaves, cmp_u64);
        } else {
            uint64_t total = lfio_part_hemi_count(p->level);
            cnt->leaves_considered += total;
            for (uint64_t id = 0; id < total && rc == 0; id++)
                rc = push_leaf(s, id);
        }
        if (rc == 0 && rows->prepare)
            rc = rows->prepare(s, t);
        for (int stage = 2 - rows->stages; stage <= 1 && rc == 0; stage++)
            for (size_t k = 0; k < s->nleaves && rc == 0; k++)
                rc = gather_leaf(ctx, p, t, s->leaves[k], ei, rows, reg, q, s, stage, cnt);
    }
    free(p);
    free(reg);
    free(q);
    return rc;
}

/* culled: the surviving leaves; Lambert times visibility for constant
 * emitters and for small or thin ones when descend is on. */
static const rl_leaf_rows culled_rows = {
    .culls = 1, .lambert = 1, .shares = 1, .shadows = 1, .stages = 1, .row = culled_row};

/* naive: every leaf of partition_n through the same per-leaf code. */
static const rl_leaf_rows naive_rows = {
    .culls = 0, .lambert = 1, .shares = 1, .shadows = 1, .stages = 1, .row = culled_row};

static int culled_gather(const rl_transfer_ctx *ctx, const rl_tile *t, uint32_t ei, rl_scratch *s, rl_counters *cnt)
{
    return rl__leaves_gather(ctx, t, ei, s, cnt, &culled_rows);
}

static int naive_gather(const rl_transfer_ctx *ctx, const rl_tile *t, uint32_t ei, rl_scratch *s, rl_counters *cnt)
{
    return rl__leaves_gather(ctx, t, ei, s, cnt, &naive_rows);
}

const rl_method_impl rl__method_culled = {.id = RL_METHOD_CULLED, .point_view = 1, .gather = culled_gather};
const rl_method_impl rl__method_naive = {.id = RL_METHOD_NAIVE, .point_view = 0, .gather = naive_gather};
