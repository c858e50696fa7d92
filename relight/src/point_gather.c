/*
 * point_gather.c - culled transfer to a point receiver, from the point's own view
 * of each emitter.
 *
 * A point x sees emitter S (clipped to x's front half-space) as a convex
 * spherical polygon. The partition's quad-tree, in S's frame as for cells,
 * is walked top-down, and each node's cone is intersected with that view
 * exactly: the node's part Q of S is S clipped by the three planes through
 * x that bound the node's cone. An empty Q culls the node exactly. The
 * pyramid of segments from x to Q is then classified against the scene
 * (shadow.h), narrowing the parent's list of possible occluders:
 *   - BLOCKED: the node adds nothing, and its subtree is dropped;
 *   - FREE, constant emitter: Lambert's formula over Q is the node's exact
 *     contribution, and the walk stops there;
 *   - otherwise the walk goes down to partition_n, where each leaf draws k
 *     directions uniformly in Q's solid angle (so none misses S) and
 *     averages the radiance that arrives, with rays traced only in PARTIAL
 *     leaves (FREE ones are known to arrive). Lambert's formula minus the
 *     sampled loss would be unbiased too, but it dips below zero next to
 *     an umbra; the plain average never does, at the same variance where
 *     visibility, not the cosine, is what varies.
 * So light is estimated only where a shadow boundary crosses the emitter,
 * and small, far, sliver and edge-on emitters are no harder than large
 * ones: Q is exact whatever its size. Samples are keyed by (seed, pass,
 * emitter, receiver, level, id), as for cells: results are deterministic.
 */
#include <stdlib.h>
#include <string.h>

#include <lfio/partition.h>

#include "sampling.h"
#include "point_gather.h"

/* Levels of the walk (partition_n is at most 4096 = 2^12, plus level 1). */
#define WALK_LEVELS 16
/* Possible occluders kept per level; beyond it a node re-queries the index. */
#define OCC_CAP 512

/* What the walk of one (point, emitter) pair shares. */
typedef struct point_walk {
    const rl_transfer_ctx *ctx;
    const rl_emitter *e;
    uint32_t ei, level, rays;
    uint64_t receiver; /* keys the samples: the point's index, or (map, cell, origin) */
    v3 x, nx;
    v3 s[RL_MAX_POLY_VERTS + 2]; /* the emitter clipped to x's front */
    size_t ns;
    double eps;
    int constant; /* EM_CONST: Lambert's formula applies */
    uint32_t *occ; /* WALK_LEVELS lists of OCC_CAP */
    rl_beam *beam; /* the room of the beam a node classifies (not needed once it recurses) */
    double *out;
    rl_counters *cnt;
} point_walk;

double rl__polygon_lambert(v3 x, v3 n, const v3 *q, size_t nq)
{
    double total = 0.0;
    v3 a = v3_norm(v3_sub(q[nq - 1], x));
    for (size_t i = 0; i < nq; i++) {
        v3 b = v3_norm(v3_sub(q[i], x)), g = v3_cross(a, b);
        double s = v3_len(g);
        if (s > 0)
            total += atan2(s, v3_dot(a, b)) * v3_dot(g, n) / s;
        a = b;
    }
    return 0.5 * fabs(total);
}

/* Clips the emitter part src (n vertices) to the directions of node (lv, id)
 * seen from w->x, into out. @return the vertex count. */
static size_t node_part(const point_walk *w, uint32_t lv, uint64_t id, const v3 *src, size_t n, v3 *out)
{
    double v[3][3];
    lfio_part_vertices(lv, id, v);
    v3 g[3];
    for (int k = 0; k < 3; k++)
        g[k] = frame_vector(&w->e->frame, v[k]);
    return rl__clip_to_view(w->x, g, src, n, out);
}

/* Samples leaf part q (nq vertices) with k directions uniform in its solid
 * angle; vis says whether rays are needed. Adds the leaf's estimate. */
static void sample_leaf(point_walk *w, uint32_t lv, uint64_t id, const v3 *q, size_t nq, rl_visibility vis)
{
    const rl_transfer_ctx *ctx = w->ctx;
    const rl_emitter *e = w->e;
    v3 dir[RL_MAX_POLY_VERTS + 8];
    double om[RL_MAX_POLY_VERTS + 8];
    double total = rl__sph_fan(q, nq, w->x, dir, om);
    if (!(total > 0))
        return;
    uint32_t k = w->rays;
    uint64_t key = ilf_hash_mix(ilf_hash_mix(rl__pair_key(ctx, w->ei, w->receiver), lv), id);
    lds_key lk = rl__lds_make(key);
    double hx = v3_dot(v3_sub(w->x, e->frame.origin), e->frame.n);
    double sum[3] = {0, 0, 0}; /* light arriving */
    v3 org[RL_RAY_PACKET], rd[RL_RAY_PACKET];
    double tn[RL_RAY_PACKET], tf[RL_RAY_PACKET], lc[RL_RAY_PACKET][3];
    int occluded[RL_RAY_PACKET];
    size_t nb = 0;
    for (uint32_t i = 0; i <= k; i++) {
        if (nb == RL_RAY_PACKET || (i == k && nb > 0)) {
            w->cnt->rays_cast += nb;
            rl__tracer_occluded_n(ctx->tracer, nb, org, rd, tn, tf, occluded);
            for (size_t r = 0; r < nb; r++) {
                w->cnt->rays_kept += !occluded[r];
                for (int c = 0; !occluded[r] && c < 3; c++)
                    sum[c] += lc[r][c];
            }
            nb = 0;
        }
        if (i == k)
            break;
        double u[4];
        rl__lds4(&lk, i, u);
        v3 to_s = rl__sph_fan_sample(dir, om, nq, total, u[0], u[1]);
        double cos_r = v3_dot(to_s, w->nx), dn = -v3_dot(to_s, e->frame.n);
        w->cnt->samples++;
        if (!(cos_r > 0) || !(dn > 0))
            continue;
        double t = hx / dn, l[3];
        if (w->constant) {
            for (int c = 0; c < 3; c++)
                l[c] = e->emission[c];
        } else {
            v2 sq = frame_project(&e->frame, v3_madd(w->x, to_s, t));
            rl__emitter_radiance_at(e, sq, v3_scale(to_s, -1.0), l);
        }
        if (!(l[0] > 0 || l[1] > 0 || l[2] > 0))
            continue;
        for (int c = 0; c < 3; c++)
            l[c] *= cos_r;
        if (vis == VIS_FREE) { /* (a constant emitter's FREE nodes never get here) */
            for (int c = 0; c < 3; c++)
                sum[c] += l[c];
            continue;
        }
        org[nb] = w->x;
        rd[nb] = to_s;
        tn[nb] = w->eps / dmax(cos_r, 1e-3);
        tf[nb] = t - w->eps / dmax(dn, 1e-3);
        memcpy(lc[nb], l, sizeof l);
        nb++;
    }
    for (int c = 0; c < 3; c++)
        w->out[c] += total * sum[c] / k;
}

/* Visits node (lv, id) whose parent's part of S is src (n vertices) and
 * whose possible occluders are list (nlist; SIZE_MAX: unknown), at depth. */
static void visit(point_walk *w, uint32_t lv, uint64_t id, const v3 *src, size_t n, const uint32_t *list,
                  size_t nlist, rl_visibility parent, int depth)
{
    const rl_transfer_ctx *ctx = w->ctx;
    w->cnt->leaves_considered++;
    if (w->e->kind == EM_SLAB && ctx->sampling->zero_culling && rl__emitter_node_dark(w->e, lv, id)) {
        w->cnt->leaves_culled++;
        return;
    }
    v3 q[RL_MAX_POLY_VERTS + 8];
    size_t nq = node_part(w, lv, id, src, n, q);
    if (nq < 3) {
        w->cnt->leaves_culled++;
        return; /* the node does not see S */
    }
    rl_beam *pyr = rl__beam_make(&w->x, 1, q, nq, w->eps, w->beam) ? w->beam : NULL;
    rl_visibility vis = VIS_FREE;
    uint32_t *mine = w->occ + (size_t)depth * OCC_CAP;
    size_t nmine = 0;
    /* no pyramid: S is within a ray's end margin of x, where no ray can be
     * blocked either (its interval is empty), so the node is FREE as rays see it */
    if (parent != VIS_FREE && pyr) {
        if (nlist == SIZE_MAX) {
            uint32_t *tmp = w->occ + (size_t)(WALK_LEVELS - 1) * OCC_CAP; /* the last level is never a node's */
            size_t found = rl__occluders_collect(ctx->occluders, pyr, w->e->polygon, tmp, OCC_CAP);
            if (found == SIZE_MAX) {
                vis = VIS_PARTIAL;
                nmine = SIZE_MAX;
            } else {
                vis = rl__occluders_classify(ctx->occluders, pyr, tmp, found, mine, &nmine);
            }
        } else {
            vis = rl__occluders_classify(ctx->occluders, pyr, list, nlist, mine, &nmine);
        }
    }
    if (vis == VIS_BLOCKED) {
        w->cnt->leaves_culled++;
        return;
    }
    if (vis == VIS_FREE && w->constant) {
        double f = rl__polygon_lambert(w->x, w->nx, q, nq);
        for (int c = 0; c < 3; c++)
            w->out[c] += w->e->emission[c] * f;
        return;
    }
    if (lv >= w->level || depth + 3 >= WALK_LEVELS) { /* the last two lists are the root's and a spare */
        sample_leaf(w, lv, id, q, nq, vis);
        return;
    }
    uint64_t ch[4];
    lfio_part_children(lv, id, ch);
    for (int k = 0; k < 4; k++)
        visit(w, 2 * lv, ch[k], q, nq, mine, nmine, vis, depth + 1);
}

int rl__point_gather(const rl_transfer_ctx *ctx, uint32_t ei, uint64_t receiver, v3 x, v3 nx, uint32_t rays,
                 double out[3], rl_scratch *s, rl_counters *cnt)
{
    const rl_emitter *e = &ctx->emitters[ei];
    if (!(v3_dot(v3_sub(x, e->frame.origin), e->frame.n) > 0))
        return 0; /* behind the emitter, or in its plane */
    if (!s->occ && !(s->occ = malloc((size_t)WALK_LEVELS * OCC_CAP * sizeof *s->occ)))
        return -1;
    if (!s->beam && !(s->beam = malloc(sizeof *s->beam)))
        return -1;
    point_walk *w = malloc(sizeof *w);
    if (!w)
        return -1;
    w->ctx = ctx;
    w->e = e;
    w->ei = ei;
    w->receiver = receiver;
    w->rays = rays;
    w->level = ctx->sampling->partition_n;
    w->x = x;
    w->nx = nx;
    w->constant = e->kind == EM_CONST;
    w->occ = s->occ;
    w->beam = s->beam;
    w->out = out;
    w->cnt = cnt;
    w->ns = rl__clip_poly3(e->verts, e->nverts, x, nx, w->s);
    if (w->ns < 3) {
        free(w);
        return 0;
    }
    /* rays stop short of both ends by eight single-precision units of the
     * largest recentred coordinate involved, as for cells */
    double r = v3_maxabs(v3_sub(x, ctx->centre));
    for (size_t i = 0; i < w->ns; i++)
        r = dmax(r, v3_maxabs(v3_sub(w->s[i], ctx->centre)));
    w->eps = dmax(1e-6 * r, ctx->eps);
    /* the whole view first: most points see most emitters unoccluded */
    rl_beam *root = s->beam; /* classified before visit() reuses it */
    {
        uint32_t *top = w->occ + (size_t)(WALK_LEVELS - 2) * OCC_CAP;
        size_t n = 0;
        rl_visibility vis = VIS_FREE; /* without a pyramid, as in visit() */
        if (rl__beam_make(&x, 1, w->s, w->ns, w->eps, root)) {
            size_t found = rl__occluders_collect(ctx->occluders, root, e->polygon, w->occ, OCC_CAP);
            n = SIZE_MAX;
            vis = VIS_PARTIAL;
            if (found != SIZE_MAX)
                vis = rl__occluders_classify(ctx->occluders, root, w->occ, found, top, &n);
        }
        if (vis != VIS_BLOCKED) {
            if (vis == VIS_FREE && w->constant) {
                double f = rl__polygon_lambert(x, nx, w->s, w->ns);
                for (int c = 0; c < 3; c++)
                    out[c] += e->emission[c] * f;
            } else {
                for (uint64_t id = 0; id < lfio_part_hemi_count(1); id++)
                    visit(w, 1, id, w->s, w->ns, top, n, vis, 0);
            }
        }
    }
    free(w);
    return 0;
}
