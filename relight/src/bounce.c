/*
 * bounce.c - a bounce pass gathered from each receiver cell's own
 * hemisphere: rays drawn cosine-weighted over the cell's front, each
 * reading the radiance its first hit re-emits.
 *
 * A bounce pass moves light that is smooth (it has no sharp shadows of its
 * own to resolve) from every lit surface at once. The methods' transfer
 * pairs each receiver tile with each lit polygon and culls the partition's
 * solid angles per pair, so its cost grows with the number of polygons
 * (the classroom's 3,035) and every ray is a shadow ray towards a point
 * chosen on one polygon; here one closest-hit ray finds whichever surface
 * a direction sees, and the cosine is in the sampling density, so that
 * each ray carries pi * L. With p(w) = cos / pi the estimate of a cell is
 * pi times the mean radiance its rays meet, unbiased for any scene; in a
 * closed room of uniform radiosity B every ray returns B / pi exactly, so
 * the white furnace holds with no variance at all (tests/test_furnace.c).
 *
 * Invariants: a cell's rays depend only on (seed, pass, receiver map,
 * cell), drawn from the 4-D Halton sequence (two numbers for the origin in
 * the cell, two for the direction), so results do not depend on threads;
 * a ray that leaves the scene, or meets a surface's back or a surface that
 * re-emits nothing, carries zero.
 */
#include <math.h>

#include "method.h"

/* Maps (a, b) in [0, 1)^2 to the unit disc, area-preserving, squares to rings (Shirley and Chiu 1997). */
static void concentric_disc(double a, double b, double *x, double *y)
{
    double sx = 2.0 * a - 1.0, sy = 2.0 * b - 1.0, r, phi;
    if (sx == 0.0 && sy == 0.0) {
        *x = *y = 0.0;
        return;
    }
    if (fabs(sx) > fabs(sy)) {
        r = sx;
        phi = (RL_PI / 4.0) * (sy / sx);
    } else {
        r = sy;
        phi = RL_PI / 2.0 - (RL_PI / 4.0) * (sx / sy);
    }
    *x = r * cos(phi);
    *y = r * sin(phi);
}

/* @return the index into ctx->emitters of the polygon a ray hit, or -1. */
static int32_t emitter_of(const rl_transfer_ctx *ctx, uint32_t polygon)
{
    return polygon < ctx->scene->npolygons ? ctx->emitter_of_polygon[polygon] : -1;
}

/* Adds to out the radiance arriving at x along unit d: what the first surface hit re-emits towards x. */
static void first_hit_radiance(const rl_transfer_ctx *ctx, v3 x, v3 d, double tnear, double out[3],
                               rl_counters *cnt)
{
    uint32_t polygon;
    double dist;
    cnt->rays_cast++;
    if (!rl__tracer_hit(ctx->tracer, x, d, tnear, INFINITY, &polygon, &dist))
        return;
    int32_t k = emitter_of(ctx, polygon);
    if (k < 0)
        return;
    const rl_emitter *e = &ctx->emitters[k];
    if (!(v3_dot(d, e->frame.n) < 0))
        return; /* its back: surfaces emit from their front alone */
    double l[3];
    rl__emitter_radiance_near(e, frame_project(&e->frame, v3_madd(x, d, dist)), d, l);
    cnt->rays_kept++;
    for (int c = 0; c < 3; c++)
        out[c] += l[c];
}

void rl__bounce_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                     rl_counters *cnt)
{
    uint32_t n = ctx->sampling->bounce_rays;
    const rl_frame *f = &m->frame;
    for (uint32_t j = row0; j < row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = m->grid[(size_t)j * m->nu + i];
            if (cell < 0)
                continue;
            rl_origin_domain dom;
            rl__cell_domain(m, (uint32_t)cell, &dom);
            lds_key key = rl__lds_make(ilf_hash_mix(rl__pair_key(ctx, UINT32_MAX, map_index), (uint64_t)cell));
            double acc[3] = {0, 0, 0};
            for (uint32_t s = 0; s < n; s++) {
                double u[4];
                rl__lds4(&key, s, u);
                /* the direction, where the light varies most, takes the sequence's best-spread pair of
                 * dimensions (bases 2 and 3); cosine-weighted: a uniform point of the unit disc
                 * (concentric map, which keeps strata compact) lifted onto the hemisphere */
                double dx, dy;
                concentric_disc(u[0], u[1], &dx, &dy);
                double cz = sqrt(fmax(0.0, 1.0 - dx * dx - dy * dy));
                v3 d = v3_madd(v3_madd(v3_scale(f->n, cz), f->e1, dx), f->e2, dy);
                v3 x = rl__domain_point(m, &dom, u[2], u[3]);
                first_hit_radiance(ctx, x, d, ctx->eps / fmax(cz, 1e-3), acc, cnt);
            }
            cnt->samples += n;
            for (int c = 0; c < 3; c++)
                m->e_pass[cell][c] += RL_PI * acc[c] / n;
        }
}
