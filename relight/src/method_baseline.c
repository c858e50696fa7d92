/*
 * method_baseline.c - the two baselines every study of light transport
 * measures against: `area` samples points uniformly on the emitter (clipped
 * to the receiver's front) and weighs them by cos cos / r^2; `solidangle`
 * samples directions uniformly in the emitter's spherical polygon (Arvo's
 * warp over a triangle fan) and weighs them by that solid angle. Each cell
 * draws samples_per_cell (origin, emitter point) pairs from its own
 * low-discrepancy sequence; the partition plays no part.
 */
#include <math.h>

#include "method.h"

/* One sample of `area` (uniform on the clipped emitter) or `solidangle`
 * (uniform in its spherical polygon) from cell point x; queues the weighted
 * radiance * cosines for acc. */
static void baseline_sample(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_frame *rf, v3 x,
                            const double u[4], double s_area, double *acc, rl_ray_batch *b, rl_counters *cnt)
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
    if (!rl__emitter_contains(e, q))
        return;
    double l[3];
    rl__emitter_radiance_at(e, q, v3_scale(to_s, -1.0), l);
    if (!(l[0] > 0 || l[1] > 0 || l[2] > 0))
        return; /* nothing to carry: no ray needed */
    for (int c = 0; c < 3; c++)
        l[c] *= cos_r * weight;
    double eps = p->eps, cos_s = -v3_dot(to_s, e->frame.n);
    rl__batch_push(ctx, b, x, to_s, eps / fmax(cos_r, 1e-3), dist - eps / fmax(cos_s, 1e-3), l, acc, cnt);
}

/* Area or solid-angle sampling of emitter ei for every cell of the tile. */
static int baseline_gather(const rl_transfer_ctx *ctx, const rl_tile *t, uint32_t ei, rl_scratch *s_unused,
                           rl_counters *cnt)
{
    (void)s_unused;
    rl_pair p;
    if (!rl__pair_setup(ctx, &ctx->emitters[ei], t, &p))
        return 0;
    cnt->pairs++;
    rl_map *m = t->m;
    v2 sp[RL_MAX_POLY_VERTS + 2];
    for (size_t i = 0; i < p.ns; i++)
        sp[i] = frame_project(&p.e->frame, p.sclip[i]);
    double s_area = rl__polygon_area2(sp, (uint32_t)p.ns);
    uint32_t n = ctx->sampling->samples_per_cell;
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = rl__map_grid_cell(m, i, j);
            if (cell < 0)
                continue;
            v2 cp[RL_MAX_POLY_VERTS + 8];
            uint32_t ncp = rl__map_cell_polygon(m, (uint32_t)cell, cp);
            lds_key key = rl__lds_make(ilf_hash_mix(rl__pair_key(ctx, ei, t->map_index), (uint64_t)cell));
            double acc[3] = {0, 0, 0};
            rl_ray_batch batch;
            batch.n = 0;
            for (uint32_t s = 0; s < n; s++) {
                double u[4];
                rl__lds4(&key, s, u);
                v3 x = frame_point(&m->frame, rl__sample_polygon(cp, ncp, u[0], u[1]));
                baseline_sample(ctx, &p, &m->frame, x, u, s_area, acc, &batch, cnt);
            }
            rl__batch_flush(ctx, &batch, cnt);
            for (int c = 0; c < 3; c++)
                m->e_pass[cell][c] += acc[c] / n;
        }
    return 0;
}

const rl_method_impl rl__method_area = {.id = RL_METHOD_AREA, .point_view = 0, .gather = baseline_gather};
const rl_method_impl rl__method_solidangle = {.id = RL_METHOD_SOLIDANGLE, .point_view = 0, .gather = baseline_gather};
