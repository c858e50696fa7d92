/*
 * views.c - the estimators that replace leaves where leaves are the wrong
 * tool, for culled and its relatives.
 *
 * A constant emitter leaves nothing unknown but visibility: its unoccluded
 * irradiance is Lambert's closed form, so rays are spent on the visible
 * fraction alone (rl__gather_lambert()). An emitter smaller than one solid
 * angle of the partition would be missed by most of the leaves aimed at it,
 * so each cell gathers it from the exact views of stratified origins
 * (rl__gather_views(), through the point receivers' rl__point_gather()).
 * Both draw origins from one low-discrepancy sequence per (seed, pass,
 * emitter, map, cell), so they are deterministic; both are exact where a
 * cell is wholly lit or wholly in shadow, and consistent (a ratio of two
 * estimates) in between, which the white-furnace test bounds.
 */
#include <math.h>

#include "method.h"

/* @return how many origins the mean of Lambert's formula over a cell takes
 * (rl__gather_lambert(), rl__gather_views()). The formula is smooth except near the
 * emitter's plane, where it falls to 0 with the distance to that plane;
 * its quasi-random mean's error was measured to fall as (cell size /
 * distance to the emitter's plane) / origins: 0.45% of the peak at 16
 * origins for 0.25 m cells 1 m under a 1 m emitter, 0.12% at 64; 0.98%
 * at 29 and 0.16% at 256 for cells 1 mm to 0.5 m under an emitter seen
 * edge-on. So the count follows that ratio, from k to 64 k. */
static uint32_t lambert_origins(const rl_pair *p, const rl_map *m, const rl_origin_domain *dom, uint32_t k)
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
int rl__gather_views(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, uint32_t ei, rl_scratch *s,
                     rl_counters *cnt)
{
    rl_map *m = t->m;
    const rl_emitter *e = &ctx->emitters[ei];
    uint32_t k = ctx->sampling->rays_per_solid_angle;
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            rl_origin_domain dom;
            if (cell < 0 || !rl__cell_domain(m, (uint32_t)cell, NULL, 0, &dom))
                continue;
            uint32_t nl = e->kind == EM_CONST ? lambert_origins(p, m, &dom, k) : 0;
            uint64_t rk = ilf_hash_mix(ilf_hash_mix(t->map_index, (uint64_t)cell), UINT64_C(0x76696577)); /* "view" */
            uint64_t emitter_key = ilf_hash_mix(ilf_hash_mix(ctx->sampling->seed, ctx->pass), ei);
            lds_key key = rl__lds_make(ilf_hash_mix(emitter_key, rk));
            double seen[3] = {0, 0, 0}, unocc = 0.0, full = 0.0;
            for (uint32_t o = 0; o < k || o < nl; o++) {
                double u[4];
                rl__lds4(&key, o, u);
                v3 x = rl__domain_point(m, &dom, u[0], u[1]);
                double f = nl ? rl__point_lambert(e, x, m->frame.n) : 0.0;
                full += f;
                if (o >= k)
                    continue;
                unocc += f;
                if (rl__point_gather(ctx, ei, ilf_hash_mix(rk, o), x, m->frame.n, 1, seen, s, cnt) != 0)
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
void rl__gather_lambert(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, uint32_t ei,
                        rl_counters *cnt)
{
    rl_map *m = t->m;
    const rl_emitter *e = p->e;
    uint32_t k = ctx->sampling->rays_per_solid_angle, n = ctx->sampling->partition_n;
    double leaf_sr = 2.0 * RL_PI / (4.0 * n * n);
    v2 sp[RL_MAX_POLY_VERTS + 2];
    for (size_t i = 0; i < p->ns; i++)
        sp[i] = frame_project(&e->frame, p->sclip[i]);
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            rl_origin_domain dom;
            if (cell < 0 || !rl__cell_domain(m, (uint32_t)cell, NULL, 0, &dom))
                continue;
            lds_key key = rl__lds_make(ilf_hash_mix(rl__pair_key(ctx, ei, t->map_index), (uint64_t)cell));
            uint32_t no = lambert_origins(p, m, &dom, k);
            double f = 0.0;
            for (uint32_t o = 0; o < no; o++) {
                double u[4];
                rl__lds4(&key, o, u);
                f += rl__point_lambert(e, rl__domain_point(m, &dom, u[0], u[1]), m->frame.n);
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
            rl_ray_batch batch;
            batch.n = 0;
            for (uint32_t r = 0; r < nr; r++) {
                double u[4];
                rl__lds4(&key, r, u);
                v3 x = rl__domain_point(m, &dom, u[0], u[1]);
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
                rl__batch_push(ctx, &batch, x, to, p->eps / fmax(cos_r, 1e-3), dist - p->eps / fmax(cos_s, 1e-3), l,
                           seen, cnt);
            }
            rl__batch_flush(ctx, &batch, cnt);
            if (!(all > 0))
                continue;
            double scale = f / no * fmin(seen[0] / all, 1.0);
            for (int ch = 0; ch < 3; ch++)
                m->e_pass[cell][ch] += e->emission[ch] * scale;
        }
}
