/*
 * method_adaptive.c - adaptive refinement of culled's leaves.
 *
 * adaptive keeps culled's walk and per-leaf regions (rl__leaves_gather())
 * and changes what one (cell, leaf) estimate is: a node whose pilot
 * samples disagree more than the cell's share of the error budget allows
 * is replaced by its four children, recursively, down to four levels below
 * the pair's. The budget comes from a first stage that measures each cell's
 * total with one sample per leaf. Pilot and budget samples come from
 * sequences of their own, so the decisions they make never enter the
 * estimate: the result stays unbiased (the white-furnace test holds it
 * within 0.05%). A time budget stops further refinement, never an estimate.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "method.h"

/* Most samples one adaptive node draws. */
#define ADAPTIVE_MAX_SAMPLES 256

/* An adaptive estimate: irradiance, its variance (of the mean channel), and the samples behind it. */
typedef struct estimate {
    double e[3];
    double var;
    double samples;
} estimate;

/* @return 1 once the adaptive time budget has run out. */
static int budget_spent(const rl_transfer_ctx *ctx)
{
    if (!(ctx->deadline > 0))
        return 0;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9 > ctx->deadline;
}

/* Salts that keep adaptive's decisions apart from its estimates: samples
 * that decide whether a node is refined never enter the result, so the
 * decision cannot bias it (0: the estimate itself, culled's sequence). */
#define SALT_BUDGET UINT64_C(0x627564676574) /* "budget": stage 0's cell totals */
#define SALT_PILOT UINT64_C(0x70696c6f74)    /* "pilot": a node's refinement decision */

/* Estimates what solid angle id at level lv sends into one cell's domain
 * with count samples of the low-discrepancy sequence keyed by salt (salt 0:
 * the one culled uses, so an unrefined adaptive leaf equals culled's
 * estimate, except for a light field's nested leaves, whose directions
 * culled draws once for all cells); the variance comes from the spread of
 * the samples. */
static estimate node_estimate(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t,
                              const rl_origin_domain *dom, uint32_t cell, const rl_leaf *L, uint32_t count,
                              uint64_t salt, rl_counters *cnt)
{
    const rl_map *m = t->m;
    uint32_t k = count > ADAPTIVE_MAX_SAMPLES ? ADAPTIVE_MAX_SAMPLES : count;
    double acc[ADAPTIVE_MAX_SAMPLES][3];
    rl_ray_batch batch;
    batch.n = 0;
    uint64_t h = ilf_hash_mix(L->key, cell);
    lds_key key = rl__lds_make(salt ? ilf_hash_mix(h, salt) : h);
    for (uint32_t i = 0; i < k; i++) {
        double u[4], w, lam[3];
        rl__lds4(&key, i, u);
        acc[i][0] = acc[i][1] = acc[i][2] = 0.0;
        v3 d, x = rl__domain_point(m, dom, u[0], u[1]);
        const rl_leaf *lp;
        if (rl__leaf_draw(p, L, x, u[2], u[3], &d, &w, lam, &lp))
            rl__shoot_back(ctx, p, x, m->frame.n, d, w, lp, lam, NULL, acc[i], &batch, cnt);
        else
            cnt->samples++;
    }
    rl__batch_flush(ctx, &batch, cnt);
    estimate est = {{0, 0, 0}, 0, k};
    double lum = 0.0, sq = 0.0;
    for (uint32_t i = 0; i < k; i++) {
        double y = (acc[i][0] + acc[i][1] + acc[i][2]) / 3;
        for (int c = 0; c < 3; c++)
            est.e[c] += acc[i][c] / k;
        lum += y / k;
        sq += y * y / k;
    }
    est.var = k > 1 ? fmax(0.0, sq - lum * lum) / (k - 1) : 0.0;
    return est;
}

/* @return the equal-weight mean of two independent estimates of one quantity. */
static estimate estimate_mean(const estimate *a, const estimate *b)
{
    estimate m;
    for (int c = 0; c < 3; c++)
        m.e[c] = 0.5 * (a->e[c] + b->e[c]);
    m.var = 0.25 * (a->var + b->var);
    m.samples = a->samples + b->samples;
    return m;
}

/* Estimates solid angle id at level lv for one cell. k pilot samples
 * decide: while their standard error exceeds tol (W m^-2) the node is
 * replaced by its four children (recursively, each held to tol / 2);
 * otherwise k fresh samples estimate it. The result is the mean of the
 * pilot's estimate and the other one, with weights 1/2 whatever the
 * decision: the pilot is unbiased by itself and the fresh or refined
 * estimate is unbiased given the decision (its samples are independent of
 * the pilot's), so their fixed-weight mean is unbiased, and an unrefined
 * node gets the variance of 2k samples for the 2k it drew. (Using the
 * pilot alone when it decides against refining, as this method once did,
 * kept nodes whose few samples all missed at zero: 0.4% low in a white
 * furnace, 2.4% with two bounces.) */
static estimate adaptive_node(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t,
                              const rl_origin_domain *dom, uint32_t cell, uint32_t ei, const rl_leaf *L,
                              uint32_t max_level, double tol, rl_counters *cnt)
{
    uint32_t k = ctx->sampling->rays_per_solid_angle;
    int pilot_drawn = 2 * L->lv <= max_level && k > 1, refine = pilot_drawn;
    estimate pilot = {{0, 0, 0}, 0, 0};
    if (pilot_drawn) {
        pilot = node_estimate(ctx, p, t, dom, cell, L, k, SALT_PILOT, cnt);
        refine = sqrt(pilot.var) > tol;
    }
    if (refine && budget_spent(ctx)) {
        cnt->budget_reached = 1;
        refine = 0;
    }
    if (!refine) {
        estimate fresh = node_estimate(ctx, p, t, dom, cell, L, k, 0, cnt);
        if (pilot_drawn)
            return estimate_mean(&pilot, &fresh);
        return fresh;
    }
    cnt->refinements++;
    uint64_t ch[4];
    lfio_part_children(L->lv, L->id, ch);
    estimate fine = {{0, 0, 0}, 0, 0};
    for (int c = 0; c < 4; c++) {
        rl_leaf child;
        rl__leaf_make(ctx, p->e, ei, t->map_index, 2 * L->lv, ch[c], &child);
        estimate r = adaptive_node(ctx, p, t, dom, cell, ei, &child, max_level, tol / 2, cnt);
        for (int j = 0; j < 3; j++)
            fine.e[j] += r.e[j];
        fine.var += r.var;
        fine.samples += r.samples;
    }
    return estimate_mean(&pilot, &fine);
}

/* The adaptive method's work on one row of cells for one kept leaf. Stage
 * 0 only measures: each cell's total from this emitter and the number of
 * leaves that carry light into it (s->pair_total, s->pair_leaves, indexed
 * from the tile's first cell). Stage 1 estimates with refinement, holding
 * each (cell, leaf) node to an equal share of the cell's error budget:
 * target_error * total / sqrt(leaves). */
static int adaptive_row(const rl_transfer_ctx *ctx, const rl_pair *p, const rl_tile *t, const rl_leaf *L,
                        uint32_t ei, uint32_t j, uint32_t i0, uint32_t i1, rl_scratch *s, int stage,
                        rl_counters *cnt)
{
    rl_map *m = t->m;
    uint32_t max_level = p->level >= (1u << 18) ? (1u << 20) : 4 * p->level;
    for (uint32_t i = i0; i <= i1; i++) {
        int32_t cell = rl__map_grid_cell(m, i, j);
        rl_origin_domain dom;
        if (cell < 0)
            continue;
        rl__cell_domain(m, (uint32_t)cell, &dom);
        size_t slot = (size_t)cell - s->first_cell;
        double tol = INFINITY;
        if (stage == 1 && s->pair_leaves[slot] > 0)
            tol = ctx->sampling->target_error * s->pair_total[slot] / sqrt(s->pair_leaves[slot]);
        /* stage 0 needs only each cell's total over all its leaves: one sample a leaf */
        estimate est = stage == 0 ? node_estimate(ctx, p, t, &dom, (uint32_t)cell, L, 1, SALT_BUDGET, cnt)
                                  : adaptive_node(ctx, p, t, &dom, (uint32_t)cell, ei, L, max_level, tol, cnt);
        double y = (est.e[0] + est.e[1] + est.e[2]) / 3;
        if (stage == 0) {
            s->pair_total[slot] += y;
            s->pair_leaves[slot] += y > 0;
            continue;
        }
        for (int c = 0; c < 3; c++)
            m->e_pass[cell][c] += est.e[c];
        cnt->variance += est.var;
    }
    return 0;
}

/* Zeroes the adaptive per-cell measures for the tile's cells, growing them as needed. @return 0 or -1. */
static int adaptive_reserve(rl_scratch *s, const rl_tile *t)
{
    const rl_map *m = t->m;
    uint32_t c0 = UINT32_MAX, c1 = 0; /* a tile's cells are numbered consecutively, row by row */
    for (uint32_t j = t->row0; j < t->row1; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            int32_t c = rl__map_grid_cell(m, i, j);
            if (c >= 0) {
                c0 = (uint32_t)c < c0 ? (uint32_t)c : c0;
                c1 = (uint32_t)c + 1 > c1 ? (uint32_t)c + 1 : c1;
            }
        }
    size_t n = c1 > c0 ? c1 - c0 : 1;
    if (n > s->pair_cap) {
        double *tot = realloc(s->pair_total, n * sizeof *tot);
        if (tot)
            s->pair_total = tot;
        uint32_t *lv = tot ? realloc(s->pair_leaves, n * sizeof *lv) : NULL;
        if (lv)
            s->pair_leaves = lv;
        if (!tot || !lv)
            return -1;
        s->pair_cap = n;
    }
    memset(s->pair_total, 0, n * sizeof *s->pair_total);
    memset(s->pair_leaves, 0, n * sizeof *s->pair_leaves);
    s->first_cell = c0 == UINT32_MAX ? 0 : c0;
    return 0;
}

/* adaptive: culled's leaves, a measuring stage, then refined estimates. */
static const rl_leaf_rows adaptive_rows = {
    .culls = 1, .lambert = 0, .stages = 2, .prepare = adaptive_reserve, .row = adaptive_row};

static int adaptive_gather(const rl_transfer_ctx *ctx, const rl_tile *t, uint32_t ei, rl_scratch *s,
                           rl_counters *cnt)
{
    return rl__leaves_gather(ctx, t, ei, s, cnt, &adaptive_rows);
}

const rl_method_impl rl__method_adaptive = {.id = RL_METHOD_ADAPTIVE, .point_view = 1, .gather = adaptive_gather};
