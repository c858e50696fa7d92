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
 * in the white furnace a bounce adds no noise of its own to what the
 * previous pass left (tests/test_furnace.c).
 *
 * Invariants: a cell's rays depend only on (seed, pass, receiver map) and
 * the cell's place, drawn from the 4-D Halton sequence (two numbers for the
 * origin in the cell, two for the direction) of one key per (pass, map), so
 * results do not depend on threads and neighbouring cells' errors are alike
 * (no mottling); each cell's rays also give its estimate's standard error
 * (the pass's histogram of them, rl_counters.cell_error), and a cell
 * gathered on its own casts as many rounds of them as that error and its
 * earlier passes' light call for, so its count too is its own;
 * a ray that leaves the scene, or meets a surface's back or a surface that
 * re-emits nothing, carries zero; where two polygons lie back to back, a ray
 * that Embree gives the back of one reads the front of the other, as a
 * shadow ray stopping short of the emitter's plane would.
 */
#include <math.h>
#include <stdlib.h>

#include "ilf/pool.h"
#include "bounce.h"
#include "pair.h"

/* Rounds of bounce_rays rays a cell gathered on its own (near an occluder) casts at most: 4, which halves
 * its noise, the noise no interpolation smooths. Measured on the demo (docs/accuracy.md): the ceiling's
 * cell-to-cell variation inside the lamp's frame 1.4% instead of 2.7% at 1 (2.0% at 2). A cell stops
 * after a round once its estimate's standard error is within RL_OWN_CELL_ERROR of its light
 * (own_cell_converged()). */
#define RL_OWN_CELL_RAYS 4u

/* The standard error, relative to the cell's light so far (earlier passes and this pass's estimate), within
 * which a cell gathered on its own casts no further round. At 2% the demo's ceiling inside the lamp's frame
 * (lit by bounces alone, so judged against the bounce itself) keeps its 1,024 rays in the first bounce and
 * its mottling (1.43% against 1.40% at 5 cm cells); on the paper's 'beams' the second bounce casts half
 * its rays (4.20 M against 8.39 M) and the first 5% fewer (BENCHMARKS-journal.md, 4c). */
#define RL_OWN_CELL_ERROR 0.02

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
        phi = (ILF_PI / 4.0) * (sy / sx);
    } else {
        r = sy;
        phi = ILF_PI / 2.0 - (ILF_PI / 4.0) * (sx / sy);
    }
    *x = r * cos(phi);
    *y = r * sin(phi);
}

/* The fill of each map emitter's glow table (ilf_parallel_for()'s fn over the emitters). */
typedef struct glow_fill {
    const rl_emitter *e;
    rl_glow *glow;
    size_t npolygons;
} glow_fill;

/* Fills the glow table of emitter k's polygon, if k re-emits a map (ilf_parallel_for()'s fn). */
static void fill_glow(void *arg, size_t k)
{
    const glow_fill *f = arg;
    const rl_map *m = f->e[k].map;
    if (f->e[k].kind != EM_MAP || f->e[k].polygon < 0 || (size_t)f->e[k].polygon >= f->npolygons ||
        f->glow[f->e[k].polygon].map != m)
        return;
    float (*rad)[3] = f->glow[f->e[k].polygon].rad;
    for (uint32_t j = 0; j < m->nv; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            v2 centre = {m->u0 + (i + 0.5) * m->cell, m->v0 + (j + 0.5) * m->cell};
            double l[3];
            rl__map_radiance(m, rl__map_cell_near(m, centre), l);
            for (int c = 0; c < 3; c++)
                rad[(size_t)j * m->nu + i][c] = (float)l[c];
        }
}

rl_status rl__glow_new(const rl_scene *scene, const rl_emitter *e, size_t ne, unsigned threads, rl_glow **out)
{
    rl_glow *glow = calloc(scene->npolygons ? scene->npolygons : 1, sizeof *glow);
    *out = NULL;
    if (!glow)
        return RL_ERR_NOMEM;
    for (size_t k = 0; k < ne; k++) {
        const rl_map *m = e[k].map;
        if (e[k].kind != EM_MAP || e[k].polygon < 0 || (size_t)e[k].polygon >= scene->npolygons)
            continue;
        rl_glow *g = &glow[e[k].polygon];
        size_t squares = (size_t)m->nu * m->nv;
        g->rad = malloc((squares ? squares : 1) * sizeof *g->rad);
        if (!g->rad) {
            rl__glow_free(glow, scene->npolygons);
            return RL_ERR_NOMEM;
        }
        g->map = m;
    }
    /* the tables are filled side by side: each emitter writes its own polygon's */
    glow_fill f = {e, glow, scene->npolygons};
    ilf_parallel_for(threads, ne, fill_glow, &f);
    *out = glow;
    return RL_OK;
}

void rl__glow_free(rl_glow *glow, size_t npolygons)
{
    for (size_t k = 0; glow && k < npolygons; k++)
        free(glow[k].rad);
    free(glow);
}

/* @return 1 if a hit at distance dist, point p, from a cell of m lies closer than half a cell above the
 * inside of m's polygon, or anywhere when the polygon is under three cells across: an occluder there
 * makes the light change within a cell, which interpolation from larger cells would blur. A surface
 * meeting a wide polygon at its edge (a wall at a floor) does not count: the interpolation carries
 * values to the edge, and its light varies slowly along it. */
static int hit_is_near(const rl_map *m, double dist, v3 p)
{
    return dist < 0.5 * m->cell &&
           (m->nu < 3 || m->nv < 3 ||
            rl__polygon_holds(m->poly, m->npoly, frame_project(&m->frame, p), 1e-3 * m->cell));
}

/* Traces the n rays of a packet from x[i] along unit d[i], from a cell of map m, and adds, in ray
 * order, the radiance each one's first hit re-emits towards it into acc and the square of its
 * luminance (the channels' mean) into *acc2; sets *near when m->near is set and a hit is near
 * (hit_is_near()). */
static void trace_packet(const rl_transfer_ctx *ctx, const rl_map *m, size_t n, const v3 *x, const v3 *d,
                         const double *tnear, double acc[3], double *acc2, int *near, rl_counters *cnt)
{
    double tfar[RL_RAY_PACKET], dist[RL_RAY_PACKET];
    uint32_t polygon[RL_RAY_PACKET];
    const float *hit[RL_RAY_PACKET];
    size_t kept = 0;
    for (size_t i = 0; i < n; i++)
        tfar[i] = INFINITY;
    rl__tracer_hit_n(ctx->tracer, n, x, d, tnear, tfar, polygon, dist);
    cnt->rays_cast += n;
    for (size_t i = 0; i < n; i++) {
        if (polygon[i] >= ctx->scene->npolygons)
            continue;
        if (m->near && !*near)
            *near = hit_is_near(m, dist[i], v3_madd(x[i], d[i], dist[i]));
        if (!(v3_dot(d[i], v3_load(ctx->scene->polygons[polygon[i]].normal)) < 0)) {
            /* a back: opaque, unless a polygon lies back to back with it there (a panel modelled as two
             * faces), whose front the ray meets at the same distance up to rounding */
            double w = ctx->eps + 1e-6 * dist[i];
            if (!rl__tracer_hit_front(ctx->tracer, x[i], d[i], fmax(tnear[i], dist[i] - w), dist[i] + w, &polygon[i],
                                      &dist[i]))
                continue;
        }
        const rl_glow *g = &ctx->glow[polygon[i]];
        const rl_map *hm = g->map;
        if (!hm)
            continue; /* re-emits nothing */
        /* the hits land anywhere in the scene's maps: ask for every hit's
         * radiance first, add them after, so that the cache misses overlap */
        hit[kept] = g->rad[rl__map_square_clamped(hm, frame_project(&hm->frame, v3_madd(x[i], d[i], dist[i])))];
#if defined(__GNUC__)
        __builtin_prefetch(hit[kept]);
#endif
        kept++;
    }
    cnt->rays_kept += kept;
    for (size_t k = 0; k < kept; k++) {
        double y = ((double)hit[k][0] + hit[k][1] + hit[k][2]) / 3.0;
        for (int c = 0; c < 3; c++)
            acc[c] += hit[k][c];
        *acc2 += y * y;
    }
}

/* @return the standard error of the mean of a cell's n rays, whose radiances summed to acc and their
 * luminances' squares to acc2, and *mean that mean's luminance: the rays are n draws of one estimator, so
 * their mean has the standard error s / sqrt(n), s their sample deviation. */
static double rays_standard_error(uint32_t n, const double acc[3], double acc2, double *mean)
{
    *mean = (acc[0] + acc[1] + acc[2]) / (3.0 * n);
    double var = n > 1 ? fmax(0.0, (acc2 - n * *mean * *mean) / (n - 1.0)) : 0.0;
    return sqrt(var / n);
}

/* Counts a cell of n rays (sums acc and acc2 as rays_standard_error()'s) in cnt's histogram of relative
 * standard errors. A cell that met no light counts as exact (bin 0): its value is 0 however many rays it
 * casts. */
static void count_cell_error(uint32_t n, const double acc[3], double acc2, rl_counters *cnt)
{
    double mean, se = rays_standard_error(n, acc, acc2, &mean);
    cnt->cell_error[mean > 0 ? rl__cell_error_bin(se / mean) : 0]++;
}

/* @return 1 if a cell of n rays (sums acc and acc2 as rays_standard_error()'s), whose earlier passes lit
 * it with luminance prior, needs no more rays: the pass's estimate, pi times the rays' mean, has a standard
 * error within RL_OWN_CELL_ERROR of the cell's light, prior plus that estimate. A later bounce carries
 * less light than the passes before it, so its cells stop sooner. The rule reads the cell's own rays and
 * earlier passes alone, so results stay independent of threads. */
static int own_cell_converged(uint32_t n, const double acc[3], double acc2, double prior)
{
    double mean, se = rays_standard_error(n, acc, acc2, &mean);
    return ILF_PI * se <= RL_OWN_CELL_ERROR * (prior + ILF_PI * mean);
}

/* Directions a tile works out once for all its cells: every cell of a map draws the same sequence, so
 * ray k's direction is the same in each; beyond these the rays' directions are worked out per cell. */
#define RL_SHARED_DIRECTIONS 1024

/* Sets d to the direction of ray k of the sequence of key in frame f, and *cz to its cosine to the normal:
 * the direction, where the light varies most, takes the sequence's best-spread pair of dimensions (bases
 * 2 and 3); cosine-weighted: a uniform point of the unit disc (concentric map, which keeps strata
 * compact) lifted onto the hemisphere. */
static void ray_direction(const lds_key *key, uint32_t k, const rl_frame *f, v3 *d, double *cz)
{
    double dx, dy;
    concentric_disc(rl__lds_coord(key, k, 0), rl__lds_coord(key, k, 1), &dx, &dy);
    *cz = sqrt(fmax(0.0, 1.0 - dx * dx - dy * dy));
    *d = v3_madd(v3_madd(v3_scale(f->n, *cz), f->e1, dx), f->e2, dy);
}

/* What every cell of a tile draws its rays from: the map's sequence and the directions worked out once. */
typedef struct tile_rays {
    const rl_transfer_ctx *ctx;
    rl_map *m;
    lds_key key;
    uint32_t nshared;
    v3 shared_d[RL_SHARED_DIRECTIONS];
    double shared_cz[RL_SHARED_DIRECTIONS];
} tile_rays;

/* Traces rays [s0, s1) of the sequence from the cell of origin domain dom and adds what they read into
 * acc, *acc2 and *near (trace_packet()). */
static void gather_rays(const tile_rays *t, const rl_origin_domain *dom, uint32_t s0, uint32_t s1, double acc[3],
                        double *acc2, int *near, rl_counters *cnt)
{
    for (; s0 < s1; s0 += RL_RAY_PACKET) {
        size_t np = s1 - s0 < RL_RAY_PACKET ? s1 - s0 : RL_RAY_PACKET;
        v3 x[RL_RAY_PACKET], d[RL_RAY_PACKET];
        double tnear[RL_RAY_PACKET];
        for (size_t k = 0; k < np; k++) {
            uint32_t s = s0 + (uint32_t)k;
            double cz;
            if (s < t->nshared)
                d[k] = t->shared_d[s], cz = t->shared_cz[s];
            else
                ray_direction(&t->key, s, &t->m->frame, &d[k], &cz);
            x[k] = rl__domain_point(t->m, dom, rl__lds_coord(&t->key, s, 2), rl__lds_coord(&t->key, s, 3));
            tnear[k] = t->ctx->eps / fmax(cz, 1e-3);
        }
        trace_packet(t->ctx, t->m, np, x, d, tnear, acc, acc2, near, cnt);
    }
}

void rl__bounce_tile(const rl_transfer_ctx *ctx, uint32_t map_index, rl_map *m, uint32_t row0, uint32_t row1,
                     rl_counters *cnt)
{
    /* the cells gathered on their own are interpolated from nothing: their noise shows cell by cell, where
     * the larger cells' is smoothed over by interpolation; up to RL_OWN_CELL_RAYS rounds of bounce_rays
     * rays halve it where it matters (own_cell_converged()); a larger cell casts one round */
    uint32_t n = ctx->sampling->bounce_rays * (m->subset ? RL_OWN_CELL_RAYS : 1u);
    uint32_t round = m->subset ? ctx->sampling->bounce_rays : n;
    /* every cell of a map, larger or gathered on its own, draws the same sequence (one key per pass and
     * map), each from its own place: the estimate's error then changes smoothly from cell to cell as its
     * rays' hits move, instead of jumping between independent draws (mottling) */
    tile_rays tr, *t = &tr;
    t->ctx = ctx, t->m = m;
    t->key = rl__lds_make(rl__pair_key(ctx, UINT32_MAX, map_index));
    t->nshared = n < RL_SHARED_DIRECTIONS ? n : RL_SHARED_DIRECTIONS;
    for (uint32_t k = 0; k < t->nshared; k++)
        ray_direction(&t->key, k, &m->frame, &t->shared_d[k], &t->shared_cz[k]);
    for (uint32_t j = row0; j < row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t cell = rl__map_grid_cell(m, i, j);
            if (cell < 0 || (m->subset && !m->subset[cell]))
                continue;
            rl_origin_domain dom;
            rl__cell_domain(m, (uint32_t)cell, &dom);
            double acc[3] = {0, 0, 0}, acc2 = 0.0;
            int near = 0;
            /* the light of the cell's earlier passes, against which its own error is judged */
            double prior = m->e_total != m->e_pass
                               ? (m->e_total[cell][0] + m->e_total[cell][1] + m->e_total[cell][2]) / 3.0
                               : 0.0;
            uint32_t cast = 0;
            do {
                uint32_t to = n - cast < round ? n : cast + round;
                gather_rays(t, &dom, cast, to, acc, &acc2, &near, cnt);
                cast = to;
            } while (cast < n && !own_cell_converged(cast, acc, acc2, prior));
            if (m->near)
                m->near[cell] = (uint8_t)near;
            cnt->samples += cast;
            count_cell_error(cast, acc, acc2, cnt);
            for (int c = 0; c < 3; c++)
                m->e_pass[cell][c] += ILF_PI * acc[c] / cast;
        }
}
