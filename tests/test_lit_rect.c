/*
 * test_lit_rect.c - the rectangle outside which a light field sends nothing
 * toward a receiver (rl__emitter_lit_rect(), relight/src/emitter.c), checked
 * against the radiance itself.
 *
 * A slab lit like a lamp (each position lit along directions near the line
 * from a point behind it, plus scattered single values) is placed with a
 * random rotation. For random receivers (a few points, from a millimetre to
 * half a metre across, near and far, ahead, grazing, and behind the slab's
 * plane) and random parts of the slab, every pair of a point of the
 * receiver's hull and a point of the part where rl__emitter_radiance_at()
 * reads light (lfio's own lookup) must have the part's point inside the
 * rectangle and must not be called dark by rl__emitter_dark_at(), a receiver
 * called dark must read none, and rl__emitter_radiance_at() (which skips
 * the lookup where it is called dark) must read what lfio does. The rectangle must also be smaller than the slab for many receivers,
 * and the test along a direction must find much of the darkness, or either
 * bound would be true and useless.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lfio/lightfield.h>
#include <lfio/partition.h>

#include "check.h"
#include "method.h"
#include "scene_model.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

/* @return a uniform number in [0, 1). */
static double rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* @return a slab of partition n, nu x nu positions over 1 m, lit around the rays from a point 0.4 m behind it
 * within a cone of half-angle cone_deg, plus scattered lone values; with cone_deg 0, each direction at
 * one position of its own; below 0, directions grazing along v alone. */
static lfio_slab *lamp_slab_new(uint32_t n, uint32_t nu, uint32_t nv, double cone_deg)
{
    lfio_slab_desc d;
    lfio_slab *slab = NULL;
    lfio_slab_desc_init(&d);
    strcpy(d.name, "lamp");
    /* nv != nu: a slab 0.6 m along v, so that swapping the axes anywhere shows */
    double lv = nv == nu ? 1.0 : 0.6;
    d.origin[0] = -0.5, d.origin[1] = -0.5 * lv;
    d.v[1] = lv;
    d.nu = nu, d.nv = nv;
    d.n = n;
    CHECK(lfio_slab_new(&d, &slab) == LFIO_OK, "new slab: %s", lfio_errmsg());
    double cos_cone = cos(cone_deg * 3.14159265358979323846 / 180.0);
    uint64_t nd = lfio_slab_dir_count(slab);
    for (uint64_t k = 0; k < nd; k++) {
        double w[3];
        lfio_part_centroid(n, k, w);
        for (uint32_t j = 0; j < nv; j++)
            for (uint32_t i = 0; i < nu; i++) {
                double c[3] = {-0.5 + (i + 0.5) / nu, lv * (-0.5 + (j + 0.5) / nv), 0.4}; /* from p = (0, 0, -0.4) */
                double cw = (c[0] * w[0] + c[1] * w[1] + c[2] * w[2]) / sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                /* cone_deg 0: each direction lit at one position alone, so that every square of the
                 * diamond a bound leaves out shows; below 0: only directions grazing the slab along v,
                 * which a receiver just above the slab's middle sees between its corners, not at them */
                int lit = cone_deg > 0.0   ? cw > cos_cone || rnd() < 0.002
                          : cone_deg == 0.0 ? (i + nu * j) == (k * 2654435761u) % (nu * nv)
                                            : fabs(w[1]) > 0.7 * (fabs(w[0]) + fabs(w[1]) + fabs(w[2]));
                float v = lit ? (float)(1.0 + rnd()) : 0.0f;
                lfio_slab_write(slab, k, i, j, (const float[3]){v, v, v});
            }
    }
    return slab;
}

/* Gives rot a random rotation (det +1). */
static void random_rotation(double rot[3][3])
{
    double q[4], len = 0.0;
    for (int k = 0; k < 4; k++)
        q[k] = rnd() - 0.5, len += q[k] * q[k];
    len = sqrt(len);
    double a = q[0] / len, b = q[1] / len, c = q[2] / len, d = q[3] / len;
    double r[3][3] = {{a * a + b * b - c * c - d * d, 2 * (b * c - a * d), 2 * (b * d + a * c)},
                      {2 * (b * c + a * d), a * a - b * b + c * c - d * d, 2 * (c * d - a * b)},
                      {2 * (b * d - a * c), 2 * (c * d + a * b), a * a - b * b - c * c + d * d}};
    memcpy(rot, r, sizeof r);
}

/* Places slab in lf scaled by scale, with a random rotation and translation, and builds its tables into tab
 * as a run makes them. */
static void place(rl_lightfield *lf, rl_slab_tables *tab, const lfio_slab *slab, double scale)
{
    memset(lf, 0, sizeof *lf);
    lf->slab = slab;
    lf->scale = scale;
    random_rotation(lf->rot);
    const lfio_slab_desc *d = lfio_slab_get_desc(slab);
    double t[3] = {rnd() * 4 - 2, rnd() * 4 - 2, rnd() * 4 - 2};
    for (int r = 0; r < 3; r++) {
        lf->origin[r] = t[r], lf->u[r] = lf->v[r] = 0.0;
        for (int c = 0; c < 3; c++) {
            lf->origin[r] += scale * lf->rot[r][c] * d->origin[c];
            lf->u[r] += scale * lf->rot[r][c] * d->u[c];
            lf->v[r] += scale * lf->rot[r][c] * d->v[c];
        }
    }
    lf->nu = d->nu, lf->nv = d->nv, lf->n = d->n;
    memset(tab, 0, sizeof *tab);
    CHECK(rl__slab_tables_make(lf, tab) == 0, "tables");
}

/* @return a random point of the convex hull of the n points p (weights skewed at times to reach corners). */
static v2 hull_point2(const v2 *p, uint32_t n)
{
    double w[RL_MAX_POLY_VERTS], sum = 0.0, skew = rnd() < 0.5 ? 1.0 : 6.0;
    v2 q = {0, 0};
    for (uint32_t i = 0; i < n; i++)
        w[i] = pow(rnd(), skew), sum += w[i];
    for (uint32_t i = 0; i < n; i++)
        q.x += p[i].x * w[i] / sum, q.y += p[i].y * w[i] / sum;
    return q;
}

static v3 hull_point3(const v3 *p, uint32_t n)
{
    double w[8], sum = 0.0, skew = rnd() < 0.5 ? 1.0 : 6.0;
    v3 q = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++)
        w[i] = pow(rnd(), skew), sum += w[i];
    for (uint32_t i = 0; i < n; i++)
        q = v3_add(q, v3_scale(p[i], w[i] / sum));
    return q;
}

/* The reference: emitter e's radiance at frame point q along d (unit, world) straight from lfio, as
 * rl__emitter_radiance_at() reads it but without its test for darkness. */
static double slab_radiance(const rl_emitter *e, v2 q, v3 d)
{
    const double(*r)[3] = e->lf->rot;
    double ds[3] = {r[0][0] * d.x + r[1][0] * d.y + r[2][0] * d.z, r[0][1] * d.x + r[1][1] * d.y + r[2][1] * d.z,
                    r[0][2] * d.x + r[1][2] * d.y + r[2][2] * d.z};
    float rgb[3] = {0, 0, 0};
    lfio_slab_radiance_interp(e->lf->slab, q.x / e->len_u, q.y / e->len_v, ds, rgb);
    return rgb[0];
}

/* One slab, many receivers: the bound's promise at random pairs of points. */
static void check_slab(uint32_t n, uint32_t nu, uint32_t nv, double cone_deg, double scale, int receivers,
                       long *tight, long *bounded, long *dark_pairs, long *dark_called)
{
    lfio_slab *slab = lamp_slab_new(n, nu, nv, cone_deg);
    rl_lightfield lf;
    rl_slab_tables tab;
    place(&lf, &tab, slab, scale);
    rl_emitter e;
    rl__emitter_from_lightfield(&lf, &tab, &e);
    for (int r = 0; r < receivers; r++) {
        /* the receiver: 1 to 8 points around a centre given in the slab's frame */
        double size = pow(10.0, -3.0 + 2.7 * rnd()), h = rnd() < 0.1 ? size * (rnd() - 0.5) : pow(10.0, -2.0 + 2.5 * rnd());
        v2 c2 = {-1.5 + 4.0 * rnd(), -1.5 + 4.0 * rnd()};
        v3 centre = v3_add(frame_point(&e.frame, c2), v3_scale(e.frame.n, h));
        v3 x[8];
        uint32_t nx = 1 + (uint32_t)(rnd() * 8);
        for (uint32_t i = 0; i < nx; i++)
            x[i] = v3_add(centre, (v3){size * (rnd() - 0.5), size * (rnd() - 0.5), size * (rnd() - 0.5)});
        /* the part of the slab: all of it, or cut by a random line through it */
        v2 y[RL_MAX_POLY_VERTS];
        uint32_t ny = e.nverts;
        memcpy(y, e.poly2, ny * sizeof *y);
        if (rnd() < 0.5) {
            v2 a = hull_point2(e.poly2, e.nverts), b = hull_point2(e.poly2, e.nverts);
            v2 cut[RL_MAX_POLY_VERTS];
            uint32_t nc = (uint32_t)rl__clip_poly2(y, ny, edge_halfplane(a, b), cut);
            if (nc >= 3 && rl__polygon_area2(cut, nc) > 1e-6)
                memcpy(y, cut, nc * sizeof *y), ny = nc;
        }
        double rect[4];
        int got = rl__emitter_lit_rect(&e, x, nx, y, ny, rect);
        int behind = 0;
        for (uint32_t i = 0; i < nx; i++)
            behind |= !(v3_dot(v3_sub(x[i], e.frame.origin), e.frame.n) > 0.0);
        CHECK(got == 0 || !behind, "receiver %d: a point behind the slab's plane but a bound %d", r, got);
        if (got == 1) {
            (*bounded)++;
            *tight += (rect[1] - rect[0]) * (rect[3] - rect[2]) < 0.8 * e.len_u * e.len_v;
        }
        for (int k = 0; k < 400; k++) {
            v3 xp = hull_point3(x, nx);
            v2 q = hull_point2(y, ny);
            v3 d = v3_sub(xp, frame_point(&e.frame, q));
            double len = v3_len(d), rad[3];
            if (!(len > 0.0) || !(v3_dot(d, e.frame.n) > 0.0))
                continue;
            rl__emitter_radiance_at(&e, q, v3_scale(d, 1.0 / len), rad);
            double ref = slab_radiance(&e, q, v3_scale(d, 1.0 / len));
            CHECK(rad[0] == ref, "receiver %d: the engine reads %g where lfio reads %g", r, rad[0], ref);
            rad[0] = ref;
            int called_dark = rl__emitter_dark_at(&e, q, v3_dot(d, e.frame.e1) / len, v3_dot(d, e.frame.e2) / len,
                                                  v3_dot(d, e.frame.n) / len);
            if (!(rad[0] > 0.0)) {
                *dark_pairs += 1, *dark_called += called_dark;
                continue;
            }
            CHECK(got >= 0, "receiver %d (size %g, height %g): called dark but reads %g at (%g, %g)", r, size, h, rad[0],
                  q.x, q.y);
            CHECK(!called_dark, "receiver %d (size %g, height %g): light at (%g, %g) called dark along its direction", r, size, h, q.x,
                  q.y);
            if (got == 1)
                CHECK(q.x >= rect[0] - 1e-12 && q.x <= rect[1] + 1e-12 && q.y >= rect[2] - 1e-12 &&
                          q.y <= rect[3] + 1e-12,
                      "receiver %d (size %g, height %g): light at (%g, %g) outside [%g, %g] x [%g, %g]", r, size, h,
                      q.x, q.y, rect[0], rect[1], rect[2], rect[3]);
        }
    }
    rl__slab_tables_free(&tab);
    lfio_slab_destroy(slab);
}

/* A slab too finely divided for the tables of squares: no bound, and nothing called dark. */
static void check_no_tables(void)
{
    lfio_slab_desc d;
    lfio_slab *slab = NULL;
    lfio_slab_desc_init(&d);
    strcpy(d.name, "fine");
    /* the smallest partition whose (2n)^2 boxes of 16 bytes pass the limit */
    while ((uint64_t)(2 * d.n) * (2 * d.n) * 16 <= RL_CONE_MAX_BYTES)
        d.n++;
    CHECK(lfio_slab_new(&d, &slab) == LFIO_OK, "new slab: %s", lfio_errmsg());
    rl_lightfield lf;
    rl_slab_tables tab;
    place(&lf, &tab, slab, 1.0);
    CHECK(tab.cone_support == NULL && tab.lit_words == 0, "no tables of squares at n = %u", d.n);
    rl_emitter e;
    rl__emitter_from_lightfield(&lf, &tab, &e);
    v3 x = v3_add(frame_point(&e.frame, (v2){0.5, 0.5}), e.frame.n);
    double rect[4];
    CHECK(rl__emitter_lit_rect(&e, &x, 1, e.poly2, e.nverts, rect) == 0, "no bound without tables");
    CHECK(!rl__emitter_dark_at(&e, (v2){0.5, 0.5}, 0.0, 0.0, 1.0), "nothing dark without bits");
    rl__slab_tables_free(&tab);
    lfio_slab_destroy(slab);
}

int main(void)
{
    check_no_tables();
    long tight = 0, bounded = 0, dark_pairs = 0, dark_called = 0;
    for (int s = 0; s < 6; s++) {
        check_slab(8, 12, 12, 15.0, 1.0, 300, &tight, &bounded, &dark_pairs, &dark_called);
        check_slab(16, 16, 16, 20.0, 1.0, 300, &tight, &bounded, &dark_pairs, &dark_called);
        check_slab(4, 5, 5, 30.0, 1.0, 100, &tight, &bounded, &dark_pairs, &dark_called);
        check_slab(8, 16, 16, 0.0, 1.0, 300, &tight, &bounded, &dark_pairs, &dark_called);
        check_slab(8, 4, 4, -1.0, 1.0, 300, &tight, &bounded, &dark_pairs, &dark_called);
        /* a grid longer along u than v on a slab shorter along v, scaled; and a finer partition */
        check_slab(8, 12, 5, 0.0, 1.7, 300, &tight, &bounded, &dark_pairs, &dark_called);
        check_slab(16, 9, 14, 15.0, 0.4, 300, &tight, &bounded, &dark_pairs, &dark_called);
        check_slab(64, 6, 6, 0.0, 1.0, 100, &tight, &bounded, &dark_pairs, &dark_called);
    }
    printf("%ld of %ld bounded receivers see light from under 80%% of the slab\n", tight, bounded);
    printf("%ld of %ld pairs of points that read zero are called dark along their direction\n", dark_called, dark_pairs);
    CHECK(dark_called > dark_pairs / 4, "the per-direction test should find most darkness: %ld of %ld", dark_called,
          dark_pairs);
    CHECK(bounded > 2000 && tight > bounded / 8, "the bound should narrow the slab often: %ld of %ld", tight, bounded);
    return check_report();
}
